// Internal to ravel_studies (not installed): the stages of run_paper and the state they
// share. run_paper (paper.cpp) calls them in order:
//
//   run_velocity_stage     velocity sweep (Fig. 8, 11-15)          paper_runs.cpp
//   run_compression_stage  compression what-if at 260 m/s          paper_runs.cpp
//   run_limit_stage        ballistic-limit searches (Fig. 16, 17)  paper_runs.cpp
//   write_images           perforation images                      paper_runs.cpp
//   make_charts            charts (SVG / CSV / PNG)                paper_report.cpp
//   make_claims            the paper's statements and verdicts     paper_claims.cpp
//   write_report           DIR/report.md                           paper_report.cpp
//
// Each stage reads what the earlier ones left in PaperState and adds its own part. The three
// run stages throw std::runtime_error when interrupted (the finished runs stay on disk; a
// rerun resumes).
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "chart.h"
#include "frame.h"
#include "limit.h"
#include "paper.h"
#include "scene.h"
#include "sweep.h"

namespace ravel::studies::paper_detail {

inline std::string num(double v, const char* f = "%g") {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}
inline bool same(double a, double b) {
  return std::abs(a - b) <= 1e-9 * std::max(1.0, std::abs(a));
}
inline double to_d(const std::string& s) {
  if (s.empty()) return NAN;
  if (s == "true") return 1;
  if (s == "false") return 0;
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  return *end ? NAN : v;
}
inline double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

constexpr double kDefaultFailure = 0.052;
constexpr double kReferenceFriction = 0.2;
// The ballistic limits the paper states in its text (§8): 71 m/s at mu = 0.1, 70 at 0.2, and
// at mu = 0 about half of BL(0.1); "about" is read as within kPaperLimitTolerance. Used by the
// Fig. 16 claim and chart, and written to claims.json for scripts/nightly.
struct PaperLimit {
  double mu, mps;
};
constexpr PaperLimit kPaperLimits[] = {{0.1, 71}, {0.2, 70}};
constexpr double kPaperLimitTolerance = 0.10;  // relative
inline double paper_limit(double mu) {
  for (const PaperLimit& p : kPaperLimits)
    if (p.mu == mu) return p.mps;
  return NAN;
}

struct VelocityRow {
  double mu = 0, failure = 0, v = 0;
  bool perforated = false;
  double energy_J = NAN, residual = NAN, perforation_time_s = NAN, friction_work_J = NAN, wall_s = NAN;
  int broken_warp_yarns = 0, broken_weft_yarns = 0;
  std::string end_reason, case_name;
};

struct CompressionRow {
  std::string key;
  double value = NAN, mu = NAN, energy_J = NAN, wall_s = NAN;
};

struct LimitEntry {
  std::string label;  // "mu=0.2" / "pin-jointed"
  double mu = NAN;    // NaN for pin-jointed
  std::vector<std::string> overrides;
  std::string dir;
  LimitResult result;
  bool have = false;
  bool kept = false;  // its limit.json was there from an earlier call
  std::string error;
  bool keep_frame = false;
  double start_mps = NAN;  // where the search began (the velocity study's fit, or the fixed start)
  std::string start_from;  // what that start is: "limit of mu=0.1", "fit", "default"
  Frame frame;             // lowest perforating run's final frame
  double frame_v = INFINITY;
};

// The paper's energy peak (Fig. 11, 13: absorbed energy rises with impact velocity "until
// about 250 m/s before it decreases with further increase"): the first velocity whose
// energy is a local maximum and falls by at least `min_fall` (relative) within the next
// `window_mps`; then whether any later velocity reaches the peak's energy again. Indices
// into the series; -1 where there is none.
struct EnergyPeak {
  int peak = -1, trough = -1;  // the peak, and the lowest point within the window after it
  double fall = 0;             // (E_peak - E_trough) / E_peak
  int regain = -1;             // the first later velocity at or above the peak's energy
};
EnergyPeak find_energy_peak(const Series& s, double min_fall = 0.15, double window_mps = 60);

// "1 weft and 0 warp yarns broken", and, when every broken yarn is one through the strike
// point (grid line 0, known from the run's broken_*_lines), that a symmetric model holds those.
std::string broken_yarns_text(const Shot& s);

// "; at the limit (its lowest perforating run, 79.5 m/s): 0.42 J before the first break
// (59.5 mm from the strike point), 19.56 J in all" for the friction claim; "" without a break.
std::string limit_friction_text(const Shot& s);

struct Claim {
  std::string figure, paper, ravel, verdict;  // verdict: agrees | partly | differs | not measured
};

// What the stages share. Filled in stage order; each field names the stage that sets it.
struct PaperState {
  PaperState(const PaperOptions& options, const std::atomic<bool>* interrupt_flag);

  // Set up by run_paper.
  const PaperOptions& opt;
  const std::atomic<bool>* interrupt = nullptr;
  const std::chrono::steady_clock::time_point t0;  // the whole call's start
  const PaperPlan plan;
  const std::vector<std::string> base;  // the user's overrides, under every run
  Scene base_scene;                     // checked once, so bad --set fails before anything runs
  PaperResult result;

  // run_velocity_stage
  SweepOptions velocity_sweep;  // also the compression what-if's options, with its own folder
  SweepReport velocity_report;
  std::vector<VelocityRow> rows;
  std::map<double, Frame> image_frames;  // by velocity, mu = 0.2, failure 5.2 %
  double velocity_wall_s = 0;

  // run_compression_stage
  std::vector<CompressionRow> compression_rows;
  int compression_runs = 0, compression_resumed = 0;
  double compression_wall_s = 0;

  // run_limit_stage
  std::vector<LimitEntry> limits;
  int limit_runs = 0;
  double limit_wall_s = 0;

  // write_images
  std::vector<std::pair<std::string, std::string>> images;  // caption, relative path
  int image_runs = 0;
  double image_wall_s = 0;

  // make_charts (histories are read there, and make_claims reads them too)
  std::vector<std::pair<std::string, std::string>> charts;  // caption, stem (relative)
  std::map<double, Csv> histories;                          // by mu, at plan.history_velocity_mps

  // make_claims
  std::vector<Claim> claims;

  void progress(const std::string& stage, int done, int total, int kept) const;
  // The user's overrides followed by `more`.
  std::vector<std::string> with(const std::vector<std::string>& more) const;
  const VelocityRow* find_row(double mu, double failure, double v) const;
  // Energy absorbed against impact velocity, over the plan's velocities that have a row.
  Series energy_series(double mu, double failure, const std::string& name) const;
};

void run_velocity_stage(PaperState& ps);
void run_compression_stage(PaperState& ps);
void run_limit_stage(PaperState& ps);
void write_images(PaperState& ps);
void make_charts(PaperState& ps);
void make_claims(PaperState& ps);
void write_report(PaperState& ps);
// DIR/claims.json (written by write_report): the verdicts and limits, for scripts.
std::string claims_json(const PaperState& ps);

}  // namespace ravel::studies::paper_detail
