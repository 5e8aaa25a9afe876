// Stage integrate (Eq 1-2): the free update of the yarn nodes and the projectile.
#include "solver/solver_t.h"

namespace ravel::detail {

// Eq 1-2: v(t+dt/2) = v(t-dt/2) + dt/m f; x(t+dt) = x(t) + dt v(t+dt/2). Fixed velocity
// components (clamps, symmetry planes) stay zero.
template <class Real>
void SolverT<Real>::integrate() {
  const int n = model_.node_count;
  const Real dt = Real(model_.dt);
  double maxr2 = 0;

#pragma omp parallel for num_threads(threads_) schedule(static) reduction(max : maxr2) if (threads_ > 1)
  for (int i = 0; i < n; ++i) {
    s_.v_prev[i] = s_.v[i];
    s_.dx_contact[i].setZero();
    const std::uint8_t fx = model_.fixed[i];
    if (fx == fix_all) continue;
    V3 v = s_.v[i] + (dt * Real(model_.inv_mass[i])) * s_.f[i];
    if (fx) zero_fixed(v, fx);
    s_.v[i] = v;
    s_.x[i] += dt * v;
    maxr2 = std::max(maxr2, double(s_.x[i].squaredNorm()));
  }
  // External loads (rare: tests and pull-out): applied after the free update.
  for (const auto& [i, F] : s_.f_ext) {
    if (model_.fixed[i] == fix_all) continue;
    V3 dv = (dt * Real(model_.inv_mass[i])) * F;
    zero_fixed(dv, model_.fixed[i]);
    s_.v[i] += dv;
    s_.x[i] += dt * dv;
  }
  s_.xp += dt * s_.vp;
  check_positions(maxr2);
}

// The two precisions (solver.h: Precision).
template void SolverT<float>::integrate();
template void SolverT<double>::integrate();

}  // namespace ravel::detail
