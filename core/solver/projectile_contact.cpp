// Stage projectile_contact (Eq 18-22), and release_held: the yarn contact's push on held nodes.
#include "solver/solver_t.h"

namespace ravel::detail {

// ------------------------------------------------------- projectile contact (Eq 18-22)
template <class Real>
void SolverT<Real>::projectile_contact() {
  const int n = model_.node_count;
  const Real dt = Real(model_.dt);
  const Real R = Real(model_.shape.bounding_radius());
  const double mu_p = model_.projectile_friction;
  const double Mp = model_.projectile_mass;
  V3 impulse_normal = V3::Zero(), impulse_fric = V3::Zero();
  int touching = 0;
  // The nodes inside the projectile's bounding box, in node order (found by the threads,
  // each in its own range, then taken range by range).
  near_part_.resize(threads_);
#pragma omp parallel num_threads(threads_) if (threads_ > 1)
  {
    int lo, hi, t;
    my_share(n, lo, hi, t);
    std::vector<int>& mine = near_part_[t];
    mine.clear();
    for (int i = lo; i < hi; ++i) {
      const V3 rel = s_.x[i] - s_.xp;
      if (!(std::abs(rel.x()) > R || std::abs(rel.y()) > R || std::abs(rel.z()) > R)) mine.push_back(i);
    }
  }
  near_.clear();
  for (const auto& part : near_part_) near_.insert(near_.end(), part.begin(), part.end());
  for (const int i : near_) {
    const V3 rel = s_.x[i] - s_.xp;
    if (model_.fixed[i] == fix_all) continue;
    V3 nrm;
    const double sd = model_.shape.sdf(rel, nrm);
    if (sd > 0) continue;
    ++touching;
    s_.ptouch_list.push_back(i);
    if (model_.projectile_holds) {
      s_.held_n[i] = nrm;
      s_.held_flag[i] = 1;
      s_.held_list.push_back(i);
    }
    const double m = model_.mass[i];
    // Eq 19: push the node back onto the surface within one step (with the split, only
    // the part this step's approach made is a velocity change; see yarn contact).
    const Real pen = Real(-sd);
    Real push = pen / dt;
    if (model_.split_penetration) {
      push = std::min(push, std::max(Real(0), -(s_.v[i] - s_.vp).dot(nrm)));
      const Real shift = pen - push * dt;
      if (shift > Real(0)) {
        V3 dx = shift * nrm;
        zero_fixed(dx, model_.fixed[i]);
        s_.x[i] += dx;
        s_.dx_contact[i] += dx;
      }
    }
    V3 dv_n = push * nrm;
    // Eq 20-22: friction from the tangential relative velocity, capped by mu_p |f_n|.
    const V3 vr = s_.v[i] + dv_n - s_.vp;
    const V3 vt = vr - vr.dot(nrm) * nrm;
    const Real vtn = vt.norm();
    V3 dv_t = V3::Zero();
    if (vtn > Real(0)) {
      const Real cap = Real(mu_p) * push;  // mu_p |f_n| dt / m, f_n of Eq 19
      dv_t = -std::min(vtn, cap) * (vt / vtn);
    }
    zero_fixed(dv_t, model_.fixed[i]);
    zero_fixed(dv_n, model_.fixed[i]);
    s_.v[i] += dv_n + dv_t;
    s_.x[i] += dt * (dv_n + dv_t);
    s_.dv_contact[i] += dv_n;
    s_.dv_pfriction[i] += dv_t;
    impulse_normal -= Real(m) * dv_n;
    impulse_fric -= Real(m) * dv_t;
  }
  // The projectile takes the reactions: momentum is conserved.
  if (touching) {
    V3 dvp_n = impulse_normal / Real(Mp), dvp_t = impulse_fric / Real(Mp);
    // In a symmetric model the mirrored parts' reactions cancel the in-plane components.
    if (model_.mirror_x) dvp_n.x() = dvp_t.x() = 0;
    if (model_.mirror_y) dvp_n.y() = dvp_t.y() = 0;
    const V3 vp_old = s_.vp;
    s_.vp += dvp_n + dvp_t;
    s_.xp += dt * (s_.vp - vp_old);
    // Work of the reactions on the projectile (it has no other force: v- = vp_old).
    const V3 vsum = vp_old + s_.vp;
    s_.book.contact_cum -= 0.5 * Mp * double(dvp_n.dot(vsum));
    s_.book.pfriction_cum -= 0.5 * Mp * double(dvp_t.dot(vsum));
    run_.last_contact_time = run_.time + model_.dt;
    run_.had_contact = true;
  }
  s_.proj_impulse = impulse_normal + impulse_fric;
  run_.nodes_on_projectile = touching;
  run_.projectile_force = double(s_.proj_impulse.norm() / dt);
}

// A node the projectile pushed out this step rests on a rigid body: the yarn contact's
// corrections do not move it back into the projectile (apply_impulse, shift_node, and the
// effective mass in pass_normal); the impulse they would have pushed it in with acts on
// the projectile instead. Summed here in node order (deterministic for any thread count).
template <class Real>
void SolverT<Real>::release_held() {
  if (s_.held_list.empty()) return;
  V3 imp = V3::Zero(), imp_f = V3::Zero(), imp_c = V3::Zero();
  for (int i : s_.held_list) {
    imp += s_.held_imp[i];
    imp_f += s_.held_fric[i];
    imp_c += s_.held_comp[i];
    s_.held_imp[i].setZero();
    s_.held_fric[i].setZero();
    s_.held_comp[i].setZero();
    s_.held_n[i].setZero();
    s_.held_flag[i] = 0;
  }
  s_.held_list.clear();
  auto dv_of = [&](const V3& p) {
    V3 dv = p / Real(model_.projectile_mass);
    if (model_.mirror_x) dv.x() = 0;
    if (model_.mirror_y) dv.y() = 0;
    return dv;
  };
  const V3 dvp = dv_of(imp);
  const V3 vp_old = s_.vp;
  s_.vp += dvp;
  s_.xp += Real(model_.dt) * dvp;
  // The work on the projectile of the friction's and the compression's shares is theirs, the
  // rest the normal correction's.
  const V3 vsum = vp_old + s_.vp;
  const double hm = 0.5 * model_.projectile_mass;
  const double w_all = hm * double(dvp.dot(vsum));
  const double w_f = hm * double(dv_of(imp_f).dot(vsum)), w_c = hm * double(dv_of(imp_c).dot(vsum));
  s_.book.contact_cum -= w_all - w_f - w_c;
  s_.book.friction_work_cum += w_f;
  s_.book.compress_work_cum += w_c;
  run_.projectile_force = double((s_.proj_impulse + imp).norm()) / model_.dt;
}

// The two precisions (solver.h: Precision).
template void SolverT<float>::projectile_contact();
template void SolverT<double>::projectile_contact();
template void SolverT<float>::release_held();
template void SolverT<double>::release_held();

}  // namespace ravel::detail
