// Where the methods fail (SPEC §10, docs/tradeoff.md): maps of runs over two keys each,
// every cell classified
//   stable    the run completed and the method's assumptions held,
//   warned    it completed but the nearest-pair assumption broke (yarns slid more than
//             one node in a step, or passed through each other: summary warnings),
//   diverged  the solver stopped it (energy balance, NaN, search lost, ...),
//   failed    it could not run (bad setting).
// The default maps: time-step factor 0.1..2 for each contact model; contact iterations
// 1..8 at friction 0.2, 1 and 10; impact velocity up to 1000 m/s at three time-step
// factors. Runs go through the sweep machinery (one sweep folder per map: parallel,
// atomic, resumable).
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "chart.h"
#include "sweep.h"

namespace ravel::studies {

struct StabilityMapSpec {
  std::string name;  // folder and file stem, e.g. "dt_factor"
  std::string title;
  Vary x, y;                       // columns, rows
  std::vector<std::string> fixed;  // extra overrides for this map only
};

// The default maps (quick: fewer cells).
std::vector<StabilityMapSpec> default_stability_maps(bool quick = false);

struct StabilityCell {
  std::string map, x_key, x_value, y_key, y_value;
  std::string status;     // stable | warned | diverged | failed
  std::string diagnosis;  // in words
  std::string cause;      // diverged: divergence_cause; warned: search | pass_through | search+pass
  std::string detail;     // warned: how often ("search 47, pass 22"); the chart's cell text
  double wall_time_s = 0;
  double end_time_us = 0;  // simulated time reached
};

// Classify a run from its summary.json text.
StabilityCell classify_summary(const std::string& summary_json_text);

struct StabilityOptions {
  std::string scene_path;
  std::vector<std::string> overrides;
  std::string out_dir;
  std::vector<StabilityMapSpec> maps;  // default_stability_maps() unless set
  int jobs = 1;
  int solver_threads = 1;
  std::function<void(const std::string&)> on_progress;
};

struct StabilityResult {
  std::vector<StabilityCell> cells;
  std::vector<StabilityMapSpec> maps;
  std::vector<std::string> critical;                        // per dt map row: the model's critical_dt_factor, in words
  std::vector<std::pair<std::string, double>> critical_dt;  // (y value, critical_dt_factor) of the dt map
  double wall_time_s = 0;
  int runs_made = 0;  // run by this invocation
  int runs_kept = 0;  // finished by an earlier, interrupted one (DIR/<map>/<case>/ kept)
  bool interrupted = false;
  std::vector<std::string> errors;
};

StabilityResult run_stability(const StabilityOptions& opt, const std::atomic<bool>* interrupt = nullptr);

std::string stability_csv(const StabilityResult& r);
// Read back stability.csv (e.g. in the app).
std::vector<StabilityCell> parse_stability_csv(const std::string& text);
// One categorical grid chart per map (file stem first), from cells alone.
std::vector<std::pair<std::string, Chart>> stability_charts(const std::vector<StabilityCell>& cells,
                                                            const std::string& subtitle = "");
// The words: per map and row, where runs stop being stable; the dt boundary against theory.
std::string stability_markdown(const StabilityResult& r, const StabilityOptions& opt);
// The one-paragraph summary per map (also the stdout verdict).
std::vector<std::string> stability_sentences(const StabilityResult& r);

}  // namespace ravel::studies
