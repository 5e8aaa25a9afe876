// Stage release_held: the end of the projectile's hold (hold.h) in each step.
#include "solver/hold.h"

namespace ravel::detail {

// The impulses the yarn contact passed to the projectile through the nodes it holds
// (pass_to_projectile) act on it, summed in node order (deterministic for any thread count);
// every hold ends with the step.
template <class Real>
void release_held(const Model& model, State<Real>& s, RunState& run) {
  using V3 = Eigen::Matrix<Real, 3, 1>;
  if (s.held_list.empty()) return;
  V3 imp = V3::Zero(), imp_f = V3::Zero(), imp_c = V3::Zero();
  for (int i : s.held_list) {
    imp += s.held_imp[i];
    imp_f += s.held_fric[i];
    imp_c += s.held_comp[i];
    s.held_imp[i].setZero();
    s.held_fric[i].setZero();
    s.held_comp[i].setZero();
    s.held_n[i].setZero();
    s.held_flag[i] = 0;
  }
  s.held_list.clear();
  auto dv_of = [&](const V3& p) {
    V3 dv = p / Real(model.projectile_mass);
    if (model.mirror_x) dv.x() = 0;
    if (model.mirror_y) dv.y() = 0;
    return dv;
  };
  const V3 dvp = dv_of(imp);
  const V3 vp_old = s.vp;
  s.vp += dvp;
  s.xp += Real(model.dt) * dvp;
  // The work on the projectile of the friction's and the compression's shares is theirs, the
  // rest the normal correction's.
  const V3 vsum = vp_old + s.vp;
  const double hm = 0.5 * model.projectile_mass;
  const double w_all = hm * double(dvp.dot(vsum));
  const double w_f = hm * double(dv_of(imp_f).dot(vsum)), w_c = hm * double(dv_of(imp_c).dot(vsum));
  s.book.contact_cum -= w_all - w_f - w_c;
  s.book.friction_work_cum += w_f;
  s.book.compress_work_cum += w_c;
  run.projectile_force = double((s.proj_impulse + imp).norm()) / model.dt;
}

// The two precisions (solver.h: Precision).
template void release_held(const Model&, State<float>&, RunState&);
template void release_held(const Model&, State<double>&, RunState&);

}  // namespace ravel::detail
