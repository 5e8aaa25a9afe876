// The yarn contact's closest points in AVX2 lanes (core/solver/simd/contact_lanes.h): the geometry of
// known crossings, lanes independent of each other, and whole runs bit-identical to the
// one-crossing-at-a-time code. Skipped (with a message) on processors without AVX2.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>

#include "solver/simd/contact_lanes.h"
#include "solver/simd/element_lanes.h"
#include "material.h"
#include "fixture.h"
#include "solver.h"

namespace ravel {
namespace {

using test::operator+;

constexpr double L = 0.844e-3;  // node spacing
constexpr double h = 0.2e-3;    // gap between the yarn axes
constexpr double band = 0.02 * 0.2e-3;

// A window: warp along x through (dx, 0, 0), weft along `weft_dir` through (wx, 0, h).
struct Win {
  double xw[9], xf[9];
};
Win crossing(double wx, bool parallel = false) {
  Win w;
  for (int k = 0; k < 3; ++k) {
    const double s = (k - 1) * L;
    w.xw[3 * k] = s, w.xw[3 * k + 1] = 0, w.xw[3 * k + 2] = 0;
    w.xf[3 * k] = parallel ? s : wx, w.xf[3 * k + 1] = parallel ? 0 : s, w.xf[3 * k + 2] = h;
  }
  return w;
}
void set_lane(lanes::ClosestBatch& b, int l, const Win& w, double side = 1) {
  b.xw[l] = w.xw;
  b.xf[l] = w.xf;
  b.band[l] = band;
  b.side[l] = side;
}

// Four elements' batch for zener4 with the Zener stepper's constants, nothing else set.
lanes::ElementBatch zener_batch(const ZenerConstants& c, const ZenerStepper& z, const double* x, const int* a,
                                const int* b, const double* rests, const double* areas, double fail, double* prev,
                                double* ev, double* strain, double* stress, double* energy, double* force) {
  lanes::ElementBatch e;
  e.x = x;
  e.a = a, e.b = b, e.rest = rests, e.area = areas;
  e.k1 = c.k1, e.k2 = c.k2, e.mu = c.mu, e.dt = z.dt, e.inv_dt = z.inv_dt, e.lam = z.lam, e.g = z.g;
  e.decay = z.decay, e.slack_decay = z.slack_decay;
  e.fail = fail;
  e.breakable = true;
  e.prev_strain = prev, e.ev = ev, e.strain = strain, e.stress = stress, e.energy = energy, e.force = force;
  return e;
}

class Lanes : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!lanes::available()) GTEST_SKIP() << "this processor has no AVX2: the solver computes one crossing at a time";
    std::printf("lane kernels: %s\n", lanes::isa_name(lanes::isa()));
  }
};

// Crossing at the tracked nodes: all four segment pairs touch at the nodes and tie, the
// contact is the node pair itself (weights 0 1 0 on both yarns), |d| = h along z.
// Weft through x = 0.3 L: only the warp segment kw..kw+1 reaches it, at a = 0.3.
TEST_F(Lanes, KnownCrossingsGiveTheirClosestPoints) {
  const Win at_node = crossing(0), offset = crossing(0.3 * L);
  lanes::ClosestBatch b;
  set_lane(b, 0, at_node);
  set_lane(b, 1, offset);
  set_lane(b, 2, at_node);
  set_lane(b, 3, offset);
  lanes::closest4(b);
  const double tol = 1e-12 * L;
  for (int l = 0; l < 4; ++l) {
    SCOPED_TRACE(l);
    EXPECT_NEAR(b.dist[l], h, tol);
    EXPECT_NEAR(b.d[0][l], 0, tol);
    EXPECT_NEAR(b.d[1][l], 0, tol);
    EXPECT_NEAR(b.d[2][l], h, tol);
    EXPECT_NEAR(b.wf[0][l], 0, 1e-12);
    EXPECT_NEAR(b.wf[1][l], 1, 1e-12);
    EXPECT_NEAR(b.wf[2][l], 0, 1e-12);
  }
  // At the node: the first pair (warp kw-1..kw, weft kf-1..kf) ends at the nodes.
  EXPECT_EQ(b.iw[0], 0);
  EXPECT_EQ(b.jf[0], 0);
  EXPECT_NEAR(b.a[0], 1, 1e-12);
  EXPECT_NEAR(b.ww[0][0], 0, 1e-12);
  EXPECT_NEAR(b.ww[1][0], 1, 1e-12);
  EXPECT_NEAR(b.ww[2][0], 0, 1e-12);
  // Offset: warp segment kw..kw+1 at a = 0.3; the other warp segment is 0.3 L away, far
  // outside the tie band.
  EXPECT_EQ(b.iw[1], 1);
  EXPECT_NEAR(b.a[1], 0.3, 1e-12);
  EXPECT_NEAR(b.ww[0][1], 0, 1e-12);
  EXPECT_NEAR(b.ww[1][1], 0.7, 1e-12);
  EXPECT_NEAR(b.ww[2][1], 0.3, 1e-12);
}

// The rest of the geometry: the side-test normal (warp along x, weft along y: x cross y =
// +z, times the side sign), |d| and d / |d|, where the contact sits along each yarn's chord
// (the weft through x = 0.3 L meets the warp 0.3 node spacings past its tracked node, and
// the warp meets the weft at the weft's node), the chords' directions, and the segment lengths.
TEST_F(Lanes, NormalChordOffsetsAndLengths) {
  const Win at_node = crossing(0), offset = crossing(0.3 * L);
  Win squeezed = crossing(0.3 * L);
  for (int k = 0; k < 3; ++k) squeezed.xw[3 * k] = 0;  // a warp of no length: no chord
  lanes::ClosestBatch b;
  set_lane(b, 0, at_node, 1);
  set_lane(b, 1, offset, -1);
  set_lane(b, 2, squeezed, 1);
  set_lane(b, 3, offset, 1);
  lanes::closest4(b);
  const double tol = 1e-12;
  for (int l : {0, 1, 3}) {
    SCOPED_TRACE(l);
    const double side = l == 1 ? -1 : 1;
    EXPECT_NEAR(b.n[0][l], 0, tol);
    EXPECT_NEAR(b.n[1][l], 0, tol);
    EXPECT_NEAR(b.n[2][l], side, tol);
    EXPECT_NEAR(b.dlen[l], h, tol * L);
    EXPECT_NEAR(b.ud[2][l], 1, tol);
    EXPECT_NEAR(b.offw[l], l == 0 ? 0 : 0.3, tol);
    EXPECT_NEAR(b.offf[l], 0, tol);
    EXPECT_NEAR(b.tw[0][l], 1, tol);
    EXPECT_NEAR(b.tf[1][l], 1, tol);
    for (int k = 0; k < 2; ++k) {
      EXPECT_NEAR(b.lw[k][l], L, tol * L);
      EXPECT_NEAR(b.lf[k][l], L, tol * L);
    }
  }
  // No warp chord: offset 0 along it and no tangent; the segments are of zero length and
  // parallel to nothing, so the normal falls back to -z for side +1.
  EXPECT_EQ(b.offw[2], 0);
  for (int m = 0; m < 3; ++m) EXPECT_EQ(b.tw[m][2], 0);
  EXPECT_EQ(b.lw[0][2], 0);
  EXPECT_EQ(b.n[2][2], -1);
}

// Parallel yarns (the closest-point system is singular): finite, |d| = h. A NaN window in
// one lane leaves the other lanes' results exactly as they are alone.
TEST_F(Lanes, ParallelSegmentsAndNaNStayInTheirLane) {
  const Win par = crossing(0, true), offset = crossing(0.3 * L);
  Win bad = offset;
  bad.xf[4] = std::numeric_limits<double>::quiet_NaN();
  lanes::ClosestBatch alone, mixed;
  for (int l = 0; l < 4; ++l) set_lane(alone, l, l == 1 ? par : offset);
  set_lane(mixed, 0, offset);
  set_lane(mixed, 1, par);
  set_lane(mixed, 2, bad);
  set_lane(mixed, 3, offset);
  lanes::closest4(alone);
  lanes::closest4(mixed);
  EXPECT_NEAR(alone.dist[1], h, 1e-12 * L);
  for (int m = 0; m < 3; ++m) EXPECT_TRUE(std::isfinite(alone.d[m][1]));
  EXPECT_NEAR(alone.d[2][1], h, 1e-12 * L);
  EXPECT_TRUE(std::isnan(mixed.dist[2]) || std::isnan(mixed.d[2][2]));
  for (int l : {0, 1, 3}) {
    SCOPED_TRACE(l);
    EXPECT_EQ(mixed.dist[l], alone.dist[l]);
    for (int m = 0; m < 3; ++m) {
      EXPECT_EQ(mixed.d[m][l], alone.d[m][l]);
      EXPECT_EQ(mixed.ww[m][l], alone.ww[m][l]);
      EXPECT_EQ(mixed.wf[m][l], alone.wf[m][l]);
    }
    EXPECT_EQ(mixed.a[l], alone.a[l]);
    EXPECT_EQ(mixed.b[l], alone.b[l]);
  }
}

// Four elements along x, stretched by 0 (slack after compression), 1 %, 3 % and 5 % from
// rest, with different viscous strains: the lanes give ZenerStepper::step's numbers bit for
// bit, and a lane past the failure strain sends the group back untouched.
TEST_F(Lanes, ElementsFollowTheZenerStepExactly) {
  const ZenerConstants c{7.28e10, 4.17e11, 6.26e8};
  const ZenerStepper z(c, 6.1e-8);
  const double rest = 0.867e-3, area = 7.64e-8;
  const double stretch[4] = {-0.002, 0.01, 0.03, 0.05}, ev0[4] = {1e-4, 0, 2e-3, 1e-2};
  std::vector<double> x;
  int a[4], b[4];
  double rests[4], areas[4];
  for (int l = 0; l < 4; ++l) {
    a[l] = 2 * l, b[l] = 2 * l + 1;
    rests[l] = rest, areas[l] = area;
    for (double v : {0.0, double(l), 0.0, rest * (1 + stretch[l]), double(l), 0.0}) x.push_back(v);
  }
  auto batch = [&](double fail, double* prev, double* ev, double* strain, double* stress, double* energy,
                   double* force) {
    return zener_batch(c, z, x.data(), a, b, rests, areas, fail, prev, ev, strain, stress, energy, force);
  };
  const double prev0[4] = {0, 0.009, 0.029, 0.049};
  double prev[4], ev[4], strain[4] = {}, stress[4] = {}, energy[4] = {}, force[12] = {};
  for (int l = 0; l < 4; ++l) ev[l] = ev0[l], prev[l] = prev0[l];
  lanes::ElementBatch e = batch(0.052, prev, ev, strain, stress, energy, force);
  ASSERT_TRUE(lanes::zener4(e));
  for (int l = 0; l < 4; ++l) {
    SCOPED_TRACE(l);
    const double len = rest * (1 + stretch[l]);
    const double eps = len / rest - 1;
    const ZenerStep zs = z.step(prev0[l], eps, ev0[l]);
    EXPECT_EQ(strain[l], eps);
    EXPECT_EQ(ev[l], zs.ev);
    EXPECT_EQ(stress[l], zs.stress);
    EXPECT_EQ(energy[l], zener_stored(c, zs.stress, zs.ev) * (area * rest));
    EXPECT_EQ(e.dd[l], zs.dissipated * (area * rest));
    EXPECT_EQ(force[3 * l], len * (-zs.stress * area / len));
    EXPECT_EQ(force[3 * l + 1], 0);
  }
  EXPECT_EQ(stress[0], 0) << "compressed: slack";
  EXPECT_GT(stress[3], stress[2]);
  // 5 % with a 4 % failure strain: nothing written.
  double prev2[4] = {0, 0, 0, 0}, ev2[4] = {0, 0, 0, 0}, strain2[4] = {9, 9, 9, 9}, stress2[4] = {}, energy2[4] = {},
         force2[12] = {};
  lanes::ElementBatch f = batch(0.04, prev2, ev2, strain2, stress2, energy2, force2);
  EXPECT_FALSE(lanes::zener4(f));
  for (int l = 0; l < 4; ++l) EXPECT_EQ(strain2[l], 9);
}

// The AVX-512 build of the kernels gives the AVX2 build's numbers bit for bit, over many
// perturbed windows (tilted, sheared, near-parallel, stretched) and element states.
TEST_F(Lanes, Avx512KernelsMatchAvx2BitForBit) {
  if (lanes::isa() != lanes::Isa::avx512) GTEST_SKIP() << "this processor has no AVX-512 (F, VL, DQ)";
  std::uint64_t seed = 12345;
  auto rnd = [&] {  // uniform in [-1, 1)
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    return double(seed >> 11) / double(1ull << 52) - 1.0;
  };
  int moved = 0;
  for (int trial = 0; trial < 500; ++trial) {
    Win w[4];
    for (int l = 0; l < 4; ++l) {
      w[l] = crossing(rnd() * 0.6 * L, trial % 7 == 0);
      for (int i = 0; i < 9; ++i) w[l].xw[i] += rnd() * 0.3 * L, w[l].xf[i] += rnd() * 0.3 * L;
    }
    lanes::ClosestBatch p, q;
    for (int l = 0; l < 4; ++l) set_lane(p, l, w[l], l % 2 ? 1 : -1), set_lane(q, l, w[l], l % 2 ? 1 : -1);
    lanes::avx2::closest4(p);
    lanes::avx512::closest4(q);
    // Every output field, compared as bytes (the inputs are the same pointers).
    const size_t from = offsetof(lanes::ClosestBatch, d);
    ASSERT_EQ(std::memcmp(reinterpret_cast<const char*>(&p) + from, reinterpret_cast<const char*>(&q) + from,
                          sizeof p - from),
              0)
        << "trial " << trial;
    for (int l = 0; l < 4; ++l) moved += p.moved[l] != 0;
  }
  EXPECT_GT(moved, 0) << "some windows should have a nearer pair than the middle one";
  // Elements: random strains around the failure strain's neighbourhood, slack ones too.
  const ZenerConstants c{7.28e10, 4.17e11, 6.26e8};
  const ZenerStepper z(c, 6.1e-8);
  int taken = 0;  // trials the lanes took (the others fell back to one element at a time)
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<double> x;
    int a[4], b[4];
    double rests[4], areas[4], prev[2][4], ev[2][4], strain[2][4], stress[2][4] = {}, energy[2][4], force[2][12];
    for (int l = 0; l < 4; ++l) {
      a[l] = 2 * l, b[l] = 2 * l + 1;
      rests[l] = 0.867e-3, areas[l] = 7.64e-8;
      // Each element taut throughout the step (strain 0.5-4.5 %, below the 5.2 % failure
      // strain, viscous strain below a third of it) or slack throughout (compressed): a group
      // in which one changes branch within the step is left to the one-element code (below).
      double eps0, e0;
      if (rnd() < 0.5) {
        eps0 = 0.005 + 0.04 * std::abs(rnd());
        e0 = eps0 * std::abs(rnd()) / 3;
      } else {
        eps0 = -0.005 - 0.01 * std::abs(rnd());
        e0 = 0.002 * std::abs(rnd());
      }
      const double len = rests[l] * (1 + eps0 + 0.002 * rnd());
      for (double v : {0.0, 0.0, 0.0, len * 0.6, len * 0.8 * rnd(), 0.0}) x.push_back(v);
      x.back() = std::sqrt(std::max(0.0, len * len - x[6 * l + 3] * x[6 * l + 3] - x[6 * l + 4] * x[6 * l + 4]));
      for (int k = 0; k < 2; ++k) prev[k][l] = eps0, ev[k][l] = e0;
    }
    lanes::ElementBatch e[2];
    for (int k = 0; k < 2; ++k) {
      e[k] = zener_batch(c, z, x.data(), a, b, rests, areas, 0.052, prev[k], ev[k], strain[k], stress[k], energy[k],
                         force[k]);
    }
    // A group with a failing element or one that changes branch (taut/slack) within the step
    // is left to the one-element code: both builds must say so for the same groups.
    const bool ok2 = lanes::avx2::zener4(e[0]), ok5 = lanes::avx512::zener4(e[1]);
    ASSERT_EQ(ok2, ok5) << "trial " << trial;
    if (!ok2) continue;
    ++taken;
    EXPECT_EQ(std::memcmp(ev[0], ev[1], sizeof ev[0]), 0);
    EXPECT_EQ(std::memcmp(stress[0], stress[1], sizeof stress[0]), 0);
    EXPECT_EQ(std::memcmp(energy[0], energy[1], sizeof energy[0]), 0);
    EXPECT_EQ(std::memcmp(force[0], force[1], sizeof force[0]), 0);
    EXPECT_EQ(std::memcmp(e[0].dd, e[1].dd, sizeof e[0].dd), 0);
  }
  // By construction no element fails or changes branch, so every group is the lanes' to take.
  EXPECT_EQ(taken, 200) << "groups the lanes should have taken fell back to one element at a time";
  // With the pin-jointed crimp stage and its damping: apparent strains across the toe
  // (below it, in it, past it), the last step's own strain a little below this one's.
  int crimp_taken = 0;
  const double ec = 0.02, w = 0.02;
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<double> x;
    int a[4], b[4];
    double rests[4], areas[4], prev[2][4], ev[2][4], strain[2][4], stress[2][4], energy[2][4], force[2][12];
    double cds[2][4];
    for (int l = 0; l < 4; ++l) {
      a[l] = 2 * l, b[l] = 2 * l + 1;
      rests[l] = 0.867e-3, areas[l] = 7.64e-8;
      const double app = -0.01 + 0.075 * std::abs(rnd());  // apparent strain, -1 % to 6.5 %
      const double len = rests[l] * (1 + app);
      for (double v : {0.0, 0.0, 0.0, len, 0.0, 0.0}) x.push_back(v);
      // The material strain a step ago a little below the crimp stage's value now: taut lanes stay taut.
      const double xx = app - ec;
      const double p = xx >= w ? xx : (xx > -w ? (xx + w) * (xx + w) / (4 * w) : 0.0);
      const double mat = 0.05 * app + 0.95 * p;
      const double p0 = mat * (1 - 0.01 * std::abs(rnd())), e0 = std::max(0.0, mat) * std::abs(rnd()) / 4;
      const double d0 = 1e6 * std::abs(rnd());
      for (int k = 0; k < 2; ++k) {
        prev[k][l] = p0;
        ev[k][l] = e0;
        strain[k][l] = (1 + app * 0.999) / (1 + ec) - 1;
        stress[k][l] = trial % 3 == 0 ? 0.0 : 1e8;  // some lanes turning taut (snap damping)
        cds[k][l] = d0;
      }
    }
    lanes::ElementBatch e[2];
    for (int k = 0; k < 2; ++k) {
      e[k] = zener_batch(c, z, x.data(), a, b, rests, areas, 0.052, prev[k], ev[k], strain[k], stress[k], energy[k],
                         force[k]);
      e[k].damping_k = 5e3;
      e[k].crimp_strain = ec, e[k].crimp_fraction = 0.05, e[k].crimp_width = w;
      e[k].crimp_damping_k = 8.7e3, e[k].crimp_damp_stress = cds[k];
    }
    const bool ok2 = lanes::avx2::zener4(e[0]), ok5 = lanes::avx512::zener4(e[1]);
    ASSERT_EQ(ok2, ok5) << "crimp trial " << trial;
    if (!ok2) continue;
    ++crimp_taken;
    EXPECT_EQ(std::memcmp(ev[0], ev[1], sizeof ev[0]), 0);
    EXPECT_EQ(std::memcmp(strain[0], strain[1], sizeof strain[0]), 0);
    EXPECT_EQ(std::memcmp(stress[0], stress[1], sizeof stress[0]), 0);
    EXPECT_EQ(std::memcmp(force[0], force[1], sizeof force[0]), 0);
    EXPECT_EQ(std::memcmp(cds[0], cds[1], sizeof cds[0]), 0);
    EXPECT_EQ(std::memcmp(e[0].cw, e[1].cw, sizeof e[0].cw), 0);
    EXPECT_EQ(std::memcmp(e[0].dw, e[1].dw, sizeof e[0].dw), 0);
  }
  EXPECT_GT(crimp_taken, 20) << "the crimp trials should mostly go through the lanes";
  // Bending springs: midpoints apart, compressed, and folded below half the rest distance.
  int regimes[3] = {0, 0, 0};
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<double> x(3 * 16);
    for (double& v : x) v = 0.3e-3 * rnd();
    lanes::BendBatch b[2];
    double rest[4], k[4], force[2][12], energy[2][4];
    for (int l = 0; l < 4; ++l) {
      rest[l] = 0.5e-3 * (1 + 0.5 * rnd()), k[l] = 1e3 * (1 + 0.5 * rnd());
      const double* p = &x[12 * l];
      double d2 = 0;
      for (int m = 0; m < 3; ++m) {
        const double dm = 0.5 * (p[6 + m] + p[9 + m]) - 0.5 * (p[m] + p[3 + m]);
        d2 += dm * dm;
      }
      const double sl = std::sqrt(d2);
      ++regimes[sl >= rest[l] ? 0 : sl >= 0.5 * rest[l] ? 1 : 2];
    }
    for (int q = 0; q < 2; ++q) {
      b[q].x = x.data();
      for (int l = 0; l < 4; ++l)
        b[q].a1[l] = 4 * l, b[q].b1[l] = 4 * l + 1, b[q].a2[l] = 4 * l + 2, b[q].b2[l] = 4 * l + 3;
      b[q].rest = rest, b[q].k = k, b[q].force = force[q], b[q].energy = energy[q];
    }
    lanes::avx2::bend4(b[0]);
    lanes::avx512::bend4(b[1]);
    EXPECT_EQ(std::memcmp(force[0], force[1], sizeof force[0]), 0) << "bend trial " << trial;
    EXPECT_EQ(std::memcmp(energy[0], energy[1], sizeof energy[0]), 0) << "bend trial " << trial;
    EXPECT_EQ(std::memcmp(b[0].held, b[1].held, sizeof b[0].held), 0) << "bend trial " << trial;
  }
  for (int g = 0; g < 3; ++g) EXPECT_GT(regimes[g], 20) << "every regime of the spring should be tried: " << g;
  // The per-node sweeps (finish_nodes, gather_forces): random states with signed zeros, every
  // fixed-axis combination, with and without the compression law, and in some trials an
  // infinity and a NaN; the nodes below lo must stay as they were.
  const int n = 61, lo = 3;
  auto value = [&](int trial) {
    const double r = rnd();
    if (r < -0.7) return r < -0.85 ? -0.0 : 0.0;
    if (trial % 5 == 4 && r > 0.995) return r > 0.9975 ? std::numeric_limits<double>::quiet_NaN() : -HUGE_VAL;
    return rnd();
  };
  auto same_bits = [](const std::vector<double>& a, const std::vector<double>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
  };
  for (int trial = 0; trial < 40; ++trial) {
    std::vector<double> sum(12 * n), corr(12 * n), v(3 * n), x(3 * n), vp(3 * n), im(n), m(n);
    std::vector<unsigned char> fixed(n);
    for (auto* a : {&sum, &corr, &v, &x, &vp})
      for (double& d : *a) d = value(trial);
    for (int i = 0; i < n; ++i) im[i] = 1 + rnd(), m[i] = 1 / im[i], fixed[i] = (i + trial) % 8;
    std::vector<double> out[2][4];
    std::vector<int> shifted[2];
    lanes::NodeFinish f[2];
    for (int k = 0; k < 2; ++k) {
      out[k][0] = sum, out[k][1] = corr, out[k][2] = v, out[k][3] = x;
      shifted[k].assign(n, -1);
      f[k] = lanes::NodeFinish{};
      f[k].pass_sum = out[k][0].data(), f[k].corr = out[k][1].data(), f[k].v = out[k][2].data();
      f[k].x = out[k][3].data(), f[k].v_prev = vp.data(), f[k].inv_mass = im.data(), f[k].mass = m.data();
      f[k].fixed = fixed.data(), f[k].dt = 6.1e-8, f[k].compressible = trial % 2 == 0;
      f[k].lo = lo, f[k].hi = n, f[k].shifted = shifted[k].data();
    }
    lanes::avx2::finish_nodes(f[0]);
    lanes::avx512::finish_nodes(f[1]);
    for (int a = 0; a < 4; ++a)
      EXPECT_TRUE(same_bits(out[0][a], out[1][a])) << "finish trial " << trial << " array " << a;
    EXPECT_EQ(f[0].shifted_count, f[1].shifted_count);
    EXPECT_GT(f[0].shifted_count, 0);
    EXPECT_EQ(shifted[0], shifted[1]);
    for (auto [p, q] : {std::pair{f[0].ke, f[1].ke},
                        {f[0].w_contact, f[1].w_contact},
                        {f[0].w_friction, f[1].w_friction},
                        {f[0].w_compress, f[1].w_compress}})
      EXPECT_EQ(std::memcmp(&p, &q, sizeof p), 0) << "finish trial " << trial;
    const std::vector<double>* before[4] = {&sum, &corr, &v, &x};
    for (int a = 0; a < 4; ++a) {
      const size_t per = a < 2 ? 12 : 3;
      EXPECT_EQ(std::memcmp(out[0][a].data(), before[a]->data(), per * lo * sizeof(double)), 0)
          << "finish trial " << trial << ": nodes below lo are left alone";
    }
    // The force gather: 2 to 4 elements and springs a node, forces of either sign.
    std::vector<int> eoff{0}, elem, boff{0};
    std::vector<char> bend;
    const int ne = 40, nb = 40;
    std::vector<double> ef(3 * ne), bf(3 * nb), fo[2], vv[2], xx[2], vpo[2], co[2];
    for (double& d : ef) d = value(trial);
    for (double& d : bf) d = value(trial);
    for (int i = 0; i < n; ++i) {
      for (int k = 0, c = 2 + (i + trial) % 3; k < c; ++k) {
        const int e = int((rnd() + 1) * 0.5 * ne) % ne;
        elem.push_back(rnd() < 0 ? e : ~e);
      }
      eoff.push_back(int(elem.size()));
      for (int k = 0, c = 2 + (i + 2 * trial) % 3; k < c; ++k) {
        const std::pair<int, double> end{int((rnd() + 1) * 0.5 * nb) % nb, rnd() < 0 ? -0.5 : 0.5};
        const char* b = reinterpret_cast<const char*>(&end);
        bend.insert(bend.end(), b, b + sizeof end);
      }
      boff.push_back(int(bend.size() / 16));
    }
    double r2[2];
    for (int k = 0; k < 2; ++k) {
      fo[k].assign(3 * n, 7.0), vv[k] = v, xx[k] = x, vpo[k].assign(3 * n, 7.0), co[k] = corr;
      lanes::NodeForces g;
      g.inc_e_off = eoff.data(), g.inc_e = elem.data(), g.inc_b_off = boff.data(), g.inc_b = bend.data();
      g.elem_force = ef.data(), g.bend_force = bf.data(), g.inv_mass = im.data(), g.fixed = fixed.data();
      g.dt = 6.1e-8, g.f = fo[k].data(), g.v = vv[k].data(), g.x = xx[k].data(), g.v_prev = vpo[k].data();
      g.corr = co[k].data(), g.lo = lo, g.hi = n;
      r2[k] = k == 0 ? lanes::avx2::gather_forces(g, 0.0) : lanes::avx512::gather_forces(g, 0.0);
    }
    EXPECT_EQ(std::memcmp(&r2[0], &r2[1], sizeof r2[0]), 0) << "gather trial " << trial;
    EXPECT_GT(r2[0], 0);
    for (auto* a : {fo, vv, xx, vpo, co}) EXPECT_TRUE(same_bits(a[0], a[1])) << "gather trial " << trial;
    EXPECT_EQ(std::memcmp(xx[0].data(), x.data(), 3 * lo * sizeof(double)), 0) << "nodes below lo are left alone";
    for (int i = lo; i < n; ++i) EXPECT_EQ(co[0][12 * i + 9] + co[0][12 * i + 10] + co[0][12 * i + 11], 0.0);
  }
}

// The run of `base` with the lanes on and off, on one thread and on two: the same state bit
// for bit at 5, 20 and 40 us, the same absorbed energy and ledger error, and some breaks.
// `check` looks at the lanes' model first.
void expect_lanes_change_nothing(const std::vector<std::string>& base,
                                 const std::function<void(const Model&)>& check = {}) {
  for (const char* threads : {"solver.threads=1", "solver.threads=2"}) {
    SCOPED_TRACE(threads);
    Simulation on(test::scene_with(base + std::vector<std::string>{threads}));
    Simulation off(test::scene_with(base + std::vector<std::string>{threads, "solver.simd=false"}));
    ASSERT_TRUE(on.solver().simd_active());
    ASSERT_FALSE(off.solver().simd_active());
    if (check) check(on.solver().model());
    for (double t : {5e-6, 20e-6, 40e-6}) {
      test::run_until(on, t);
      test::run_until(off, t);
      EXPECT_EQ(on.state_hash(), off.state_hash()) << "at " << t * 1e6 << " us";
    }
    const Summary s = on.summary(), r = off.summary();
    EXPECT_GT(s.broken_warp + s.broken_weft, 0) << "the run should exercise breaks";
    EXPECT_EQ(s.energy_absorbed_J, r.energy_absorbed_J);
    EXPECT_EQ(s.energy_balance_error, r.energy_balance_error) << "the ledger (sums booked in the same order)";
  }
}

// A whole impact (breaks, ravelled and released crossings, windows at yarn ends that the
// lanes leave to the one-crossing code) gives the same state bit for bit with the lanes
// on and off, on one thread and on two.
TEST_F(Lanes, RunsAreBitIdenticalToOneCrossingAtATime) {
  expect_lanes_change_nothing(test::small_patch() +
                              std::vector<std::string>{"projectile.velocity_mps=400", "solver.end_time_us=40"});
}

// The pin-jointed model's elements go through the lanes with their crimp stage and crimp
// damping (element_lanes.h): a whole impact, through the toe, breaks and the clamps, the same.
TEST_F(Lanes, PinJointedRunsAreBitIdenticalToOneElementAtATime) {
  expect_lanes_change_nothing(
      test::small_patch() +
          std::vector<std::string>{"solver.model=pin_jointed", "projectile.velocity_mps=400", "solver.end_time_us=40"},
      [](const Model& m) {
        ASSERT_GT(m.crimp_strain, 0) << "the pin-jointed model should have its crimp stage";
        ASSERT_GT(m.crimp_damping_beta, 0) << "and its crimp damping";
      });
}

}  // namespace
}  // namespace ravel
