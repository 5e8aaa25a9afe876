// Ballistic limit: the lowest impact velocity that perforates (SPEC §8), found by
// bracketing and bisection, and the Lambert-Jonas fit of residual velocity above it:
//   Vr = a (V^p - Vbl^p)^(1/p)   for V > Vbl,  0 below.
//
// The search is written against a "shoot" function (velocity -> outcome) so it can be
// tested on synthetic targets and run on any scene. Bisection assumes perforation is
// monotone in velocity; runs that contradict that are kept and reported as warnings.
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "simulation.h"

namespace ravel::studies {

struct Shot {
  double velocity_mps = 0;
  bool perforated = false;
  double residual_velocity_mps = 0;
  double energy_absorbed_J = 0;
  double perforation_time_s = -1;
  std::string end_reason;        // perforated | rebounded | end_time | ...
  bool decided = true;           // false: reached end_time neither perforated nor turned back
  bool decided_passing = false;  // perforated by solver.decide_passing's early decision (FastRules)
  double wall_time_s = 0;
  int broken_warp_yarns = 0, broken_weft_yarns = 0;
  // Their grid lines (Summary's).
  std::vector<int> broken_warp_lines, broken_weft_lines;
  // Yarn-yarn friction work over the run and up to the first broken element, and where that
  // element was (Summary's; -1: no break, or a run kept before these were).
  double friction_work_J = 0, friction_work_to_first_break_J = 0, first_break_distance_mm = -1;
  std::string purpose;   // bracket | bisect | fit
  bool failed = false;   // the run diverged: its outcome means nothing
  std::string error;     // why
  bool resumed = false;  // read back from a kept run, not run now
  // The fast search (find_ballistic_limit_fast) stops a run the moment its outcome became
  // moot: it then has no outcome (decided = false, perforated = false, end_reason
  // "cancelled") and says why; it is listed, never used.
  bool cancelled = false;
  std::string cancel_reason;
  double started_s = -1;  // fast search: when the run started and ended, from the search's start
  double ended_s = -1;
  int round = 0;  // fast search: 1 + the deepest round of the runs finished before it started
};

// The velocity a search's run simulates and lists: v to 1e-6 m/s, the 6 decimals with which
// scene_runner writes it into the run's scene (projectile.velocity_mps). Both searches run and
// record only such velocities. Near the ballistic limit an outcome can flip under a change of
// 1e-9 of the velocity (docs/MODEL.md §9: 75.942528 m/s perforates on the default scene, 6e-8
// m/s more rebounds), so the number a search lists must be the one its run had, or rerunning
// a listed velocity does not reproduce its outcome (until 2026-12-07 the list kept the
// search's unrounded number, up to 5e-7 m/s off).
double run_velocity(double v);

using ShootFn = std::function<Shot(double velocity_mps, const std::string& purpose)>;
// A run that can be stopped on its own: when `stop` becomes true the run ends at once and
// comes back with cancelled = true (it is not kept in a cache).
using RunFn = std::function<Shot(double velocity_mps, const std::string& purpose, const std::atomic<bool>* stop)>;

// The fast search's rules (docs/studies.md, "The fast search"). Each can be turned off to
// measure what it saves (`ravel tradeoff --searches`, bench/limit_speed); none of them moves
// the bracket's guarantee: its ends are always full runs that stopped / perforated.
struct FastRules {
  // Several runs in flight (LimitOptions::jobs): when every slot is free the bracket is cut
  // into jobs + 1 parts; a slot that frees while others run splits the part most likely to
  // hold the limit.
  bool ksection = true;
  // A run whose outcome can no longer move the bracket (a sibling below it perforated, or
  // one above it stopped, or the bracket reached the tolerance) is stopped at once.
  bool cancel_moot = true;
  // Residual velocities place the next points: Lambert-Jonas with p = 2 through the
  // perforating runs closest to the limit (Vbl^2 = V^2 - (Vr/a)^2; a from two runs, 1 from
  // one), as a prior that the points split; 25 % of the prior stays uniform over the bracket.
  bool residual_guess = true;
  // The first round tries the start and one growth step below it at once.
  bool two_sided_start = true;
  // The fit's runs only where no perforating run of the search is already within 10 % of the
  // fit's velocity (BL x factor); a bracket run made moot that would be such a point is kept.
  bool reuse_fit_points = true;
  // Once the bracket reaches the tolerance, runs at hi x (1 - k probe_step), k = 1 ..
  // probe_count, below it. The limit is the lowest velocity that perforates (SPEC §8), and
  // near it outcomes need not be monotone (at mu = 1.0 on the default scene 80 and 85 m/s
  // perforate, 90-100.8 m/s stop, 101.6 m/s perforates): a bracket of two runs cannot see a
  // perforation below it. A probe that perforates moves the bracket down to it and the
  // search goes on there; the answer stands once every probe below it stopped.
  bool probe_below = true;
  // With probe_below: the probes sample the velocities below the bracket no coarser than the
  // fixed probes would (gaps of at most probe_step x hi plus the 2 % the fixed probes' stand-ins
  // may leave, down to lo x (1 - probe_count probe_step)), and a run of the search already
  // there stands for a probe: the stopped bisection runs below the bracket count, so a probe
  // is made only where they leave a gap.
  // Probes also take slots the bracket has no use for once it is narrower than one probe
  // step, before it reaches the tolerance. Off: probes at the fixed hi x (1 - k probe_step),
  // each stood for only by a run within 1 % of it, once the bracket has converged.
  bool probe_gaps = true;
  // A bracket point a little more than the tolerance above the stopped end lo (or below the
  // perforating end hi) is moved to just inside it, by at most half the tolerance:
  // its perforation (or stop) then ends the search on its own. Left where the prior put it, a
  // point at lo + 1.0025 tol that perforated first left a bracket a hair wider than the
  // tolerance, which waited 25 s for the slower run beside it (default scene, 2026-12-07).
  bool decisive_points = true;
  // Runs end as perforated once the projectile is passing through (the scene key
  // solver.decide_passing, docs/MODEL.md §8): after some element broke, held only by yarns
  // with no intact path to a clamp, and at its present drag it would travel further than the
  // fabric's largest half-size before stopping. Near the limit a perforating run otherwise drags the free yarns through
  // the weave for another millisecond at an almost constant speed.
  bool decide_passing = true;
};

// The fast search's rules by name (--without, limit.json's rules): what each does.
struct FastRuleInfo {
  const char* name;
  bool FastRules::*on;
  const char* what;
};
const std::vector<FastRuleInfo>& fast_rule_table();
// "ksection, cancel_moot, ...": the names, for messages and help.
std::string fast_rule_names();
// Turn the rule named `name` off in `rules`; false (nothing changed) for a name not in the table.
bool leave_out_rule(FastRules& rules, const std::string& name);
// The scene overrides the rules ask of every run (decide_passing: solver.decide_passing=true).
void add_rule_overrides(const FastRules& rules, std::vector<std::string>& overrides);
struct LimitOptions {
  double start_mps = 100;  // first velocity tried
  double growth = 1.5;     // bracketing factor
  // Each further bracketing step raises the factor to this power (1 = constant steps): a
  // search that starts near its limit takes small steps, one that starts far off still
  // reaches it in a few (1.15, 1.23, 1.37, 1.6, 2.0, ... with 1.5).
  double growth_accel = 1.0;
  double tolerance_mps = 1.0;  // stop when hi - lo <= tolerance
  double min_mps = 1, max_mps = 3000;
  int max_runs = 60;
  std::vector<double> fit_factors{1.25, 1.6, 2.2, 3.0};  // extra runs at BL x factor for the fit
  // The fast search only (find_ballistic_limit_fast): runs in flight at once, and its rules.
  int jobs = 1;
  FastRules rules;
  double fit_reuse_window = 0.10;  // a run within this fraction of BL x factor stands for that fit run
  double probe_step = 0.05;        // FastRules::probe_below: probes at hi x (1 - k probe_step) ...
  int probe_count = 4;             // ... k = 1 .. probe_count (down to 80 % of hi)
};

struct LambertJonas {
  bool ok = false;
  double a = 1, p = 2, vbl_mps = 0;
  double rms_mps = 0;  // root-mean-square residual of the fit
  int points = 0;
  std::string note;
  double residual_at(double v) const;
};

// Least squares over (a, p, Vbl): for fixed (p, Vbl) the best a is closed-form; (p, Vbl)
// by Nelder-Mead with Vbl in [0, min V) and p in [1, 10]. Needs >= 3 points with Vr > 0.
// `vbl_hint` seeds the search (e.g. the bisection result); <= 0: from the data.
LambertJonas fit_lambert_jonas(const std::vector<double>& v, const std::vector<double>& vr, double vbl_hint = -1);

struct LimitResult {
  bool bracketed = false, converged = false;
  double lo_mps = 0;               // highest velocity that did not perforate
  double hi_mps = 0;               // lowest velocity that perforated
  double ballistic_limit_mps = 0;  // (lo + hi) / 2, within tolerance / 2 of either end
  std::vector<Shot> runs;          // every run, in order
  LambertJonas fit;
  std::vector<std::string> warnings;
  double wall_time_s = 0;
  bool interrupted = false;  // the search stopped at an interruption: runs holds what finished
  // How it was found: "reference" (find_ballistic_limit: bisection, one run at a time, every
  // run to its end) or "fast" (find_ballistic_limit_fast), the rules that were on, and runs in
  // flight at once.
  std::string method = "reference";
  std::vector<std::string> rules;
  int jobs = 1;
  int rounds = 0;          // the longest chain of runs each started after the one before ended
  int runs_cancelled = 0;  // runs stopped before their end (fast search): listed, never used
  // Error estimate of ballistic_limit_mps: half the final bracket (the limit is in it when the
  // outcome is a threshold in velocity) plus what the rules may add (none of today's: each
  // bracket end is a full run).
  double error_mps = -1;
  std::string error_note;
};

// Whether a search's runs form a threshold in velocity. Decided runs only (no cancelled,
// failed or undecided one). The outcome is a threshold when every stop lies below the lowest
// perforation; otherwise [lowest_perforation, highest_stop] is a band where outcomes
// alternate, and `against` counts the runs whose outcome contradicts the bracket (a
// perforation below lo or a stop above hi).
//
// With it the V50 of ballistic testing (MIL-STD-662F, "V50 ballistic test for armor"): the
// mean of an equal number of the highest stops (partial penetrations) and the lowest
// perforations (complete penetrations), here up to kV50Pairs of each, from the same runs
// (decided, not failed or cancelled); `v50_spread` is the range of the velocities averaged.
// It is the mean of the runs nearest the limit on each side, not necessarily inside the
// band (a stopped fit run far above the bracket counts too), and the search places no run
// for it.
constexpr int kV50Pairs = 3;
struct OutcomeBand {
  double lowest_perforation = -1;  // -1: no run perforated
  double highest_stop = -1;        // -1: no run stopped
  bool threshold = true;
  int against = 0;
  double v50 = -1;         // -1: no stop or no perforation among the decided runs
  int v50_pairs = 0;       // stops (= perforations) averaged
  double v50_spread = -1;  // highest minus lowest velocity averaged
};
OutcomeBand outcome_band(const LimitResult& r);

// What a fast search reports as it goes (hooks called on the search's own thread).
struct LimitProgress {
  double lo_mps = -1, hi_mps = -1;  // the bracket so far (-1: no such end yet)
  double guess_mps = -1;            // the residual-velocity guess of the limit (-1: none)
  int finished = 0, cancelled = 0;  // runs so far
  std::vector<Shot> in_flight;      // velocity, purpose and started_s of each run still going
  double elapsed_s = 0;
  double eta_s = -1;  // time left (-1: not known yet)
  int jobs = 1;
  std::string line() const;  // "12 runs (2 cancelled), bracket 70.1 - 71.0 m/s, 2 in flight, ~40 s left"
};

struct LimitHooks {
  std::function<void(const Shot&)> on_start;                         // a run started
  std::function<void(const Shot&, const LimitProgress&)> on_finish;  // a run ended (or was cancelled)
};

LimitResult find_ballistic_limit(const ShootFn& shoot, const LimitOptions& opt, bool with_fit = true);

// The fast search: the same bracket guarantee (a stopped and a perforating full run at most
// tolerance apart) with opt.jobs runs in flight, each on its own thread, and opt.rules.
// `prior` holds runs already made (e.g. kept in a cache folder by an interrupted search):
// they count as finished runs. On `interrupt` every run is stopped and the result says
// interrupted. Throws what `run` throws (other than stopping).
LimitResult find_ballistic_limit_fast(const RunFn& run, const LimitOptions& opt, bool with_fit = true,
                                      const std::atomic<bool>* interrupt = nullptr, const LimitHooks& hooks = {},
                                      const std::vector<Shot>& prior = {});

// The same search on a virtual clock, without threads: each run of `target` lasts its
// Shot::wall_time_s (<= 0: 1 s) and a cancelled one ends when cancelled. Deterministic; for
// tests and for what-if estimates of a rule's saving. wall_time_s is the virtual time.
LimitResult simulate_fast_search(const ShootFn& target, const LimitOptions& opt, bool with_fit = true);

// A progress line for a search that has made `runs` so far: "run k of about N, ~T left"
// once the outcomes bracket the limit (N = k + the bisections that take the bracket below
// the tolerance + the fit runs still to make; T from the mean time of the runs made here),
// "run k, bracketing (P perforated, S stopped)" before.
std::string limit_progress(const std::vector<Shot>& runs, const LimitOptions& opt, bool with_fit);

// A ShootFn that runs `scene_path` with `overrides` plus projectile.velocity_mps=V.
// `on_run` (optional) sees each finished Simulation (e.g. to keep a frame). A diverged
// run comes back with failed = true (the search stops there: a bracket built on it would
// be meaningless); an interrupted one throws std::runtime_error.
// With `cache_dir`, each finished run is kept as cache_dir/runs/v<V>.json and a later call
// for the same velocity, scene and ravel build reads it back (Shot::resumed) instead of
// running again: an interrupted search resumes where it stopped.
ShootFn scene_shooter(const std::string& scene_path, const std::vector<std::string>& overrides,
                      const std::atomic<bool>* interrupt = nullptr, std::function<void(const Simulation&)> on_run = {},
                      const std::string& cache_dir = "");

// scene_shooter's runs as a RunFn: each call runs with its own `stop` flag (the search sets
// it when the run became moot, and on an interruption).
RunFn scene_runner(const std::string& scene_path, const std::vector<std::string>& overrides,
                   std::function<void(const Simulation&)> on_run = {}, const std::string& cache_dir = "");
// The runs kept in cache_dir/runs/ that stand for this scene and build (resumed = true), by
// velocity: a fast search's `prior`.
std::vector<Shot> kept_runs(const std::string& scene_path, const std::vector<std::string>& overrides,
                            const std::string& cache_dir);

// One run of limit.json's "runs" (or of a kept DIR/runs/ file) read back.
Shot shot_from_json(const nlohmann::json& q);

// A lumped or graded mesh moves the default scene's ballistic limit by several m/s
// (docs/tradeoff.md): the warning a search on such a scene carries, "" for a full mesh.
std::string lumped_mesh_warning(const Scene& scene);

// limit.json: the result, the fit, every run, and what was run.
std::string limit_json(const LimitResult& r, const LimitOptions& opt, const std::string& scene_path,
                       const std::vector<std::string>& overrides);
// ... and read back (throws on text that is not JSON).
LimitResult limit_from_json(const std::string& text);

}  // namespace ravel::studies
