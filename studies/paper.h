// The paper's studies (SPEC §9) reproduced with the default scene, written as charts,
// images and DIR/report.md with a claim-by-claim comparison.
//
// Runs go through the sweep machinery (parallel, resumable) and the ballistic-limit
// search (one search per friction coefficient, searches in parallel). Images are drawn
// by a callback so this library stays free of OpenGL.
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "frame.h"

namespace ravel::studies {

struct PaperPlan {
  bool quick = false;
  std::vector<double> velocities_mps;         // Fig. 11, 13
  std::vector<double> frictions;              // Fig. 13, 14
  std::vector<double> failure_strains;        // Fig. 11 (at mu = 0.2)
  std::vector<double> limit_frictions;        // Fig. 16 (plus the pin-jointed model)
  std::vector<double> image_velocities_mps;   // Fig. 8, 12 (at mu = 0.2)
  std::vector<double> image_limit_frictions;  // Fig. 17: images at the BL
  double history_velocity_mps = 260;          // Fig. 14, 15
  double limit_tolerance_mps = 1;
  // Every run ends at perforation or rebound (solver.end_time_us = auto, at most
  // solver.max_end_time_us): an energy absorbed or a BL outcome taken from an undecided run
  // would mean nothing.
  // What-if of the crossings' compression law (docs/MODEL.md §4): 260 m/s runs at mu = 0 and
  // 0.2 with each F_half (N) and each c_min (mm), the other at the scene's value.
  std::vector<double> compression_forces_n, flattened_gaps_mm;
  std::vector<std::string> velocity_overrides;  // what quick mode changes for Fig. 8, 11-15
  std::vector<std::string> limit_overrides;     // ... and for the BL searches (Fig. 16, 17)
  std::string description;                      // one line for charts and the report
};

PaperPlan paper_plan(bool quick);

struct PaperOptions {
  std::string scene_path;              // resolved path of the base scene
  std::vector<std::string> overrides;  // user --set, applied before the plan's
  std::string out_dir;
  int jobs = 1;
  bool quick = false;
  // The ballistic-limit searches: false (default), the fast search of `ravel limit`, one run
  // in flight per search, with its probes below the bracket (the limit is the lowest velocity
  // that perforates, SPEC §8); true, the bisection of `ravel limit --reference`, which can
  // land on a higher alternation where outcomes are not a threshold in velocity.
  bool reference_limits = false;
  // Draw `frame` to a PNG at `path`; returns false and says why when it cannot.
  std::function<bool(const Frame& frame, const std::string& path, std::string* error)> render_png;
  // Progress: stage name, cases done, cases total, and how many of the done ones were
  // found finished by an earlier, interrupted call (kept, not run again).
  std::function<void(const std::string& stage, int done, int total, int kept)> on_progress;
};

struct PaperResult {
  std::string report_path;
  double wall_time_s = 0;
  int runs = 0;
  double runs_per_hour = 0;
  int claims_agree = 0, claims_partly = 0, claims_differ = 0, claims_unknown = 0;
  std::vector<std::string> warnings;
};

// Throws on bad input / output errors; an interrupt stops between runs (rerun resumes).
PaperResult run_paper(const PaperOptions& opt, const std::atomic<bool>* interrupt = nullptr);

}  // namespace ravel::studies
