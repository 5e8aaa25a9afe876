// Time travel and picking: the time slider under the 3D view, the frames kept of the
// run (app/worker/timeline.h), and the element or crossing the user clicked (render/picking.h).
#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "gui_app.h"
#include "gui_jobs.h"
#include "vtk.h"

namespace ravel::app::gui {

GuiApp::GuiApp() : studies(std::make_unique<StudiesWindow>()) {}
GuiApp::~GuiApp() = default;

// The size of the model a frame shows (nodes, elements, crossings): a pick names parts of it.
static std::array<std::size_t, 3> model_size(const Frame& f) {
  return {f.node_pos.size(), f.elem_a.size(), f.crossing_warp_node.size()};
}

void GuiApp::scrub_to(double t_s) {
  if (timeline.empty()) return;
  // The kept frame nearest to t.
  std::size_t i = timeline.index_at(t_s);
  if (i + 1 < timeline.size() && std::abs(timeline.time(i + 1) - t_s) < std::abs(timeline.time(i) - t_s)) ++i;
  if (!live && i == scrub_index && !scrub_frame.node_pos.empty()) return;
  scrub_index = i;
  scrub_frame = timeline.frame(i);
  live = false;
  ++scrub_serial;
}

void update_timeline(GuiApp& app) {
  if (app.view.run_id != app.timeline.run_id()) {
    app.timeline.reset(app.view.run_id);
    app.live = true;
    app.timeline_serial = 0;
  }
  // The same model keeps its numbering: a pick survives Reset; a different one clears it.
  if (app.picked.any() && !app.view.frame.node_pos.empty() && model_size(app.view.frame) != app.picked_model)
    app.picked = Picked{};
  // Every frame the worker published since the last sync (queue_frames), then the newest.
  for (const auto& [f, step] : app.view.new_frames) app.timeline.add(f, step);
  app.view.new_frames.clear();
  if (app.view.frame_serial != app.timeline_serial && !app.view.frame.node_pos.empty()) {
    app.timeline.add(app.view.frame, app.view.step_count);
    app.timeline_serial = app.view.frame_serial;
  }
  // Thinning may have dropped the frame on show: keep showing the nearest one kept.
  if (!app.live && !app.timeline.empty() &&
      (app.scrub_index >= app.timeline.size() || app.timeline.time(app.scrub_index) != app.scrub_frame.time_s)) {
    const double t = app.scrub_frame.time_s;
    app.scrub_index = app.timeline.index_at(t);
    app.scrub_frame = app.timeline.frame(app.scrub_index);
    ++app.scrub_serial;
  }
}

void draw_timeline_bar(GuiApp& app) {
  ImGui::SetNextWindowPos(ImVec2(app.view_x, app.view_y + app.view_h));
  ImGui::SetNextWindowSize(ImVec2(app.view_w, app.timeline_h));
  ImGui::Begin("timeline", nullptr,
               ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoScrollbar | ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoBringToFrontOnFocus |
                   ImGuiWindowFlags_NoBackground);
  const float fs = ImGui::GetFontSize();
  const Timeline& tl = app.timeline;
  const bool any = !tl.empty();
  // Live: the view follows the run. Otherwise it shows a kept frame and the run goes on.
  if (app.live) {
    ImGui::PushStyleColor(ImGuiCol_Button, ImVec4(0.78f, 0.45f, 0.10f, 1.0f));
    ImGui::Button("Live", ImVec2(fs * 4, 0));
    ImGui::PopStyleColor();
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("The view follows the run. Drag the slider to go back in time.");
  } else if (ImGui::Button("Live", ImVec2(fs * 4, 0))) {
    app.go_live();
  } else if (ImGui::IsItemHovered()) {
    ImGui::SetTooltip("Back to the run's latest state [End]");
  }
  ImGui::SameLine();
  ImGui::BeginDisabled(!any);
  const std::size_t cur = app.live ? (any ? tl.size() - 1 : 0) : app.scrub_index;
  if (ImGui::ArrowButton("##prev", ImGuiDir_Left) && any) app.scrub_to(tl.time(cur > 0 ? cur - 1 : 0));
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Previous kept frame [,]");
  ImGui::SameLine();
  if (ImGui::ArrowButton("##next", ImGuiDir_Right) && any) {
    if (cur + 1 >= tl.size())
      app.go_live();
    else
      app.scrub_to(tl.time(cur + 1));
  }
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Next kept frame [.]");
  ImGui::SameLine();
  const double t_end_us = std::max(tl.last_time(), app.view.frame.time_s) * 1e6;
  float t_us = float(app.shown().time_s * 1e6);
  char fmt[64];
  std::snprintf(fmt, sizeof fmt, "t = %%.2f \xC2\xB5s%s", app.live ? " (live)" : "");
  const float info_w = ImGui::CalcTextSize("999 frames, 999 MB").x + fs;
  ImGui::SetNextItemWidth(std::max(fs * 6, ImGui::GetContentRegionAvail().x - info_w));
  if (ImGui::SliderFloat("##time", &t_us, 0.0f, float(std::max(1e-3, t_end_us)), fmt) && any)
    app.scrub_to(double(t_us) * 1e-6);
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::TextDisabled("%zu frames, %.0f MB", tl.size(), double(tl.bytes()) / (1 << 20));
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip(
        "Frames of this run kept for going back in time: %zu of %ld published, %.0f of %.0f MB%s. "
        "When the budget is full every other frame is dropped, so the kept frames stay evenly spread.",
        tl.size(), tl.frames_seen(), double(tl.bytes()) / (1 << 20), double(tl.budget_bytes()) / (1 << 20),
        tl.spacing_s() > 0 ? (", at least " + std::to_string(tl.spacing_s() * 1e6).substr(0, 5) + " us apart").c_str()
                           : "");
  check_layout(app, "time slider");
  ImGui::End();
}

// ----------------------------------------------------------------------------- picking

namespace {

void report_pick(const GuiApp& app) {
  const Frame& f = app.shown();
  if (app.picked.element >= 0 && std::size_t(app.picked.element) < f.elem_strain.size()) {
    const std::size_t e = std::size_t(app.picked.element);
    std::printf("ravel gui: picked element %d (copy %d) at t = %.6f us: strain %.9g, stress %.9g Pa, broken %d\n",
                app.picked.element, app.picked.copy, f.time_s * 1e6, double(f.elem_strain[e]),
                double(f.elem_stress_pa[e]), e < f.elem_broken.size() ? int(f.elem_broken[e]) : 0);
  } else if (app.picked.crossing >= 0 && std::size_t(app.picked.crossing) < f.crossing_normal_force_n.size()) {
    const std::size_t c = std::size_t(app.picked.crossing);
    std::printf("ravel gui: picked crossing %d (I=%d, J=%d) at t = %.6f us: normal force %.9g N, slip rate %.9g m/s\n",
                app.picked.crossing, f.crossing_i[c], f.crossing_j[c], f.time_s * 1e6,
                double(f.crossing_normal_force_n[c]), double(f.crossing_slip_rate[c]));
  }
  std::fflush(stdout);
}

}  // namespace

void pick_at(GuiApp& app, float x, float y, bool crossing) {
  const int w = int(app.view_w), h = int(app.view_h);
  const float px = x - app.view_x, py = y - app.view_y;
  const render::Pick p = crossing ? render::pick_crossing(app.shown(), app.camera, app.view_options, w, h, px, py)
                                  : render::pick_element(app.shown(), app.camera, app.view_options, w, h, px, py);
  app.picked = Picked{};
  app.picked.element = p.element;
  app.picked.crossing = p.crossing;
  app.picked.copy = p.copy;
  app.picked.mirror = p.mirror;
  app.picked_model = model_size(app.view.frame);
}

void pick_element(GuiApp& app, int element) {
  app.picked = Picked{};
  if (element < 0 || std::size_t(element) >= app.shown().elem_a.size()) {
    app.notice = "pick: no element " + std::to_string(element) + " (the model has " +
                 std::to_string(app.shown().elem_a.size()) + ")";
    app.notice_is_error = true;
    return;
  }
  app.picked.element = element;
  app.picked_model = model_size(app.view.frame);
  report_pick(app);
}

void pick_crossing(GuiApp& app, int crossing) {
  app.picked = Picked{};
  if (crossing < 0 || std::size_t(crossing) >= app.shown().crossing_warp_node.size()) {
    app.notice = "pick-crossing: no crossing " + std::to_string(crossing) + " (the model has " +
                 std::to_string(app.shown().crossing_warp_node.size()) + ")";
    app.notice_is_error = true;
    return;
  }
  app.picked.crossing = crossing;
  app.picked_model = model_size(app.view.frame);
  report_pick(app);
}

void draw_picked_window(GuiApp& app) {
  if (!app.picked.any()) return;
  const Frame& f = app.shown();
  const float fs = ImGui::GetFontSize();
  // Bottom right of the 3D view when it appears (below the colour bar where there is room);
  // it can be dragged aside or collapsed.
  ImGui::SetNextWindowPos(ImVec2(app.view_x + app.view_w - fs * 0.6f, app.view_y + app.view_h - fs * 0.6f),
                          ImGuiCond_Appearing, ImVec2(1, 1));
  ImGui::SetNextWindowBgAlpha(0.88f);
  bool open = true;
  if (!ImGui::Begin("Picked", &open, ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoSavedSettings)) {
    ImGui::End();
    return;
  }
  const Timeline& tl = app.timeline;
  std::vector<float> history;
  const char* history_label = "";
  if (app.picked.element >= 0 && std::size_t(app.picked.element) < f.elem_strain.size()) {
    const std::size_t e = std::size_t(app.picked.element);
    const bool warp = e < f.elem_family.size() && f.elem_family[e] == 0;
    const int yarn = whole_fabric_yarn_id(f, app.picked.element, app.picked.mirror[0], app.picked.mirror[1]);
    ImGui::Text("element %d", app.picked.element);
    if (app.picked.copy > 0) {
      ImGui::SameLine();
      ImGui::TextDisabled("(mirrored copy %d of it)", app.picked.copy);
    }
    ImGui::Text("%s yarn %d (runs along %s)", warp ? "warp" : "weft", yarn, warp ? "y" : "x");
    const double strain = f.elem_strain[e], fail = f.failure_strain;
    const bool broken = e < f.elem_broken.size() && f.elem_broken[e];
    ImGui::Text("strain   %.3f %%", strain * 100);
    ImGui::Text("stress   %.3f GPa", double(f.elem_stress_pa[e]) * 1e-9);
    if (broken)
      ImGui::TextColored(ImVec4(1.0f, 0.42f, 0.38f, 1.0f), "broken");
    else
      ImGui::Text("failure margin %.1f %% (fails at %.2f %%)", fail > 0 ? 100 * (1 - strain / fail) : 0.0, fail * 100);
    history.reserve(tl.size());
    for (std::size_t i = 0; i < tl.size(); ++i) history.push_back(100 * tl.strain(i, e));
    history_label = "strain (%) over the kept frames";
  } else if (app.picked.crossing >= 0 && std::size_t(app.picked.crossing) < f.crossing_normal_force_n.size()) {
    const std::size_t c = std::size_t(app.picked.crossing);
    ImGui::Text("crossing %d  (I = %d, J = %d)", app.picked.crossing, f.crossing_i[c], f.crossing_j[c]);
    ImGui::Text("normal force %.3f N", double(f.crossing_normal_force_n[c]));
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip(
          "Eq 11, last step; a crossing on a symmetry plane is half (a quarter at the corner) of a real one");
    ImGui::Text("slip rate    %.3f m/s", double(f.crossing_slip_rate[c]));
    if (c < f.crossing_active.size() && !f.crossing_active[c]) ImGui::TextDisabled("released (not a contact any more)");
    history.reserve(tl.size());
    for (std::size_t i = 0; i < tl.size(); ++i) history.push_back(tl.crossing_force(i, c));
    history_label = "normal force (N) over the kept frames";
  }
  if (history.size() >= 2) {
    ImGui::TextDisabled("%s", history_label);
    ImGui::PlotLines("##history", history.data(), int(history.size()), 0, nullptr, FLT_MAX, FLT_MAX,
                     ImVec2(fs * 16, fs * 3));
    const ImVec2 p0 = ImGui::GetItemRectMin(), p1 = ImGui::GetItemRectMax();
    const std::size_t i = app.live ? history.size() - 1 : std::min(app.scrub_index, history.size() - 1);
    const float x = p0.x + (p1.x - p0.x) * float(i) / float(history.size() - 1);
    ImGui::GetWindowDrawList()->AddLine(ImVec2(x, p0.y), ImVec2(x, p1.y), IM_COL32(255, 80, 210, 220), 2.0f);
  }
  ImGui::TextDisabled("click: element, ctrl+click: crossing, Esc: clear");
  ImGui::End();
  if (!open) app.picked = Picked{};
}

}  // namespace ravel::app::gui
