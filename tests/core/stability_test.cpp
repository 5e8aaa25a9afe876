// Stability (SPEC §3): below the central-difference limit a run is stable; well above
// it the solver notices and stops with a diagnosis that says what to change.
#include <gtest/gtest.h>

#include "fixture.h"

namespace ravel {
namespace {

using test::operator+;

std::vector<std::string> patch(const char* model, const char* alpha) {
  return test::small_patch() + std::vector<std::string>{model, alpha, "projectile.velocity_mps=200"};
}

TEST(Stability, StableBelowTheLimit) {
  // Chains of lumped masses m and springs k are stable for dt < sqrt(m/k), dt_factor ~ 0.99
  // here (m = rho A L); 0.9 leaves a margin for the projectile's push-out (Eq 19).
  for (const char* model : {"solver.model=pin_jointed", "solver.model=sliding"}) {
    const Summary s = test::simulate(test::scene_with(patch(model, "solver.dt_factor=0.9")));
    EXPECT_EQ(s.status, RunStatus::completed) << model << ": " << s.diagnosis;
    // Each failure books the element's energy at the step it broke, which misses the
    // work of its last half step: O(f v dt) per break, a few % here with ~200 breaks.
    EXPECT_LT(s.energy_balance_error, 0.05) << model;
  }
}

TEST(Stability, WellAboveTheLimitIsReportedAsDiverged) {
  for (const char* model : {"solver.model=pin_jointed", "solver.model=sliding"}) {
    const Scene sc = test::scene_with(patch(model, "solver.dt_factor=2"));
    // The scene itself warns before the run.
    ASSERT_FALSE(sc.warnings.empty());
    EXPECT_NE(sc.warnings[0].find("solver.dt_factor"), std::string::npos);
    Simulation sim(sc);
    sim.run();
    const Summary s = sim.summary();
    EXPECT_EQ(s.status, RunStatus::diverged) << model;
    EXPECT_EQ(s.end_reason, EndReason::diverged) << model;
    EXPECT_NE(s.diagnosis.find("diverged at step"), std::string::npos) << s.diagnosis;
    EXPECT_NE(s.diagnosis.find("lower solver.dt_factor"), std::string::npos) << s.diagnosis;
    // It stopped early rather than running on with garbage.
    EXPECT_LT(s.end_time_s, 30e-6) << model;
  }
}

}  // namespace
}  // namespace ravel
