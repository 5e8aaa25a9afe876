// The slipping clamp (fabric.clamp = slipping, docs/MODEL.md §7): the clamp feeds yarn into
// the element that ends in it, against the clamp faces' Coulomb grip, once that element pulls
// harder than the grip. Checked against one-dimensional wave theory on a single elastic yarn, by the
// energy book, and on the default scene where the rigid clamp misplaces the breaks (issue 37).
#include <gtest/gtest.h>

#include <cmath>

#include "fixture.h"
#include "single_yarn.h"

namespace ravel {
namespace {

using test::operator+;

using namespace test::single;

// The single yarn of wave_test.cpp at 100 m/s, for 40 us (single_yarn.h).
std::vector<std::string> single_yarn() {
  return test::single::single_yarn(100) + std::vector<std::string>{"solver.end_time_us=40"};
}

TEST(SlippingClamp, GripsOnlyTheClampedYarnEnds) {
  // Quarter model of the default ply: each weft ends in the clamp at x = +60 mm once, and the
  // clamp feeds its last element; the warp along the clamp line and the warps' free ends
  // have no grip.
  for (const char* model : {"sliding", "pin_jointed"}) {
    const Scene sc =
        test::scene_with({"fabric.clamp=slipping", "fabric.clamp_grip_n=200", std::string("solver.model=") + model});
    Simulation sim(sc);
    const Model& m = sim.solver().model();
    ASSERT_EQ(int(m.grips.size()), m.weft_count) << model;
    for (const auto& g : m.grips) {
      EXPECT_EQ(m.fixed[size_t(g.node)], fix_all);  // the clamped end stays where it is
      EXPECT_TRUE(m.elem_a[size_t(g.element)] == g.node || m.elem_b[size_t(g.element)] == g.node);
      EXPECT_EQ(m.yarn_family[size_t(m.elem_yarn[size_t(g.element)])], weft);
      EXPECT_NEAR(m.x0[size_t(g.node)].x(), 0.5 * sc.fabric.width_m, 0.5 * kL0);
      // the pole weft lies on the symmetry plane y = 0: half a yarn, half the grip
      const bool on_plane = std::abs(m.x0[size_t(g.node)].y()) < 1e-9;
      EXPECT_DOUBLE_EQ(g.force, on_plane ? 100.0 : 200.0) << model << " node " << g.node;
    }
  }
  // Clamped all round, the corner node ends two clamped yarns: it stays rigid.
  Simulation all(test::scene_with({"fabric.clamp=slipping", "fabric.clamped=all"}));
  const Model& m = all.solver().model();
  EXPECT_EQ(int(m.grips.size()), m.weft_count + m.warp_count - 2);  // the corner ends a weft and a warp
  // Rigid clamps (the paper, the default): no grips at all.
  Simulation rigid(test::scene_with({}));
  EXPECT_TRUE(rigid.solver().model().grips.empty());
}

// A grip the yarn never reaches holds like the rigid clamp: the run is the same to the bit.
TEST(SlippingClamp, AGripNeverReachedIsTheRigidClamp) {
  auto rigid = single_yarn(), held = single_yarn();
  held.push_back("fabric.clamp=slipping");
  held.push_back("fabric.clamp_grip_n=1000");
  Simulation a(test::scene_with(rigid)), b(test::scene_with(held));
  a.run();
  b.run();
  const Model& m = a.solver().model();
  ASSERT_EQ(b.solver().model().grips.size(), 1u);
  ASSERT_EQ(a.step_count(), b.step_count());
  for (int i = 0; i < m.node_count; ++i) ASSERT_EQ(a.solver().position(i), b.solver().position(i)) << i;
  EXPECT_EQ(b.solver().ledger().clamp_friction_J, 0.0);
  EXPECT_EQ(b.solver().grip_payout(0), 0.0);
}

// The stretch wave Smith's theory puts behind the front (strain e_i, the material moving
// towards the impact at c e_i) meets a clamp that slips at grip G, with e_i < G / EA < 2 e_i:
// a rigid clamp would double the strain (wave_test.cpp), this one caps it at e_G = G / EA,
// and the yarn comes out of the clamp at c (2 e_i - e_G) / (1 + e_G) (the incident and
// reflected waves superposed with the strain at the clamp held at e_G: the material by the
// clamp moves at c (2 e_i - e_G), stretched by 1 + e_G against the yarn in the clamp).
// Tolerances: 1 % on the strain by the clamp (the rigid-plastic slider holds the last
// element's pull at G to the bisection's precision whenever it feeds), 5 % on the feed rate
// (the incident strain rises 4 % along the yarn, wave_test). The energy balance is checked
// as in every run.
TEST(SlippingClamp, CapsTheReflectedStrainAndFeedsYarnAtTheWaveTheorysRate) {
  const double c = std::sqrt(kE / kRho), ei = smith_strain(100, c), G = 1.5 * kE * kA * ei;
  auto opts = single_yarn();
  opts.push_back("fabric.clamp=slipping");
  char grip[64];
  std::snprintf(grip, sizeof grip, "fabric.clamp_grip_n=%.9g", G);
  opts.push_back(grip);
  Simulation sim(test::scene_with(opts));
  const Solver& s = sim.solver();
  const Model& m = s.model();
  ASSERT_EQ(m.grips.size(), 1u);
  const int end = m.grips[0].node, e_end = m.grips[0].element;
  const double yc = m.x0[size_t(end)].y();
  const double t0 = yc / c;  // the front reaches the clamp
  // From 6 to 16 us after the front arrived (the reflection then fills 70 mm of yarn, short of
  // the transverse wave): the strain of the fed element, step by step, and the feed rate.
  test::run_until(sim, t0 + 6e-6);
  const double fed6 = s.grip_payout(0);
  double strain_sum = 0;
  int n = 0;
  while (sim.time_s() < t0 + 16e-6) {
    sim.step();
    strain_sum += s.strain(e_end);
    ++n;
  }
  const double fed16 = s.grip_payout(0), dt_window = sim.time_s() - (t0 + 6e-6);
  const double eG = G / (kE * kA), at_clamp = strain_sum / n;
  ASSERT_GT(n, 100);
  EXPECT_NEAR(at_clamp / eG, 1.0, 0.01) << "strain at the clamp " << at_clamp << ", grip strain " << eG;
  const double rate = (fed16 - fed6) / dt_window, theory = c * (2 * ei - eG) / (1 + eG);
  EXPECT_NEAR(rate / theory, 1.0, 0.05) << "fed at " << rate << " m/s, theory " << theory;
  EXPECT_EQ(s.position(end), m.x0[size_t(end)]);  // the clamped end stays put
  EXPECT_LT(std::abs(sim.summary().energy_balance_error), 1e-3);
}

// The clamp's friction in the ledger is what the fed element took from its nodes and does
// not hold: for a yarn fed at the grip G that is G x the yarn fed, (1 + e_G / 2) per metre
// (the element grows by the fed yarn stretched to e_G, and stores e_G G / 2 of it), 0.16 %
// above G x fed here. Booking instead the energy of the element stretched past the grip less
// that of the fed one counted the overstretch of each step the nodes never felt: 9.0 % too
// much at the default step, 4.6 % at half of it. Checked at both steps within 0.5 % (the
// front's ringing), with the energy balance.
TEST(SlippingClamp, ItsFrictionIsGripTimesYarnFedAtAnyStep) {
  const double c = std::sqrt(kE / kRho), G = 1.5 * kE * kA * smith_strain(100, c);
  char grip[64];
  std::snprintf(grip, sizeof grip, "fabric.clamp_grip_n=%.9g", G);
  for (const char* dt : {"solver.dt_factor=0.5", "solver.dt_factor=0.25"}) {
    auto opts = single_yarn();
    opts.push_back("fabric.clamp=slipping");
    opts.push_back(grip);
    opts.push_back(dt);
    Simulation sim(test::scene_with(opts));
    test::run_until(sim, 0.150 / c + 16e-6);
    const double fed = sim.solver().grip_payout(0), work = sim.solver().ledger().clamp_friction_J;
    ASSERT_GT(fed, 5e-5) << dt;
    EXPECT_NEAR(work / (G * fed), 1.0, 0.005) << dt << ": booked " << work << " J, G x yarn fed " << G * fed;
    EXPECT_LT(std::abs(sim.summary().energy_balance_error), 1e-3) << dt;
  }
}

// The slider runs inside the element loop, on whichever thread has the element; its payout
// and friction are per clamp and summed in clamp order, so 1 and 2 threads give the same
// state, payouts included (knobs_test's Determinism for rigid clamps).
TEST(SlippingClamp, OneAndTwoThreadsGiveTheSameState) {
  const auto base = test::small_patch() + std::vector<std::string>{"projectile.velocity_mps=400",
                                                                   "fabric.clamp=slipping", "fabric.clamp_grip_n=40"};
  std::uint64_t h[2];
  double fed[2];
  for (int t = 0; t < 2; ++t) {
    Simulation sim(test::scene_with(base + std::vector<std::string>{t ? "solver.threads=2" : "solver.threads=1"}));
    test::run_until(sim, 40e-6);
    h[t] = sim.state_hash();
    fed[t] = sim.summary().clamp_slip_max_m;
  }
  EXPECT_GT(fed[0], 1e-4);  // the clamps fed yarn
  EXPECT_EQ(h[0], h[1]);
  EXPECT_EQ(fed[0], fed[1]);
}

// A clamp holds fabric.clamp_depth_mm of yarn: fed out past it, the yarn has left the clamp,
// pulls on nothing and anchors nothing. A 1 g sphere at 300 m/s on a 30 mm patch whose clamps
// grip 60 N a yarn (a fifth of the break load) pulls the yarns under it out of their clamps
// and carries them away: perforated with no element broken, the clamps' feed capped at their
// depth. (Before the depth, such a run fed yarn without end until a node left the domain.)
TEST(SlippingClamp, AYarnFedPastTheClampsDepthIsFree) {
  const Summary s = test::simulate(test::scene_with(
      {"fabric.width_mm=30", "fabric.length_mm=30", "projectile.diameter_mm=4", "projectile.mass_g=1",
       "projectile.velocity_mps=300", "fabric.clamp=slipping", "fabric.clamp_grip_n=60", "fabric.clamp_depth_mm=25"}));
  EXPECT_EQ(s.status, RunStatus::completed);
  EXPECT_TRUE(s.perforated);
  EXPECT_EQ(s.broken_warp + s.broken_weft, 0);
  EXPECT_GE(s.clamp_pulled_out, 1.0);
  EXPECT_DOUBLE_EQ(s.clamp_slip_max_m, 25e-3);
  EXPECT_GT(s.clamp_friction_J, 0.0);
  EXPECT_LT(std::abs(s.energy_balance_error), 2e-3);
}

// Issue 37, item 4: on the default scene at 260 m/s the rigid clamp makes the pin-jointed net
// tear along the clamp lines (63 % of the elements broken before perforation lie within 2 mm
// of a clamp, the first break 18 mm out). A clamp that slips at 250 N a yarn, below the yarn's
// break load E A e_f = 289 N, caps the clamp line's tension, and both models break at the
// impact point: the first break within 8 mm of it and at most a quarter of the breaks by a
// clamp (measured: pin-jointed 3.0 mm and 52 of 470, sliding 2.6 mm and 0 of 90).
TEST(SlippingClamp, BothModelsBreakAtTheImpactPointNotAtTheClamps) {
  for (const char* model : {"pin_jointed", "sliding"}) {
    const Summary s = test::simulate(
        test::scene_with({"fabric.clamp=slipping", "fabric.clamp_grip_n=250", std::string("solver.model=") + model}));
    ASSERT_TRUE(s.perforated) << model;
    EXPECT_LT(s.first_break_distance_m, 8e-3) << model;
    EXPECT_GT(s.broken_before_perforation, 0) << model;
    EXPECT_LE(4 * s.broken_near_clamp, s.broken_before_perforation)
        << model << ": " << s.broken_near_clamp << " of " << s.broken_before_perforation << " by a clamp";
    EXPECT_GT(s.clamp_friction_J, 0.0) << model;
    EXPECT_LT(std::abs(s.energy_balance_error), 2e-3) << model;
  }
  // ... where the rigid clamp tears the pinned net (the guard: fails on the rigid clamp).
  const Summary r = test::simulate(test::scene_with({"solver.model=pin_jointed"}));
  EXPECT_GT(4 * r.broken_near_clamp, r.broken_before_perforation);
}

}  // namespace
}  // namespace ravel
