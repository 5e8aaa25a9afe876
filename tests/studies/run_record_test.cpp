// The one reader of summary.json (studies/run_record.h) against its writer
// (core/results.h): a real run's record reads back with the values the run reported, and
// a missing, broken or diverged record is said to be so.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "results.h"
#include "run_record.h"
#include "scene.h"
#include "simulation.h"
#include "study_test_util.h"

namespace ravel::studies {
namespace {

TEST(RunRecord, ReadsBackWhatARunWrote) {
  auto ov = testing::cheap_scene();
  ov.push_back("projectile.velocity_mps=300");
  Simulation sim(load_scene(default_scene_path(), ov));
  sim.run();
  const Summary s = sim.summary();
  ASSERT_TRUE(s.perforated);
  const std::string dir = testing::scratch_dir();
  std::ofstream(dir + "/summary.json") << summary_json(s, sim.scene());
  const RunRecord r = read_run_record(dir);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.status, "completed");
  EXPECT_EQ(r.end_reason, "perforated");
  EXPECT_TRUE(r.perforated);
  // JSON keeps doubles to 17 digits: the values come back bit for bit.
  EXPECT_EQ(r.residual_velocity_mps, s.residual_velocity_mps);
  EXPECT_EQ(r.energy_absorbed_J, s.energy_absorbed_J);
  EXPECT_EQ(r.perforation_time_s, s.perforation_time_s);
  EXPECT_EQ(r.dt_s, s.dt_s);
  EXPECT_EQ(r.step_count, double(s.step_count));
  EXPECT_EQ(r.number("impact_velocity_mps"), 300.0);
  EXPECT_TRUE(std::isnan(r.number("no_such_key")));
  EXPECT_EQ(r.number("no_such_key", -7), -7);
}

TEST(RunRecord, SaysWhyARecordCannotBeRead) {
  const std::string dir = testing::scratch_dir();
  RunRecord r = read_run_record(dir);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.error, "missing");
  std::ofstream(dir + "/summary.json") << "{\"status\": \"comp";
  r = read_run_record(dir);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("unreadable"), std::string::npos) << r.error;
  r = parse_run_record("[1, 2]");
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.error, "not a JSON object");
  // A diverged run's undefined results are null: NaN and "no perforation" here.
  r = parse_run_record(R"({"status": "diverged", "divergence_cause": "non_finite", "diagnosis": "diverged at step 3",
                           "perforated": null, "residual_velocity_mps": null, "perforation_time_s": null,
                           "warnings": ["w1", 2, "w2"]})");
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.status, "diverged");
  EXPECT_EQ(r.divergence_cause, "non_finite");
  EXPECT_EQ(r.diagnosis, "diverged at step 3");
  EXPECT_FALSE(r.perforated);
  EXPECT_TRUE(std::isnan(r.residual_velocity_mps));
  EXPECT_EQ(r.perforation_time_s, -1);
  EXPECT_EQ(r.warnings, (std::vector<std::string>{"w1", "w2"}));
}

}  // namespace
}  // namespace ravel::studies
