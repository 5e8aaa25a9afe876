#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "study_test_util.h"
#include "sweep_runner.h"

namespace ravel::studies {
namespace {

// The app's path: start on a background thread, poll snapshots, get the live chart data.
TEST(SweepRunner, RunsInTheBackgroundAndFeedsTheLiveChart) {
  const std::string dir = testing::scratch_dir();
  SweepRunner runner;
  SweepOptions o;
  o.overrides = testing::cheap_scene();
  o.out_dir = dir;
  o.jobs = 2;
  std::string error;
  ASSERT_TRUE(runner.start(o, {"projectile.velocity_mps=100,150,200"}, &error)) << error;
  int polls = 0, max_rows = 0, partial_polls = 0;
  for (auto t0 = std::chrono::steady_clock::now(); runner.running();) {
    const auto s = runner.snapshot();
    EXPECT_LE(s.progress.done, s.progress.total);
    max_rows = std::max(max_rows, int(s.results.rows.size()));
    if (!s.finished && !s.results.rows.empty() && s.results.rows.size() < 3) ++partial_polls;
    ++polls;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    ASSERT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(120));
  }
  const auto s = runner.snapshot();
  EXPECT_TRUE(s.finished) << s.error;
  EXPECT_EQ(s.progress.done, 3);
  ASSERT_EQ(s.results.rows.size(), 3u);
  // The live chart was fed while the sweep ran: with two jobs for three cases, the third
  // runs alone for seconds after the first two finished, and the 5 ms polls saw their rows.
  EXPECT_GT(partial_polls, 0) << "max rows seen while running: " << max_rows;
  const auto charts = s.charts();
  ASSERT_EQ(charts.size(), 2u);  // energy absorbed and residual velocity
  // Charts leave out cases that diverged (they have no answer to plot).
  const int status = s.results.column("status");
  ASSERT_GE(status, 0);
  int completed = 0;
  for (const auto& r : s.results.rows) completed += r[size_t(status)] == "completed";
  EXPECT_EQ(finite_point_count(charts[0].second), completed);
  EXPECT_GT(polls, 0);
  // Bad input is refused on the calling thread, nothing starts.
  EXPECT_FALSE(runner.start(o, {"projectile.nope=1,2"}, &error));
  EXPECT_NE(error.find("projectile.nope"), std::string::npos);
  EXPECT_FALSE(runner.running());
}

}  // namespace
}  // namespace ravel::studies
