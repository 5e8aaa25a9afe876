// Waves on a single elastic yarn struck transversely, against classical single-yarn
// theory (Smith et al.): the longitudinal front runs at c = sqrt(E/rho); the strain
// behind it and the transverse wave speed follow from the impact velocity.
#include <gtest/gtest.h>

#include <cmath>

#include "fixture.h"
#include "single_yarn.h"

namespace ravel {
namespace {

using namespace test::single;

struct Profile {
  std::vector<double> y, strain, z;  // per element midpoint (y), strain; per node z
};

Profile profile(const Simulation& sim) {
  const Solver& s = sim.solver();
  const Model& m = s.model();
  Profile p;
  for (int e = 0; e < m.element_count; ++e) {
    p.y.push_back(0.5 * (s.position(m.elem_a[e]).y() + s.position(m.elem_b[e]).y()));
    p.strain.push_back(s.strain(e));
  }
  return p;
}

// Position of the last element (from the centre out) whose strain is above `level`.
double front(const Profile& p, double level) {
  double y = 0;
  for (size_t e = 0; e < p.strain.size(); ++e)
    if (p.strain[e] > level) y = std::max(y, p.y[e]);
  return y;
}

TEST(SingleYarn, LongitudinalFrontRunsAtWaveSpeed) {
  Simulation sim(test::scene_with(single_yarn(100)));
  const double c = std::sqrt(kE / kRho);
  const double eps = smith_strain(100, c);
  test::run_until(sim, 8e-6);
  const double t1 = sim.time_s(), y1 = front(profile(sim), 0.5 * eps);
  test::run_until(sim, 18e-6);
  const double t2 = sim.time_s(), y2 = front(profile(sim), 0.5 * eps);
  const double speed = (y2 - y1) / (t2 - t1);
  // The discrete front is smeared over a few elements; half-plateau crossings taken 71 mm
  // apart locate it to about one element each: 2 x 0.844 / 71 = 2.4 %.
  EXPECT_NEAR(speed / c, 1.0, 0.024) << "measured " << speed << " m/s, theory " << c;
}

// The strain plateau between the transverse and the longitudinal front, as a fraction of
// Smith's strain, on a chain of elements h_rel x 0.844 mm struck by the 12 mm sphere.
double plateau_over_smith(double v, double h_rel) {
  auto ov = single_yarn(v);
  char spacing[64], mass[64];
  std::snprintf(spacing, sizeof spacing, "fabric.spacing_mm=%.9g", kL0 * h_rel * 1e3);
  std::snprintf(mass, sizeof mass, "fabric.node_mass_g=%.9g", kRho * kA * kL0 * h_rel * 1e3);
  ov.push_back(spacing);
  ov.push_back(mass);  // rho A h: the chain's wave speed stays c
  Simulation sim(test::scene_with(ov));
  const double c = std::sqrt(kE / kRho);
  test::run_until(sim, 15e-6);
  const Profile p = profile(sim);
  // Plateau: between the transverse front (U t from the centre) and the longitudinal
  // front (c t), away from both.
  const double t = sim.time_s();
  const double eps_th = smith_strain(v, c);
  const double U = c * (std::sqrt(eps_th * (1 + eps_th)) - eps_th);
  double sum = 0;
  int n = 0;
  for (size_t e = 0; e < p.strain.size(); ++e)
    if (p.y[e] > 1.3 * U * t + 6e-3 && p.y[e] < 0.8 * c * t) sum += p.strain[e], ++n;
  EXPECT_GT(n, 10);
  return n > 0 ? sum / n / eps_th : 0;
}

// Smith's plateau strain is exact for an elastic string once the transverse front has left
// the projectile (the yarn leaves a blunt nose tangentially at the nose's speed, as it
// leaves a point load), so the only error is the chain's: the 12 mm sphere touches the yarn
// at nodes h apart, and the polygon it wraps misfits the strain by O(h). At the paper's
// h = 0.844 mm that is 5.5 % at 50 m/s (the smallest kink angle, most sensitive to the
// wrap), 1-2 % at 100-200 m/s. Checked: the error shrinks at least at first order as h
// halves twice (|e(h/4)| <= 0.4 |e(h)|; first order gives 0.25), and the first-order
// Richardson limit 2 e(h/4) - e(h/2) is within 1 % of Smith (what remains is the explicit
// integration's and the plateau window's, both well under 1 %).
TEST(SingleYarn, StrainBehindTheFrontConvergesToSmith) {
  for (double v : {50.0, 100.0, 200.0}) {
    SCOPED_TRACE("V = " + std::to_string(v) + " m/s");
    const double e1 = plateau_over_smith(v, 1.0) - 1, e2 = plateau_over_smith(v, 0.5) - 1,
                 e4 = plateau_over_smith(v, 0.25) - 1;
    EXPECT_LE(std::abs(e4), 0.4 * std::abs(e1)) << "e(h) " << e1 << ", e(h/2) " << e2 << ", e(h/4) " << e4;
    EXPECT_LE(std::abs(e2), std::abs(e1));
    EXPECT_NEAR(2 * e4 - e2, 0.0, 0.01) << "e(h/2) " << e2 << ", e(h/4) " << e4;
  }
}

// Why a rigid clamp is a place where yarns break (docs/MODEL.md §10): a stretch wave that
// meets a fixed end comes back with the material stopped and the strain doubled. Method of
// images: while only longitudinal waves have reached it, the region by the clamp moves
// linearly (the chain is linear in its Lagrangian strain), so the clamped yarn's strain at
// y is the strain an endless yarn has at y plus the strain it has at the mirror point
// 2 y_c - y, both at the same time. A yarn twice as long (whose own ends the waves have not
// reached) stands for the endless one. The relation holds to rounding (4e-10 of the strain
// here, after 455 double-precision steps; bound 1e-8), and the strain at the clamp is
// then twice the incident one (2.09: the incident strain still rises along the 5 mm averaged).
TEST(SingleYarn, ReflectionAtAClampDoublesTheStrain) {
  auto clamped = single_yarn(100), endless = single_yarn(100);
  clamped.push_back("solver.end_time_us=40");
  endless.push_back("solver.end_time_us=40");
  endless.push_back("fabric.length_mm=600");
  Simulation a(test::scene_with(clamped)), b(test::scene_with(endless));
  const double c = std::sqrt(kE / kRho);
  const double yc = std::floor(0.150 / kL0) * kL0;  // the clamped end node
  const double t = yc / c + 6e-6;                   // the reflection is c x 6 us = 43 mm back
  test::run_until(a, t);
  test::run_until(b, t);
  ASSERT_EQ(a.step_count(), b.step_count());
  const Profile pa = profile(a), pb = profile(b);
  auto strain_at = [&](const Profile& p, double y) {  // the element whose midpoint is y
    for (size_t e = 0; e < p.y.size(); ++e)
      if (std::abs(p.y[e] - y) < 0.3 * kL0) return p.strain[e];
    ADD_FAILURE() << "no element at y = " << y;
    return 0.0;
  };
  double worst = 0, incident = 0, at_clamp = 0;
  int n = 0;
  for (size_t e = 0; e < pa.y.size(); ++e) {
    const double y = pa.y[e];
    if (y < yc - 40e-3 || y > yc) continue;
    const double direct = strain_at(pb, y), image = strain_at(pb, 2 * yc - y);
    worst = std::max(worst, std::abs(pa.strain[e] - (direct + image)));
    if (y > yc - 5e-3) incident += direct, at_clamp += pa.strain[e], ++n;
  }
  ASSERT_GT(n, 4);
  incident /= n;
  at_clamp /= n;
  EXPECT_GT(incident, 0.5 * smith_strain(100, c));
  EXPECT_LT(worst, 1e-8 * incident) << "clamped = endless + image, worst difference " << worst;
  EXPECT_NEAR(at_clamp / incident, 2.0, 0.1) << "incident " << incident << ", at the clamp " << at_clamp;
}

}  // namespace
}  // namespace ravel
