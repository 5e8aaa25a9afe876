#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "results.h"
#include "study_test_util.h"
#include "sweep.h"

namespace ravel::studies {
namespace {

namespace fs = std::filesystem;
using testing::cheap_scene;
using testing::scratch_dir;

std::vector<Case> cheap_cases() {
  return expand_cases({parse_vary("projectile.velocity_mps=60:180:60", "", cheap_scene()),
                       parse_vary("yarn.friction=0.1,0.3", "", cheap_scene())});
}

SweepOptions cheap_options(const std::string& dir, int jobs = 2) {
  SweepOptions o;
  o.overrides = cheap_scene();
  o.out_dir = dir;
  o.jobs = jobs;
  return o;
}

const std::vector<std::string> kKeys{"projectile.velocity_mps", "yarn.friction"};

TEST(Sweep, ParseVaryRangeAndList) {
  const Vary r = parse_vary("projectile.velocity_mps=180:500:20");
  ASSERT_EQ(r.values.size(), 17u);  // 180, 200, ..., 500 inclusive
  EXPECT_EQ(r.values.front(), "180");
  EXPECT_EQ(r.values.back(), "500");
  const Vary f = parse_vary("yarn.friction=0:0.3:0.1");  // 0.1 steps do not add up exactly
  ASSERT_EQ(f.values.size(), 4u);
  EXPECT_EQ(f.values[3], "0.3");
  const Vary l = parse_vary("solver.model=sliding,pin_jointed");
  EXPECT_EQ(l.values, (std::vector<std::string>{"sliding", "pin_jointed"}));
}

TEST(Sweep, BadVaryNamesFlagKeyAndProblem) {
  auto message = [](const std::string& text) {
    try {
      parse_vary(text);
    } catch (const StudyError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("projectile.speed=1,2").find("--vary projectile.speed: unknown scene key"), std::string::npos);
  EXPECT_NE(message("projectile.velocity_mps=300:100:10").find("stop < start"), std::string::npos);
  EXPECT_NE(message("projectile.velocity_mps=1:2:0").find("step must be > 0"), std::string::npos);
  EXPECT_NE(message("projectile.velocity_mps=1:2").find("start:stop:step"), std::string::npos);
  EXPECT_NE(message("projectile.velocity_mps=100,-3").find("value '-3'"), std::string::npos);
  EXPECT_NE(message("solver.model=sliding,banana").find("value 'banana'"), std::string::npos);
  EXPECT_NE(message("yarn.friction").find("expected key="), std::string::npos);
  EXPECT_THROW(parse_shard("0/4"), StudyError);
  EXPECT_THROW(parse_shard("5/4"), StudyError);
  EXPECT_THROW(parse_shard("1-4"), StudyError);
}

TEST(Sweep, CasesAreTheCartesianProductLastKeyFastest) {
  const auto cases = expand_cases({{"a.x", {"1", "2", "3"}}, {"b.y", {"p", "q"}}});
  ASSERT_EQ(cases.size(), 6u);
  EXPECT_EQ(cases[1].settings[0].second, "1");
  EXPECT_EQ(cases[1].settings[1].second, "q");
  std::set<std::string> names;
  for (size_t i = 0; i < cases.size(); ++i) {
    EXPECT_EQ(cases[i].index, int(i));
    names.insert(cases[i].name());
  }
  EXPECT_EQ(names.size(), cases.size());  // folder names are unique
}

// --repeats: each velocity N times, 1e-6 m/s apart, each repeat its own case; velocities closer
// than that are refused; the table counts each velocity's decided runs and their perforations.
TEST(Sweep, RepeatsRunEachVelocityNTimesAndCountPerforations) {
  std::map<std::string, std::string> base;
  const Vary r = repeat_velocities(parse_vary("projectile.velocity_mps=78,80"), 3, &base);
  EXPECT_EQ(r.values, (std::vector<std::string>{"78", "78.000001", "78.000002", "80", "80.000001", "80.000002"}));
  EXPECT_EQ(base.at("80.000002"), "80");
  EXPECT_EQ(expand_cases({r, {"yarn.friction", {"0.2"}}}).size(), 6u);  // a case each
  auto message = [](const Vary& v, int n) {
    try {
      repeat_velocities(v, n, nullptr);
    } catch (const StudyError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message({"projectile.velocity_mps", {"80", "80.000002"}}, 3).find("lie closer than 3 x 1e-6 m/s"),
            std::string::npos);
  EXPECT_EQ(message({"projectile.velocity_mps", {"80", "80.000002"}}, 2), "no error");
  EXPECT_NE(message(r, 0).find("--repeats 0"), std::string::npos);
  // results.csv rows: at 78 m/s one of three perforates; at 80 two perforate, one is still
  // creeping at its end time (undecided: not in the probability) and one diverged.
  Csv csv = parse_csv(
      "case,projectile.velocity_mps,status,end_reason,perforated,residual_velocity_mps,energy_absorbed_J\n"
      "a,78,completed,rebounded,false,0,20\n"
      "b,78.000001,completed,perforated,true,4,19\n"
      "c,78.000002,completed,caught,false,0,21\n"
      "d,80,completed,perforated,true,10,22\n"
      "e,80.000001,completed,end_time,false,1,22\n"
      "f,80.000002,diverged,,false,,\n"
      "g,80.000003,completed,perforated,true,14,20\n");
  base["80.000003"] = "80";
  const auto t = perforation_table(csv, {"projectile.velocity_mps"}, base);
  EXPECT_EQ(t.groups, 2);
  const Csv out = parse_csv(t.csv);
  ASSERT_EQ(out.rows.size(), 2u);
  EXPECT_EQ(out.cell(out.rows[0], "projectile.velocity_mps"), "78");
  EXPECT_EQ(out.cell(out.rows[0], "runs"), "3");
  EXPECT_EQ(out.cell(out.rows[0], "perforated"), "1");
  EXPECT_EQ(out.cell(out.rows[0], "perforation_probability"), "0.333333");
  EXPECT_EQ(out.cell(out.rows[0], "residual_velocity_mps"), "4");
  EXPECT_EQ(out.cell(out.rows[0], "energy_absorbed_J"), "20");
  EXPECT_EQ(out.cell(out.rows[1], "runs"), "4");
  EXPECT_EQ(out.cell(out.rows[1], "decided"), "2");
  EXPECT_EQ(out.cell(out.rows[1], "perforation_probability"), "1");
  EXPECT_EQ(out.cell(out.rows[1], "undecided"), "1");
  EXPECT_EQ(out.cell(out.rows[1], "diverged"), "1");
  EXPECT_EQ(out.cell(out.rows[1], "residual_velocity_mps"), "12");
  ASSERT_EQ(t.chart.series.size(), 1u);
  EXPECT_EQ(t.chart.series[0].x, (std::vector<double>{78, 80}));
  EXPECT_NEAR(t.chart.series[0].y[0], 1.0 / 3, 1e-12);
}

// With two varied keys (friction put first, as --chart-x yarn.friction does) the table
// groups by both, each velocity at its base, and the chart has a series per velocity.
TEST(Sweep, RepeatsTableGroupsByEveryKeyWhicheverComesFirst) {
  std::map<std::string, std::string> base;
  repeat_velocities(parse_vary("projectile.velocity_mps=80,90"), 2, &base);
  const Csv csv = parse_csv(
      "case,projectile.velocity_mps,yarn.friction,status,end_reason,perforated,residual_velocity_mps\n"
      "a,80,0.2,completed,rebounded,false,0\n"
      "b,80.000001,0.2,completed,perforated,true,5\n"
      "c,80,1,completed,perforated,true,30\n"
      "d,80.000001,1,completed,perforated,true,20\n"
      "e,90,0.2,completed,perforated,true,15\n"
      "f,90.000001,0.2,completed,perforated,true,17\n");
  const auto t = perforation_table(csv, {"yarn.friction", "projectile.velocity_mps"}, base);
  EXPECT_EQ(t.groups, 3);
  const Csv out = parse_csv(t.csv);
  ASSERT_EQ(out.rows.size(), 3u);
  EXPECT_EQ(out.header[0], "yarn.friction");
  EXPECT_EQ(out.cell(out.rows[0], "projectile.velocity_mps"), "80");
  EXPECT_EQ(out.cell(out.rows[0], "perforation_probability"), "0.5");
  EXPECT_EQ(out.cell(out.rows[1], "yarn.friction"), "1");
  EXPECT_EQ(out.cell(out.rows[1], "residual_velocity_mps"), "25");
  EXPECT_EQ(out.cell(out.rows[2], "projectile.velocity_mps"), "90");
  ASSERT_EQ(t.chart.series.size(), 2u);  // one per velocity, x = friction
  EXPECT_EQ(t.chart.series[0].name, "projectile.velocity_mps = 80");
  EXPECT_EQ(t.chart.series[0].x, (std::vector<double>{0.2, 1.0}));
  EXPECT_EQ(t.chart.series[0].y, (std::vector<double>{0.5, 1.0}));
}

TEST(Sweep, ShardsPartitionTheCasesExactlyOnce) {
  const auto all = expand_cases({{"a.x", {"1", "2", "3", "4", "5", "6", "7"}}, {"b.y", {"p", "q", "r"}}});
  for (int n = 1; n <= 25; ++n) {
    std::vector<int> seen(all.size(), 0);
    size_t biggest = 0, smallest = all.size();
    for (int i = 1; i <= n; ++i) {
      const auto part = shard_cases(all, parse_shard(std::to_string(i) + "/" + std::to_string(n)));
      biggest = std::max(biggest, part.size());
      smallest = std::min(smallest, part.size());
      for (const auto& c : part) ++seen[size_t(c.index)];
    }
    for (size_t k = 0; k < all.size(); ++k) EXPECT_EQ(seen[k], 1) << "case " << k << " with " << n << " shards";
    EXPECT_LE(biggest - smallest, 1u) << n << " shards are balanced to one case";
  }
}

// results.csv has one row per finished case and its numbers are the case's summary.json.
void expect_results_match_summaries(const std::string& dir, const std::vector<Case>& cases) {
  const Csv csv = parse_csv(read_text_file(dir + "/results.csv"));
  ASSERT_GE(csv.column("projectile.velocity_mps"), 0);
  ASSERT_GE(csv.column("yarn.friction"), 0);
  for (const char* k :
       {"perforated", "residual_velocity_mps", "energy_absorbed_J", "perforation_time_s", "wall_time_s"})
    ASSERT_GE(csv.column(k), 0) << k;
  int finished = 0;
  for (const auto& c : cases) finished += case_finished(dir, c);
  ASSERT_EQ(int(csv.rows.size()), finished);
  for (const auto& row : csv.rows) {
    const std::string name = row[size_t(csv.column("case"))];
    const auto j = nlohmann::json::parse(read_text_file(dir + "/" + name + "/summary.json"));
    EXPECT_EQ(row[size_t(csv.column("perforated"))], j["perforated"].get<bool>() ? "true" : "false");
    EXPECT_NEAR(std::stod(row[size_t(csv.column("energy_absorbed_J"))]), j["energy_absorbed_J"].get<double>(),
                1e-8 * std::abs(j["energy_absorbed_J"].get<double>()));
    EXPECT_NEAR(std::stod(row[size_t(csv.column("residual_velocity_mps"))]), j["residual_velocity_mps"].get<double>(),
                1e-8 * std::abs(j["residual_velocity_mps"].get<double>()) + 1e-12);
    EXPECT_NEAR(std::stod(row[size_t(csv.column("projectile.velocity_mps"))]), j["impact_velocity_mps"].get<double>(),
                1e-9);
    EXPECT_NEAR(std::stod(row[size_t(csv.column("yarn.friction"))]), j["yarn_friction"].get<double>(), 1e-12);
  }
}

TEST(Sweep, RunsEveryCaseIntoItsOwnFolderAndResultsMatchSummaries) {
  const std::string dir = scratch_dir();
  const auto cases = cheap_cases();
  const auto rep = run_sweep(cases, cases, cheap_options(dir), kKeys);
  EXPECT_EQ(rep.cases_run, int(cases.size()));
  EXPECT_EQ(rep.cases_failed, 0);
  for (const auto& c : cases) {
    EXPECT_TRUE(case_finished(dir, c)) << c.name();
    for (const char* f : {"history.csv", "scene.toml", "case.json"})
      EXPECT_TRUE(fs::exists(case_dir(dir, c) + "/" + f)) << c.name() << "/" << f;
  }
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_NE(e.path().filename().string().rfind(".tmp-", 0), 0u) << "temporary left: " << e.path();
  expect_results_match_summaries(dir, cases);
  EXPECT_TRUE(fs::exists(dir + "/sweep.json"));
}

TEST(Sweep, RerunResumesAndSkipsFinishedCases) {
  const std::string dir = scratch_dir();
  const auto cases = cheap_cases();
  run_sweep(cases, cases, cheap_options(dir), kKeys);
  const std::string kept = read_text_file(case_dir(dir, cases[0]) + "/summary.json");
  fs::remove_all(case_dir(dir, cases[3]));
  const auto rep = run_sweep(cases, cases, cheap_options(dir), kKeys);
  EXPECT_EQ(rep.cases_run, 1);
  EXPECT_EQ(rep.cases_skipped, int(cases.size()) - 1);
  EXPECT_TRUE(case_finished(dir, cases[3]));
  EXPECT_EQ(read_text_file(case_dir(dir, cases[0]) + "/summary.json"), kept) << "a finished case was rewritten";
  // A longer --vary list reuses the cases it shares with the first sweep.
  auto more = expand_cases({parse_vary("projectile.velocity_mps=60:240:60", "", cheap_scene()),
                            parse_vary("yarn.friction=0.1,0.3", "", cheap_scene())});
  const auto rep2 = run_sweep(more, more, cheap_options(dir), kKeys);
  EXPECT_EQ(rep2.cases_run, 2);
  EXPECT_EQ(rep2.cases_skipped, int(cases.size()));
  expect_results_match_summaries(dir, more);
}

TEST(Sweep, RefusesToMixCasesOfAnotherBaseScene) {
  const std::string dir = scratch_dir();
  const auto cases = cheap_cases();
  run_sweep(cases, {cases[0]}, cheap_options(dir), kKeys);
  auto other = cheap_options(dir);
  other.overrides.push_back("yarn.failure_strain=0.057");
  try {
    run_sweep(cases, cases, other, kKeys);
    ADD_FAILURE() << "mixed two sweeps in one folder";
  } catch (const StudyError& e) {
    EXPECT_NE(std::string(e.what()).find("different sweep"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(case_finished(dir, cases[1]));
}

TEST(Sweep, CaseFoldersAppearWholeOrNotAtAll) {
  const std::string dir = scratch_dir();
  const auto cases = cheap_cases();
  fs::create_directories(dir);
  // What a killed run leaves: a half-written temporary of a dead process, and a case
  // folder without summary.json (e.g. copied by hand). Neither counts as finished.
  const std::string stale = dir + "/.tmp-" + cases[0].name() + "-" + [] {
    char h[256] = {0};
    gethostname(h, sizeof h - 1);
    std::string s(h);
    for (char& c : s)
      if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    return s;
  }() + "-2147483000-0";
  fs::create_directories(stale);
  write_file_atomic(stale + "/history.csv", "t_s\n0\n");
  fs::create_directories(case_dir(dir, cases[1]));
  write_file_atomic(case_dir(dir, cases[1]) + "/history.csv", "partial");
  EXPECT_FALSE(case_finished(dir, cases[0]));
  EXPECT_FALSE(case_finished(dir, cases[1]));
  EXPECT_EQ(parse_csv(results_csv(dir, cases, kKeys)).rows.size(), 0u);

  // A case whose outputs fail mid-way leaves nothing behind.
  SweepHooks hooks;
  hooks.on_simulation = [&](const Case& c, const Simulation&, const std::string& tmp) {
    EXPECT_TRUE(fs::exists(tmp + "/case.json"));
    if (c.index != 1) {  // case 1's incomplete folder was planted above
      EXPECT_FALSE(fs::exists(case_dir(dir, c))) << "the final folder exists before the case is complete";
    }
    if (c.index == 2) throw OutputError("disk full (simulated)");
  };
  const auto rep = run_sweep(cases, cases, cheap_options(dir), kKeys, hooks);
  EXPECT_EQ(rep.cases_failed, 1);
  EXPECT_FALSE(fs::exists(case_dir(dir, cases[2])));
  EXPECT_FALSE(fs::exists(stale)) << "the dead process's temporary was not cleaned up";
  EXPECT_TRUE(case_finished(dir, cases[1])) << "the incomplete folder was not redone";
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_NE(e.path().filename().string().rfind(".tmp-", 0), 0u) << "temporary left: " << e.path();
  expect_results_match_summaries(dir, cases);
}

TEST(Sweep, ResultsDoNotDependOnJobs) {
  const std::string dir = scratch_dir();
  const auto cases = cheap_cases();
  run_sweep(cases, cases, cheap_options(dir + "/one", 1), kKeys);
  run_sweep(cases, cases, cheap_options(dir + "/two", 2), kKeys);
  for (const auto& c : cases) {
    auto a = nlohmann::json::parse(read_text_file(case_dir(dir + "/one", c) + "/summary.json"));
    auto b = nlohmann::json::parse(read_text_file(case_dir(dir + "/two", c) + "/summary.json"));
    for (auto* j : {&a, &b}) j->erase("wall_time_s"), j->erase("node_steps_per_s");
    EXPECT_EQ(a, b) << c.name();
    EXPECT_EQ(read_text_file(case_dir(dir + "/one", c) + "/history.csv"),
              read_text_file(case_dir(dir + "/two", c) + "/history.csv"));
  }
}

TEST(Sweep, ShardsTogetherFinishTheSweep) {
  const std::string dir = scratch_dir();
  const auto cases = cheap_cases();
  int run = 0;
  for (int i = 1; i <= 3; ++i) {
    auto o = cheap_options(dir, 1);
    o.shard = parse_shard(std::to_string(i) + "/3");
    run += run_sweep(cases, shard_cases(cases, o.shard), o, kKeys).cases_run;
  }
  EXPECT_EQ(run, int(cases.size()));
  expect_results_match_summaries(dir, cases);
  EXPECT_EQ(parse_csv(read_text_file(dir + "/results.csv")).rows.size(), cases.size());
  EXPECT_TRUE(fs::exists(dir + "/sweep_shard3of3.json"));
}

}  // namespace
}  // namespace ravel::studies
