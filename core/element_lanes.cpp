// Lane version of the Zener element update of SolverT::internal_forces (see element_lanes.h).
// Every line mirrors the one-element code: the same operations in the same order, selects
// where that code branches. Built with -ffp-contract=off (core/CMakeLists.txt).
#include "element_lanes.h"

#include <immintrin.h>

#include <cstring>

namespace ravel::lanes {

namespace {

using v4 = __m256d;
using m4 = __attribute__((vector_size(32))) long long;

#define RAVEL_AVX2 __attribute__((target("avx2"), always_inline)) inline

RAVEL_AVX2 v4 load(const double* p) {
  v4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
RAVEL_AVX2 void store(double* p, v4 v) {
  std::memcpy(p, &v, sizeof v);
}
RAVEL_AVX2 v4 splat(double x) {
  return v4{x, x, x, x};
}

}  // namespace

__attribute__((target("avx2"))) bool zener4(ElementBatch& s) {
  // dx = x_b - x_a, |dx|, strain (SolverT::internal_forces).
  v4 dx[3];
  for (int m = 0; m < 3; ++m) {
    const double* x = s.x;
    const v4 xa = _mm256_set_pd(x[3 * s.a[3] + m], x[3 * s.a[2] + m], x[3 * s.a[1] + m], x[3 * s.a[0] + m]);
    const v4 xb = _mm256_set_pd(x[3 * s.b[3] + m], x[3 * s.b[2] + m], x[3 * s.b[1] + m], x[3 * s.b[0] + m]);
    dx[m] = xb - xa;
  }
  const v4 len = _mm256_sqrt_pd(dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2]);
  const v4 rest = load(s.rest), area = load(s.area);
  const v4 eps1 = len / rest - splat(1);
  if (s.breakable) {
    const m4 fails = eps1 >= splat(s.fail);
    if (!_mm256_testz_si256(__m256i(fails), __m256i(fails))) return false;
  }
  const v4 vol = area * rest;
  // ZenerStepper::step(eps0, eps1, ev0).
  const v4 eps0 = load(s.prev_strain), ev0 = load(s.ev);
  const v4 g = splat(s.g), lam = splat(s.lam), decay = splat(s.decay);
  const v4 r = (eps1 - eps0) * splat(s.inv_dt);
  const v4 C = ev0 - g * (eps0 - r / lam);
  const v4 ev1 = g * (eps1 - r / lam) + C * decay;
  const v4 stress = splat(s.k1) * (eps1 - ev1);
  const m4 taut = stress >= splat(0);
  const v4 diss_taut = splat(s.mu) * (g * g * r * r * splat(s.dt) - splat(2.0) * g * r * C * (splat(1.0) - decay) +
                                      splat(0.5) * lam * C * C * (splat(1.0) - decay * decay));
  const v4 evs = ev0 * splat(s.slack_decay);
  const v4 diss_slack = splat(0.5) * splat(s.k2) * (ev0 * ev0 - evs * evs);
  const v4 ev = taut ? ev1 : evs, sig = taut ? stress : splat(0.0), diss = taut ? diss_taut : diss_slack;
  // zener_stored(c, sig, ev) * vol; the dashpot's energy * vol.
  const v4 u = (sig * sig / (splat(2.0) * splat(s.k1)) + splat(0.5) * splat(s.k2) * ev * ev) * vol;
  const v4 dd = diss * vol;
  store(s.ev, ev);
  store(s.prev_strain, eps1);
  store(s.strain, eps1);
  store(s.stress, sig);
  store(s.energy, u);
  store(s.u, u);
  store(s.dd, dd);
  store(s.eps, eps1);
  // Force on node b: dx * (-sigma A / |dx|), zero for an element of no length.
  const v4 k = (-sig * area) / len;
  const m4 some = len > splat(0);
  double f[3][kWidth];
  for (int m = 0; m < 3; ++m) store(f[m], some ? dx[m] * k : splat(0));
  for (int l = 0; l < kWidth; ++l)
    for (int m = 0; m < 3; ++m) s.force[3 * l + m] = f[m][l];
  return true;
}

}  // namespace ravel::lanes
