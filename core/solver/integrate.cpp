// Stage integrate (Eq 1-2): the free update of the yarn nodes and the projectile.
#include "solver/stage.h"

namespace ravel::detail {

// Eq 1-2 for the yarn nodes: free_update (stage.h), run inside internal_forces' force gather
// while each node's force is at hand (one sweep over the nodes instead of two). Here: the
// external loads, the projectile's free flight and the check of the nodes' positions.
template <class Real>
void integrate(const Model& model, State<Real>& s, RunState& run, const Context<Real>& ctx) {
  using V3 = Eigen::Matrix<Real, 3, 1>;
  const Real dt = Real(model.dt);
  // External loads (rare: tests and pull-out): applied after the free update.
  for (const auto& [i, F] : s.f_ext) {
    if (model.fixed[i] == fix_all) continue;
    V3 dv = (dt * Real(model.inv_mass[i])) * F;
    zero_fixed(dv, model.fixed[i]);
    s.v[i] += dv;
    s.x[i] += dt * dv;
  }
  s.xp += dt * s.vp;
  check_positions(run, ctx.escape_radius2, ctx.max_r2);
}

// The two precisions (solver.h: Precision).
template void integrate(const Model&, State<float>&, RunState&, const Context<float>&);
template void integrate(const Model&, State<double>&, RunState&, const Context<double>&);

}  // namespace ravel::detail
