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
  EXPECT_LT(sim.summary().node_count * 3, forced.summary().node_count);
}

// Residual velocity and absorbed energy agree between quarter and full. The two differ
// only in the order the Gauss-Seidel contact sweep visits crossings and in rounding, which
// after failure (a threshold event) can shift a break by a step: 1 % of the residual
// velocity and 3 % of the absorbed energy bound that.
TEST(Symmetry, QuarterAndFullAgree) {
  for (const char* model : {"solver.model=pin_jointed", "solver.model=sliding"}) {
    const auto base = test::small_patch() + std::vector<std::string>{model, "projectile.velocity_mps=400"};
    const Summary q = test::simulate(test::scene_with(base));
    const Summary f = test::simulate(test::scene_with(base + std::vector<std::string>{"solver.symmetry=full"}));
    ASSERT_EQ(q.model, "quarter");
    ASSERT_EQ(f.model, "full");
    EXPECT_EQ(q.perforated, f.perforated) << model;
    EXPECT_NEAR(q.residual_velocity_mps, f.residual_velocity_mps, 0.01 * f.residual_velocity_mps) << model;
    EXPECT_NEAR(q.energy_absorbed_J, f.energy_absorbed_J, 0.03 * f.energy_absorbed_J) << model;
    if (f.perforated) EXPECT_NEAR(q.perforation_time_s, f.perforation_time_s, 0.05 * f.perforation_time_s) << model;
  }
}

// Before anything breaks the two models are the same to rounding: compare the ledger at
// a fixed time with elastic, unbreakable yarns.
TEST(Symmetry, QuarterAndFullLedgersMatchBeforeFailure) {
  for (const char* model : {"solver.model=pin_jointed", "solver.model=sliding"}) {
    const auto base = test::small_patch() + std::vector<std::string>{model, "yarn.breakable=false",
                                                                     "projectile.velocity_mps=200"};
    Simulation q(test::scene_with(base));
    Simulation f(test::scene_with(base + std::vector<std::string>{"solver.symmetry=full"}));
    test::run_until(q, 10e-6);
    test::run_until(f, 10e-6);
    const HistoryRow& a = q.history().back();
    const HistoryRow& b = f.history().back();
    EXPECT_NEAR(a.projectile_velocity_mps, b.projectile_velocity_mps, 1e-3) << model;
    EXPECT_NEAR(a.ledger.strain_energy_J, b.ledger.strain_energy_J, 1e-3 * b.ledger.strain_energy_J) << model;
    EXPECT_NEAR(a.ledger.fabric_ke_J, b.ledger.fabric_ke_J, 1e-3 * b.ledger.fabric_ke_J) << model;
  }
}

}  // namespace
}  // namespace ravel
