// Internal to the app's GUI files: the state of a running export and of the Studies
// windows, owned by GuiApp (gui_app.h) through unique_ptrs.
#pragma once

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "vtk.h"
#include "gui_app.h"
#include "render/render_target.h"
#include "limit.h"
#include "sweep_runner.h"
#ifdef RAVEL_HAVE_STUDIES_IMGUI
#include "chart_imgui.h"
#include "stability.h"
#endif

namespace ravel::app::gui {

// A VTK series or an image sequence of the kept frames, a few frames per UI frame.
struct ExportJob {
  enum class Kind { vtk, images } kind = Kind::vtk;
  std::string dir;
  std::vector<double> times;        // the kept frames' times when it started (the timeline may thin)
  std::size_t next = 0, total = 0;  // kept frames done / to do
  std::size_t written = 0;          // files written (frames thinned away meanwhile are skipped)
  long run_id = -1;                 // the run whose frames these are
  std::vector<PvdEntry> entries;    // vtk: the series so far
  render::RenderTarget target;      // images: drawn here at the view's size
  render::Camera camera;            // images: the view's camera when the export started
  render::ViewOptions options;
  int width = 0, height = 0;
  std::string error;
  bool done = false;
  std::string mp4;         // images: the movie written (ffmpeg), if any
  std::string mp4_status;  // images: why there is no movie (no ffmpeg, or ffmpeg failed)
};

// A ballistic-limit search on a background thread (the Studies window's limit tab).
class LimitRunner {
 public:
  struct Snapshot {
    bool running = false, finished = false;
    std::vector<studies::Shot> runs;       // every run so far, in the order they ended
    std::vector<studies::Shot> in_flight;  // runs going now (velocity, purpose, started_s)
    studies::LimitProgress progress;       // the bracket, guess and ETA after the last run
    studies::LimitResult result;           // valid when finished
    std::string error, out_dir;
    std::chrono::steady_clock::time_point started;
  };
  ~LimitRunner();
  bool start(const std::string& scene_path, const std::vector<std::string>& overrides, const std::string& out_dir,
             double tolerance_mps, int jobs, std::string* error);
  void cancel();
  bool running() const;
  Snapshot snapshot() const;

 private:
  mutable std::mutex mu_;
  Snapshot state_;
  std::atomic<bool> interrupt_{false};
  std::thread thread_;
};

struct StudiesWindow {
  bool show_sweep = false, show_limit = false;
  // Sweep: the --vary lines, folder, jobs.
  char vary[1024] = "projectile.velocity_mps=180:500:40";
  char sweep_dir[512] = "";
  int jobs = 1;
  int repeats = 1;  // each velocity of a projectile.velocity_mps line run this many times (ravel sweep --repeats)
  std::string sweep_error;
  int chart_index = 0;
  std::string chart_x;  // the charts' x axis: a varied key ("" = the first), as `ravel sweep --chart-x`
  studies::SweepRunner sweep;
  // Ballistic limit.
  char limit_dir[512] = "";
  double tolerance_mps = 2;
  int limit_jobs = int(std::max(1u, std::thread::hardware_concurrency()));  // runs in flight (`ravel limit --jobs`)
  std::string limit_error;
  LimitRunner limit;
};

#ifdef RAVEL_HAVE_STUDIES_IMGUI
// "Stability map" window (docs/tradeoff.md): loads DIR/stability.csv written by
// `ravel stability`, or runs the small time-step map of the current scene on a background
// thread (studies::run_stability, into <export folder>/stability), and draws each map
// with the ImGui chart backend (the same grid chart as the PNG/SVG files).
struct StabilityWindow {
  bool open = false;
  bool env_checked = false;  // RAVEL_STABILITY_CSV looked at
  char path[512] = "stability/stability.csv";
  std::vector<std::pair<std::string, studies::Chart>> charts;
  std::vector<std::string> sentences;
  std::string message;
  std::thread worker;
  std::atomic<bool> running{false}, interrupt{false};
  std::string result_csv;  // set by the worker before running = false
  ~StabilityWindow() {
    interrupt = true;
    if (worker.joinable()) worker.join();
  }
  void load_text(const std::string& text, const std::string& from) {
    const auto cells = studies::parse_stability_csv(text);
    charts = studies::stability_charts(cells, from);
    message = cells.empty() ? from + ": no cells" : std::to_string(cells.size()) + " cells from " + from;
  }
};

#else
struct StabilityWindow {};
#endif

}  // namespace ravel::app::gui
