#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "limit.h"
#include "study_test_util.h"

namespace ravel::studies {
namespace {

// A target with a known limit and Lambert-Jonas residual law: perforated iff V >= vbl.
ShootFn synthetic_target(double a, double p, double vbl, int* calls = nullptr) {
  return [=](double v, const std::string&) {
    if (calls) ++*calls;
    Shot s;
    s.perforated = v >= vbl;
    s.residual_velocity_mps = s.perforated ? a * std::pow(std::pow(v, p) - std::pow(vbl, p), 1 / p) : 0;
    s.end_reason = s.perforated ? "perforated" : "rebounded";
    return s;
  };
}

TEST(BallisticLimit, BracketsAndBisectsToTheTolerance) {
  for (double vbl : {12.3, 70.4, 71.0, 99.99, 100.0, 433.3}) {
    for (double tol : {1.0, 0.25}) {
      int calls = 0;
      LimitOptions o;
      o.tolerance_mps = tol;
      const auto r = find_ballistic_limit(synthetic_target(0.9, 2.0, vbl, &calls), o, false);
      ASSERT_TRUE(r.bracketed) << vbl;
      EXPECT_TRUE(r.converged);
      EXPECT_LE(r.hi_mps - r.lo_mps, tol);
      EXPECT_LT(r.lo_mps, vbl) << "lo must not perforate";
      EXPECT_GE(r.hi_mps, vbl) << "hi must perforate";
      EXPECT_NEAR(r.ballistic_limit_mps, vbl, tol / 2 + 1e-12);
      EXPECT_EQ(calls, int(r.runs.size()));
      // Bisection halves the bracket each run: from a bracket of width w it needs
      // ceil(log2(w / tol)) runs; the growth walk from 100 m/s adds a few.
      EXPECT_LE(int(r.runs.size()), 8 + int(std::ceil(std::log2(100.0 / tol))));
      EXPECT_TRUE(r.warnings.empty());
      for (const auto& s : r.runs) EXPECT_EQ(s.perforated, s.velocity_mps >= vbl);
    }
  }
}

// `ravel limit`'s progress line: once bracketed, "of about N" counts the bisections that
// halve the bracket below the tolerance and the fit runs still to make. On a sharp
// threshold bisection halves the bracket exactly, so the estimate made after the first
// bracketing run is the search's final length, and stays so to the end.
TEST(BallisticLimit, ProgressLineCountsTheRunsStillToMake) {
  for (double vbl : {12.3, 70.4, 433.3}) {
    for (bool with_fit : {false, true}) {
      SCOPED_TRACE("vbl " + std::to_string(vbl) + (with_fit ? " with fit" : ""));
      LimitOptions o;
      std::vector<Shot> made;
      std::vector<std::string> lines;
      const auto target = synthetic_target(0.9, 2.0, vbl);
      auto shoot = [&](double v, const std::string& why) {
        Shot s = target(v, why);
        s.velocity_mps = v;
        s.purpose = why;
        s.wall_time_s = 30;
        made.push_back(s);
        lines.push_back(limit_progress(made, o, with_fit));
        return s;
      };
      const auto r = find_ballistic_limit(shoot, o, with_fit);
      ASSERT_TRUE(r.converged);
      const int n = int(r.runs.size());
      bool bracketed = false;
      for (int k = 1; k <= n; ++k) {
        const std::string& line = lines[size_t(k - 1)];
        if (line.find("bracketing") != std::string::npos) {
          EXPECT_FALSE(bracketed) << line;  // once bracketed, it stays so
          EXPECT_EQ(line.rfind("run " + std::to_string(k) + ", bracketing (", 0), 0u) << line;
          continue;
        }
        bracketed = true;
        if (k == n) {
          EXPECT_EQ(line.rfind("run " + std::to_string(n) + " of " + std::to_string(n) + ",", 0), 0u) << line;
        } else {
          EXPECT_EQ(line.rfind("run " + std::to_string(k) + " of about " + std::to_string(n) + ",", 0), 0u) << line;
          // 30 s per run: (n - k) runs left.
          const double left = 30.0 * (n - k);
          char want[64];
          if (left < 120)
            std::snprintf(want, sizeof want, "~%.0f s left", left);
          else
            std::snprintf(want, sizeof want, "~%.1f min left", left / 60);
          EXPECT_NE(line.find(want), std::string::npos) << line << " wants " << want;
        }
      }
      EXPECT_TRUE(bracketed);
    }
  }
}

TEST(BallisticLimit, ReportsNoBracketAndFailedRuns) {
  LimitOptions o;
  o.max_mps = 500;
  const auto none = find_ballistic_limit(synthetic_target(1, 2, 5000), o, false);
  EXPECT_FALSE(none.bracketed);
  EXPECT_FALSE(none.warnings.empty());
  // A run that diverges stops the search; nothing after it is trusted.
  auto diverging = [](double v, const std::string&) {
    Shot s;
    s.perforated = v >= 70;
    s.failed = v < 80 && v > 60;
    s.error = "diverged";
    return s;
  };
  const auto r = find_ballistic_limit(diverging, o, true);
  EXPECT_FALSE(r.converged);
  ASSERT_FALSE(r.runs.empty());
  EXPECT_TRUE(r.runs.back().failed);
  EXPECT_FALSE(r.warnings.empty());
}

// Growing steps overshoot a bound quickly: the search fires once at the bound before it
// gives up, so a limit between the last step and the bound is still bracketed.
TEST(BallisticLimit, GrowingStepsFireAtTheBoundBeforeGivingUp) {
  LimitOptions o;
  o.start_mps = 100;
  o.growth = 1.25;
  o.growth_accel = 1.5;  // 100, 125, 175, 288, then 611: past the bound
  o.max_mps = 500;
  o.tolerance_mps = 1;
  const auto r = find_ballistic_limit(synthetic_target(0.9, 2.0, 480), o, false);
  ASSERT_TRUE(r.bracketed);
  EXPECT_NEAR(r.ballistic_limit_mps, 480, 0.5 + 1e-12);
  bool at_bound = false;
  for (const auto& s : r.runs) at_bound |= s.velocity_mps == 500;
  EXPECT_TRUE(at_bound);
  // With the limit beyond the bound, the last run is at the bound, and there is no bracket.
  const auto none = find_ballistic_limit(synthetic_target(0.9, 2.0, 520), o, false);
  EXPECT_FALSE(none.bracketed);
  ASSERT_FALSE(none.runs.empty());
  EXPECT_EQ(none.runs.back().velocity_mps, 500);
  EXPECT_EQ(none.runs.size(), 5u);
}

// Runs that end neither perforated nor stopped (undecided) never count as stopped: they are
// left out of the bracket, and the bisection goes on beside them. Here every run within
// 3 m/s below the true limit is undecided: the bracket's ends are decided runs, so the limit
// is found within the tolerance plus that band, and a warning names each undecided run.
TEST(BallisticLimit, UndecidedRunsAreLeftOutOfTheBracket) {
  const double vbl = 70.4, band = 3;
  int undecided = 0;
  auto target = [&](double v, const std::string&) {
    Shot s;
    s.perforated = v >= vbl;
    s.decided = s.perforated || v < vbl - band;
    s.end_reason = s.perforated ? "perforated" : s.decided ? "rebounded" : "end_time";
    s.residual_velocity_mps = s.perforated ? 0.9 * std::sqrt(v * v - vbl * vbl) : 0;
    undecided += !s.decided;
    return s;
  };
  LimitOptions o;
  o.tolerance_mps = 1;
  const auto r = find_ballistic_limit(target, o, false);
  ASSERT_TRUE(r.bracketed);
  EXPECT_LT(r.lo_mps, vbl - band) << "an undecided run was counted as stopped";
  EXPECT_GE(r.hi_mps, vbl);
  for (const auto& s : r.runs) {
    if (!s.decided && !s.perforated) {
      EXPECT_TRUE(s.velocity_mps > r.lo_mps && s.velocity_mps < r.hi_mps);
    }
  }
  EXPECT_LE(r.hi_mps - r.lo_mps, band + o.tolerance_mps);
  ASSERT_GT(undecided, 0);
  int warned = 0;
  for (const auto& w : r.warnings) warned += w.find("undecided") != std::string::npos;
  EXPECT_GE(warned, undecided);
}

TEST(LambertJonas, RecoversKnownParametersFromSyntheticPoints) {
  struct Law {
    double a, p, vbl;
  };
  for (const Law law : {Law{0.9, 2.0, 70.0}, Law{0.75, 2.6, 120.0}, Law{1.0, 1.5, 35.0}}) {
    std::vector<double> v, vr;
    for (double f : {1.05, 1.2, 1.5, 2.0, 3.0, 4.0}) {
      v.push_back(law.vbl * f);
      vr.push_back(law.a * std::pow(std::pow(v.back(), law.p) - std::pow(law.vbl, law.p), 1 / law.p));
    }
    const auto fit = fit_lambert_jonas(v, vr);
    ASSERT_TRUE(fit.ok) << fit.note;
    // Exact data: the least-squares optimum is the law itself; the tolerance is the
    // simplex's convergence, far tighter than any measured scatter.
    EXPECT_NEAR(fit.a, law.a, 1e-3 * law.a);
    EXPECT_NEAR(fit.p, law.p, 1e-2 * law.p);
    EXPECT_NEAR(fit.vbl_mps, law.vbl, 1e-3 * law.vbl);
    EXPECT_LT(fit.rms_mps, 1e-3);
  }
}

TEST(LambertJonas, NoisyPointsStayCloseAndTooFewPointsAreRefused) {
  // +-1 m/s scatter (about what a 1 m/s bisection tolerance implies) moves Vbl by a few m/s.
  const double a = 0.85, p = 2.2, vbl = 70;
  std::vector<double> v, vr;
  int k = 0;
  for (double f : {1.1, 1.3, 1.6, 2.0, 2.5, 3.0, 4.0}) {
    v.push_back(vbl * f);
    vr.push_back(a * std::pow(std::pow(v.back(), p) - std::pow(vbl, p), 1 / p) + ((k++ % 2) ? 1.0 : -1.0));
  }
  const auto fit = fit_lambert_jonas(v, vr);
  ASSERT_TRUE(fit.ok);
  EXPECT_NEAR(fit.vbl_mps, vbl, 5.0);
  EXPECT_LT(fit.rms_mps, 1.1);
  EXPECT_FALSE(fit_lambert_jonas({100, 200}, {50, 150}).ok);
}

TEST(BallisticLimit, SearchWithTheFitRecoversTheSyntheticLaw) {
  LimitOptions o;
  o.tolerance_mps = 0.5;
  const auto r = find_ballistic_limit(synthetic_target(0.8, 2.4, 73.3), o, true);
  ASSERT_TRUE(r.fit.ok) << r.fit.note;
  EXPECT_NEAR(r.fit.vbl_mps, 73.3, 0.5);
  EXPECT_NEAR(r.fit.a, 0.8, 0.01);
}

// A fit run that stops above the bracket is reported: the outcome is then no threshold in
// velocity (the pin-jointed default scene stopped at 133 m/s after perforating at 107-125).
TEST(BallisticLimit, AStoppedFitRunAboveTheBracketIsReported) {
  const ShootFn law = synthetic_target(0.9, 2.0, 70.0);
  const ShootFn island = [&](double v, const std::string& why) {
    Shot s = law(v, why);
    if (v > 85 && v < 90) s = Shot{}, s.end_reason = "rebounded";  // 70 x 1.25 = 87.5 lands here
    return s;
  };
  LimitOptions o;
  o.tolerance_mps = 0.5;
  const auto r = find_ballistic_limit(island, o, true);
  EXPECT_NEAR(r.ballistic_limit_mps, 70.0, 0.25);
  bool reported = false;
  for (const auto& w : r.warnings) reported |= w.find("non-monotone outcome: 87.") != std::string::npos;
  EXPECT_TRUE(reported) << "no warning for the stopped fit run";
  // limit.json says the outcomes are no threshold, and where they alternate.
  const auto band = outcome_band(r);
  EXPECT_FALSE(band.threshold);
  EXPECT_EQ(band.against, 1);
  EXPECT_DOUBLE_EQ(band.lowest_perforation, r.hi_mps);
  EXPECT_GT(band.highest_stop, 85.0);
  EXPECT_LT(band.highest_stop, 90.0);
  const auto j = nlohmann::json::parse(limit_json(r, o, "s", {}));
  EXPECT_EQ(j["threshold"], false);
  EXPECT_EQ(j["runs_against_threshold"], 1);
  EXPECT_NE(j["threshold_note"].get<std::string>().find("alternate"), std::string::npos);
  // Without it the same search is clean.
  EXPECT_TRUE(find_ballistic_limit(law, o, true).warnings.empty());
}

// The V50 of ballistic testing (MIL-STD-662F) in limit.json: the mean of the three highest
// stops and the three lowest perforations among the decided runs; cancelled, failed and
// undecided runs are no outcome. Runs by hand: stops 40, 45, 47, 49 and perforations 48, 50,
// 55, 60 (one alternation, 48 P below 49 S), plus a cancelled 48.5, an undecided 46 and a
// failed 44: V50 = (49 + 47 + 45 + 48 + 50 + 55) / 6 = 49, spread 55 - 45 = 10.
TEST(BallisticLimit, V50IsTheMeanOfTheHighestStopsAndLowestPerforations) {
  LimitResult r;
  auto shot = [&](double v, bool perf) {
    Shot s;
    s.velocity_mps = v;
    s.perforated = perf;
    s.end_reason = perf ? "perforated" : "rebounded";
    r.runs.push_back(s);
    return &r.runs.back();
  };
  for (double v : {40, 45, 47, 49}) shot(v, false);
  for (double v : {48, 50, 55, 60}) shot(v, true);
  shot(48.5, false)->cancelled = true;
  shot(46, false)->decided = false;
  shot(44, true)->failed = true;
  r.bracketed = true, r.lo_mps = 47, r.hi_mps = 48;
  OutcomeBand b = outcome_band(r);
  EXPECT_EQ(b.v50_pairs, 3);
  EXPECT_DOUBLE_EQ(b.v50, 49.0);
  EXPECT_DOUBLE_EQ(b.v50_spread, 10.0);
  EXPECT_FALSE(b.threshold);  // 48 perforated below the stop at 49
  const auto j = nlohmann::json::parse(limit_json(r, LimitOptions{}, "s", {}));
  EXPECT_DOUBLE_EQ(j["v50_mps"].get<double>(), 49.0);
  EXPECT_EQ(j["v50_pairs"], 3);
  EXPECT_DOUBLE_EQ(j["v50_spread_mps"].get<double>(), 10.0);
  EXPECT_NE(j["v50_note"].get<std::string>().find("MIL-STD-662F"), std::string::npos);
  // Fewer runs on one side: as many pairs as that side has (one stop: 49 and 48).
  r.runs.erase(r.runs.begin(), r.runs.begin() + 3);
  b = outcome_band(r);
  EXPECT_EQ(b.v50_pairs, 1);
  EXPECT_DOUBLE_EQ(b.v50, 48.5);
  EXPECT_DOUBLE_EQ(b.v50_spread, 1.0);
  // No stop at all: no V50, null in limit.json.
  r.runs.erase(r.runs.begin());
  b = outcome_band(r);
  EXPECT_EQ(b.v50_pairs, 0);
  EXPECT_LT(b.v50, 0);
  const auto none = nlohmann::json::parse(limit_json(r, LimitOptions{}, "s", {}));
  EXPECT_TRUE(none["v50_mps"].is_null());
  EXPECT_TRUE(none["v50_spread_mps"].is_null());
}

// The real thing on the cheap scene: the bracket's ends are runs that did (not) perforate,
// and the search stops at the tolerance.
TEST(BallisticLimit, CheapSceneBracketsAndConverges) {
  LimitOptions o;
  o.start_mps = 50;
  o.tolerance_mps = 1.0;
  const auto r = find_ballistic_limit(scene_shooter("", testing::cheap_scene()), o, false);
  for (const auto& w : r.warnings) ADD_FAILURE() << w;
  ASSERT_TRUE(r.bracketed);
  ASSERT_TRUE(r.converged);
  EXPECT_LE(r.hi_mps - r.lo_mps, 1.0);
  bool saw_lo = false, saw_hi = false;
  for (const auto& s : r.runs) {
    EXPECT_TRUE(s.decided) << s.velocity_mps << " m/s ended " << s.end_reason;
    if (s.velocity_mps == r.lo_mps) saw_lo = !s.perforated;
    if (s.velocity_mps == r.hi_mps) saw_hi = s.perforated;
  }
  EXPECT_TRUE(saw_lo && saw_hi);
  EXPECT_GT(r.ballistic_limit_mps, r.lo_mps);
  EXPECT_LT(r.ballistic_limit_mps, r.hi_mps);
}

// A scene whose runs near the limit outlast its end time: the shooter continues each
// undecided run to solver.max_end_time_us, so no undecided run is counted as stopped, and the
// search finds the same limit as one that gave its runs the long end time from the start (the
// same runs, continued: bit for bit).
TEST(BallisticLimit, RunsThatOutlastTheEndTimeAreExtended) {
  LimitOptions o;
  o.start_mps = 50;
  o.tolerance_mps = 2.0;
  auto scene = testing::cheap_scene();
  auto short_end = scene, long_end = scene;
  short_end.push_back("solver.end_time_us=60");  // far shorter than the near-limit runs
  short_end.push_back("solver.max_end_time_us=1500");
  const auto a = find_ballistic_limit(scene_shooter("", short_end), o, false);
  const auto b = find_ballistic_limit(scene_shooter("", long_end), o, false);
  ASSERT_TRUE(a.bracketed && b.bracketed);
  for (const auto& s : a.runs) EXPECT_TRUE(s.decided) << s.velocity_mps << " m/s ended " << s.end_reason;
  EXPECT_EQ(a.ballistic_limit_mps, b.ballistic_limit_mps);
  ASSERT_EQ(a.runs.size(), b.runs.size());
  for (size_t i = 0; i < a.runs.size(); ++i)
    EXPECT_EQ(a.runs[i].residual_velocity_mps, b.runs[i].residual_velocity_mps);
}

// limit.json says how the answer was found and how far off it may be: the reference's
// method, rules (none), jobs (1), rounds (its run count) and an error of half the bracket;
// the new keys read back, and every key of before is still written.
TEST(BallisticLimit, LimitJsonStatesMethodAndErrorEstimate) {
  LimitOptions o;
  const auto r = find_ballistic_limit(synthetic_target(0.9, 2.0, 70.4), o, true);
  ASSERT_TRUE(r.converged);
  EXPECT_EQ(r.method, "reference");
  EXPECT_TRUE(r.rules.empty());
  EXPECT_EQ(r.rounds, int(r.runs.size()));
  EXPECT_DOUBLE_EQ(r.error_mps, 0.5 * (r.hi_mps - r.lo_mps));
  EXPECT_LE(std::abs(r.ballistic_limit_mps - 70.4), r.error_mps + 1e-12);
  const std::string text = limit_json(r, o, "scene.toml", {"a=1"});
  const auto j = nlohmann::json::parse(text);
  // clang-format off
  for (const char* key : {"ballistic_limit_mps", "bracket_mps", "bracket_note", "tolerance_mps", "bracketed",
                          "converged", "lambert_jonas", "runs", "warnings", "interrupted", "scene", "overrides",
                          "start_mps", "growth", "growth_accel", "wall_time_s", "runs_per_hour", "method",
                          "method_note", "rules", "jobs", "rounds", "runs_finished", "runs_cancelled",
                          "skipped_full_runs", "error_mps", "error_note"})
    // clang-format on
    EXPECT_TRUE(j.contains(key)) << key;
  for (const char* key :
       {"lowest_perforation_mps", "highest_stop_mps", "threshold", "runs_against_threshold", "threshold_note"})
    EXPECT_TRUE(j.contains(key)) << key;
  // A threshold target: the bracket's ends are the lowest perforation and the highest stop.
  EXPECT_EQ(j["threshold"], true);
  EXPECT_EQ(j["runs_against_threshold"], 0);
  EXPECT_DOUBLE_EQ(j["lowest_perforation_mps"].get<double>(), r.hi_mps);
  EXPECT_DOUBLE_EQ(j["highest_stop_mps"].get<double>(), r.lo_mps);
  EXPECT_EQ(j["method"], "reference");
  EXPECT_EQ(j["skipped_full_runs"], false);
  EXPECT_EQ(j["runs_finished"], int(r.runs.size()));
  const auto back = limit_from_json(text);
  EXPECT_EQ(back.method, "reference");
  EXPECT_DOUBLE_EQ(back.error_mps, r.error_mps);
  EXPECT_EQ(back.rounds, r.rounds);
  // A cancelled run round-trips as cancelled.
  Shot c;
  c.velocity_mps = 90;
  c.cancelled = true;
  c.decided = false;
  c.cancel_reason = "moot";
  LimitResult withc = r;
  withc.runs.push_back(c);
  withc.runs_cancelled = 1;
  const auto j2 = nlohmann::json::parse(limit_json(withc, o, "s", {}));
  EXPECT_EQ(j2["skipped_full_runs"], true);
  EXPECT_TRUE(j2.contains("skipped_note"));
  EXPECT_EQ(j2["runs"].back()["cancelled"], true);
  EXPECT_TRUE(limit_from_json(j2.dump()).runs.back().cancelled);
  // A run decided as passing is a perforation not run to its end: said so, and round-trips.
  LimitResult withd = r;
  for (auto& s : withd.runs)
    if (s.perforated) {
      s.decided_passing = true;
      break;
    }
  const auto j3 = nlohmann::json::parse(limit_json(withd, o, "s", {}));
  EXPECT_EQ(j3["skipped_full_runs"], true);
  EXPECT_EQ(j3["runs_decided_passing"], 1);
  EXPECT_NE(j3["skipped_note"].get<std::string>().find("passing through"), std::string::npos);
  int back_decided = 0;
  for (const auto& s : limit_from_json(j3.dump()).runs) back_decided += s.decided_passing;
  EXPECT_EQ(back_decided, 1);
  // The broken yarns' grid lines round-trip; a file without them (written before they were
  // kept) reads as none.
  LimitResult withl = r;
  withl.runs.front().broken_weft_lines = {-2, 0, 2};
  withl.runs.front().broken_warp_lines = {0};
  const auto j4 = nlohmann::json::parse(limit_json(withl, o, "s", {}));
  const auto back4 = limit_from_json(j4.dump());
  EXPECT_EQ(back4.runs.front().broken_weft_lines, (std::vector<int>{-2, 0, 2}));
  EXPECT_EQ(back4.runs.front().broken_warp_lines, (std::vector<int>{0}));
  // ... and so do the friction split and where the first break was.
  withl.runs.front().friction_work_J = 18.5;
  withl.runs.front().friction_work_to_first_break_J = 0.41;
  withl.runs.front().first_break_distance_mm = 59.5;
  const auto back6 = limit_from_json(limit_json(withl, o, "s", {}));
  EXPECT_DOUBLE_EQ(back6.runs.front().friction_work_J, 18.5);
  EXPECT_DOUBLE_EQ(back6.runs.front().friction_work_to_first_break_J, 0.41);
  EXPECT_DOUBLE_EQ(back6.runs.front().first_break_distance_mm, 59.5);
  auto j5 = j4;
  j5["runs"][0].erase("broken_weft_lines");
  j5["runs"][0].erase("first_break_distance_mm");
  j5["runs"][0]["broken_warp_lines"] = "x";
  const auto back5 = limit_from_json(j5.dump());
  EXPECT_TRUE(back5.runs.front().broken_weft_lines.empty());
  EXPECT_TRUE(back5.runs.front().broken_warp_lines.empty());
  EXPECT_DOUBLE_EQ(back5.runs.front().first_break_distance_mm, -1);  // absent: not known
}

}  // namespace
}  // namespace ravel::studies
