// Sweeps: many runs of one scene with some keys varied, each run a "case".
//
// A case is a list of scene overrides ("projectile.velocity_mps=300"). Its folder name is
// made from those settings, so a rerun (even with a longer --vary list) finds the cases it
// already finished. Each case is run in a hidden temporary folder and renamed into place
// only when history.csv, scene.toml, case.json and summary.json are all written: a case
// folder either exists complete or not at all. Cases run on a pool of threads, each with
// its own Simulation (solver.threads = 1 unless asked otherwise), so results never depend
// on --jobs. --shard i/n keeps cases whose index k satisfies k mod n == i - 1.
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "chart.h"
#include "scene.h"
#include "simulation.h"

namespace ravel::studies {

// A bad --vary / --shard / --jobs value: names the flag (and key) and the problem.
class StudyError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Vary {
  std::string key;                  // scene key, e.g. projectile.velocity_mps
  std::vector<std::string> values;  // as text, exactly as they go into --set
};

// "key=start:stop:step" (inclusive of stop within 1e-9 of a step) or "key=v1,v2,...".
// Checks the key against scene_keys() and each value against the scene's validation
// (applied to `base`). Throws StudyError naming the flag, key and problem.
Vary parse_vary(const std::string& text, const std::string& base_scene_path = "",
                const std::vector<std::string>& base_overrides = {});

struct Case {
  int index = 0;                                              // position in the full sweep
  std::vector<std::pair<std::string, std::string>> settings;  // key, value
  std::string name() const;                                   // folder name, from the settings
  std::vector<std::string> overrides() const;                 // "key=value"
};

// Every combination; the last --vary changes fastest.
std::vector<Case> expand_cases(const std::vector<Vary>& vary);

// Repeats (`ravel sweep --repeats N`): near the ballistic limit the outcome of one run is a
// random variable. A change of 1e-9 of the impact velocity changes which crossing slips or
// which element breaks first, and that decides perforation (docs/studies.md, "The zone of
// mixed results"). Each velocity v of a --vary projectile.velocity_mps becomes N velocities
// v + k x 1e-6 m/s, k = 0..N-1, each its own case (repeat 0 is v as given, the others have 6
// decimals), and base_of maps each value to the v it was made from. Throws StudyError when two values lie closer than
// N x 1e-6 m/s (their repeats would overlap) or N is outside [1, 1000].
inline constexpr double kRepeatStep_mps = 1e-6;
Vary repeat_velocities(const Vary& velocities, int repeats, std::map<std::string, std::string>* base_of);
// `ravel sweep --repeats N` and the app's Sweep window: N from 1 to 1000, and with N > 1 the
// --vary projectile.velocity_mps among `vary` repeated (repeat_velocities). Throws StudyError
// naming the problem (N out of range, no velocity varied, overlapping repeats).
void apply_repeats(std::vector<Vary>& vary, int repeats, std::map<std::string, std::string>* base_of);

struct Shard {
  int index = 1, count = 1;  // 1-based: 1/1 = everything
  bool contains(int case_index) const { return case_index % count == index - 1; }
};
Shard parse_shard(const std::string& text);  // "i/n", 1 <= i <= n
std::vector<Case> shard_cases(const std::vector<Case>& all, Shard shard);

struct SweepOptions {
  std::string scene_path;              // "" = default scene
  std::vector<std::string> overrides;  // base --set overrides, applied before each case's
  std::string out_dir;
  int jobs = 1;            // concurrent cases
  int solver_threads = 1;  // solver.threads of each case
  Shard shard;
  // A case that reaches its end time undecided (neither perforated nor stopped) goes on to
  // solver.max_end_time_us, so that no undecided run counts as stopped (SPEC §8). false: the
  // scene's end time is a hard end (`ravel sweep --no-extend`).
  bool extend_undecided = true;
  // The folder holds finished cases of another sweep (another scene, --set, scene file
  // content or ravel build): false refuses to mix them in, true removes them first.
  bool restart = false;
  // Whether the command offers --restart (the refusal above says so only then).
  bool offers_restart = false;
};

// One finished (or previously finished) case.
struct CaseResult {
  Case c;
  bool skipped = false;  // found finished on disk, not run now
  bool ok = true;        // false: failed to run (error text in error)
  std::string error;
  std::string summary_json_text;  // the case's summary.json
};

// The pace of a batch of runs, for progress lines: after each run, "[k/N]" and, while runs
// remain, "  (about T s left)" at the mean time of the runs done so far (runs found
// finished cost nothing and do not count in the pace).
class TimeLeft {
 public:
  explicit TimeLeft(int total);
  void step(bool skipped);      // counts one finished run
  std::string counter() const;  // "[k/N]"
  std::string left() const;     // "  (about T s left)", or "" when none remain or none ran yet
  // For a stage that reports only done of total: "[k/N]" and the time left at the pace of
  // the done ones that were not kept from an earlier call.
  std::string at(int done, int total, int kept = 0) const;

 private:
  int total_, ended_ = 0, ran_ = 0;
  double t0_s_;
};

struct SweepProgress {
  int total = 0;    // cases in this shard
  int done = 0;     // finished now or before
  int skipped = 0;  // found finished
  int failed = 0;
  double wall_time_s = 0;
};

struct SweepReport {
  int cases_total = 0;  // in the whole sweep
  int cases_in_shard = 0;
  int cases_run = 0;      // run now
  int cases_skipped = 0;  // already finished
  int cases_failed = 0;
  int cases_diverged = 0;  // ran but the simulation diverged (still written)
  double wall_time_s = 0;
  double cases_per_hour = 0;  // cases run now / wall hours
  bool interrupted = false;
  std::vector<std::string> errors;
};

// Hooks are called from worker threads, one at a time (under a lock).
struct SweepHooks {
  std::function<void(const SweepProgress&)> on_progress;
  std::function<void(const CaseResult&)> on_case;
  // Called after each case's Simulation finished, before its folder is renamed into place
  // (extra outputs, e.g. images; `case_tmp_dir` is the folder being prepared).
  std::function<void(const Case&, const Simulation&, const std::string& case_tmp_dir)> on_simulation;
};

// Run `to_run` (this shard's cases) in parallel; resumes; writes DIR/results.csv with
// every finished case of `all_cases` (not only this shard's), and DIR/sweep.json.
SweepReport run_sweep(const std::vector<Case>& all_cases, const std::vector<Case>& to_run, const SweepOptions& opt,
                      const std::vector<std::string>& varied_keys, const SweepHooks& hooks = {},
                      const std::atomic<bool>* interrupt = nullptr);

// Is the case finished in `out_dir` (its folder holds summary.json)?
bool case_finished(const std::string& out_dir, const Case& c);
std::string case_dir(const std::string& out_dir, const Case& c);

// results.csv: columns = varied keys, then every scalar key of summary.json, in order.
// One row per finished case (cases not finished are left out). Returns the CSV text.
std::string results_csv(const std::string& out_dir, const std::vector<Case>& cases,
                        const std::vector<std::string>& varied_keys);

// Parse a CSV (as written here) into a header and rows of cells.
struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  int column(const std::string& name) const;  // -1 if absent
  // A row's value in the named column; "" when the column is absent or the row is short.
  std::string cell(const std::vector<std::string>& row, const std::string& name) const;
};
Csv parse_csv(const std::string& text);

// Charts of a sweep's results.csv: energy absorbed and residual velocity, then each of
// `extra_y` (other columns of results.csv, `ravel sweep --chart-y`), against the first
// varied key (when its values are numbers), one series per combination of the other varied
// keys. Each chart's file stem is returned beside it.
std::vector<std::pair<std::string, Chart>> sweep_charts(const Csv& results, const std::vector<std::string>& varied_keys,
                                                        const std::vector<std::string>& extra_y = {});
// The perforation probability of a sweep with repeats: results.csv's rows grouped by every
// varied key, velocities by the value they were repeated from (base_of, from
// repeat_velocities; a value not in it stands for itself). `csv`: one row per group, the
// varied keys then runs, perforated, perforation_probability (perforated / decided runs;
// undecided and diverged runs are counted apart), residual_velocity_mps (mean over the
// perforating runs) and energy_absorbed_J (mean); `chart`: the probability against
// varied_keys[0], one series per combination of the others (empty when that key is not
// numeric).
struct PerforationTable {
  std::string csv;
  Chart chart;
  int groups = 0;
};
PerforationTable perforation_table(const Csv& results, const std::vector<std::string>& varied_keys,
                                   const std::map<std::string, std::string>& base_of);
// After a sweep into out_dir: with repeats > 1 (and some finished cases) perforation.csv and
// charts/perforation_probability_vs_<varied_keys[0]>.{png,svg,csv}, written atomically; the
// paths written are returned (the chart's as its stem) and *groups set. With repeats <= 1
// those files are removed if a rerun with repeats left them: they would disagree with
// results.csv.
std::vector<std::string> write_perforation_outputs(const std::string& out_dir, const Csv& results,
                                                   const std::vector<std::string>& varied_keys,
                                                   const std::map<std::string, std::string>& base_of, int repeats,
                                                   int* groups = nullptr);

// The unit a results.csv column's name ends in ("energy_absorbed_J" -> "J", "_mps" -> "m/s";
// "" for counts and ratios), and its words ("energy absorbed").
std::string column_unit(const std::string& column);
std::string column_label(const std::string& column);
// The varied keys with x_key first, for sweep_charts (`ravel sweep --chart-x`, the app's x
// axis): false, keys unchanged, when x_key is not among them.
bool put_chart_x_first(std::vector<std::string>* keys, const std::string& x_key);
// "a, b, c": the keys a sweep varies, for messages.
std::string joined_keys(const std::vector<std::string>& keys);
std::string read_text_file(const std::string& path);

}  // namespace ravel::studies
