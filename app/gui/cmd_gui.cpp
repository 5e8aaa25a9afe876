// `ravel gui [SCENE] [--set k=v ...]`: the interactive app. GLFW window, Dear ImGui and
// all GL on this (the main) thread; the simulation on SimWorker's std::thread
// (app/worker/sim_worker.h). Each UI frame: poll events, sync() the worker's last published
// step into the UI's own copy under a short lock, keep it in the timeline, lay out the
// panels, draw the frame on show (the run's latest, or a kept one while scrubbing) with
// render::Renderer into the 3D view, draw ImGui on top, swap.
//
// For tests and picture export the app can drive itself:
//   --frames N             quit after N frames (exit 0; non-zero if a scripted action failed)
//   --screenshot FILE      PNG of the whole window (UI included) at the last frame
//   --do FRAME:ACTION      at UI frame FRAME do ACTION (repeatable): play, pause, step,
//                          reset, restart, clear, fast, slow:US_PER_S, set:KEY=VALUE
//                          (edit a panel value), view:NAME, field:NAME, colormap:NAME,
//                          range:LO:HI | range:auto, scrub:T_US, live, pick:ELEMENT_ID,
//                          pick-crossing:ID, open:PATH, screenshot:FILE, export-results,
//                          export-scene, export-vtk:DIR, record:DIR (image sequence),
//                          sweep:KEY=LIST[;KEY=LIST][;repeats=N], sweep-charts[:X_KEY], limit[:JOBS] (into
//                          --export-dir; JOBS runs in flight), demo:NAME, continue, compare-exit
//   --pause-at-us T        pause the run when simulated time reaches T; with --frames the
//                          app keeps going past frame N until then (for reproducible pictures),
//                          and until scripted exports and studies have finished
//   --paused               open paused at t = 0
//   --view / --field       initial camera preset / colour field
//   --size WxH             window size (default 1600x1000, or 90 % of a smaller screen)
//   --export-dir DIR       the Export panel's folder (default ./ravel_export)
//   --budget-mb MB         memory for the kept frames (default 256)
#include <glad/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <cstdint>
#include <ctime>
#include <map>

#include "cli.h"
#include "commands.h"
#include "gui_app.h"
#include "gui_demos.h"
#include "gui_jobs.h"
#include "modes.h"
#include "render/render_target.h"
#include "render/renderer.h"
#include "results.h"
#include "sim_worker.h"

namespace ravel::app {

namespace {

using gui::GuiApp;

// CPU seconds used by this thread (the UI thread: events, ImGui, all GL submission and,
// under llvmpipe, vertex processing) and by the whole process.
double cpu_seconds(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

std::string g_glfw_error;
void on_glfw_error(int, const char* description) {
  g_glfw_error = description ? description : "?";
}
void* glfw_loader(const char* name) {
  return reinterpret_cast<void*>(glfwGetProcAddress(name));
}

struct ScriptAction {
  std::string action, arg;
};

std::multimap<long, ScriptAction> parse_script(const std::vector<std::string>& items) {
  std::multimap<long, ScriptAction> script;
  for (const auto& item : items) {
    const auto colon = item.find(':');
    char* end = nullptr;
    const long frame = colon == std::string::npos ? -1 : std::strtol(item.c_str(), &end, 10);
    if (colon == std::string::npos || end != item.c_str() + colon || frame < 0)
      throw UsageError("--do: expected FRAME:ACTION, got '" + item + "'");
    ScriptAction a;
    a.action = item.substr(colon + 1);
    if (const auto c2 = a.action.find(':'); c2 != std::string::npos) {
      a.arg = a.action.substr(c2 + 1);
      a.action = a.action.substr(0, c2);
    }
    static const char* known[] = {
        "play",          "pause", "step",       "reset",          "restart",      "clear",      "fast",   "slow",
        "set",           "view",  "field",      "colormap",       "range",        "scrub",      "live",   "pick",
        "pick-crossing", "open",  "screenshot", "export-results", "export-scene", "export-vtk", "record", "sweep",
        "sweep-charts",  "limit", "demo",       "continue",       "compare-exit", "wait"};
    if (std::find_if(std::begin(known), std::end(known), [&](const char* k) { return a.action == k; }) ==
        std::end(known))
      throw UsageError(
          "--do: unknown action '" + a.action +
          "' (play, pause, step, reset, restart, clear, fast, slow:RATE, set:KEY=VALUE, view:NAME, "
          "field:NAME, colormap:NAME, range:LO:HI, scrub:T_US, live, pick:ID, pick-crossing:ID, open:PATH, "
          "screenshot:FILE, export-results, export-scene, export-vtk:DIR, record:DIR, "
          "sweep:KEY=LIST[;KEY=LIST][;repeats=N], "
          "sweep-charts[:X_KEY], limit, wait, demo:NAME, continue, compare-exit)");
    // Arguments that can be checked before the window opens.
    if ((a.action == "scrub" || a.action == "pick" || a.action == "pick-crossing") &&
        (a.arg.empty() || !std::isfinite(std::strtod(a.arg.c_str(), &end)) || *end))
      throw UsageError("--do " + a.action + ": expected a number, got '" + a.arg + "'");
    if ((a.action == "open" || a.action == "export-vtk" || a.action == "record" || a.action == "sweep") &&
        a.arg.empty())
      throw UsageError("--do " + a.action + ": needs an argument (" + a.action + ":...)");
    if (a.action == "colormap" && !render::parse_color_map(a.arg, nullptr))
      throw UsageError("--do colormap: expected turbo, viridis, inferno or gray, got '" + a.arg + "'");
    script.emplace(frame, a);
  }
  return script;
}

// A scripted action that fails is reported (the notice and stderr) and the app goes on;
// the exit code at the end says a scripted action failed.
void script_failed(GuiApp& app, const std::string& what) {
  app.notice = what;
  app.notice_is_error = true;
  app.script_failed = true;
  app.script_error = what;
  std::fprintf(stderr, "ravel: --do: %s\n", what.c_str());
}

void apply_script_action(GuiApp& app, const ScriptAction& a) {
  SimWorker& w = *app.worker;
  if (a.action == "play")
    w.play();
  else if (a.action == "pause")
    w.pause();
  else if (a.action == "step")
    w.step_once(a.arg.empty() ? 1 : std::max(1, std::atoi(a.arg.c_str())));
  else if (a.action == "reset")
    w.reset();
  else if (a.action == "restart") {
    if (!gui::restart_with_draft(app)) script_failed(app, "restart refused: " + app.scene_error);
  } else if (a.action == "clear")
    w.clear_past_runs();
  else if (a.action == "fast") {
    app.pacing.max_speed = true;
    w.set_pacing(app.pacing);
  } else if (a.action == "slow") {
    app.pacing.max_speed = false;
    if (!a.arg.empty()) app.pacing.sim_us_per_wall_s = std::max(1e-3, std::atof(a.arg.c_str()));
    w.set_pacing(app.pacing);
  } else if (a.action == "set") {
    try {
      gui::set_draft_value(app, a.arg);
    } catch (const std::exception& e) {
      script_failed(app, std::string("set refused, the panels keep their values: ") + e.what());
    }
  } else if (a.action == "view") {
    if (!render::parse_view_preset(a.arg, &app.view_options.view))
      script_failed(app, "view: unknown view '" + a.arg + "' (oblique, top, back, section)");
    app.camera_needs_fit = true;
  } else if (a.action == "field") {
    if (!render::parse_color_field(a.arg, &app.view_options.field))
      script_failed(app, "field: unknown field '" + a.arg + "' (strain, velocity, sliding)");
  } else if (a.action == "colormap") {
    render::parse_color_map(a.arg, &app.view_options.map);
  } else if (a.action == "range") {
    float lo = 0, hi = 0;
    if (a.arg == "auto") {
      app.range_locked = false;
      app.view_options.range_min = app.view_options.range_max = 0;
    } else if (std::sscanf(a.arg.c_str(), "%f:%f", &lo, &hi) == 2 && hi > lo) {
      app.range_locked = true;
      app.view_options.range_min = lo;
      app.view_options.range_max = hi;
    } else {
      script_failed(app, "range: expected LO:HI with HI > LO, or auto, got '" + a.arg + "'");
    }
  } else if (a.action == "scrub") {
    if (app.compare && app.compare->active()) {  // compare / demos: every run to the same time
      app.compare->scrub_to(std::atof(a.arg.c_str()) * 1e-6);
      std::printf("ravel gui: compare runs shown at t = %.6f us\n", app.compare->scrub_time_s() * 1e6);
      for (std::size_t i = 0; i < app.compare->views().size(); ++i)
        std::printf("ravel gui: compare run %zu shows t = %.6f us\n", i + 1, app.compare->shown(i).time_s * 1e6);
      return;
    }
    app.scrub_to(std::atof(a.arg.c_str()) * 1e-6);
    std::printf("ravel gui: showing t = %.6f us (run at %.6f us)\n", app.shown().time_s * 1e6,
                app.view.frame.time_s * 1e6);
  } else if (a.action == "live") {
    app.go_live();
    if (app.compare) app.compare->go_live();
  } else if (a.action == "pick") {
    gui::pick_element(app, std::atoi(a.arg.c_str()));
    if (app.notice_is_error) script_failed(app, app.notice);
  } else if (a.action == "pick-crossing") {
    gui::pick_crossing(app, std::atoi(a.arg.c_str()));
    if (app.notice_is_error) script_failed(app, app.notice);
  } else if (a.action == "open") {
    if (!gui::open_scene(app, a.arg)) script_failed(app, "open " + a.arg + ": " + app.open_error);
  } else if (a.action == "export-results") {
    if (!gui::export_results(app)) script_failed(app, app.notice);
  } else if (a.action == "export-scene") {
    if (!gui::export_scene(app)) script_failed(app, app.notice);
  } else if (a.action == "export-vtk") {
    if (!gui::start_vtk_export(app, a.arg)) script_failed(app, app.notice);
  } else if (a.action == "record") {
    if (!gui::start_image_export(app, a.arg)) script_failed(app, app.notice);
  } else if (a.action == "sweep") {
    if (!gui::start_scripted_sweep(app, a.arg)) script_failed(app, app.notice);
  } else if (a.action == "sweep-charts") {
    if (!gui::write_scripted_sweep_charts(app, a.arg)) script_failed(app, app.notice);
  } else if (a.action == "limit") {
    if (!gui::start_scripted_limit(app, a.arg)) script_failed(app, app.notice);
  } else if (a.action == "demo") {  // the Demos menu (app/gui/gui_demos.h)
    if (!app.compare || !app.compare->start_demo(app, a.arg)) script_failed(app, "demo: " + app.notice);
  } else if (a.action == "continue") {
    if (app.compare) app.compare->resume();
  } else if (a.action == "compare-exit") {
    if (app.compare && app.compare->active()) app.compare->stop(app);
  } else if (a.action == "screenshot") {
    app.screenshot_requested = true;
    app.screenshot_path = a.arg.empty() ? gui::next_screenshot_path(app) : a.arg;
  } else if (a.action == "wait") {
    app.script_waiting = true;  // the script holds until the run, exports and studies are idle
  }
}

// The whole window as it is in the back buffer (UI included), written as a PNG.
bool save_screenshot(const std::string& path, int w, int h, std::string* error) {
  std::vector<std::uint8_t> rgb(size_t(w) * size_t(h) * 3), flipped(rgb.size());
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, w, h, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
  for (int y = 0; y < h; ++y)
    std::copy_n(rgb.begin() + long(y) * w * 3, size_t(w) * 3, flipped.begin() + long(h - 1 - y) * w * 3);
  const auto parent = std::filesystem::path(path).parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(parent, ec);
  }
  return render::write_png(path, w, h, flipped, error);
}

void setup_style(float scale) {
  ImGuiStyle& st = ImGui::GetStyle();
  ImGui::StyleColorsDark(&st);
  st.WindowRounding = 0;
  st.FrameRounding = 3;
  st.GrabRounding = 3;
  st.WindowBorderSize = 0;
  st.WindowPadding = ImVec2(12, 10);
  st.FramePadding = ImVec2(7, 4);
  st.ItemSpacing = ImVec2(8, 6);
  st.ItemInnerSpacing = ImVec2(6, 4);
  st.ScrollbarSize = 12;
  ImVec4* c = st.Colors;
  c[ImGuiCol_WindowBg] = ImVec4(0.105f, 0.115f, 0.135f, 1.0f);
  c[ImGuiCol_Header] = ImVec4(0.22f, 0.26f, 0.33f, 1.0f);
  c[ImGuiCol_HeaderHovered] = ImVec4(0.28f, 0.34f, 0.44f, 1.0f);
  c[ImGuiCol_HeaderActive] = ImVec4(0.32f, 0.40f, 0.52f, 1.0f);
  c[ImGuiCol_FrameBg] = ImVec4(0.17f, 0.19f, 0.23f, 1.0f);
  c[ImGuiCol_Button] = ImVec4(0.22f, 0.28f, 0.38f, 1.0f);
  c[ImGuiCol_ButtonHovered] = ImVec4(0.30f, 0.38f, 0.52f, 1.0f);
  c[ImGuiCol_ButtonActive] = ImVec4(0.36f, 0.46f, 0.62f, 1.0f);
  c[ImGuiCol_SliderGrab] = ImVec4(0.95f, 0.62f, 0.20f, 0.9f);
  c[ImGuiCol_SliderGrabActive] = ImVec4(1.0f, 0.70f, 0.30f, 1.0f);
  c[ImGuiCol_CheckMark] = ImVec4(0.95f, 0.62f, 0.20f, 1.0f);
  c[ImGuiCol_PlotHistogram] = ImVec4(0.30f, 0.55f, 0.85f, 1.0f);
  st.ScaleAllSizes(scale);
}

void load_font(float size_px) {
  ImGuiIO& io = ImGui::GetIO();
  static const char* candidates[] = {"/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
                                     "/usr/share/fonts/TTF/DejaVuSans.ttf"};
  for (const char* path : candidates)
    if (std::filesystem::exists(path) && io.Fonts->AddFontFromFileTTF(path, size_px)) return;
  // Without DejaVu: ImGui's built-in 13 px font, scaled.
  io.Fonts->AddFontDefault();
  io.FontGlobalScale = size_px / 13.0f;
}

// Mouse and keyboard in the 3D view and the global shortcuts.
void handle_input(GuiApp& app) {
  const ImGuiIO& io = ImGui::GetIO();
  const ImVec2 m = io.MousePos;
  const bool in_view =
      m.x >= app.view_x && m.x < app.view_x + app.view_w && m.y >= app.view_y && m.y < app.view_y + app.view_h;
  if (!io.WantCaptureMouse && in_view) {
    if (ImGui::IsMouseDoubleClicked(ImGuiMouseButton_Left)) app.camera_needs_fit = true;
    if (io.MouseWheel != 0) app.camera.zoom(std::pow(0.88f, io.MouseWheel));
  }
  // Drags that started in the view keep going even if the mouse leaves it. A left click
  // that does not move (less than 4 px) picks: an element, or a crossing with Ctrl.
  bool& dragging = app.dragging;
  float& moved = app.drag_px;
  const bool any_down = ImGui::IsMouseDown(0) || ImGui::IsMouseDown(1) || ImGui::IsMouseDown(2);
  if (!any_down) dragging = false;
  if (any_down && !dragging && !io.WantCaptureMouse && in_view &&
      (ImGui::IsMouseClicked(0) || ImGui::IsMouseClicked(1) || ImGui::IsMouseClicked(2))) {
    dragging = true;
    app.press_x = m.x;
    app.press_y = m.y;
    moved = 0;
  }
  if (dragging) {
    const ImVec2 d = io.MouseDelta;
    moved = std::max(moved, std::hypot(m.x - app.press_x, m.y - app.press_y));
    const bool pan = ImGui::IsMouseDown(1) || ImGui::IsMouseDown(2) || (ImGui::IsMouseDown(0) && io.KeyShift);
    if (pan)
      app.camera.pan(-d.x / std::max(1.0f, app.view_h), d.y / std::max(1.0f, app.view_h));
    else if (ImGui::IsMouseDown(0) && moved >= 4)
      app.camera.orbit(-d.x * 0.35f, d.y * 0.35f);
  }
  if (ImGui::IsMouseReleased(0) && !io.WantCaptureMouse && in_view && moved < 4 && !io.KeyShift) {
    gui::pick_at(app, m.x, m.y, io.KeyCtrl);
    moved = 1e9f;
  }
  if (io.WantCaptureKeyboard) return;
  SimWorker& w = *app.worker;
  if (ImGui::IsKeyPressed(GLFW_KEY_SPACE, false)) w.toggle_pause();
  if (ImGui::IsKeyPressed(GLFW_KEY_S) || ImGui::IsKeyPressed(GLFW_KEY_RIGHT)) w.step_once(1);
  if (ImGui::IsKeyPressed(GLFW_KEY_R, false)) w.reset();
  if (ImGui::IsKeyPressed(GLFW_KEY_ENTER, false) || ImGui::IsKeyPressed(GLFW_KEY_KP_ENTER, false))
    gui::restart_with_draft(app);
  if (ImGui::IsKeyPressed(GLFW_KEY_F, false)) app.camera_needs_fit = true;
  if (ImGui::IsKeyPressed(GLFW_KEY_C, false)) w.clear_past_runs();
  if (ImGui::IsKeyPressed(GLFW_KEY_P, false)) {
    app.screenshot_requested = true;
    app.screenshot_path = gui::next_screenshot_path(app);
  }
  if (ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false)) app.picked = gui::Picked{};
  // Time travel: , and . step through the kept frames, End goes back to the run.
  if (!app.timeline.empty()) {
    const std::size_t cur = app.live ? app.timeline.size() - 1 : app.scrub_index;
    if (ImGui::IsKeyPressed(GLFW_KEY_COMMA)) app.scrub_to(app.timeline.time(cur > 0 ? cur - 1 : 0));
    if (ImGui::IsKeyPressed(GLFW_KEY_PERIOD)) {
      if (cur + 1 >= app.timeline.size())
        app.go_live();
      else
        app.scrub_to(app.timeline.time(cur + 1));
    }
  }
  if (ImGui::IsKeyPressed(GLFW_KEY_END, false)) app.go_live();
  if (ImGui::IsKeyPressed(GLFW_KEY_O, false) && io.KeyCtrl) app.show_open = true;
  for (int i = 0; i < 4; ++i)
    if (ImGui::IsKeyPressed(GLFW_KEY_1 + i, false)) {
      app.view_options.view = render::ViewPreset(i);
      app.camera_needs_fit = true;
    }
  if (ImGui::IsKeyPressed(GLFW_KEY_F1, false) || ImGui::IsKeyPressed(GLFW_KEY_H, false)) app.show_help = !app.show_help;
}

void draw_help(GuiApp& app) {
  if (!app.show_help) return;
  ImGui::SetNextWindowPos(ImVec2(app.view_x + app.view_w * 0.5f, app.view_y + app.view_h * 0.5f), ImGuiCond_Always,
                          ImVec2(0.5f, 0.5f));
  ImGui::Begin("Keys and mouse", &app.show_help,
               ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoMove);
  const char* rows[][2] = {{"Space", "play / pause"},
                           {"S or Right", "one time step"},
                           {"R", "reset to t = 0"},
                           {"Enter", "restart with the edited values"},
                           {"1 2 3 4", "oblique / top / back / section view"},
                           {"F, double-click", "fit the fabric in the view"},
                           {"left drag", "orbit"},
                           {"right drag, shift+left drag", "pan"},
                           {"wheel", "zoom"},
                           {"click, ctrl+click", "pick an element / a crossing (Esc: clear)"},
                           {", and .", "previous / next kept frame (time slider)"},
                           {"End", "back to the live run"},
                           {"Ctrl+O", "open a scene"},
                           {"C", "clear the earlier runs from the charts"},
                           {"P", "screenshot into the export folder"},
                           {"H or F1", "this help"}};
  if (ImGui::BeginTable("keys", 2)) {
    for (auto& r : rows) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextColored(ImVec4(0.95f, 0.62f, 0.20f, 1.0f), "%s", r[0]);
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(r[1]);
    }
    ImGui::EndTable();
  }
  ImGui::End();
}

// The main menu bar across the top of the window.
void draw_menu_bar(GuiApp& app, gui::CompareMode& compare) {
  if (!ImGui::BeginMainMenuBar()) return;
  app.menu_h = ImGui::GetWindowSize().y;
  if (ImGui::BeginMenu("File")) {
    if (ImGui::MenuItem("Open scene...", "Ctrl+O")) app.show_open = true;
    if (ImGui::MenuItem("Scene keys...", nullptr, app.show_keys)) app.show_keys = !app.show_keys;
    ImGui::Separator();
    if (ImGui::MenuItem("Export history.csv + summary.json")) gui::export_results(app);
    if (ImGui::MenuItem("Export scene TOML")) gui::export_scene(app);
    if (ImGui::MenuItem("Export VTK series of the kept frames", nullptr, false, !app.timeline.empty()))
      gui::start_vtk_export(app, app.export_dir + "/vtk");
    if (ImGui::MenuItem("Export images of the kept frames (+ MP4)", nullptr, false, !app.timeline.empty()))
      gui::start_image_export(app, app.export_dir + "/images");
    if (ImGui::MenuItem("Screenshot", "P")) {
      app.screenshot_requested = true;
      app.screenshot_path = gui::next_screenshot_path(app);
    }
    ImGui::Separator();
    if (ImGui::MenuItem("Quit")) app.quit = true;
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("Studies")) {
    gui::studies_menu_items(app);
    ImGui::EndMenu();
  }
  compare.menu_items(app);
  if (ImGui::BeginMenu("Help")) {
    if (ImGui::MenuItem("Keys and mouse", "H")) app.show_help = true;
    ImGui::EndMenu();
  }
  ImGui::EndMainMenuBar();
}

// The window's first size: --size, else 1600 x 1000 or 90 % of a smaller screen.
void initial_window_size(bool given, int* w, int* h) {
  if (given) return;
  GLFWmonitor* mon = glfwGetPrimaryMonitor();
  int mx = 0, my = 0, mw = 0, mh = 0;
  if (mon) glfwGetMonitorWorkarea(mon, &mx, &my, &mw, &mh);
  if (mw <= 0 || mh <= 0) return;
  *w = std::max(640, std::min(*w, int(mw * 0.9)));
  *h = std::max(480, std::min(*h, int(mh * 0.9)));
}

// A file dropped on the window: open it (the window's user pointer is the app).
void on_drop(GLFWwindow* window, int count, const char** paths) {
  auto* app = static_cast<GuiApp*>(glfwGetWindowUserPointer(window));
  if (app && count > 0 && paths[0]) {
    app->open_path = paths[0];
    gui::open_scene(*app, paths[0]);
    app->show_open = true;
  }
}

std::vector<std::string> shipped_scenes() {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(assets_dir() + "/scenes", ec))
    if (e.path().extension() == ".toml") out.push_back(e.path().string());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

int cmd_gui(const Args& args) {
  try {
    CommonArgs a = parse_args(args, "gui");
    long frames = -1;
    if (a.flags.count("frames")) {
      char* end = nullptr;
      frames = std::strtol(a.flags["frames"].c_str(), &end, 10);
      if (a.flags["frames"].empty() || *end || frames < 1)
        throw UsageError("--frames: expected a whole number >= 1, got '" + a.flags["frames"] + "'");
    }
    const std::string screenshot = a.flags.count("screenshot") ? a.flags["screenshot"] : "";
    if (!screenshot.empty() && frames < 0) throw UsageError("--screenshot needs --frames N");
    const auto script = parse_script(a.multi.count("do") ? a.multi["do"] : std::vector<std::string>{});
    double pause_at_us = -1;
    if (a.flags.count("pause-at-us")) {
      char* end = nullptr;
      pause_at_us = std::strtod(a.flags["pause-at-us"].c_str(), &end);
      if (*end || !(pause_at_us > 0)) throw UsageError("--pause-at-us: expected a time in microseconds > 0");
    }
    render::ViewOptions view_options;
    if (a.flags.count("view") && !render::parse_view_preset(a.flags["view"], &view_options.view))
      throw UsageError("--view: expected " + render::view_preset_names() + ", got '" + a.flags["view"] + "'");
    if (a.flags.count("field") && !render::parse_color_field(a.flags["field"], &view_options.field))
      throw UsageError("--field: expected " + render::color_field_names() + ", got '" + a.flags["field"] + "'");
    int win_w = 1600, win_h = 1000;
    if (a.flags.count("size")) {
      char x = 0, rest = 0;
      if (std::sscanf(a.flags["size"].c_str(), "%d%c%d%c", &win_w, &x, &win_h, &rest) != 3 || x != 'x' || win_w < 640 ||
          win_h < 480 || win_w > 8192 || win_h > 8192)
        throw UsageError("--size: expected WxH of at least 640x480, got '" + a.flags["size"] + "'");
    }
    std::size_t budget_mb = 256;
    if (a.flags.count("budget-mb")) {
      char* end = nullptr;
      const long mb = std::strtol(a.flags["budget-mb"].c_str(), &end, 10);
      if (a.flags["budget-mb"].empty() || *end || mb < 16 || mb > 65536)
        throw UsageError("--budget-mb: expected a whole number of MB, 16..65536, got '" + a.flags["budget-mb"] + "'");
      budget_mb = std::size_t(mb);
    }
    Scene scene = load_scene_from(a);

    // No display: say so in one line and point to the headless commands.
    const char* display = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    if ((!display || !*display) && (!wayland || !*wayland)) {
      std::fprintf(stderr,
                   "ravel: no display (DISPLAY is not set), so no window; for headless work use "
                   "'ravel run --out DIR' or 'ravel snapshot --at T_US --out DIR'\n");
      return exit_usage;
    }
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit()) {
      std::fprintf(stderr,
                   "ravel: cannot open the display (%s); for headless work use 'ravel run --out DIR' "
                   "or 'ravel snapshot --at T_US --out DIR'\n",
                   g_glfw_error.c_str());
      return exit_usage;
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    // No multisampling: under a software GL (llvmpipe) it multiplies the fabric's cost.
    glfwWindowHint(GLFW_SAMPLES, 0);
    initial_window_size(a.flags.count("size") > 0, &win_w, &win_h);
    const std::string title = "ravel \xE2\x80\x94 " + scene.name;
    GLFWwindow* window = glfwCreateWindow(win_w, win_h, title.c_str(), nullptr, nullptr);
    if (!window) {
      std::fprintf(stderr, "ravel: cannot create an OpenGL 3.3 core window (%s); use 'ravel run' or 'ravel snapshot'\n",
                   g_glfw_error.c_str());
      glfwTerminate();
      return exit_failure;
    }
    glfwMakeContextCurrent(window);
    glfwSwapInterval(frames > 0 ? 0 : 1);
    std::string gl_error;
    if (!render::load_gl(glfw_loader, &gl_error)) {
      std::fprintf(stderr, "ravel: cannot load OpenGL: %s\n", gl_error.c_str());
      glfwDestroyWindow(window);
      glfwTerminate();
      return exit_failure;
    }

    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // the layout is fixed; no imgui.ini next to the user's files
    float xscale = 1, yscale = 1;
    glfwGetWindowContentScale(window, &xscale, &yscale);
    // The UI scales with the monitor's content scale (a 4K screen at 200 %: twice the size).
    const float ui_scale = std::clamp(std::max(xscale, yscale), 1.0f, 3.0f);
    load_font(16.0f * ui_scale);
    setup_style(ui_scale);
    ImGui_ImplGlfw_InitForOpenGL(window, true);
    ImGui_ImplOpenGL3_Init("#version 330 core");

    int exit_code = exit_ok;
    {
      render::Renderer renderer;
      SimWorker worker(scene, has_switch(a, "paused"));
      GuiApp app;
      app.timeline.set_budget_bytes(budget_mb << 20);
      app.layout_check = std::getenv("RAVEL_LAYOUT_CHECK") != nullptr;
      app.ui_scale = ui_scale;
      gui::CompareMode compare;
      app.compare = &compare;
      glfwSetWindowUserPointer(window, &app);
      glfwSetDropCallback(window, on_drop);
      app.worker = &worker;
      worker.queue_frames(true);  // the timeline keeps every published frame
      app.draft = scene;
      app.view_options = view_options;
      app.camera = render::Camera::preset(view_options.view);
      app.shipped_scenes = shipped_scenes();
      if (a.flags.count("export-dir")) app.export_dir = a.flags["export-dir"];
      if (pause_at_us > 0) {
        app.pause_at_us = pause_at_us;
        worker.pause_at(pause_at_us * 1e-6);
      }
      worker.sync(app.view);

      gui::SingleRunMode single;
      const auto t0 = std::chrono::steady_clock::now();
      const double ui_cpu0 = cpu_seconds(CLOCK_THREAD_CPUTIME_ID), process_cpu0 = cpu_seconds(CLOCK_PROCESS_CPUTIME_ID);
      auto last_frame_end = t0;
      double worst_frame_ms = 0, view_ms_total = 0;
      long frame = 0;
      int win_w_final = win_w, win_h_final = win_h;
      long script_frame = 0;    // the --do frame counter (held by `wait`)
      long playing_frames = 0;  // UI frames while the run played, and their wall time
      double playing_s = 0;
      double sim_at_end_us = 0;
      while (!glfwWindowShouldClose(window) && !app.quit) {
        const auto frame_start = std::chrono::steady_clock::now();
        glfwPollEvents();
        ++frame;
        // The active mode: the single run, or compare / demos while a comparison runs.
        gui::Mode& mode = compare.active() ? static_cast<gui::Mode&>(compare) : single;
        worker.sync(app.view);
        gui::update_timeline(app);
        // Scripted actions run at their script frame; `wait` holds the script frame (not the
        // UI) until the run is paused or ended and no export or study is running.
        if (app.script_waiting && app.view.state != WorkerState::running && !gui::export_running(app) &&
            !gui::studies_running(app) && !worker.busy() && !compare.busy())
          app.script_waiting = false;
        if (!app.script_waiting) {
          ++script_frame;
          for (auto [it, end] = script.equal_range(script_frame); it != end && !app.script_waiting; ++it)
            apply_script_action(app, it->second);
          worker.sync(app.view);
          gui::update_timeline(app);
        }

        int fb_w = 0, fb_h = 0, win_w_now = 0, win_h_now = 0;
        glfwGetFramebufferSize(window, &fb_w, &fb_h);
        glfwGetWindowSize(window, &win_w_now, &win_h_now);
        if (fb_w <= 0 || fb_h <= 0) {  // minimised
          glfwWaitEventsTimeout(0.1);
          continue;
        }
        ImGui_ImplOpenGL3_NewFrame();
        ImGui_ImplGlfw_NewFrame();
        ImGui::NewFrame();
        const ImVec2 ds = ImGui::GetIO().DisplaySize;
        const float fs = ImGui::GetFontSize();
        draw_menu_bar(app, compare);
        // Layout: menu bar on top; the left panel (scrolls when it does not fit); the 3D view
        // with the time slider under it; the charts and the status at the bottom. Sizes follow
        // the font (and so the monitor's content scale) and the window.
        app.left_w = std::clamp(ds.x * 0.25f, fs * 21.0f, fs * 27.0f);
        app.bottom_h = std::clamp(ds.y * 0.34f, fs * 13.0f, fs * 25.0f);
        app.status_w = std::clamp(ds.x * 0.22f, fs * 18.0f, fs * 24.0f);
        app.timeline_h =
            mode.has_time_slider() ? ImGui::GetFrameHeight() + 2 * ImGui::GetStyle().WindowPadding.y + 2.0f : 0.0f;
        app.view_x = app.left_w;
        app.view_y = app.menu_h;
        app.view_w = std::max(1.0f, ds.x - app.left_w);
        app.view_h = std::max(1.0f, ds.y - app.bottom_h - app.menu_h - app.timeline_h);
        app.fps = ImGui::GetIO().Framerate;

        handle_input(app);
        const bool dragging = !ImGui::GetIO().WantCaptureMouse &&
                              (ImGui::IsMouseDown(0) || ImGui::IsMouseDown(1) || ImGui::IsMouseDown(2));
        app.mode_field = mode.field();
        gui::draw_left_panel(app);
        mode.update(app);
        // A comparison may have started or ended in the left panel or a menu.
        gui::Mode& shown_mode = compare.active() ? static_cast<gui::Mode&>(compare) : single;
        shown_mode.draw_panels(app);
        compare.draw_dialogs(app);
        gui::draw_keys_window(app);
        gui::draw_open_window(app);
        gui::draw_studies_windows(app);
        gui::draw_export_progress(app);
        draw_help(app);
        // The picked item is drawn over the fabric in the copy it was picked in.
        app.view_options.highlight_element = app.picked.element;
        app.view_options.highlight_crossing = app.picked.crossing;
        app.view_options.highlight_mirror = app.picked.mirror;
        // The 3D view's overlay text about as tall as the UI's (stb_easy_font is 7 px high).
        const float overlay_scale = std::max(1.0f, std::round(fs / 8.0f));

        // The 3D view: the renderer draws the UI's copy of the frame into the cached
        // texture (when due), which ImGui then shows behind the panels.
        const float sx = float(fb_w) / float(std::max(1, win_w_now)), sy = float(fb_h) / float(std::max(1, win_h_now));
        const int vw = std::max(1, int(app.view_w * sx)), vh = std::max(1, int(app.view_h * sy));
        if (app.camera_needs_fit && !app.shown().node_pos.empty()) {
          app.camera = render::fitted_camera(app.shown(), app.view_options.view, float(vw) / float(vh));
          app.camera_needs_fit = false;
        }
        const bool shot_due = app.screenshot_requested || (frames > 0 && frame >= frames && !screenshot.empty());
        const auto v0 = std::chrono::steady_clock::now();
        shown_mode.render_view(app, renderer, vw, vh, overlay_scale,
                               dragging || (app.live && app.view.state == WorkerState::running), shot_due);
        gui::step_export(app, renderer, vw, vh);
        view_ms_total += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - v0).count();
        ImGui::Render();
        glViewport(0, 0, fb_w, fb_h);
        glClearColor(0.105f, 0.115f, 0.135f, 1.0f);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        // The cached 3D view is copied into the window 1:1 (a blit: no shader or blending,
        // slightly cheaper under llvmpipe than ImGui drawing it as a textured quad); the
        // panels are drawn over it.
        shown_mode.blit_view(int(app.view_x * sx), fb_h - int((app.view_y + app.view_h) * sy));
        ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());

        const auto now = std::chrono::steady_clock::now();
        const double frame_ms = std::chrono::duration<double, std::milli>(now - last_frame_end).count();
        last_frame_end = now;
        if (frame > 1) worst_frame_ms = std::max(worst_frame_ms, frame_ms);
        if (frame > 1 && app.view.state == WorkerState::running) {
          ++playing_frames;
          playing_s += frame_ms * 1e-3;
        }
        // With --frames the app ends at frame N, but not before a --pause-at-us time is reached
        // or a scripted export or study has finished (at most 10 minutes in all).
        const bool waiting = (pause_at_us > 0 && app.view.state == WorkerState::running) || gui::export_running(app) ||
                             gui::studies_running(app) || app.script_waiting ||
                             script.upper_bound(script_frame) != script.end();
        const bool last = frames > 0 && frame >= frames &&
                          (!waiting || std::chrono::steady_clock::now() - t0 > std::chrono::seconds(600));
        if (last && !screenshot.empty()) {
          app.screenshot_requested = true;
          app.screenshot_path = screenshot;
        }
        if (app.screenshot_requested) {
          app.screenshot_requested = false;
          std::string error;
          if (save_screenshot(app.screenshot_path, fb_w, fb_h, &error)) {
            app.notice = "wrote " + app.screenshot_path;
            app.notice_is_error = false;
          } else {
            app.notice = "screenshot failed: " + error;
            app.notice_is_error = true;
            if (last) exit_code = exit_failure;
          }
        }
        glfwSwapBuffers(window);
        if (last) {
          sim_at_end_us = app.view.frame.time_s * 1e6;
          glfwGetWindowSize(window, &win_w_final, &win_h_final);
          break;
        }
        // At most ~60 UI frames a second: a software GL would otherwise take the core
        // the solver needs. Input wakes the loop early.
        const double spent_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - frame_start).count();
        if (spent_s < 1.0 / 60.0) glfwWaitEventsTimeout(1.0 / 60.0 - spent_s);
      }
      if (frames > 0) {
        const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        double load1 = -1;  // the machine's load: frame rates under a software GL depend on it
        if (std::FILE* f = std::fopen("/proc/loadavg", "r")) {
          if (std::fscanf(f, "%lf", &load1) != 1) load1 = -1;
          std::fclose(f);
        }
        const double ui_cpu = cpu_seconds(CLOCK_THREAD_CPUTIME_ID) - ui_cpu0,
                     process_cpu = cpu_seconds(CLOCK_PROCESS_CPUTIME_ID) - process_cpu0;
        std::printf(
            "ravel gui: %ld frames in %.2f s (%.1f fps, slowest %.0f ms; while playing %.1f fps over "
            "%.1f s; UI thread CPU %.1f ms per frame, process CPU %.0f %% of one core), 3D view drawn "
            "%ld times (%.0f ms each), %d UI vertices, simulated time %.2f us, run %ld %s, mu %.2f, "
            "load %.2f; kept %zu frames, %.0f MB\n",
            frame, wall, double(frame) / wall, worst_frame_ms, playing_s > 0 ? double(playing_frames) / playing_s : 0.0,
            playing_s, 1e3 * ui_cpu / double(frame), 100.0 * process_cpu / wall, single.draws(),
            view_ms_total / double(std::max(1L, single.draws())), ImGui::GetIO().MetricsRenderVertices, sim_at_end_us,
            app.view.run_id, to_string(app.view.state), app.view.scene.yarn.friction, load1, app.timeline.size(),
            double(app.timeline.bytes()) / (1 << 20));
        // (an error a scripted action reported is on stderr already)
        if (app.notice_is_error && app.notice != app.script_error)
          std::fprintf(stderr, "ravel: %s\n", app.notice.c_str());
      }
      if (app.layout_check) {
        // Each problem once (they repeat every frame).
        std::vector<std::string> seen;
        for (const auto& p : app.layout_problems)
          if (std::find(seen.begin(), seen.end(), p) == seen.end()) seen.push_back(p);
        if (seen.empty()) {
          std::printf("ravel gui: layout check at %dx%d: every panel fits\n", win_w_final, win_h_final);
        } else {
          std::printf("ravel gui: layout check at %dx%d: %zu problems\n", win_w_final, win_h_final, seen.size());
          for (const auto& p : seen) std::printf("  %s\n", p.c_str());
          if (exit_code == exit_ok) exit_code = exit_failure;
        }
      }
      if (app.script_failed && exit_code == exit_ok) exit_code = exit_failure;
      glfwSetWindowUserPointer(window, nullptr);
      worker.request_exit();
      single.release();
    }  // worker joined, renderer destroyed with the context current

    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
    glfwDestroyWindow(window);
    glfwTerminate();
    return exit_code;
  } catch (const std::exception& e) {
    return report_error(e);
  }
}

}  // namespace ravel::app
