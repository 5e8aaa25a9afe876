// The fast ballistic-limit search (studies/limit_fast.cpp): each rule on synthetic targets
// whose limit is known, against the reference search (find_ballistic_limit) at the same
// settings: the same answer within the tolerance, in fewer rounds (or less time). Most run
// on the virtual clock (simulate_fast_search: deterministic); a few on real threads, and
// one on the cheap scene.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <set>
#include <thread>

#include "limit.h"
#include "study_test_util.h"

namespace ravel::studies {
namespace {

// Perforated iff V >= vbl, residual velocity by Lambert-Jonas (a, p). Each run lasts
// `duration(v)` on the virtual clock (default 1 s).
ShootFn target(double a, double p, double vbl, std::function<double(double)> duration = {}) {
  return [=](double v, const std::string&) {
    Shot s;
    s.perforated = v >= vbl;
    s.residual_velocity_mps = s.perforated ? a * std::pow(std::pow(v, p) - std::pow(vbl, p), 1 / p) : 0;
    s.end_reason = s.perforated ? "perforated" : "rebounded";
    s.wall_time_s = duration ? duration(v) : 1.0;
    return s;
  };
}

// A run near the limit lasts longest (the projectile is caught or pushes through slowly).
std::function<double(double)> slow_near(double vbl) {
  return [vbl](double v) { return 1.0 + 4.0 * std::exp(-std::abs(v - vbl) / (0.1 * vbl)); };
}

struct Law {
  double a, p, vbl;
};
const std::vector<Law> kLaws{{0.9, 2.0, 12.3},   {0.9, 2.0, 70.4},  {0.75, 2.6, 77.9}, {1.0, 1.6, 99.99},
                             {0.85, 2.2, 100.0}, {0.8, 3.0, 433.3}, {0.95, 2.0, 61.0}};

LimitOptions only(bool ksection, bool cancel, bool guess, bool two_sided, bool reuse, int jobs) {
  LimitOptions o;
  o.jobs = jobs;
  o.rules.ksection = ksection;
  o.rules.cancel_moot = cancel;
  o.rules.residual_guess = guess;
  o.rules.two_sided_start = two_sided;
  o.rules.reuse_fit_points = reuse;
  o.rules.probe_below = false;
  o.rules.decisive_points = false;
  o.rules.decide_passing = false;  // a scene rule: the synthetic runner has no scene
  return o;
}

// The fast answer is a verified bracket within the tolerance, within tolerance / 2 of the
// true limit and within the tolerance of the reference's.
void expect_same_answer(const LimitResult& f, const LimitResult& ref, double vbl, double tol) {
  ASSERT_TRUE(f.bracketed);
  EXPECT_TRUE(f.converged);
  EXPECT_LE(f.hi_mps - f.lo_mps, tol);
  EXPECT_LT(f.lo_mps, vbl);
  EXPECT_GE(f.hi_mps, vbl);
  EXPECT_NEAR(f.ballistic_limit_mps, vbl, tol / 2 + 1e-9);
  EXPECT_NEAR(f.ballistic_limit_mps, ref.ballistic_limit_mps, tol + 1e-9);
  EXPECT_LE(std::abs(f.ballistic_limit_mps - vbl), f.error_mps + 1e-9);
  bool saw_lo = false, saw_hi = false;
  for (const auto& s : f.runs) {
    if (s.cancelled) {
      EXPECT_FALSE(s.decided);
      EXPECT_NE(s.velocity_mps, f.lo_mps);
      EXPECT_NE(s.velocity_mps, f.hi_mps);
      continue;
    }
    EXPECT_EQ(s.perforated, s.velocity_mps >= vbl) << s.velocity_mps;
    saw_lo |= s.velocity_mps == f.lo_mps && !s.perforated;
    saw_hi |= s.velocity_mps == f.hi_mps && s.perforated;
  }
  EXPECT_TRUE(saw_lo && saw_hi) << "the bracket's ends must be full runs";
  EXPECT_TRUE(f.warnings.empty()) << f.warnings.front();
  EXPECT_EQ(f.method, "fast");
}

// Rule ksection: two runs in flight, the bracket cut in thirds (then the part most likely
// to hold the limit split as a slot frees). Never more rounds than bisection, fewer in all,
// same answer. (With a uniform prior the two parts beside a run in flight can hold the same
// mass; the part split is then a tie, and at vbl 99.99 and 100, just under the start, the
// lower part taken costs the round the upper one would have saved: as many rounds as
// bisection there, since the searches run velocities to 1e-6 m/s, run_velocity.)
TEST(FastLimit, KsectionMatchesTheReferenceInFewerRounds) {
  int fast_rounds = 0, ref_rounds = 0;
  for (const Law& law : kLaws)
    for (double tol : {1.0, 0.25}) {
      SCOPED_TRACE("vbl " + std::to_string(law.vbl) + " tol " + std::to_string(tol));
      LimitOptions ro;
      ro.tolerance_mps = tol;
      const auto ref = find_ballistic_limit(target(law.a, law.p, law.vbl), ro, false);
      auto o = only(true, false, false, false, false, 2);
      o.tolerance_mps = tol;
      const auto f = simulate_fast_search(target(law.a, law.p, law.vbl), o, false);
      expect_same_answer(f, ref, law.vbl, tol);
      EXPECT_LE(f.rounds, ref.rounds);
      fast_rounds += f.rounds;
      ref_rounds += ref.rounds;
      EXPECT_EQ(f.runs_cancelled, 0);  // cancel_moot off: every run to its end
      EXPECT_EQ(f.rules, std::vector<std::string>{"ksection"});
    }
  EXPECT_LT(fast_rounds, 0.85 * ref_rounds);  // 112 against 140 (2026-12-07)
}

// Rule cancel_moot: a run a sibling made moot is stopped at once; the search ends sooner on
// the clock, with the same bracket, and every stopped run is listed as cancelled.
TEST(FastLimit, CancelMootStopsMootRunsAndEndsSooner) {
  double with_s = 0, without_s = 0;
  int cancelled = 0;
  for (const Law& law : kLaws) {
    SCOPED_TRACE("vbl " + std::to_string(law.vbl));
    const auto t = target(law.a, law.p, law.vbl, slow_near(law.vbl));
    const auto ref = find_ballistic_limit(t, LimitOptions{}, false);
    const auto a = simulate_fast_search(t, only(true, true, false, false, false, 2), false);
    const auto b = simulate_fast_search(t, only(true, false, false, false, false, 2), false);
    expect_same_answer(a, ref, law.vbl, 1.0);
    expect_same_answer(b, ref, law.vbl, 1.0);
    EXPECT_LE(a.wall_time_s, b.wall_time_s + 1e-9);
    with_s += a.wall_time_s;
    without_s += b.wall_time_s;
    cancelled += a.runs_cancelled;
    int listed = 0;
    for (const auto& s : a.runs) {
      listed += s.cancelled;
      if (s.cancelled) {
        EXPECT_EQ(s.cancel_reason.rfind("moot: ", 0), 0u) << s.cancel_reason;
      }
    }
    EXPECT_EQ(listed, a.runs_cancelled);
  }
  EXPECT_GT(cancelled, 0);
  EXPECT_LT(with_s, without_s);
}

// Rule residual_guess: Lambert-Jonas p = 2 through the residual velocities places the next
// points. One run at a time (jobs 1) it needs fewer runs than bisection, also for targets
// whose p is not 2; with two in flight (where the k-section already does most of the work) it
// costs at most a round more on any target.
TEST(FastLimit, ResidualGuessNeedsFewerRuns) {
  int guess_rounds = 0, plain_rounds = 0, guess_runs = 0, ref_runs = 0;
  for (const Law& law : kLaws)
    for (double tol : {1.0, 0.25}) {
      SCOPED_TRACE("vbl " + std::to_string(law.vbl) + " p " + std::to_string(law.p) + " tol " + std::to_string(tol));
      LimitOptions ro;
      ro.tolerance_mps = tol;
      const auto t = target(law.a, law.p, law.vbl);
      const auto ref = find_ballistic_limit(t, ro, false);
      auto one = only(false, true, true, false, false, 1);
      one.tolerance_mps = tol;
      const auto f1 = simulate_fast_search(t, one, false);
      expect_same_answer(f1, ref, law.vbl, tol);
      EXPECT_LE(f1.runs.size(), ref.runs.size());  // a run at the limit itself has Vr = 0: no guess
      guess_runs += int(f1.runs.size());
      ref_runs += int(ref.runs.size());
      auto two = only(true, true, true, false, false, 2), plain = only(true, true, false, false, false, 2);
      two.tolerance_mps = plain.tolerance_mps = tol;
      const auto f2 = simulate_fast_search(t, two, false);
      const auto p2 = simulate_fast_search(t, plain, false);
      expect_same_answer(f2, ref, law.vbl, tol);
      EXPECT_LE(f2.rounds, p2.rounds + 1);
      guess_rounds += f2.rounds;
      plain_rounds += p2.rounds;
    }
  EXPECT_LE(guess_rounds, plain_rounds + 3);
  EXPECT_LT(guess_runs, ref_runs * 0.85);
}

// Rule two_sided_start: the first round tries the start and one growth step below it: a
// limit below the start is bracketed a round sooner.
TEST(FastLimit, TwoSidedStartBracketsSooner) {
  for (const Law& law : {Law{0.9, 2.0, 70.4}, Law{0.75, 2.6, 77.9}, Law{0.9, 2.0, 85.0}}) {
    const auto t = target(law.a, law.p, law.vbl);
    const auto ref = find_ballistic_limit(t, LimitOptions{}, false);
    const auto on = simulate_fast_search(t, only(true, true, false, true, false, 2), false);
    const auto off = simulate_fast_search(t, only(true, true, false, false, false, 2), false);
    expect_same_answer(on, ref, law.vbl, 1.0);
    EXPECT_LT(on.rounds, off.rounds) << law.vbl;
  }
}

// Rule reuse_fit_points: the perforating runs the search made stand for fit runs near them,
// so fewer fit runs are added than the reference's four; the fit still recovers the law.
TEST(FastLimit, FitRunsOnlyWhereTheFitLacksAPoint) {
  for (const Law& law : {Law{0.9, 2.0, 70.4}, Law{0.8, 2.4, 73.3}, Law{0.75, 2.6, 77.9}}) {
    SCOPED_TRACE("vbl " + std::to_string(law.vbl));
    LimitOptions ro;
    ro.tolerance_mps = 0.5;
    const auto t = target(law.a, law.p, law.vbl);
    const auto ref = find_ballistic_limit(t, ro, true);
    auto o = only(true, true, true, true, true, 2);
    o.tolerance_mps = 0.5;
    const auto f = simulate_fast_search(t, o, true);
    expect_same_answer(f, ref, law.vbl, 0.5);
    int ref_fit = 0, fast_fit = 0;
    for (const auto& s : ref.runs) ref_fit += s.purpose == "fit";
    for (const auto& s : f.runs) fast_fit += s.purpose == "fit" && !s.cancelled;
    EXPECT_EQ(ref_fit, 4);
    EXPECT_LE(fast_fit, 4);
    ASSERT_TRUE(f.fit.ok) << f.fit.note;
    EXPECT_NEAR(f.fit.vbl_mps, law.vbl, 0.5);
    EXPECT_NEAR(f.fit.a, law.a, 0.02);
    EXPECT_NEAR(f.fit.p, law.p, 0.1);
    EXPECT_LT(f.rounds, ref.rounds);
    // The fit's velocities are covered: within 10 % of each BL x factor there is a perforating run.
    for (double k : o.fit_factors) {
      bool covered = false;
      for (const auto& s : f.runs)
        covered |= !s.cancelled && s.perforated && std::abs(s.velocity_mps / (k * f.ballistic_limit_mps) - 1) <= 0.1;
      EXPECT_TRUE(covered) << k;
    }
  }
}

// Every rule at once (the default of `ravel limit`): same answers, far fewer rounds. On a
// threshold target the probes below the bracket all stop, so they cost time and change no
// answer: without them the search takes under 0.65 of the reference's time, with them
// under 0.8.
TEST(FastLimit, AllRulesMatchTheReference) {
  for (const Law& law : kLaws) {
    SCOPED_TRACE("vbl " + std::to_string(law.vbl));
    const auto t = target(law.a, law.p, law.vbl, slow_near(law.vbl));
    const auto ref = find_ballistic_limit(t, LimitOptions{}, true);
    double ref_time = 0;
    for (const auto& s : ref.runs) ref_time += s.wall_time_s;
    LimitOptions o;
    o.jobs = 2;
    const auto f = simulate_fast_search(t, o, true);
    expect_same_answer(f, ref, law.vbl, 1.0);
    EXPECT_LT(f.rounds, ref.rounds);
    EXPECT_LT(f.wall_time_s, 0.8 * ref_time);
    o.rules.probe_below = false;
    const auto np = simulate_fast_search(t, o, true);
    expect_same_answer(np, ref, law.vbl, 1.0);
    EXPECT_LT(np.wall_time_s, 0.65 * ref_time);
  }
}

// The answer of a search with probe_below stands on stopped full runs below its bracket.
// Fixed probes (probe_gaps off): one within 1 % of each probe velocity hi x (1 - k step).
// By gaps: from lo down to lo x (1 - count step) no two neighbouring stopped runs are more
// than step x hi apart (plus 2 % of the upper one: fixed probes' stand-ins may lie 1 % off each),
// and the lowest lies within 1 % of that velocity or below it.
void expect_probes_stopped(const LimitResult& r, const LimitOptions& o) {
  if (!o.rules.probe_gaps) {
    for (int k = 1; k <= o.probe_count; ++k) {
      const double v = r.hi_mps * (1 - k * o.probe_step);
      if (v >= r.lo_mps)
        continue;  // inside a bracket wider than a step: its stopped end lies below (as the search skips it)
      bool stopped_there = false;
      for (const auto& s : r.runs)
        stopped_there |= !s.cancelled && s.decided && !s.perforated && std::abs(s.velocity_mps / v - 1) <= 0.01;
      EXPECT_TRUE(stopped_there) << "no stopped run within 1 % of the probe at " << v << " m/s";
    }
    return;
  }
  const double step = o.probe_step * r.hi_mps, bottom = r.lo_mps * (1 - o.probe_count * o.probe_step);
  std::vector<double> stops;
  for (const auto& s : r.runs)
    if (!s.cancelled && s.decided && !s.perforated && s.velocity_mps <= r.lo_mps) stops.push_back(s.velocity_mps);
  std::sort(stops.begin(), stops.end(), std::greater<double>());
  ASSERT_FALSE(stops.empty());
  EXPECT_DOUBLE_EQ(stops.front(), r.lo_mps);
  for (size_t i = 0; i + 1 < stops.size() && stops[i] > bottom * 1.01; ++i)
    EXPECT_LE(stops[i] - stops[i + 1], step + 0.02 * stops[i] + 1e-9) << "a gap below the bracket at " << stops[i];
  EXPECT_LE(stops.back(), bottom * 1.01) << "no stopped run down at the lowest probe, " << bottom << " m/s";
}

// Outcomes that are not a threshold (measured on the default scene at mu = 1.0: 80 and 85
// m/s perforate, 90 to 100.8 m/s stop, 101.6 m/s perforates): the bisection from 100 m/s
// finds the crossing at 101, above a perforation 20 m/s lower. The probes below the bracket
// find the lower band, and the answer is its lowest perforation, within the tolerance.
TEST(FastLimit, ProbesBelowFindTheLowestPerforation) {
  const ShootFn t = [](double v, const std::string&) {
    Shot s;
    s.perforated = (v >= 80.0 && v < 88.0) || v >= 101.5;
    s.residual_velocity_mps = s.perforated ? 0.5 * v : 0;
    s.end_reason = s.perforated ? "perforated" : "rebounded";
    s.wall_time_s = 1.0;
    return s;
  };
  const auto ref = find_ballistic_limit(t, LimitOptions{}, false);
  ASSERT_TRUE(ref.converged);
  EXPECT_GT(ref.lo_mps, 100.0);  // the bisection's answer: the upper crossing
  LimitOptions o;
  o.jobs = 2;
  o.rules.probe_below = false;
  const auto np = simulate_fast_search(t, o, false);
  ASSERT_TRUE(np.converged);
  EXPECT_GT(np.lo_mps, 88.0);  // without probes: a crossing above the lower band
  o.rules.probe_below = true;
  for (const bool gaps : {true, false}) {
    SCOPED_TRACE(gaps ? "probe_gaps" : "fixed probes");
    o.rules.probe_gaps = gaps;
    const auto f = simulate_fast_search(t, o, false);
    ASSERT_TRUE(f.converged);
    EXPECT_GE(f.hi_mps, 80.0);
    EXPECT_LE(f.hi_mps, 81.0);
    EXPECT_LT(f.lo_mps, 80.0);
    EXPECT_NE(std::find(f.rules.begin(), f.rules.end(), "probe_below"), f.rules.end());
    // The answer stands on every probe below it having stopped.
    expect_probes_stopped(f, o);
    // The runs above the lower band that stopped say the outcome is no threshold; the band
    // reaches from the answer's perforation to the highest of them.
    const auto band = outcome_band(f);
    EXPECT_FALSE(band.threshold);
    EXPECT_DOUBLE_EQ(band.lowest_perforation, f.hi_mps);
    EXPECT_GE(band.highest_stop, 88.0);
    EXPECT_LT(band.highest_stop, 101.5);
    EXPECT_GE(band.against, 1);
  }
}

// A threshold whose perforating runs leave with a residual velocity of at least `jump` (the
// default scene at mu = 0.2: 79.92 m/s perforates at 11.1 m/s, 79.07 m/s stops): the
// Lambert-Jonas guess through the lowest perforations lies below the limit, so the
// bisection leaves stopped runs below the bracket.
ShootFn target_jump(double a, double vbl, double jump) {
  return [=](double v, const std::string&) {
    Shot s;
    s.perforated = v >= vbl;
    s.residual_velocity_mps = s.perforated ? std::sqrt(a * a * (v * v - vbl * vbl) + jump * jump) : 0;
    s.end_reason = s.perforated ? "perforated" : "rebounded";
    s.wall_time_s = slow_near(vbl)(v);
    return s;
  };
}

// Rule probe_gaps: the bisection's stopped runs below the bracket stand for probes, so the
// probes sample the same stretch below the bracket (no gap wider than a probe step) with no
// more runs than the fixed probes, and with fewer where the bisection left stops there (the
// residual-jump targets); the same answers, in less time on the clock.
TEST(FastLimit, ProbeGapsLetBisectionRunsStandForProbes) {
  struct Case {
    ShootFn t;
    double vbl;
    bool jump;
  };
  std::vector<Case> cases;
  for (const Law& law : kLaws) cases.push_back({target(law.a, law.p, law.vbl, slow_near(law.vbl)), law.vbl, false});
  for (double vbl : {44.1, 65.5, 79.5, 107.7}) cases.push_back({target_jump(0.95, vbl, 0.14 * vbl), vbl, true});
  double gaps_s = 0, fixed_s = 0;
  int gaps_probes = 0, fixed_probes = 0, jump_gaps_probes = 0, jump_fixed_probes = 0;
  for (const Case& c : cases)
    for (int jobs : {1, 2}) {
      SCOPED_TRACE("vbl " + std::to_string(c.vbl) + (c.jump ? " (jump)" : "") + " jobs " + std::to_string(jobs));
      const auto& t = c.t;
      const double vbl = c.vbl;
      const auto ref = find_ballistic_limit(t, LimitOptions{}, true);
      LimitOptions o;
      o.jobs = jobs;
      o.rules.decide_passing = false;
      const auto g = simulate_fast_search(t, o, true);
      expect_same_answer(g, ref, vbl, 1.0);
      expect_probes_stopped(g, o);
      EXPECT_NE(std::find(g.rules.begin(), g.rules.end(), "probe_gaps"), g.rules.end());
      o.rules.probe_gaps = false;
      const auto f = simulate_fast_search(t, o, true);
      expect_same_answer(f, ref, vbl, 1.0);
      expect_probes_stopped(f, o);
      EXPECT_EQ(std::find(f.rules.begin(), f.rules.end(), "probe_gaps"), f.rules.end());
      int gp = 0, fp = 0;
      for (const auto& s : g.runs) gp += s.purpose == "probe" && !s.cancelled;
      for (const auto& s : f.runs) fp += s.purpose == "probe" && !s.cancelled;
      // (Where the fixed search's bracket is wider than a probe step, as at 12.3 m/s with a 1 m/s
      // tolerance, its first probe falls inside the bracket and is skipped: it samples less
      // below the bracket, and the gaps rule may then make one probe more.)
      if (f.hi_mps - f.lo_mps <= o.probe_step * f.hi_mps) EXPECT_LE(gp, fp);
      gaps_probes += gp;
      fixed_probes += fp;
      if (c.jump) jump_gaps_probes += gp, jump_fixed_probes += fp;
      gaps_s += g.wall_time_s;
      fixed_s += f.wall_time_s;
    }
  EXPECT_LT(jump_gaps_probes, jump_fixed_probes);
  EXPECT_LT(gaps_s, fixed_s);
  std::printf("probe_gaps: %d probes (%d on the jump targets), %.1f s on the clock; fixed probes: %d (%d), %.1f s\n",
              gaps_probes, jump_gaps_probes, gaps_s, fixed_probes, jump_fixed_probes, fixed_s);
}

// Rule decisive_points: a point just beyond lo + tolerance (or hi - tolerance) moved inside
// it ends the search with its own outcome instead of waiting for the run beside it. On every
// target (threshold laws and residual jumps, runs slowest near the limit), 1 and 2 runs in
// flight, tolerance 1 and 0.25 m/s: the same verified answer; over them all less time on the
// clock, and no single search more than 10 % slower (a moved point is a slightly worse split
// of the prior, which can cost a round where it does not end one).
TEST(FastLimit, DecisivePointsEndSearchesWithoutWaiting) {
  std::vector<std::pair<ShootFn, double>> cases;
  for (const Law& law : kLaws) cases.push_back({target(law.a, law.p, law.vbl, slow_near(law.vbl)), law.vbl});
  for (double vbl : {44.1, 65.5, 79.5, 107.7}) cases.push_back({target_jump(0.95, vbl, 0.14 * vbl), vbl});
  double with_s = 0, without_s = 0;
  int sooner = 0, later = 0, moved = 0;
  for (const auto& [t, vbl] : cases)
    for (int jobs : {1, 2})
      for (double tol : {1.0, 0.25}) {
        SCOPED_TRACE("vbl " + std::to_string(vbl) + " jobs " + std::to_string(jobs) + " tol " + std::to_string(tol));
        LimitOptions o;
        o.jobs = jobs;
        o.tolerance_mps = tol;
        o.rules.decide_passing = false;
        const auto ref = find_ballistic_limit(t, o, true);
        const auto d = simulate_fast_search(t, o, true);
        expect_same_answer(d, ref, vbl, tol);
        EXPECT_NE(std::find(d.rules.begin(), d.rules.end(), "decisive_points"), d.rules.end());
        o.rules.decisive_points = false;
        const auto n = simulate_fast_search(t, o, true);
        expect_same_answer(n, ref, vbl, tol);
        EXPECT_EQ(std::find(n.rules.begin(), n.rules.end(), "decisive_points"), n.rules.end());
        EXPECT_LE(d.wall_time_s, 1.10 * n.wall_time_s);
        with_s += d.wall_time_s;
        without_s += n.wall_time_s;
        sooner += d.wall_time_s < n.wall_time_s - 1e-9;
        later += d.wall_time_s > n.wall_time_s + 1e-9;
        std::set<double> a, b;
        for (const auto& s : d.runs) a.insert(s.velocity_mps);
        for (const auto& s : n.runs) b.insert(s.velocity_mps);
        moved += a != b;
      }
  EXPECT_GT(moved, 0);
  EXPECT_LT(with_s, without_s);
  std::printf(
      "decisive_points: %.1f s on the clock against %.1f s without (%d searches sooner, %d later, %d of %zu "
      "placed a run elsewhere)\n",
      with_s, without_s, sooner, later, moved, 4 * cases.size());
}

// Undecided runs are left out of the bracket (as the reference does), and a failed run
// stops the search.
TEST(FastLimit, UndecidedRunsAreLeftOutAndAFailedRunStops) {
  const double vbl = 70.4, band = 3;
  auto t = [&](double v, const std::string&) {
    Shot s;
    s.perforated = v >= vbl;
    s.decided = s.perforated || v < vbl - band;
    s.end_reason = s.perforated ? "perforated" : s.decided ? "rebounded" : "end_time";
    s.residual_velocity_mps = s.perforated ? 0.9 * std::sqrt(v * v - vbl * vbl) : 0;
    return s;
  };
  LimitOptions o;
  o.jobs = 2;
  const auto r = simulate_fast_search(t, o, false);
  ASSERT_TRUE(r.bracketed);
  EXPECT_LT(r.lo_mps, vbl - band);
  EXPECT_GE(r.hi_mps, vbl);
  EXPECT_LE(r.hi_mps - r.lo_mps, band + o.tolerance_mps);
  int warned = 0;
  for (const auto& w : r.warnings) warned += w.find("undecided") != std::string::npos;
  EXPECT_GT(warned, 0);

  auto diverging = [](double v, const std::string&) {
    Shot s;
    s.perforated = v >= 70;
    s.failed = v < 80 && v > 60;
    s.error = "diverged";
    return s;
  };
  const auto d = simulate_fast_search(diverging, o, true);
  EXPECT_FALSE(d.converged);
  bool any_failed = false;
  for (const auto& s : d.runs) any_failed |= s.failed;
  EXPECT_TRUE(any_failed);
  EXPECT_FALSE(d.warnings.empty());
}

// On real threads: each run sleeps in small steps, watching its stop flag. The answer is
// the virtual clock's, moot runs come back cancelled, and the hooks see every run.
RunFn sleepy(double vbl, double ms_per_run) {
  const ShootFn t = target(0.9, 2.0, vbl);
  return [=](double v, const std::string& why, const std::atomic<bool>* stop) {
    const int steps = int(ms_per_run);
    for (int i = 0; i < steps; ++i) {
      if (stop && stop->load()) {
        Shot c;
        c.cancelled = true;
        c.decided = false;
        return c;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return t(v, why);
  };
}

TEST(FastLimit, ThreadsFindTheSameLimitAndHooksSeeEveryRun) {
  LimitOptions o;
  o.jobs = 2;
  int started = 0, ended = 0;
  LimitHooks h;
  std::vector<std::string> lines;
  h.on_start = [&](const Shot&) { ++started; };
  h.on_finish = [&](const Shot&, const LimitProgress& p) {
    ++ended;
    lines.push_back(p.line());
  };
  const auto r = find_ballistic_limit_fast(sleepy(70.4, 20), o, true, nullptr, h);
  ASSERT_TRUE(r.converged);
  EXPECT_NEAR(r.ballistic_limit_mps, 70.4, 0.5 + 1e-9);
  EXPECT_EQ(started, int(r.runs.size()));
  EXPECT_EQ(ended, int(r.runs.size()));
  EXPECT_EQ(r.jobs, 2);
  ASSERT_FALSE(lines.empty());
  EXPECT_NE(lines.back().find("bracket "), std::string::npos) << lines.back();
  for (const auto& s : r.runs) {
    EXPECT_GE(s.started_s, 0);
    EXPECT_GE(s.ended_s, s.started_s);
  }
}

// An interruption stops every run in flight: they are listed as cancelled ("interrupted"),
// the result says interrupted; the finished runs given back as `prior` resume the search.
TEST(FastLimit, InterruptStopsEveryRunAndPriorRunsResume) {
  std::atomic<bool> interrupt{false};
  LimitOptions o;
  o.jobs = 2;
  LimitHooks h;
  int ended = 0;
  h.on_finish = [&](const Shot&, const LimitProgress&) {
    if (++ended == 3) interrupt = true;
  };
  const auto part = find_ballistic_limit_fast(sleepy(70.4, 30), o, false, &interrupt, h);
  EXPECT_TRUE(part.interrupted);
  bool saw_interrupted = false;
  std::vector<Shot> kept;
  for (const auto& s : part.runs) {
    if (s.cancelled)
      saw_interrupted |= s.cancel_reason == "interrupted";
    else
      kept.push_back(s);
  }
  EXPECT_TRUE(saw_interrupted);
  ASSERT_GE(kept.size(), 2u);
  int made = 0;
  LimitHooks count;
  count.on_start = [&](const Shot&) { ++made; };
  const auto full = find_ballistic_limit_fast(sleepy(70.4, 5), o, false, nullptr, count, kept);
  ASSERT_TRUE(full.converged);
  EXPECT_NEAR(full.ballistic_limit_mps, 70.4, 0.5 + 1e-9);
  EXPECT_EQ(int(full.runs.size()), int(kept.size()) + made);
  int resumed = 0;
  for (const auto& s : full.runs) resumed += s.resumed;
  EXPECT_EQ(resumed, int(kept.size()));
}

// Both searches run and list velocities to 1e-6 m/s, the precision a run's scene gets
// (run_velocity): near the limit an outcome can flip under a change of 1e-9 of the velocity
// (docs/MODEL.md §9), so a listed velocity must be the one that was run. Bisecting 0-100 m/s
// gives thirds and halves that are not on that grid (33.333333..., 83.333333...).
TEST(FastLimit, ListedVelocitiesAreTheOnesRun) {
  std::set<double> ran;
  std::mutex mu;
  const ShootFn law = target(0.9, 2.0, 70.4);
  const ShootFn recording = [&](double v, const std::string& why) {
    std::lock_guard<std::mutex> lock(mu);
    ran.insert(v);
    return law(v, why);
  };
  auto check = [&](const LimitResult& r) {
    ASSERT_TRUE(r.converged);
    int off_grid_before = 0;
    for (const auto& s : r.runs) {
      EXPECT_EQ(s.velocity_mps, run_velocity(s.velocity_mps)) << s.velocity_mps;
      EXPECT_EQ(ran.count(s.velocity_mps), 1u) << s.velocity_mps << " listed but never run";
      char b[64];
      std::snprintf(b, sizeof b, "%.17g", s.velocity_mps);
      off_grid_before += std::string(b).size() > 12;  // e.g. 83.333333000000004
    }
    EXPECT_GT(off_grid_before, 0) << "the search met no velocity that needed rounding: the test checks nothing";
  };
  LimitOptions ro;
  ro.tolerance_mps = 0.25;
  check(find_ballistic_limit(recording, ro, false));
  ran.clear();
  auto o = only(true, true, true, true, true, 2);
  o.tolerance_mps = 0.25;
  check(simulate_fast_search(recording, o, true));
  EXPECT_EQ(run_velocity(75.94252806184204), 75.942528);
  EXPECT_EQ(run_velocity(80.0), 80.0);
}

// The real thing: the cheap scene, two runs in flight on one thread each, against the
// reference search at the same settings. Without the probes below the bracket both searches
// bisect the same threshold; with them the fast search also checks 5-20 % below its answer,
// and on this scene finds a perforation there (45.6 m/s perforates, 46.9 and 50.0 m/s stop:
// the outcomes near the limit are not a threshold), so its answer is the lower one and every
// probe below that stopped.
TEST(FastLimit, CheapSceneMatchesTheReference) {
  auto ov = testing::cheap_scene();
  ov.push_back("solver.threads=1");
  LimitOptions o;
  o.start_mps = 50;
  o.tolerance_mps = 1.0;
  const auto ref = find_ballistic_limit(scene_shooter("", ov), o, false);
  ASSERT_TRUE(ref.converged);
  // The fast search's runs decide passing projectiles early (FastRules::decide_passing); the
  // reference runs every run to its end.
  add_rule_overrides(o.rules, ov);
  ASSERT_EQ(ov.back(), "solver.decide_passing=true");
  o.jobs = 2;
  o.rules.probe_below = false;
  const auto f = find_ballistic_limit_fast(scene_runner("", ov), o, false);
  int decided = 0;
  for (const auto& s : f.runs) decided += s.decided_passing;
  EXPECT_GT(decided, 0);
  for (const auto& w : f.warnings) ADD_FAILURE() << w;
  ASSERT_TRUE(f.converged);
  EXPECT_LE(f.hi_mps - f.lo_mps, 1.0);
  EXPECT_NEAR(f.ballistic_limit_mps, ref.ballistic_limit_mps, 1.0);
  // Both brackets hold the limit: they overlap.
  EXPECT_LT(std::max(f.lo_mps, ref.lo_mps), std::min(f.hi_mps, ref.hi_mps));
  EXPECT_LT(f.rounds, ref.rounds);
  // With the probes: never above the same search's answer without them, and standing on
  // stopped probes. One run in flight, so both take the same path up to the first probe (with
  // two, the order runs end in picks the velocities and the two paths differ).
  o.jobs = 1;
  o.rules.probe_below = false;
  const auto np = find_ballistic_limit_fast(scene_runner("", ov), o, false);
  o.rules.probe_below = true;
  const auto p = find_ballistic_limit_fast(scene_runner("", ov), o, false);
  ASSERT_TRUE(np.converged);
  ASSERT_TRUE(p.converged);
  EXPECT_LE(p.hi_mps - p.lo_mps, 1.0);
  EXPECT_LE(p.hi_mps, np.hi_mps + 1e-9);
  expect_probes_stopped(p, o);
}

}  // namespace
}  // namespace ravel::studies
