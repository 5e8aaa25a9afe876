// The energy book (docs/MODEL.md §3, §8): the ledger row at t - dt/2 and the end-of-step sums.
#include "solver/solver_t.h"

namespace ravel::detail {

// The ledger at t - dt/2 (see the header comment): kinetic energy of v(t - dt/2), the
// mean of stored / cumulative-dissipation values at t - dt and t.
template <class Real>
void SolverT<Real>::close_ledger_row() {
  if (steps_ == 0) {
    compress_prev_ = compress_end_;
    stick_prev_ = stick_end_;
    stored_prev_ = stored_now_;
    viscous_prev_ = viscous_cum_;
    released_prev_ = released_cum_;
    return;
  }
  Ledger& l = ledger_;
  l.fabric_ke_J = ke_fabric_half_;
  l.projectile_ke_J = ke_half_ - ke_fabric_half_;
  l.strain_energy_J = 0.5 * (stored_prev_ + stored_now_);
  l.viscous_J = 0.5 * (viscous_prev_ + viscous_cum_);
  l.damping_J = damping_cum_;
  l.released_J = 0.5 * (released_prev_ + released_cum_);
  // Dissipated by friction: the work its impulses took from the yarns (and the projectile)
  // less what the stick penalty springs hold (Eq 12: a stuck contact stores K/2 e^2 and
  // gives it back; only the rest is lost).
  l.projectile_friction_J = pfriction_cum_;
  l.contact_loss_J = contact_cum_;
  l.shift_work_J = shift_cum_;
  l.compression_J = 0.5 * (compress_prev_ + compress_end_);
  l.stick_energy_J = 0.5 * (stick_prev_ + stick_end_);
  l.friction_work_J = 0.0 - (friction_work_cum_ + l.stick_energy_J);  // (0.0 - : no negative zero)
  l.compression_loss_J = -compress_work_cum_ - l.compression_J;
  l.external_work_J = external_cum_;
  stored_prev_ = stored_now_;
  viscous_prev_ = viscous_cum_;
  released_prev_ = released_cum_;
  compress_prev_ = compress_end_;
  stick_prev_ = stick_end_;
  check_balance(l.total());
}

template <class Real>
double SolverT<Real>::fabric_ke() const {
  double ke = 0;
  for (int i = 0; i < model_.node_count; ++i) ke += 0.5 * model_.mass[i] * double(v_[i].squaredNorm());
  return ke;
}

// The energy this step's position shifts put into the yarns (elements and bending springs),
// from the laws themselves: the energy of each element or spring a shifted node belongs to,
// at the end of the step, less its energy with the shifts taken back (its internal strain
// e_v as it is: a shift is instantaneous). The velocity-driven part of the step's change is
// the leapfrog's work of the element forces, so this split is exact in the shift. (The
// trapezoid rule booked before, half with the next step's force, erred by shift x motion:
// 20 % of the impact energy created over 1.4-3.6 ms of low-friction runs near the limit,
// where whipping yarn ends were shifted tens of um per step at 200 m/s.)
template <class Real>
RAVEL_INLINE double SolverT<Real>::shift_energy() {
  shifted_.clear();
  for (int i = 0; i < model_.node_count; ++i)
    if (dx_contact_[i].x() != Real(0) || dx_contact_[i].y() != Real(0) || dx_contact_[i].z() != Real(0))
      shifted_.push_back(i);
  if (shifted_.empty()) return 0;
  if (elem_mark_.empty()) elem_mark_.assign(model_.element_count, 0), bend_mark_.assign(model_.bend_k.size(), 0);
  if (++mark_ == 0) {  // wrapped: clear the marks
    std::fill(elem_mark_.begin(), elem_mark_.end(), 0u);
    std::fill(bend_mark_.begin(), bend_mark_.end(), 0u);
    mark_ = 1;
  }
  auto before = [&](int i) { return V3(x_[i] - dx_contact_[i]); };
  double du = 0;
  for (const int i : shifted_) {
    for (int k = inc_e_off_[i]; k < inc_e_off_[i + 1]; ++k) {
      const int e = inc_e_[k].first;
      if (elem_mark_[e] == mark_ || broken_flag_[e]) continue;
      elem_mark_[e] = mark_;
      const int a = model_.elem_a[e], b = model_.elem_b[e];
      du += element_energy_at(e, (x_[b] - x_[a]).norm()) - element_energy_at(e, (before(b) - before(a)).norm());
    }
    for (int k = inc_b_off_[i]; k < inc_b_off_[i + 1]; ++k) {
      const int sp = inc_b_[k].first;
      if (bend_mark_[sp] == mark_) continue;
      bend_mark_[sp] = mark_;
      du += bend_energy_at(sp, [&](int n) { return x_[n]; }) - bend_energy_at(sp, before);
    }
  }
  return du;
}

// An element's stored energy at length len with its current internal strain.
template <class Real>
inline double SolverT<Real>::element_energy_at(int e, Real len) const {
  const double rest = model_.elem_rest[e], vol = model_.elem_area[e] * rest;
  Real eps = len / Real(rest) - Real(1), mat = eps, dg = Real(1);
  if (model_.crimp_strain > 0) crimp_stage(eps, mat, dg);
  if (model_.material == Material::zener) {
    const double sig = std::max(0.0, zener_.c.k1 * (double(mat) - double(ev_[e])));
    return zener_stored(zener_.c, sig, double(ev_[e])) * vol;
  }
  const double sig = std::max(0.0, model_.modulus_inst * double(mat));
  return sig * sig / (2 * model_.modulus_inst) * vol;
}

// Kinetic energy of v(t + dt/2) and the work of this step's corrections, in one sweep.
// Work of a correction in the leapfrog's own energy statement: with v- = v(t - dt/2) and
// v+ = v(t + dt/2) after all corrections, KE(v+) - KE(v-) = sum over forces F of
// F . (dx(t - dt/2) + dx(t + dt/2)) / 2 exactly; a correction dv is a force m dv/dt, so
// its work is m dv . (v- + v+) / 2. (Booking the bare kinetic-energy change of each
// correction instead would count, every step, energy a resting contact never takes.)
template <class Real>
void SolverT<Real>::finish_step() {
  double ke = 0, w_contact = 0, w_friction = 0, w_pfriction = 0, w_compress = 0;
  const int n = model_.node_count;
#pragma omp parallel for num_threads(threads_) schedule(static) reduction(+ : ke, w_contact, w_friction, w_pfriction, w_compress) if (threads_ > 1)
  for (int i = 0; i < n; ++i) {
    const double hm = 0.5 * model_.mass[i];
    ke += hm * double(v_[i].squaredNorm());
    const V3 vsum = v_prev_[i] + v_[i];
    w_contact += hm * double(dv_contact_[i].dot(vsum));
    w_friction += hm * double(dv_friction_[i].dot(vsum));
    dv_contact_[i].setZero();  // ready for the next step's corrections
    dv_friction_[i].setZero();
    if (compressible_) {
      w_compress += hm * double(dv_compress_[i].dot(vsum));
      dv_compress_[i].setZero();
    }
  }
  // The projectile's friction touched only the nodes on it (in node order).
  for (int i : ptouch_list_) {
    w_pfriction += 0.5 * model_.mass[i] * double(dv_pfriction_[i].dot(v_prev_[i] + v_[i]));
    dv_pfriction_[i].setZero();
  }
  ptouch_list_.clear();
  // External loads: F . (dx(t - dt/2) + dx(t + dt/2)) / 2.
  for (const auto& [i, F] : f_ext_) external_cum_ += 0.5 * double(model_.dt) * double(F.dot(v_prev_[i] + v_[i]));
  contact_cum_ -= w_contact;
  shift_cum_ -= shift_energy();
  compress_work_cum_ += w_compress;
  friction_work_cum_ += w_friction;
  pfriction_cum_ -= w_pfriction;
  ke_fabric_half_ = ke;
  ke_half_ = ke_fabric_half_ + 0.5 * model_.projectile_mass * double(vp_.squaredNorm());
  time_ += model_.dt;
  ++steps_;
}

// The two precisions (solver.h: Precision).
template void SolverT<float>::close_ledger_row();
template void SolverT<double>::close_ledger_row();
template double SolverT<float>::fabric_ke() const;
template double SolverT<double>::fabric_ke() const;
template void SolverT<float>::finish_step();
template void SolverT<double>::finish_step();

}  // namespace ravel::detail
