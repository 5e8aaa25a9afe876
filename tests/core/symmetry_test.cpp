// SPEC §6: a symmetric scene modelled as a quarter gives the answers of the full model.
#include <gtest/gtest.h>

#include <cmath>

#include "fixture.h"

namespace ravel {
namespace {

using test::operator+;

TEST(Symmetry, QuarterIsChosenForTheCentredStrike) {
  Simulation sim(test::scene_with(test::small_patch()));
  EXPECT_EQ(sim.summary().model, "quarter");
  Simulation off(test::scene_with(test::small_patch() + std::vector<std::string>{"projectile.offset_x_mm=2"}));
  EXPECT_EQ(off.summary().model, "half");
  Simulation one_clamp(test::scene_with(test::small_patch() + std::vector<std::string>{"fabric.clamped=left"}));
  EXPECT_EQ(one_clamp.summary().model, "half");
  Simulation forced(test::scene_with(test::small_patch() + std::vector<std::string>{"solver.symmetry=full"}));
  EXPECT_EQ(forced.summary().model, "full");
  // The quarter holds a quarter of the full model's crossings (plus the plane rows).
  EXPECT_LT(sim.summary().modelled_node_count * 3, forced.summary().modelled_node_count);
  EXPECT_EQ(sim.summary().node_count, forced.summary().node_count);  // both count the whole fabric
  EXPECT_EQ(sim.summary().element_count, forced.summary().element_count);
  EXPECT_EQ(sim.summary().crossing_count, forced.summary().crossing_count);
}

// Through impact and failure the quarter and the full model agree. After failure both are
// sensitive to which element breaks first (rounding differs between them), and on small
// patches the outcome can even branch (the central yarn snapping early or late). On a
// 36 mm patch struck at 200 m/s by a 6 mm, 2 g sphere, each model's own spread when V0
// moves by 0.1 m/s (measured) is: projectile velocity at 60 us 0.4 %; absorbed energy at
// 100 us 8.8-9.0 J (sliding) and 10.1-12.5 J (pin-jointed, whose free warp yarns break one
// by one after 60 us); broken weft yarns +-1. The tolerances below cover those spreads.
double velocity_at(const std::vector<HistoryRow>& h, double t) {
  const HistoryRow* best = &h.front();
  for (const auto& r : h)
    if (std::abs(r.t_s - t) < std::abs(best->t_s - t)) best = &r;
  return best->projectile_velocity_mps;
}

// After failure single runs scatter (changing V0 by 0.1 m/s moves the absorbed energy by
// several %), so the quarter and full models are compared as ensembles of nearby impacts:
// their mean absorbed energies agree within three standard errors of the difference (from
// the runs' own spread) plus 1 % for what the plane treatment approximates, and the
// projectile velocity at 60 us, before the first break, within 0.5 %.
TEST(Symmetry, QuarterAndFullAgree) {
  for (const char* model : {"solver.model=pin_jointed", "solver.model=sliding"}) {
    SCOPED_TRACE(model);
    std::vector<double> eq, ef;
    for (const char* v :
         {"projectile.velocity_mps=199.9", "projectile.velocity_mps=200", "projectile.velocity_mps=200.1"}) {
      const std::vector<std::string> base{"fabric.width_mm=36",
                                          "fabric.length_mm=36",
                                          "projectile.diameter_mm=6",
                                          "projectile.mass_g=2",
                                          "solver.end_time_us=100",
                                          model,
                                          v};
      Simulation q(test::scene_with(base));
      Simulation f(test::scene_with(base + std::vector<std::string>{"solver.symmetry=full"}));
      q.run();
      f.run();
      ASSERT_EQ(q.summary().model, "quarter");
      ASSERT_EQ(f.summary().model, "full");
      const double vq = velocity_at(q.history(), 60e-6), vf = velocity_at(f.history(), 60e-6);
      EXPECT_NEAR(vq, vf, 0.005 * vf);
      EXPECT_LT(vq, 0.95 * 200);  // the fabric did slow it
      eq.push_back(q.summary().energy_absorbed_J);
      ef.push_back(f.summary().energy_absorbed_J);
    }
    auto mean = [](const std::vector<double>& x) { return (x[0] + x[1] + x[2]) / 3; };
    auto var = [&](const std::vector<double>& x) {
      const double m = mean(x);
      return ((x[0] - m) * (x[0] - m) + (x[1] - m) * (x[1] - m) + (x[2] - m) * (x[2] - m)) / 2;
    };
    const double se = std::sqrt((var(eq) + var(ef)) / 3);
    EXPECT_NEAR(mean(eq), mean(ef), 3 * se + 0.01 * mean(ef))
        << "quarter " << eq[0] << " " << eq[1] << " " << eq[2] << ", full " << ef[0] << " " << ef[1] << " " << ef[2];
  }
}

// Before anything breaks the two models are the same to rounding: compare the ledger at
// a fixed time with elastic, unbreakable yarns. The bounds are what each model's arithmetic
// allows, not what a run happened to give. Pin-jointed: the same operations on the same
// numbers in another order (the quarter's nodes are numbered differently and its sums run
// over fewer terms), so 160 steps leave differences of 1e-16..1e-14 (measured 1.4e-16 in the
// projectile's speed, 1.6e-14 in strain energy); bound 1e-12. Sliding: the yarn contact's
// decisions (stick or slip, which pair is nearest, tie weights within 2 % of D) switch on
// quantities that differ at rounding level, and a switched decision moves a crossing's
// impulse by a finite amount, so the difference grows to a few 1e-6 (measured 7e-9 in speed,
// 7.5e-6 in strain energy, 1.7e-6 in fabric KE); bound 1e-4, under which a 0.05 % asymmetry
// (the size of bug the old 1e-3 bound let through) fails.
TEST(Symmetry, QuarterAndFullLedgersMatchBeforeFailure) {
  for (const char* model : {"solver.model=pin_jointed", "solver.model=sliding"}) {
    const bool pinned = std::string(model).find("pin") != std::string::npos;
    const double tol = pinned ? 1e-12 : 1e-4;
    const auto base =
        test::small_patch() + std::vector<std::string>{model, "yarn.breakable=false", "projectile.velocity_mps=200"};
    Simulation q(test::scene_with(base));
    Simulation f(test::scene_with(base + std::vector<std::string>{"solver.symmetry=full"}));
    test::run_until(q, 10e-6);
    test::run_until(f, 10e-6);
    const HistoryRow& a = q.history().back();
    const HistoryRow& b = f.history().back();
    EXPECT_NEAR(a.projectile_velocity_mps, b.projectile_velocity_mps, tol * b.projectile_velocity_mps) << model;
    EXPECT_NEAR(a.ledger.strain_energy_J, b.ledger.strain_energy_J, tol * b.ledger.strain_energy_J) << model;
    EXPECT_NEAR(a.ledger.fabric_ke_J, b.ledger.fabric_ke_J, tol * b.ledger.fabric_ke_J) << model;
  }
}

}  // namespace
}  // namespace ravel
