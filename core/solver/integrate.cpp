// Stage integrate (Eq 1-2): the free update of the yarn nodes and the projectile.
#include "solver/stage.h"

namespace ravel::detail {

// Eq 1-2: v(t+dt/2) = v(t-dt/2) + dt/m f; x(t+dt) = x(t) + dt v(t+dt/2). Fixed velocity
// components (clamps, symmetry planes) stay zero.
template <class Real>
void integrate(const Model& model, State<Real>& s, RunState& run, const Context<Real>& ctx) {
  using V3 = Eigen::Matrix<Real, 3, 1>;
  const int n = model.node_count;
  const Real dt = Real(model.dt);
  double maxr2 = 0;

#pragma omp parallel for num_threads(ctx.threads) schedule(static) reduction(max : maxr2) if (ctx.threads > 1)
  for (int i = 0; i < n; ++i) {
    s.v_prev[i] = s.v[i];
    s.corr[i].dx_contact.setZero();
    const std::uint8_t fx = model.fixed[i];
    if (fx == fix_all) continue;
    V3 v = s.v[i] + (dt * Real(model.inv_mass[i])) * s.f[i];
    if (fx) zero_fixed(v, fx);
    s.v[i] = v;
    s.x[i] += dt * v;
    maxr2 = std::max(maxr2, double(s.x[i].squaredNorm()));
  }
  // External loads (rare: tests and pull-out): applied after the free update.
  for (const auto& [i, F] : s.f_ext) {
    if (model.fixed[i] == fix_all) continue;
    V3 dv = (dt * Real(model.inv_mass[i])) * F;
    zero_fixed(dv, model.fixed[i]);
    s.v[i] += dv;
    s.x[i] += dt * dv;
  }
  s.xp += dt * s.vp;
  check_positions(run, ctx.escape_radius2, maxr2);
}

// The two precisions (solver.h: Precision).
template void integrate(const Model&, State<float>&, RunState&, const Context<float>&);
template void integrate(const Model&, State<double>&, RunState&, const Context<double>&);

}  // namespace ravel::detail
