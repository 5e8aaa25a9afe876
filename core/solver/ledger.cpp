// The energy book (docs/MODEL.md §3, §8): the ledger row at t - dt/2 and the end-of-step sums.
#include "solver/stage.h"

namespace ravel::detail {
namespace {

// The stage's inputs, bound for its helpers.
template <class Real>
struct Book {
  using V3 = Eigen::Matrix<Real, 3, 1>;
  const Model& model_;
  State<Real>& s_;
  RunState& run_;
  Context<Real>& ctx_;

  double shift_energy();
  double element_energy_at(int e, Real len) const;
  // A bending spring's energy with node positions from pos (internal_forces' law; 0 when
  // either element is broken).
  template <class Pos>
  double bend_energy_at(int sp, Pos&& pos) const {
    const int e1 = model_.bend_e1[sp], e2 = model_.bend_e2[sp];
    if (s_.broken_flag[e1] || s_.broken_flag[e2]) return 0;
    const double k = model_.bend_k[sp], r = model_.bend_rest[sp];
    if (const int ax = model_.bend_mirror[sp]; ax >= 0) {
      const double mc = 0.5 * double(pos(model_.elem_a[e1])[ax] + pos(model_.elem_b[e1])[ax]);
      const double comp = r - 2 * std::abs(mc);
      return comp > 0 ? 0.25 * k * comp * comp : 0.0;
    }
    const V3 m1 = Real(0.5) * (pos(model_.elem_a[e1]) + pos(model_.elem_b[e1]));
    const V3 m2 = Real(0.5) * (pos(model_.elem_a[e2]) + pos(model_.elem_b[e2]));
    const double sl = double((m2 - m1).norm());
    if (sl >= r) return 0;
    return sl >= 0.5 * r ? 0.5 * k * (r - sl) * (r - sl) : 0.25 * k * r * r - 0.5 * k * sl * sl;
  }
  void finish_step();
};

}  // namespace

// The ledger at t - dt/2 (EnergyBook::close_row), and the energy-balance check on it.
template <class Real>
void close_ledger_row(const Model& model, State<Real>& s, RunState& run, double max_balance_error) {
  if (run.steps == 0) {
    s.book.start();
    return;
  }
  s.book.close_row(run.ledger);
  check_balance(model, s, run, max_balance_error, run.ledger.total());
}

template <class Real>
double fabric_ke(const Model& model, const State<Real>& s) {
  double ke = 0;
  for (int i = 0; i < model.node_count; ++i) ke += 0.5 * model.mass[i] * double(s.v[i].squaredNorm());
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
// s_.shifted: the shifted nodes in node order (finish_step lists them).
template <class Real>
RAVEL_INLINE double Book<Real>::shift_energy() {
  if (s_.shifted.empty()) return 0;
  if (s_.elem_mark.empty()) s_.elem_mark.assign(model_.element_count, 0), s_.bend_mark.assign(model_.bend_k.size(), 0);
  if (++s_.mark == 0) {  // wrapped: clear the marks
    std::fill(s_.elem_mark.begin(), s_.elem_mark.end(), 0u);
    std::fill(s_.bend_mark.begin(), s_.bend_mark.end(), 0u);
    s_.mark = 1;
  }
  auto before = [&](int i) { return V3(s_.x[i] - s_.corr[i].dx_contact); };
  double du = 0;
  for (const int i : s_.shifted) {
    for (int k = ctx_.inc_e_off[i]; k < ctx_.inc_e_off[i + 1]; ++k) {
      const int e = ctx_.inc_e[k] >= 0 ? ctx_.inc_e[k] : ~ctx_.inc_e[k];
      if (s_.elem_mark[e] == s_.mark || s_.broken_flag[e]) continue;
      s_.elem_mark[e] = s_.mark;
      const int a = model_.elem_a[e], b = model_.elem_b[e];
      du += element_energy_at(e, (s_.x[b] - s_.x[a]).norm()) - element_energy_at(e, (before(b) - before(a)).norm());
    }
    for (int k = ctx_.inc_b_off[i]; k < ctx_.inc_b_off[i + 1]; ++k) {
      const int sp = ctx_.inc_b[k].first;
      if (s_.bend_mark[sp] == s_.mark) continue;
      s_.bend_mark[sp] = s_.mark;
      du += bend_energy_at(sp, [&](int n) { return s_.x[n]; }) - bend_energy_at(sp, before);
    }
  }
  return du;
}

// An element's stored energy at length len with its current internal strain.
template <class Real>
inline double Book<Real>::element_energy_at(int e, Real len) const {
  const double rest = elem_rest_now(model_, s_, e), vol = model_.elem_area[e] * rest;
  Real eps = len / Real(rest) - Real(1), mat = eps, dg = Real(1);
  if (model_.crimp_strain > 0) crimp_stage(model_, eps, mat, dg);
  if (model_.material == Material::zener) {
    const double sig = std::max(0.0, ctx_.zener.c.k1 * (double(mat) - double(s_.ev[e])));
    return zener_stored(ctx_.zener.c, sig, double(s_.ev[e])) * vol;
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
void Book<Real>::finish_step() {
  double ke = 0, w_contact = 0, w_friction = 0, w_pfriction = 0, w_compress = 0;
  const int n = model_.node_count;
  // Yarn-yarn friction and compression act only where yarns cross and slide (the sliding
  // model); the pin-jointed net has no crossings, and their velocity changes stay zero.
  const bool yarn_contact = !model_.crossings.empty();
  s_.shifted.clear();
  if (!yarn_contact) {
    // No crossings (the pin-jointed net, a single yarn): only the projectile's contact moved
    // nodes or changed their velocities this step, and only on the nodes it touched
    // (ptouch_list, in node order). The kinetic energy is summed over every node here; the
    // contact's work over the touched nodes alone (with the projectile's friction, below),
    // which leaves out only terms that are zero (in node order on one thread; at 2+ threads
    // the serial sum can differ in its last bits from the per-thread sums before, where the
    // touched nodes straddle the threads' shares).
#pragma omp parallel for num_threads(ctx_.threads) schedule(static) reduction(+ : ke) if (ctx_.threads > 1)
    for (int i = 0; i < n; ++i) ke += 0.5 * model_.mass[i] * double(s_.v[i].squaredNorm());
  } else {
    // The yarn contact's last pass took these sums over each thread's nodes
    // (YarnContact::finish_last_pass): summed here in thread order. (Its shares are the pass's
    // node ranges, my_share; with a node count the threads do not divide they split the nodes
    // elsewhere than the static loop that summed them until 2026-12-08, so at 2+ threads the
    // ledger's last bits can move against that code. The state does not; 1 thread is the same.)
    for (const NodeBook& b : ctx_.node_book)
      ke += b.ke, w_contact += b.w_contact, w_friction += b.w_friction, w_compress += b.w_compress;
    for (const auto& part : ctx_.shifted_part) s_.shifted.insert(s_.shifted.end(), part.begin(), part.end());
  }
  // The projectile's friction touched only the nodes on it (in node order), and without
  // crossings so did every contact correction (above).
  for (int i : s_.ptouch_list) {
    const double hm = 0.5 * model_.mass[i];
    const V3 vsum = s_.v_prev[i] + s_.v[i];
    if (!yarn_contact) {
      auto& c = s_.corr[i];
      w_contact += hm * double(c.dv_contact.dot(vsum));
      c.dv_contact.setZero();
      if (c.dx_contact.x() != Real(0) || c.dx_contact.y() != Real(0) || c.dx_contact.z() != Real(0))
        s_.shifted.push_back(i);
    }
    w_pfriction += hm * double(s_.dv_pfriction[i].dot(vsum));
    s_.dv_pfriction[i].setZero();
  }
  s_.ptouch_list.clear();
  // External loads: F . (dx(t - dt/2) + dx(t + dt/2)) / 2.
  for (const auto& [i, F] : s_.f_ext)
    s_.book.external_cum += 0.5 * double(model_.dt) * double(F.dot(s_.v_prev[i] + s_.v[i]));
  s_.book.contact_cum -= w_contact;
  s_.book.shift_cum -= shift_energy();
  s_.book.compress_work_cum += w_compress;
  s_.book.friction_work_cum += w_friction;
  s_.book.pfriction_cum -= w_pfriction;
  s_.book.ke_fabric_half = ke;
  s_.book.ke_half = s_.book.ke_fabric_half + 0.5 * model_.projectile_mass * double(s_.vp.squaredNorm());
  run_.time += model_.dt;
  ++run_.steps;
}

template <class Real>
void finish_step(const Model& model, State<Real>& s, RunState& run, Context<Real>& ctx) {
  Book<Real>{model, s, run, ctx}.finish_step();
}

// The two precisions (solver.h: Precision).
template void close_ledger_row(const Model&, State<float>&, RunState&, double);
template void close_ledger_row(const Model&, State<double>&, RunState&, double);
template double fabric_ke(const Model&, const State<float>&);
template double fabric_ke(const Model&, const State<double>&);
template void finish_step(const Model&, State<float>&, RunState&, Context<float>&);
template void finish_step(const Model&, State<double>&, RunState&, Context<double>&);

}  // namespace ravel::detail
