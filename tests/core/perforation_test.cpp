// Outcomes of a run (SPEC §8, docs/MODEL.md §8): perforation needs the projectile to have
// passed through the fabric, so a caught projectile is never reported as perforated; the
// ledger's friction term is a dissipation; the state hashes are the recorded ones.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "fixture.h"
#include "hash_probe.h"
#include "results.h"

namespace ravel {
namespace {

using test::operator+;

// A projectile the fabric catches, light (kg typed for g: 0.007 g) or slow, ends stopped
// (rebounded or caught), never perforated: with nothing broken the fabric is still ahead of it.
TEST(Perforation, ACaughtProjectileIsNeverPerforated) {
  for (const char* what : {"projectile.mass_g=0.007", "projectile.velocity_mps=20"}) {
    SCOPED_TRACE(what);
    const Summary s = test::simulate(test::scene_with(
        {"fabric.width_mm=40", "fabric.length_mm=40", "projectile.diameter_mm=6", "projectile.mass_g=1.75", what}));
    EXPECT_FALSE(s.perforated) << s.diagnosis;
    // Stopped: turned back, or held below 1 % of its impact speed (caught).
    EXPECT_TRUE(s.end_reason == EndReason::rebounded || s.end_reason == EndReason::caught) << s.diagnosis;
    EXPECT_EQ(s.residual_velocity_mps, 0.0);
    EXPECT_EQ(s.broken_warp + s.broken_weft, 0);
  }
}

// The early decision of solver.decide_passing (docs/MODEL.md §8, "Passing"; the fast limit
// search's rule decide_passing) is never reversed by running on: on the 20 mm patch of the
// limit tests, near its limit (rebounds at 44-46 and 50 m/s, perforations between) and at
// mu = 0, every run gives the same outcome with and without it, the decided ones end sooner
// (measured: 47 m/s at 347 instead of 1060 us, 49 m/s at 511 instead of 1242 us) and their
// residual velocity is the speed at the decision, at most 1 m/s above the exit speed
// (measured: 0.79 m/s at 54 m/s, the drag of the last yarns not yet paid).
TEST(Perforation, APassingDecisionIsNeverReversed) {
  const std::vector<std::string> patch = {"fabric.width_mm=20",    "fabric.length_mm=20",  "projectile.diameter_mm=4",
                                          "projectile.mass_g=0.5", "solver.dt_factor=0.3", "solver.end_time_us=auto"};
  int decided = 0;
  double saved = 0;
  auto check = [&](const std::string& mu, double v) {
    SCOPED_TRACE(mu + " at " + std::to_string(v) + " m/s");
    auto run = [&](bool early) {
      return test::simulate(test::scene_with(
          patch + std::vector<std::string>{mu, "projectile.velocity_mps=" + std::to_string(v),
                                           std::string("solver.decide_passing=") + (early ? "true" : "false")}));
    };
    const Summary full = run(false), early = run(true);
    ASSERT_EQ(full.status, RunStatus::completed) << full.diagnosis;
    EXPECT_EQ(early.perforated, full.perforated) << early.diagnosis;
    EXPECT_FALSE(full.decided_passing);
    EXPECT_LE(early.end_time_s, full.end_time_s);
    if (!early.decided_passing) {
      EXPECT_EQ(early.end_time_s, full.end_time_s);
      return;
    }
    ++decided;
    saved += full.end_time_s - early.end_time_s;
    EXPECT_TRUE(early.perforated);
    EXPECT_GE(early.residual_velocity_mps, full.residual_velocity_mps - 1e-9);
    EXPECT_LT(early.residual_velocity_mps, full.residual_velocity_mps + 1.0);
  };
  for (double v : {44, 45, 46, 47, 48, 49, 50, 51, 52, 54}) check("yarn.friction=0.2", v);
  for (double v : {36, 44}) check("yarn.friction=0", v);
  EXPECT_GE(decided, 6);
  EXPECT_GT(saved, 1e-3) << "simulated time the decisions saved (s)";
}

// No passing decision before the first element breaks (docs/MODEL.md §8, "Passing"): on a
// 24 mm ply the 12 mm sphere first touches only the free pole warp, which no element ties to
// a clamp, and for the first 150 us the drag of the still undeflected fabric is low enough
// to pass the drag test. Without the break condition runs at 1, 8 and 24 m/s were decided
// passing at 152 us (residual 0.999, 7.93 and 23.0 m/s) that run on to a rebound (measured
// 2026-12-06): the fast limit search on that ply then found "perforations" down to 1 m/s.
TEST(Perforation, NoPassingDecisionBeforeTheFirstBreak) {
  for (const double v : {1.0, 8.0, 24.0}) {
    SCOPED_TRACE(std::to_string(v) + " m/s");
    const Summary s = test::simulate(
        test::scene_with({"fabric.width_mm=24", "fabric.length_mm=24", "projectile.velocity_mps=" + std::to_string(v),
                          "solver.end_time_us=auto", "solver.decide_passing=true"}));
    ASSERT_EQ(s.status, RunStatus::completed) << s.diagnosis;
    EXPECT_FALSE(s.decided_passing) << s.diagnosis;
    EXPECT_FALSE(s.perforated) << s.diagnosis;
    EXPECT_EQ(s.end_reason, EndReason::rebounded) << s.diagnosis;
  }
}

// The passing and caught rules leave no gap in speed (docs/MODEL.md §8, "Passing"): on the
// default scene at mu = 0.02 and 50 m/s (at its ballistic limit) the central clamped weft
// breaks, the projectile slips through the opened weave and then coasts at 0.72 m/s (1.4 % of
// the impact speed) with nothing on it but the ravelled pole warp, which the weave lets go
// at no cost. With the passing rule's old floor of 2 % the run stayed undecided to
// solver.max_end_time_us (0.72-0.75 m/s from 1.2 to 5 ms, measured); with the caught rule's
// 1 % it is decided passing at 1.69 ms. It was coasting: over the 0.4 ms before the decision
// its speed stayed within 2 % of the speed at the decision (the kinetic energy the ravelled
// yarn takes and gives back), so there was no drag that could have stopped it.
TEST(Perforation, ACoastingProjectileIsDecidedPassing) {
  const double v0 = 50;
  Simulation sim(test::scene_with({"yarn.friction=0.02", "projectile.velocity_mps=50", "solver.threads=1",
                                   "solver.decide_passing=true", "solver.max_end_time_us=2500"}));
  sim.run();
  const Summary s = sim.summary();
  ASSERT_EQ(s.status, RunStatus::completed) << s.diagnosis;
  EXPECT_TRUE(s.perforated) << s.diagnosis;
  EXPECT_TRUE(s.decided_passing);
  // The case the rule's floor closed: between the caught rule's 1 % and the old 2 %.
  const double vr = s.residual_velocity_mps;
  EXPECT_GT(vr, 0.01 * v0);
  EXPECT_LT(vr, 0.02 * v0);
  EXPECT_LT(s.perforation_time_s, 2.0e-3);
  int rows = 0;
  for (const HistoryRow& r : sim.history()) {
    if (r.t_s < s.perforation_time_s - 0.4e-3) continue;
    ++rows;
    EXPECT_NEAR(r.projectile_velocity_mps, vr, 0.02 * vr) << r.t_s;
  }
  EXPECT_GT(rows, 10);
}

// friction_work_J is the work of the friction impulses less the energy the stick penalty
// springs hold (docs/MODEL.md §4): a dissipation, never below zero (to rounding: 1e-6 of the
// impact energy covers the half-step timing of the springs' energy), whatever mu.
TEST(Friction, WorkIsDissipation) {
  for (const char* mu : {"yarn.friction=0.2", "yarn.friction=1"}) {
    SCOPED_TRACE(mu);
    Simulation sim(test::scene_with(
        {"fabric.width_mm=40", "fabric.length_mm=40", "projectile.diameter_mm=6", "projectile.mass_g=1.75", mu}));
    sim.run();
    const double e0 = sim.history().front().ledger.total();
    double stick_max = 0;
    for (const HistoryRow& r : sim.history()) {
      EXPECT_GE(r.ledger.friction_work_J, -1e-6 * e0) << r.t_s;
      EXPECT_GE(r.ledger.stick_energy_J, 0.0) << r.t_s;
      stick_max = std::max(stick_max, r.ledger.stick_energy_J);
    }
    EXPECT_GT(stick_max, 0.0);
    EXPECT_GT(sim.history().back().ledger.friction_work_J, 0.0);
    EXPECT_LT(sim.summary().energy_balance_error, 5e-3);
  }
}

// The friction-work windows of the summary (docs/MODEL.md §8) are the ledger's yarn-yarn
// friction work at the step of the first break and at the perforation time (the projectile's
// last touch of the attached fabric), taken in the step loop. Checked against the history,
// which samples the same ledger: at each window's time the sampled friction work brackets
// it within one history interval's change (plus rounding). Without friction every window is
// zero; with it they rise in order (friction work only grows, up to the stick springs' few
// hundredths of a J, bounded as in WorkIsDissipation).
double history_friction_at(const std::vector<HistoryRow>& h, double t, double* spread) {
  for (size_t i = 1; i < h.size(); ++i) {
    if (h[i].t_s < t) continue;
    const double a = h[i - 1].ledger.friction_work_J, b = h[i].ledger.friction_work_J;
    *spread = std::abs(b - a);
    const double w = (t - h[i - 1].t_s) / std::max(1e-30, h[i].t_s - h[i - 1].t_s);
    return a + std::clamp(w, 0.0, 1.0) * (b - a);
  }
  *spread = 0;
  return h.back().ledger.friction_work_J;
}

TEST(Friction, WorkWindowsAreTheLedgerAtFirstBreakAndPerforation) {
  const std::vector<std::string> base{"fabric.width_mm=36", "fabric.length_mm=36", "projectile.diameter_mm=6",
                                      "projectile.mass_g=2", "projectile.velocity_mps=200"};
  for (const char* mu : {"yarn.friction=0", "yarn.friction=0.2"}) {
    SCOPED_TRACE(mu);
    Simulation sim(test::scene_with(base + std::vector<std::string>{mu}));
    sim.run();
    const Summary s = sim.summary();
    ASSERT_TRUE(s.perforated) << s.diagnosis;
    ASSERT_GT(s.first_break_time_s, 0.0);
    EXPECT_LT(s.first_break_time_s, s.perforation_time_s);
    const double e0 = sim.history().front().ledger.total();
    if (std::string(mu) == "yarn.friction=0") {
      EXPECT_EQ(s.friction_work_J, 0.0);
      EXPECT_EQ(s.friction_work_to_first_break_J, 0.0);
      EXPECT_EQ(s.friction_work_to_perforation_J, 0.0);
      continue;
    }
    EXPECT_GT(s.friction_work_to_first_break_J, 0.0);
    EXPECT_LE(s.friction_work_to_first_break_J, s.friction_work_to_perforation_J + 1e-6 * e0);
    EXPECT_LE(s.friction_work_to_perforation_J, s.friction_work_J + 1e-6 * e0);
    EXPECT_LT(s.friction_work_to_first_break_J, 0.5 * s.friction_work_J);  // most of it comes after the first break
    double spread = 0;
    const double at_break = history_friction_at(sim.history(), s.first_break_time_s, &spread);
    EXPECT_NEAR(s.friction_work_to_first_break_J, at_break, spread + 1e-9 * e0);
    const double at_perf = history_friction_at(sim.history(), s.perforation_time_s, &spread);
    EXPECT_NEAR(s.friction_work_to_perforation_J, at_perf, spread + 1e-9 * e0);
  }
}

// The end of the event on the paper's own scene (issue 37, docs/MODEL.md §10 "After the
// first break"; default scene, full mesh, 260 m/s). The clamped wefts break first, near the
// impact point, not at the clamps; what follows is the free warps under the projectile
// pulled through the weave, so at mu = 0.2 most of the friction work comes after the first
// break (measured: 3.68 J by it at 87.0 us, 31.02 J by perforation at 186.4 us). At mu = 1.0
// the weave sticks, nothing is pulled through, and the projectile perforates earlier with a
// fraction of the friction (0.87 J by the first break, 4.56 J by perforation at 112.8 us).
// The bounds are the mechanism's (pull-out carries at least 5x the friction before the
// break; sticking cuts it to under a quarter), not the measured values: the run after the
// first break is chaotic (§10) and moves these figures by several per cent between builds.
TEST(EndOfEvent, FreeWarpsPulledThroughCarryTheFrictionAfterTheFirstBreak) {
  auto run = [](const char* mu) {
    Simulation sim(test::scene_with({mu, "solver.threads=2"}));
    sim.run();
    return sim.summary();
  };
  const Summary low = run("yarn.friction=0.2"), high = run("yarn.friction=1.0");
  for (const Summary* s : {&low, &high}) {
    ASSERT_TRUE(s->perforated) << s->diagnosis;
    ASSERT_GT(s->first_break_time_s, 0.0);
    EXPECT_LT(s->energy_balance_error, 0.02);
  }
  // Where the first break is and where the elements broken before perforation lie, at
  // mu = 0.2: within 8 mm of the impact point, at most a quarter by a clamp (measured: 2.6 mm;
  // 6 of 110 by a clamp).
  EXPECT_LT(low.first_break_distance_m, 8e-3);
  ASSERT_GT(low.broken_before_perforation, 0);
  EXPECT_LE(4 * low.broken_near_clamp, low.broken_before_perforation)
      << low.broken_near_clamp << " of " << low.broken_before_perforation << " by a clamp";
  // Friction work before the break: a few J at mu = 0.2 (the whole deflected ply slides), less
  // at mu = 1.0 (the weave sticks).
  EXPECT_GT(low.friction_work_to_first_break_J, 1.0);
  EXPECT_LT(low.friction_work_to_first_break_J, 8.0);
  EXPECT_LT(high.friction_work_to_first_break_J, low.friction_work_to_first_break_J);
  // After it: pull-out at mu = 0.2, none at mu = 1.0.
  EXPECT_GT(low.friction_work_to_perforation_J, 5 * low.friction_work_to_first_break_J);
  EXPECT_LT(high.friction_work_to_perforation_J, 0.25 * low.friction_work_to_perforation_J);
  // Paper Fig. 14: mu = 1.0 perforates earlier than mu = 0.2.
  EXPECT_LT(high.perforation_time_s, low.perforation_time_s);
}

// After the first breaks no yarn is broken by the contact's position shifts (docs/MODEL.md §4,
// "Force cap and shift"). A shift moves nodes without a force, so the elements of a shifted
// node are stretched without resisting; removing a crossing's closure below its flattened
// distance in one step (all but half of c_min, the rule until 2026-12-05) moved nodes by
// 50-100 um at crossings passed through or re-paired in the bunched weave near the projectile
// and broke yarns that carried no load. On a 60 mm ply (the 12 mm sphere at 70 m/s, both yarn
// families loaded, the clamped wefts broken first) that rule broke 4 elements from about zero
// strain to 6-9 % in one step (measured; Solver diagnostics' shift_broken counts them).
// Paced at 0.02 D per step, every element breaks under its own tension.
TEST(EndOfEvent, NoYarnIsBrokenByAContactShift) {
  Simulation sim(test::scene_with(
      {"fabric.width_mm=60", "fabric.length_mm=60", "projectile.velocity_mps=70", "solver.threads=2"}));
  sim.run();
  const Summary& s = sim.summary();
  ASSERT_GT(s.broken_weft_yarns + s.broken_warp_yarns, 0) << "the run must break yarns to test this";
  EXPECT_EQ(sim.solver().diagnostics().shift_broken, 0)
      << "first at " << sim.solver().diagnostics().first_shift_break_time;
  EXPECT_LT(std::abs(s.energy_balance_error), 0.01);
  for (const auto& w : s.warnings)
    EXPECT_EQ(w.find("stretched to failure by contact position shifts"), std::string::npos) << w;
}

// The map of where friction heats the yarns (Solver::crossing_friction_heat; the app's and
// the snapshots' "friction" field, the VTK files' friction_heat_J_per_g): each crossing's
// friction force times its slip speed, summed over the steps. None without friction, never
// negative, and in all it accounts for what the ledger says friction dissipated. It is the
// Coulomb dissipation of each contact as the contact sees it, not the ledger's own sum: the
// resultant of the two yarns' forces (a square cone, up to sqrt 2 mu f_n) times the stuck
// point's speed counts some of what the stick springs give back, so it runs above the
// ledger, by 14-18 % on the default scene at 260 m/s (docs/MODEL.md §10) and by 12-17 % here.
TEST(Friction, HeatMapIsTheContactsDissipation) {
  for (const char* mu : {"yarn.friction=0", "yarn.friction=0.2", "yarn.friction=1"}) {
    SCOPED_TRACE(mu);
    Simulation sim(test::scene_with({"fabric.width_mm=40", "fabric.length_mm=40", "projectile.diameter_mm=6",
                                     "projectile.mass_g=1.75", mu, "solver.threads=2"}));
    sim.run();
    const Solver& s = sim.solver();
    double heat = 0, most = 0;
    for (int c = 0; c < int(s.model().crossings.size()); ++c) {
      ASSERT_GE(s.crossing_friction_heat(c), 0.0) << "crossing " << c;
      heat += s.crossing_friction_heat(c);
      most = std::max(most, s.crossing_friction_heat(c));
    }
    const Ledger& l = s.ledger();
    const double booked = l.friction_work_J + l.stick_energy_J;
    if (std::string(mu) == "yarn.friction=0") {
      EXPECT_EQ(heat, 0.0);
      continue;
    }
    // Measured 1.174 (mu = 0.2) and 1.122 (mu = 1) here. Above 1.35 the map would no longer
    // be the contacts' share of the ledger (the square cone's resultant alone can add at most
    // sqrt 2 = 1.41); below 0.9 it would miss dissipation (the slip speed is capped by the
    // yarns' relative motion, which can only lower it a little).
    EXPECT_GT(heat, 0.9 * booked) << "heat " << heat << " J, ledger " << booked << " J";
    EXPECT_LT(heat, 1.35 * booked) << "heat " << heat << " J, ledger " << booked << " J";
    EXPECT_LT(most, 0.5 * heat);  // spread over the crossings, not one
  }
}

// Where the rule above fails, the run says so. On the default scene (full mesh) at mu = 1.0
// with crossings that flatten less (fabric.flattened_gap_mm = 0.16), the soft stick springs
// (solver.friction_penalty = 0.25) feed energy into the yarns before any yarn breaks:
// friction_work_J falls to -0.21 J by 52 us (measured; docs/MODEL.md §4), and the summary
// warns (below -0.05 % of the initial energy, 0.12 J). With alpha_f = 0.75 the same run stays
// dissipative to rounding and does not warn.
TEST(Friction, NegativeFrictionWorkIsReported) {
  auto friction_warning = [](const Summary& s) {
    for (const auto& w : s.warnings)
      if (w.find("friction work went below zero") != std::string::npos) return true;
    return false;
  };
  const std::vector<std::string> base = {"yarn.friction=1.0", "fabric.flattened_gap_mm=0.16", "solver.end_time_us=52",
                                         "solver.threads=2"};
  Simulation soft(test::scene_with(base));
  soft.run();
  const double e0 = soft.history().front().ledger.total();
  EXPECT_LT(soft.history().back().ledger.friction_work_J, -5e-4 * e0);
  EXPECT_TRUE(friction_warning(soft.summary()));
  Simulation stiff(test::scene_with(base + std::vector<std::string>{"solver.friction_penalty=0.75"}));
  stiff.run();
  for (const HistoryRow& r : stiff.history()) EXPECT_GE(r.ledger.friction_work_J, -1e-6 * e0) << r.t_s;
  EXPECT_FALSE(friction_warning(stiff.summary()));
}

// The hash probe (bench/hash_probe): the state hash of a fixed set of scenes after a fixed
// number of steps. A change that should move no number must leave these the same; a change
// that moves them updates them in its own commit, saying why.
TEST(HashProbe, StateHashesAreTheRecordedOnes) {
  const std::vector<std::pair<std::string, std::uint64_t>> expect = {
#include "hash_probe_expected.inc"
  };
  for (const auto& [name, hash] : expect) {
    bool found = false;
    for (const auto& c : probe_cases()) {
      if (c.name != name) continue;
      found = true;
      EXPECT_EQ(run_probe(c).hash, hash) << name;
    }
    EXPECT_TRUE(found) << name;
  }
}

// The broken yarns' grid lines (Summary::broken_*_lines): the count of each family's yarns,
// ascending, and in the quarter model every yarn off a symmetry plane listed with its mirror
// image; the full model of the same strike breaks the same lines (quarter = full, §6).
TEST(Perforation, BrokenYarnLinesAreTheBrokenYarnsOverTheWholeFabric) {
  auto run = [](const char* symmetry) {
    Simulation sim(
        test::scene_with(test::small_patch() + std::vector<std::string>{"projectile.velocity_mps=400", symmetry}));
    sim.run();
    return sim.summary();
  };
  const Summary q = run("solver.symmetry=auto");
  ASSERT_EQ(q.model, "quarter");
  ASSERT_GT(q.broken_weft_yarns + q.broken_warp_yarns, 0) << "the run must break yarns to test this";
  for (const auto* lines : {&q.broken_warp_lines, &q.broken_weft_lines}) {
    EXPECT_TRUE(std::is_sorted(lines->begin(), lines->end()));
    for (int l : *lines) EXPECT_EQ(std::count(lines->begin(), lines->end(), -l), 1) << l;
  }
  EXPECT_EQ(int(q.broken_warp_lines.size()), q.broken_warp_yarns);
  EXPECT_EQ(int(q.broken_weft_lines.size()), q.broken_weft_yarns);
  const Summary f = run("solver.symmetry=full");
  EXPECT_EQ(f.model, "full");
  EXPECT_EQ(f.broken_warp_lines, q.broken_warp_lines);
  EXPECT_EQ(f.broken_weft_lines, q.broken_weft_lines);
}

// How `ravel run` and the app write them: consecutive lines as one range.
TEST(Perforation, BrokenLinesAreWrittenAsRanges) {
  EXPECT_EQ(line_ranges({}), "");
  EXPECT_EQ(line_ranges({0}), "0");
  EXPECT_EQ(line_ranges({-1, 0, 1}), "-1..1");
  EXPECT_EQ(line_ranges({-6, -5, -4, 0, 4, 5, 6}), "-6..-4, 0, 4..6");
  EXPECT_EQ(line_ranges({-3, 3}), "-3, 3");
}

}  // namespace
}  // namespace ravel
