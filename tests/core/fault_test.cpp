// Numerical faults (issue 8): each stops the run with status diverged, the cause, the
// step and the time, in the Summary and in summary.json, and the message says what to
// change. Faults a scene can produce are produced by scenes; NaN and a lost nearest-pair
// search are injected through the solver's state setters.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "fixture.h"
#include "results.h"

namespace ravel {
namespace {

using test::operator+;

// Run to the end, write the outputs, and return summary.json as parsed JSON.
nlohmann::json run_and_read(Simulation& sim, const std::string& name) {
  sim.run();
  const std::string dir = (std::filesystem::temp_directory_path() / ("ravel_fault_" + name)).string();
  prepare_output_dir(dir);
  write_run_outputs(dir, sim);
  std::ifstream in(dir + "/summary.json");
  std::stringstream b;
  b << in.rdbuf();
  std::filesystem::remove_all(dir);
  return nlohmann::json::parse(b.str());
}

// The cause, step and time are the same in the Summary, summary.json and the message.
void expect_fault(const Simulation& sim, const nlohmann::json& j, const std::string& cause) {
  const Summary s = sim.summary();
  EXPECT_EQ(s.status, RunStatus::diverged);
  EXPECT_EQ(s.end_reason, EndReason::diverged);
  EXPECT_EQ(s.divergence_cause, cause) << s.diagnosis;
  ASSERT_GE(s.divergence_step, 0);
  EXPECT_LE(s.divergence_step, s.step_count);
  EXPECT_NEAR(s.divergence_time_s, double(s.divergence_step) * s.dt_s, 1e-9 * s.dt_s * double(s.divergence_step + 1));
  char head[96];
  std::snprintf(head, sizeof head, "diverged at step %ld (t = %.4g us): ", s.divergence_step,
                s.divergence_time_s * 1e6);
  EXPECT_EQ(s.diagnosis.rfind(head, 0), 0u) << s.diagnosis;
  EXPECT_NE(s.diagnosis.find("solver.dt_factor"), std::string::npos) << s.diagnosis;  // says what to change
  EXPECT_EQ(j["status"], "diverged");
  EXPECT_EQ(j["end_reason"], "diverged");
  EXPECT_EQ(j["divergence_cause"], cause);
  EXPECT_EQ(j["divergence_step"].get<long>(), s.divergence_step);
  EXPECT_DOUBLE_EQ(j["divergence_time_s"].get<double>(), s.divergence_time_s);
  EXPECT_EQ(j["diagnosis"], s.diagnosis);
}

Scene patch(std::vector<std::string> extra = {}) {
  return test::scene_with(test::small_patch() + extra);
}

TEST(Fault, NanInTheStateStopsTheRunAtTheNextStep) {
  Simulation sim(patch());
  for (int i = 0; i < 20; ++i) sim.step();
  const Model& m = sim.solver().model();
  sim.solver().set_position(m.yarn_node(0, m.yarn_size(0) / 2), Vec3d::Constant(std::nan("")));
  const auto j = run_and_read(sim, "nan");
  expect_fault(sim, j, "non_finite");
  EXPECT_EQ(sim.summary().divergence_step, 20);  // found in the very next step
  EXPECT_NE(sim.summary().diagnosis.find("NaN/infinite"), std::string::npos);
}

TEST(Fault, RunawayEnergyIsFoundByTheLedger) {
  // alpha = 2 is twice the central-difference limit: unstable modes pump energy in.
  Simulation sim(patch({"solver.dt_factor=2", "projectile.velocity_mps=200"}));
  const auto j = run_and_read(sim, "energy");
  expect_fault(sim, j, "energy_balance");
  EXPECT_NE(sim.summary().diagnosis.find("the energy ledger is off by"), std::string::npos);
  EXPECT_NE(sim.summary().diagnosis.find("at or beyond the central-difference stability limit"), std::string::npos);
  EXPECT_LT(sim.summary().divergence_time_s, 30e-6);  // stopped early, not run on with garbage
}

TEST(Fault, ProjectileLeavingTheDomain) {
  // 200 km/s crosses the fabric within one step: no contact is ever found, and the
  // projectile flies off; the scene warns beforehand.
  const Scene sc = patch({"projectile.velocity_mps=2e5"});
  bool warned = false;
  for (const auto& w : sc.warnings)
    warned |= w.find("mm per time step, more than the fabric thickness") != std::string::npos;
  EXPECT_TRUE(warned);
  Simulation sim(sc);
  const auto j = run_and_read(sim, "left");
  expect_fault(sim, j, "projectile_left_domain");
  EXPECT_NE(sim.summary().diagnosis.find("without touching the fabric"), std::string::npos) << sim.summary().diagnosis;
  // The domain is 10 x (W/2 + L/2) + 1 m = 1.24 m from the centre: 6.2 us at 200 km/s (plus
  // the start above the fabric), checked every 16 steps.
  EXPECT_NEAR(sim.summary().divergence_time_s, 1.24 / 2e5, 16 * sim.summary().dt_s + 1e-6);
}

// Every weft yarn jumps 2.5 node spacings along itself: a rigid shift, no energy change,
// so only the nearest-pair search can notice.
void shift_weft_yarns(Simulation& sim) {
  Solver& solver = sim.solver();
  const Model& m = solver.model();
  for (int y = 0; y < m.yarn_count(); ++y) {
    if (m.yarn_family[y] != weft) continue;
    for (int k = 0; k < m.yarn_size(y); ++k) {
      const int i = m.yarn_node(y, k);
      solver.set_position(i, solver.position(i) + Vec3d(2.5 * sim.scene().fabric.spacing_m, 0, 0));
    }
  }
}

TEST(Fault, NearestPairSearchLostAtManyCrossingsDiverges) {
  Simulation sim(patch());
  for (int i = 0; i < 10; ++i) sim.step();
  shift_weft_yarns(sim);
  const auto j = run_and_read(sim, "lost");
  expect_fault(sim, j, "search_lost");
  EXPECT_EQ(sim.summary().divergence_step, 11);  // counted at the end of the step that lost them
  EXPECT_NE(sim.summary().diagnosis.find("the nearest-pair search lost track at"), std::string::npos);
  EXPECT_NE(sim.summary().diagnosis.find("solver.max_search_lost = 0.01"), std::string::npos);
}

TEST(Fault, SearchLostThresholdIsASceneKey) {
  // With the check off (1), the same break is only a warning: the run goes on and ends
  // "completed", its contact state no longer the model's (the warning says where).
  Simulation sim(patch({"solver.max_search_lost=1", "solver.end_time_us=3"}));
  for (int i = 0; i < 10; ++i) sim.step();
  shift_weft_yarns(sim);
  sim.run();
  const Summary s = sim.summary();
  EXPECT_EQ(s.status, RunStatus::completed) << s.diagnosis;
  bool warned = false;
  for (const auto& w : s.warnings)
    warned |= w.find("nearest-pair search: yarns slid more than one node") != std::string::npos;
  EXPECT_TRUE(warned);
}

TEST(Fault, OrdinaryRunsNeverTripTheSearchCheck) {
  // Perforation at several speeds: at most an isolated lost pair, far below the limit.
  for (const char* v : {"projectile.velocity_mps=200", "projectile.velocity_mps=800", "projectile.velocity_mps=1500"}) {
    const Summary s = test::simulate(patch({v}));
    EXPECT_EQ(s.status, RunStatus::completed) << v << ": " << s.diagnosis;
    EXPECT_TRUE(s.divergence_cause.empty());
  }
}

TEST(Fault, CompletedRunsWriteNullFaultFields) {
  Simulation sim(patch({"solver.end_time_us=2"}));
  const auto j = run_and_read(sim, "ok");
  EXPECT_EQ(j["status"], "completed");
  EXPECT_TRUE(j["divergence_cause"].is_null());
  EXPECT_TRUE(j["divergence_step"].is_null());
  EXPECT_TRUE(j["divergence_time_s"].is_null());
}

// The default scene at 260 m/s re-chooses tracked pairs in the folded, bunched yarns under
// the projectile after the first breaks (116 times here, SPEC §4's search assumption was
// reported as "lower solver.dt_factor" beside a suggestion to raise it). The yarns moved
// less than half a node against each other in those steps (relative speeds 40-460 m/s
// against L0 / dt = 14,300 m/s): they are counted as re-pairings, not as yarns outrunning
// the search; a real outrun (the weft shifted 2.5 L0 in one step, above) still is.
TEST(Fault, RepairingInAFoldedWeaveIsNotALostSearch) {
  // To 125 us: the first re-pairings come at 118 us. (At dt_factor 0.25 they remain, 34 by
  // perforation, first at 114 us: measured, docs/MODEL.md §4; too slow for this suite.)
  Simulation sim(test::scene_with({"solver.end_time_us=125", "solver.threads=1"}));
  sim.run();
  const auto& d = sim.solver().diagnostics();
  EXPECT_EQ(d.skipped_nodes, 0);
  EXPECT_GT(d.repaired, 0);  // the folded weave under the projectile does re-pair
}

// Slip is material: a crossing's slip rate never exceeds how fast its two yarns move
// against each other, bounded by twice the fastest node plus the largest position shift a
// compressed crossing makes per step (2 % of D, docs/MODEL.md §4). Before, re-paired or
// kinked contacts showed up to 12 km/s where no node moved faster than 530 m/s.
TEST(Fault, SlipRateIsBoundedByTheYarnsRelativeSpeed) {
  Simulation sim(patch({"projectile.velocity_mps=400", "solver.end_time_us=40"}));
  const Model& m = sim.solver().model();
  const double shift_rate = 2 * 0.02 * 0.5 * sim.scene().fabric.thickness_m / m.dt;
  double worst = 0, any = 0;
  while (!sim.finished()) {
    sim.step();
    double vmax = 0;
    for (int i = 0; i < m.node_count; ++i) vmax = std::max(vmax, sim.solver().velocity(i).norm());
    for (int c = 0; c < int(m.crossings.size()); ++c) {
      const double s = sim.solver().crossing_slip_rate(c);
      any = std::max(any, s);
      worst = std::max(worst, s / (2 * vmax + shift_rate));
    }
  }
  EXPECT_GT(any, 1.0);  // yarns do slip in this run
  EXPECT_LE(worst, 1.0);
}

}  // namespace
}  // namespace ravel
