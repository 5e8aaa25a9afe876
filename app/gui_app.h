// The app's UI-thread state and panels (app/cmd_gui.cpp runs the window and the loop).
//
// Everything here lives on the main thread: the panels edit `draft` (a Scene) and send
// commands to the SimWorker; they read only `view`, the copy SimWorker::sync() brings
// up to date once per UI frame.
#pragma once

#include <string>
#include <vector>

#include "render/renderer.h"
#include "sim_worker.h"

namespace ravel::app::gui {

struct GuiApp {
  SimWorker* worker = nullptr;
  WorkerView view;  // the UI's copy of the worker's last published step

  Scene draft;                // what the Scene / Projectile / Solver panels edit
  bool auto_restart = false;  // restart as soon as a panel value changes
  std::string scene_error;    // the draft does not validate (names the key)

  Pacing pacing;  // mirrors the worker's
  double pause_at_us = -1;

  render::Camera camera;
  render::ViewOptions view_options;
  bool camera_needs_fit = true;
  // 3D view resolution while a run plays or the mouse drags (render::ViewOptions::
  // render_scale); the view settles to full resolution when everything is still.
  float playing_render_scale = 1.0f;

  std::string export_dir = "ravel_export";
  std::string notice;  // last export / action result, shown in the status panel
  bool notice_is_error = false;
  bool screenshot_requested = false;
  std::string screenshot_path;  // where the requested screenshot goes

  bool show_help = false;
  bool quit = false;

  // Layout (pixels, window coordinates), computed each frame.
  float left_w = 0, bottom_h = 0, status_w = 0;
  float view_x = 0, view_y = 0, view_w = 0, view_h = 0;  // 3D view, y from the top

  float fps = 0;
  std::vector<std::string> shipped_scenes;  // paths of assets/scenes/*.toml
};

// Validate the draft (round trip through the scene parser so warnings are fresh) and
// restart the worker with it. Returns false (and sets scene_error) if it is invalid.
bool restart_with_draft(GuiApp& app);
// Apply `key=value` to the draft the way `--set` does. Throws SceneError.
void set_draft_value(GuiApp& app, const std::string& key_value);

// Panels. Each lays itself out in the rectangle given by the layout fields of app.
void draw_left_panel(GuiApp& app);    // run controls, scene, projectile, friction, solver, view, export
void draw_charts_panel(GuiApp& app);  // projectile velocity and the energy ledger vs time
void draw_status_panel(GuiApp& app);  // time, speed, model size, outcome, warnings

// Exports (atomic files). Each sets app.notice.
void export_results(GuiApp& app);  // history.csv + summary.json
void export_scene(GuiApp& app);    // scene.toml that reproduces the current run
std::string next_screenshot_path(const GuiApp& app);

}  // namespace ravel::app::gui
