// The app's UI-thread state and panels (app/gui/cmd_gui.cpp runs the window and the loop).
//
// Everything here lives on the main thread: the panels edit `draft` (a Scene) and send
// commands to the SimWorker; they read only `view`, the copy SimWorker::sync() brings
// up to date once per UI frame, and the timeline of frames kept from it.
//
// Files: gui_panels.cpp (left panel, charts, status), gui_timeline.cpp (time slider,
// picking, the picked item), gui_keys.cpp (every scene key, Open scene), gui_export.cpp
// (VTK series, image sequences), gui_studies.cpp (sweep and ballistic-limit windows),
// gui_demos.cpp (demos and compare, a mode of its own).
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "render/picking.h"
#include "render/renderer.h"
#include "sim_worker.h"
#include "timeline.h"

namespace ravel::app::gui {

struct ExportJob;        // gui_export.cpp
struct StudiesWindow;    // gui_studies.cpp
class CompareMode;       // gui_demos.h
struct StabilityWindow;  // gui_jobs.h (with the studies' ImGui charts)

// What the user picked in the 3D view (render/picking.h): an element or a crossing of the
// modelled part, seen in one mirrored copy.
struct Picked {
  int element = -1;
  int crossing = -1;
  int copy = 0;
  std::array<float, 3> mirror{1, 1, 1};
  bool any() const { return element >= 0 || crossing >= 0; }
};

struct GuiApp {
  GuiApp();
  ~GuiApp();
  GuiApp(const GuiApp&) = delete;
  GuiApp& operator=(const GuiApp&) = delete;

  SimWorker* worker = nullptr;
  WorkerView view;  // the UI's copy of the worker's last published step

  // Time travel: the frames kept of the current run, and whether the view follows the run
  // (live) or shows a kept frame (scrubbing; the run goes on behind it).
  Timeline timeline;
  std::uint64_t timeline_serial = 0;  // the newest frame the timeline has seen
  bool live = true;
  std::size_t scrub_index = 0;
  Frame scrub_frame;               // timeline.frame(scrub_index) while !live
  std::uint64_t scrub_serial = 1;  // changes when the scrubbed frame does (the view cache redraws)
  // The frame on screen and its time (the scrubbed one, or the run's latest).
  const Frame& shown() const { return live ? view.frame : scrub_frame; }
  std::uint64_t shown_serial() const { return live ? view.frame_serial : (std::uint64_t(1) << 62) + scrub_serial; }
  // Show the kept frame nearest to t (seconds). It stays a kept frame even at the run's
  // newest one: go_live() (the Live button, End key) follows the run again.
  void scrub_to(double t_s);
  void go_live() { live = true; }

  Picked picked;
  // The size of the model the pick was made on (nodes, elements, crossings): a run of a
  // different model clears the pick, since its numbers name other parts.
  std::array<std::size_t, 3> picked_model{0, 0, 0};

  Scene draft;                // what the Scene / Projectile / Solver panels edit
  bool auto_restart = false;  // restart as soon as a panel value changes
  std::string scene_error;    // the draft does not validate (names the key)

  Pacing pacing;  // mirrors the worker's
  double pause_at_us = -1;

  render::Camera camera;
  render::ViewOptions view_options;
  bool camera_needs_fit = true;
  bool range_locked = false;  // view_options.range_min/max hold a fixed colour range
  std::string mode_field;     // compare / demos: the colour field they draw with ("" = the View panel's)
  // 3D view resolution while a run plays or the mouse drags (render::ViewOptions::
  // render_scale); the view settles to full resolution when everything is still.
  float playing_render_scale = 1.0f;
  float ui_scale = 1.0f;  // the monitor's content scale (fonts, paddings, 3D overlays)

  std::string export_dir = "ravel_export";
  std::string notice;  // last export / action result, shown in the status panel
  bool notice_is_error = false;
  bool script_failed = false;   // a scripted action failed: the app exits non-zero at the end
  std::string script_error;     // its message, already on stderr (not repeated at exit)
  bool script_waiting = false;  // a scripted `wait` holds the script until the app is idle
  bool layout_check = false;    // RAVEL_LAYOUT_CHECK: open every section, report clipped panels
  std::vector<std::string> layout_problems;
  bool screenshot_requested = false;
  std::string screenshot_path;  // where the requested screenshot goes

  // Open scene: the path typed, recent files (newest first), the last error.
  std::string open_path;
  std::deque<std::string> recent_scenes;
  std::string open_error;
  bool show_open = false;
  bool show_keys = false;  // the "All scene keys" window

  // The "Scene keys" window: the filter, the last refused edit, the field being typed in.
  std::string keys_filter, keys_error, keys_active;
  std::map<std::string, std::string> keys_editing;

  // The 3D view's mouse: a drag that started in the view, where it started, how far it went.
  bool dragging = false;
  float press_x = 0, press_y = 0, drag_px = 0;

  std::unique_ptr<ExportJob> export_job;
  std::unique_ptr<StudiesWindow> studies;
  std::unique_ptr<StabilityWindow> stability;
  CompareMode* compare = nullptr;  // the compare / demos mode (owned by the main loop)

  bool show_help = false;
  bool quit = false;

  // Layout (pixels, window coordinates), computed each frame.
  float menu_h = 0;
  float left_w = 0, bottom_h = 0, status_w = 0, timeline_h = 0;
  float view_x = 0, view_y = 0, view_w = 0, view_h = 0;  // 3D view, y from the top

  float fps = 0;
  std::vector<std::string> shipped_scenes;  // paths of assets/scenes/*.toml
};

// Validate the draft (round trip through the scene parser so warnings are fresh) and
// restart the worker with it. Returns false (and sets scene_error) if it is invalid.
bool restart_with_draft(GuiApp& app);
// Apply `key=value` to the draft the way `--set` does. Throws SceneError.
void set_draft_value(GuiApp& app, const std::string& key_value);
// Load a scene file (or a run folder holding scene.toml) through the scene checker; on
// success it becomes the draft and the run restarts with it, on failure the current run is
// kept and app.open_error (and the notice) say what is wrong, with file:line.
bool open_scene(GuiApp& app, const std::string& path);

// Panels. Each lays itself out in the rectangle given by the layout fields of app.
void draw_left_panel(GuiApp& app);    // run controls, scene, projectile, friction, solver, view, export
void draw_charts_panel(GuiApp& app);  // projectile velocity and the energy ledger vs time
void draw_status_panel(GuiApp& app);  // time, speed, model size, outcome, warnings
void draw_timeline_bar(GuiApp& app);  // the time slider under the 3D view (gui_timeline.cpp)
// With app.layout_check: note the current fixed panel's content that does not fit it
// (wider than the panel, or taller without a scroll bar). Call before its End().
void check_layout(GuiApp& app, const char* panel);
// A "(?)" after the last item whose tooltip is `text` (gui_panels.cpp).
void help_marker(const char* text);
void draw_picked_window(GuiApp& app);    // the picked element or crossing (gui_timeline.cpp)
void draw_keys_window(GuiApp& app);      // every scene key (gui_keys.cpp)
void draw_open_window(GuiApp& app);      // Open scene (gui_keys.cpp)
void draw_export_progress(GuiApp& app);  // a running export (gui_export.cpp)
void draw_studies_windows(GuiApp& app);  // sweep and limit (gui_studies.cpp)
void studies_menu_items(GuiApp& app);    // entries of the Studies menu

// Picking at a pixel of the 3D view (window coordinates); `crossing` picks crossings.
void pick_at(GuiApp& app, float x, float y, bool crossing);
void pick_element(GuiApp& app, int element);    // by id (copy 0)
void pick_crossing(GuiApp& app, int crossing);  // by id (copy 0)
// Keep the timeline in step with the worker (once per UI frame, after sync).
void update_timeline(GuiApp& app);

// Exports (atomic files). Each sets app.notice; false on failure.
bool export_results(GuiApp& app);  // history.csv + summary.json
bool export_scene(GuiApp& app);    // scene.toml that reproduces the current run
// The kept frames as a VTK series into dir (one VTU per frame + frame.pvd), or the 3D view
// of each kept frame as PNGs (and an MP4 when ffmpeg is installed). Both run a few frames
// per UI frame with a progress bar; false if they cannot start (app.notice says why).
bool start_vtk_export(GuiApp& app, const std::string& dir);
bool start_image_export(GuiApp& app, const std::string& dir);
// Advance a running export (call once per UI frame with a current GL context); the image
// export draws with `renderer` into its own target at the 3D view's size.
void step_export(GuiApp& app, render::Renderer& renderer, int view_w_px, int view_h_px);
bool export_running(const GuiApp& app);
bool studies_running(const GuiApp& app);
// Scripted studies (--do sweep:KEY=LIST, --do limit): start into export_dir/sweep, /limit.
bool start_scripted_sweep(GuiApp& app, const std::string& vary);  // KEY=LIST[;KEY=LIST...]
// The sweep's charts into its folder's charts/ (the window's Save charts), x = x_key if given.
bool write_scripted_sweep_charts(GuiApp& app, const std::string& x_key);
bool start_scripted_limit(GuiApp& app, const std::string& jobs = "");  // jobs: runs in flight, "" = the window's
std::string next_screenshot_path(const GuiApp& app);

}  // namespace ravel::app::gui
