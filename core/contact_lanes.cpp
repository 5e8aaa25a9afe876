// Lane version of SolverT::closest (see contact_lanes.h). Every line mirrors the one-crossing
// code: the same operations in the same order, selects where that code branches, so that
// each lane's result is bit-identical to it (NaN states included). Built with
// -ffp-contract=off (core/CMakeLists.txt) and without FMA, so no multiply-add is fused.
#include "contact_lanes.h"

#include <immintrin.h>

#include <cstring>

namespace ravel::lanes {

bool available() {
  static const bool ok = __builtin_cpu_supports("avx2");
  return ok;
}

namespace {

using v4 = __m256d;  // GCC vector of four doubles: + - * / and comparisons work lane-wise
using m4 = __attribute__((vector_size(32))) long long;

#define RAVEL_AVX2 __attribute__((target("avx2"), always_inline)) inline
#define RAVEL_AVX2_LAMBDA __attribute__((target("avx2"), always_inline))

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
// std::clamp(v, 0, 1): v < 0 ? 0 : (1 < v ? 1 : v), NaN passing through.
RAVEL_AVX2 v4 clamp01(v4 v) {
  const v4 z = splat(0), o = splat(1);
  return v < z ? z : (o < v ? o : v);
}
RAVEL_AVX2 v4 dot(v4 ax, v4 ay, v4 az, v4 bx, v4 by, v4 bz) {
  return ax * bx + ay * by + az * bz;
}

// SolverT::chord_coord with both neighbours of the tracked node present: the offset of
// point p along the chord xs[0] -> xs[2] from xs[1], in node spacings (span 2), clamped to
// [-1, 1], and the chord's unit tangent; 0 and a zero tangent for a chord of no length.
RAVEL_AVX2 void chord4(const v4 (*xs)[3], const v4* p, double* off, double (*tangent)[kWidth]) {
  const v4 zero = splat(0), one = splat(1), lo = splat(-1);
  const v4 T[3] = {xs[2][0] - xs[0][0], xs[2][1] - xs[0][1], xs[2][2] - xs[0][2]};
  const v4 T2 = dot(T[0], T[1], T[2], T[0], T[1], T[2]);
  const m4 none = T2 <= zero;
  const v4 r = one / _mm256_sqrt_pd(T2);
  for (int m = 0; m < 3; ++m) store(tangent[m], none ? zero : T[m] * r);
  const v4 q[3] = {p[0] - xs[1][0], p[1] - xs[1][1], p[2] - xs[1][2]};
  const v4 o = (dot(q[0], q[1], q[2], T[0], T[1], T[2]) / T2) * splat(2);
  store(off, none ? zero : (o < lo ? lo : (one < o ? one : o)));
}

}  // namespace

__attribute__((target("avx2"))) void closest4(ClosestBatch& s) {
  const v4 zero = splat(0), one = splat(1);
  v4 xw[3][3], xf[3][3];
  for (int k = 0; k < 3; ++k)
    for (int m = 0; m < 3; ++m) {
      const int i = 3 * k + m;
      xw[k][m] = _mm256_set_pd(s.xw[3][i], s.xw[2][i], s.xw[1][i], s.xw[0][i]);
      xf[k][m] = _mm256_set_pd(s.xf[3][i], s.xf[2][i], s.xf[1][i], s.xf[0][i]);
    }
  // SolverT::track's test: is any other node pair of the window closer than the middle one?
  {
    auto d2 = [&](int iw, int jf) RAVEL_AVX2_LAMBDA {
      const v4 dx = xf[jf][0] - xw[iw][0], dy = xf[jf][1] - xw[iw][1], dz = xf[jf][2] - xw[iw][2];
      return dot(dx, dy, dz, dx, dy, dz);
    };
    const v4 mid = d2(1, 1);
    m4 moved = {0, 0, 0, 0};
    for (int iw = 0; iw < 3; ++iw)
      for (int jf = 0; jf < 3; ++jf)
        if (iw != 1 || jf != 1) moved |= d2(iw, jf) < mid;
    std::memcpy(s.moved, &moved, sizeof moved);
  }
  // The segments next to the tracked node: start point, direction, squared length.
  v4 d1[2][3], d2[2][3], aa[2], ee[2];
  for (int k = 0; k < 2; ++k) {
    for (int m = 0; m < 3; ++m) d1[k][m] = xw[k + 1][m] - xw[k][m], d2[k][m] = xf[k + 1][m] - xf[k][m];
    aa[k] = dot(d1[k][0], d1[k][1], d1[k][2], d1[k][0], d1[k][1], d1[k][2]);
    ee[k] = dot(d2[k][0], d2[k][1], d2[k][2], d2[k][0], d2[k][1], d2[k][2]);
  }
  // The four segment pairs, in the scalar code's order (warp segment outer).
  v4 cd[4][3], ca[4], cb[4], c2[4];
  v4 best2 = splat(1e30);
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      const int q = 2 * i + j;
      const v4* p0 = xw[i];
      const v4* q0 = xf[j];
      const v4 rx = p0[0] - q0[0], ry = p0[1] - q0[1], rz = p0[2] - q0[2];
      const v4 A = aa[i], E = ee[j];
      const v4 F = dot(d2[j][0], d2[j][1], d2[j][2], rx, ry, rz);
      const v4 C = dot(d1[i][0], d1[i][1], d1[i][2], rx, ry, rz);
      const v4 B = dot(d1[i][0], d1[i][1], d1[i][2], d2[j][0], d2[j][1], d2[j][2]);
      const v4 denom = A * E - B * B;
      v4 sa = denom > splat(1e-12) * A * E ? clamp01((B * F - C * E) / denom) : zero;
      v4 tb = (B * sa + F) / E;
      const m4 below = tb < zero, above = ~below & (tb > one);
      const v4 end = clamp01((below ? -C : B - C) / A);  // one division for either end
      sa = (below | above) ? end : sa;
      tb = below ? zero : (above ? one : tb);
      for (int m = 0; m < 3; ++m) cd[q][m] = (q0[m] + tb * d2[j][m]) - (p0[m] + sa * d1[i][m]);
      ca[q] = sa;
      cb[q] = tb;
      c2[q] = dot(cd[q][0], cd[q][1], cd[q][2], cd[q][0], cd[q][1], cd[q][2]);
      best2 = c2[q] < best2 ? c2[q] : best2;  // std::min(best2, c2)
    }
  // The tie band: pairs within `band` of the closest share the contact.
  const v4 best = _mm256_sqrt_pd(best2), band = load(s.band), inv_band = one / band;
  const v4 reach2 = (best + band) * (best + band);
  v4 wsum = zero, gd[3] = {zero, zero, zero}, ww[3] = {zero, zero, zero}, wf[3] = {zero, zero, zero};
  v4 ga = zero, gb = zero;
  m4 gi = {0, 0, 0, 0}, gj = {0, 0, 0, 0}, first = ~gi;
  for (int q = 0; q < 4; ++q) {
    const int i = q >> 1, j = q & 1;
    const m4 is_first = first & (c2[q] == best2);
    gi = is_first ? m4{i, i, i, i} : gi;
    gj = is_first ? m4{j, j, j, j} : gj;
    ga = is_first ? ca[q] : ga;
    gb = is_first ? cb[q] : gb;
    first &= ~is_first;
    const v4 wq = one - (_mm256_sqrt_pd(c2[q]) - best) * inv_band;
    const m4 keep = ~(c2[q] >= reach2) & ~(wq <= zero);
    wsum = keep ? wsum + wq : wsum;
    for (int m = 0; m < 3; ++m) gd[m] = keep ? gd[m] + wq * cd[q][m] : gd[m];
    ww[i] = keep ? ww[i] + wq * (one - ca[q]) : ww[i];
    ww[i + 1] = keep ? ww[i + 1] + wq * ca[q] : ww[i + 1];
    wf[j] = keep ? wf[j] + wq * (one - cb[q]) : wf[j];
    wf[j + 1] = keep ? wf[j + 1] + wq * cb[q] : wf[j + 1];
  }
  const v4 inv = one / wsum;
  v4 d[3];
  for (int m = 0; m < 3; ++m) d[m] = gd[m] * inv, store(s.d[m], d[m]);
  for (int k = 0; k < 3; ++k) ww[k] = ww[k] * inv, wf[k] = wf[k] * inv, store(s.ww[k], ww[k]), store(s.wf[k], wf[k]);
  store(s.dist, best);
  store(s.a, ga);
  store(s.b, gb);
  std::memcpy(s.iw, &gi, sizeof gi);
  std::memcpy(s.jf, &gj, sizeof gj);

  // SolverT::pass_normal's side-test normal: the first closest pair's segments crossed
  // (Eigen's cross), scaled by side / |.|, or (0, 0, -+1) when they are parallel.
  const m4 i0 = gi == m4{0, 0, 0, 0}, j0 = gj == m4{0, 0, 0, 0};
  v4 tw[3], tf[3];
  for (int m = 0; m < 3; ++m) tw[m] = i0 ? d1[0][m] : d1[1][m], tf[m] = j0 ? d2[0][m] : d2[1][m];
  v4 n[3] = {tw[1] * tf[2] - tw[2] * tf[1], tw[2] * tf[0] - tw[0] * tf[2], tw[0] * tf[1] - tw[1] * tf[0]};
  const v4 nn = _mm256_sqrt_pd(dot(n[0], n[1], n[2], n[0], n[1], n[2]));
  const v4 side = load(s.side), sn = side / nn;
  const m4 flat = ~(nn > splat(1e-20));
  n[0] = flat ? zero : n[0] * sn;
  n[1] = flat ? zero : n[1] * sn;
  n[2] = flat ? (side > zero ? splat(-1) : one) : n[2] * sn;
  for (int m = 0; m < 3; ++m) store(s.n[m], n[m]);
  // |d| and d / |d|.
  const v4 dlen = _mm256_sqrt_pd(dot(d[0], d[1], d[2], d[0], d[1], d[2]));
  store(s.dlen, dlen);
  const v4 inv_dlen = one / dlen;
  for (int m = 0; m < 3; ++m) store(s.ud[m], d[m] * inv_dlen);
  // SolverT::friction_setup: the contact points (pa on the warp from the weights
  // -(-ww), pb on the weft), then SolverT::chord_coord of each on the other yarn's chord
  // through its tracked node (both neighbours present: span 2, offsets clamped to [-1, 1]).
  v4 pa[3] = {zero, zero, zero}, pb[3] = {zero, zero, zero};
  for (int k = 0; k < 3; ++k) {
    const v4 rw = -ww[k];
    for (int m = 0; m < 3; ++m) pa[m] = pa[m] - rw * xw[k][m], pb[m] = pb[m] + wf[k] * xf[k][m];
  }
  chord4(xw, pb, s.offw, s.tw);
  chord4(xf, pa, s.offf, s.tf);
  // Segment lengths (SolverT::seg_len), for the friction's arc lengths.
  for (int k = 0; k < 2; ++k) store(s.lw[k], _mm256_sqrt_pd(aa[k])), store(s.lf[k], _mm256_sqrt_pd(ee[k]));
}

}  // namespace ravel::lanes
