// The app's Demos menu and "Compare runs" (app/gui/gui_demos.h).
#include "gui_demos.h"

#include <glad/gl.h>
#include <imgui.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <sstream>

#include "chart_imgui.h"
#include "demo_render.h"
#include "gui_app.h"
#include "render/annotate.h"
#include "render/render_target.h"
#include "render/renderer.h"

namespace ravel::app::gui {

namespace {

double wall_now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

bool run_done(const WorkerView& v) {
  return v.state == WorkerState::finished || v.state == WorkerState::diverged;
}

}  // namespace

// The split views, drawn into a render target when the runs publish new frames (at most
// every 120 ms while playing), copied into the window every UI frame.
struct CompareMode::Cache {
  render::RenderTarget target;
  std::vector<std::uint64_t> serials;
  std::vector<render::Camera> cameras;
  double last_draw = 0;
  bool valid = false;
  std::unique_ptr<render::Annotator> annotator;

  void release() {
    target.release();
    valid = false;
  }
  void resize(int nw, int nh) {
    if (target.resize(nw, nh)) {
      valid = false;
      cameras.clear();
    }
  }
};

CompareMode::CompareMode() : cache_(std::make_unique<Cache>()) {}
CompareMode::~CompareMode() = default;

void CompareMode::start(GuiApp& app, const demos::Demo& demo, const std::vector<Scene>& scenes) {
  // The new runs are built aside first: a scene that cannot be built (too big, say) throws
  // here and leaves the comparison on show, and the single run, as they were.
  std::vector<std::unique_ptr<SimWorker>> workers;
  for (const Scene& s : scenes) {
    workers.push_back(std::make_unique<SimWorker>(s, /*start_paused=*/true));
    workers.back()->queue_frames(true);  // every run keeps its frames for the shared slider
    workers.back()->set_pacing(Pacing{true, 0});
    workers.back()->pause_at(0);
  }
  for (auto& w : workers_) w->request_exit();
  workers_ = std::move(workers);  // the old ones join as they go
  views_.assign(workers_.size(), WorkerView{});
  demo_ = demo;
  app.worker->pause();  // the single run waits behind the comparison
  clock_.reset();
  clock_.set_rate(demo.slow_motion_us_per_s * 1e-6);
  key_ = 0;
  at_key_ = false;
  playing_ = true;
  last_wall_ = -1;
  caption_ = {demo.title + ": " + demo.summary, "Runs: "};
  for (std::size_t i = 0; i < demo.runs.size(); ++i) caption_[1] += (i ? ", " : "") + demo.runs[i].label;
  cache_->cameras.clear();
  cache_->serials.assign(scenes.size(), ~std::uint64_t(0));
  // Each run keeps its frames for the shared time slider (the budget shared between them).
  timelines_.assign(scenes.size(), Timeline((std::size_t(256) << 20) / std::max<std::size_t>(1, scenes.size())));
  for (std::size_t i = 0; i < timelines_.size(); ++i) timelines_[i].reset(long(i));
  kept_serial_.assign(scenes.size(), 0);
  scrubbing_ = false;
  scrub_frames_.assign(scenes.size(), Frame{});
  app.notice = "started " + demo.title;
  app.notice_is_error = false;
}

bool CompareMode::start_demo(GuiApp& app, const std::string& name) {
  const demos::Demo* d = demos::find_demo(name);
  if (!d) {
    app.notice = "no demo '" + name + "'";
    app.notice_is_error = true;
    return false;
  }
  try {
    std::vector<Scene> scenes;
    for (std::size_t i = 0; i < d->runs.size(); ++i) scenes.push_back(demos::demo_scene(*d, i));
    start(app, *d, scenes);
    render::parse_view_preset(d->view, &app.view_options.view);
    return true;
  } catch (const std::exception& e) {
    app.notice = std::string("demo: ") + e.what();
    app.notice_is_error = true;
    return false;
  }
}

bool CompareMode::start_compare(GuiApp& app, const std::vector<std::string>& labels,
                                const std::vector<std::vector<std::string>>& overrides) {
  try {
    demos::Demo d;
    d.name = "compare";
    d.title = "Compare runs";
    d.summary = "the current scene with different values, time kept in step";
    d.view = render::to_string(app.view_options.view);
    d.field = render::to_string(app.view_options.field);
    d.charts = {demos::DemoChart::velocity_history};
    d.slow_motion_us_per_s = app.pacing.max_speed ? 20 : app.pacing.sim_us_per_wall_s;
    const std::string base = scene_to_toml(app.draft);
    std::vector<Scene> scenes;
    for (std::size_t i = 0; i < overrides.size(); ++i) {
      Scene s = parse_scene(base, "compare", overrides[i]);
      s.output.progress = false;
      d.end_time_us = std::max(d.end_time_us, s.solver.end_time_s * 1e6);
      d.runs.push_back({labels[i], overrides[i]});
      scenes.push_back(s);
    }
    start(app, d, scenes);
    return true;
  } catch (const std::exception& e) {
    app.notice = std::string("compare: ") + e.what();
    app.notice_is_error = true;
    return false;
  }
}

void CompareMode::stop(GuiApp& app) {
  for (auto& w : workers_) w->request_exit();
  workers_.clear();  // joins
  views_.clear();
  app.camera_needs_fit = true;
  app.notice = "back to the single run";
}

void CompareMode::resume() {
  at_key_ = false;
  playing_ = true;
  last_wall_ = -1;
}

double CompareMode::next_stop_s() const {
  if (key_ < int(demo_.key_frames.size()) && demo_.key_frames[key_].t_us >= 0)
    return demo_.key_frames[key_].t_us * 1e-6;
  return -1;
}

bool CompareMode::busy() const {
  if (!active() || at_key_ || !playing_) return false;
  for (const WorkerView& v : views_)
    if (!run_done(v) && v.frame.time_s < demo_.end_time_us * 1e-6 - 0.5 * v.summary.dt_s) return true;
  return false;
}

void CompareMode::scrub_to(double t_s) {
  if (!active()) return;
  scrubbing_ = true;
  scrub_t_ = t_s;
  for (std::size_t i = 0; i < timelines_.size(); ++i)
    if (!timelines_[i].empty()) scrub_frames_[i] = timelines_[i].frame(timelines_[i].index_at(t_s));
  ++scrub_serial_;
}

void CompareMode::update() {
  if (!active()) return;
  for (std::size_t i = 0; i < workers_.size(); ++i) {
    workers_[i]->sync(views_[i]);
    for (const auto& [f, step] : views_[i].new_frames) timelines_[i].add(f, step);
    views_[i].new_frames.clear();
    if (views_[i].frame_serial != kept_serial_[i] && !views_[i].frame.node_pos.empty()) {
      timelines_[i].add(views_[i].frame, views_[i].step_count);
      kept_serial_[i] = views_[i].frame_serial;
    }
  }
  std::vector<double> times;
  double max_dt = 0;
  bool all_done = true;
  for (const WorkerView& v : views_) {
    const bool done = run_done(v) || v.frame.time_s >= demo_.end_time_us * 1e-6 - 0.5 * v.summary.dt_s;
    times.push_back(done ? HUGE_VAL : v.frame.time_s);
    max_dt = std::max(max_dt, v.summary.dt_s);
    all_done = all_done && done;
  }
  const double now = wall_now();
  const double dt_wall = last_wall_ < 0 ? 0 : std::min(0.25, now - last_wall_);
  last_wall_ = now;
  if (at_key_ || !playing_) return;
  const double stop = next_stop_s();
  const double lead = std::max(0.5e-6, clock_.rate() * 0.3);
  const double t = clock_.advance(dt_wall, times, stop, lead);
  for (std::size_t i = 0; i < workers_.size(); ++i) {
    if (times[i] == HUGE_VAL) continue;
    if (views_[i].frame.time_s < t - 0.5 * views_[i].summary.dt_s) {
      workers_[i]->pause_at(t, /*hold=*/true);  // (the view may lag the run: never let it play past t)
      if (workers_[i]->paused()) workers_[i]->play();
    }
  }
  // A key frame: every run at the stop (within half a step) or ended.
  bool reached = false;
  if (key_ < int(demo_.key_frames.size())) {
    if (stop >= 0) {
      reached = true;
      for (std::size_t i = 0; i < views_.size(); ++i)
        if (times[i] != HUGE_VAL && views_[i].frame.time_s < stop - 0.5 * views_[i].summary.dt_s) reached = false;
    } else {
      reached = all_done;
    }
  }
  if (reached) {
    std::vector<demos::RunState> runs;
    for (std::size_t i = 0; i < views_.size(); ++i)
      runs.push_back({demo_.runs[i].label, views_[i].frame, views_[i].summary, views_[i].history});
    caption_ = demos::caption(demo_, demo_.key_frames[key_], runs);
    ++key_;
    at_key_ = true;
  }
}

void CompareMode::menu_items(GuiApp& app) {
  if (ImGui::BeginMenu("Demos")) {
    for (const demos::Demo& d : demos::catalogue()) {
      if (ImGui::MenuItem(d.title.c_str())) start_demo(app, d.name);
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", d.summary.c_str());
    }
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("Compare")) {
    if (ImGui::MenuItem("Compare runs...")) show_compare_dialog_ = true;
    if (ImGui::MenuItem("Back to the single run", nullptr, false, active())) stop(app);
    ImGui::EndMenu();
  }
}

void CompareMode::draw_dialogs(GuiApp& app) {
  if (!show_compare_dialog_) return;
  ImGui::SetNextWindowPos(ImVec2(app.view_x + app.view_w * 0.5f, app.view_y + app.view_h * 0.4f), ImGuiCond_Appearing,
                          ImVec2(0.5f, 0.5f));
  if (ImGui::Begin("Compare runs", &show_compare_dialog_, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::TextUnformatted("The current scene (the panels' values) with different settings,");
    ImGui::TextUnformatted("side by side with time kept in step. One line per run: key=value ...");
    ImGui::SliderInt("runs", &compare_n_, 2, 4);
    for (int i = 0; i < compare_n_; ++i) {
      ImGui::PushID(i);
      ImGui::InputText("##ov", compare_text_[i], sizeof compare_text_[i]);
      ImGui::PopID();
    }
    if (ImGui::Button("Start")) {
      std::vector<std::string> labels;
      std::vector<std::vector<std::string>> ov;
      for (int i = 0; i < compare_n_; ++i) {
        std::istringstream ss(compare_text_[i]);
        std::vector<std::string> items;
        for (std::string item; ss >> item;) items.push_back(item);
        ov.push_back(items);
        labels.push_back(items.empty() ? "as is" : compare_text_[i]);
      }
      if (start_compare(app, labels, ov)) show_compare_dialog_ = false;
    }
  }
  ImGui::End();
}

void CompareMode::draw_panels(GuiApp& app) {
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(app.left_w, io.DisplaySize.y - app.bottom_h));
  ImGui::SetNextWindowSize(ImVec2(io.DisplaySize.x - app.left_w, app.bottom_h));
  ImGui::Begin("##compare_panel", nullptr,
               ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoSavedSettings);
  ImGui::TextColored(ImVec4(0.95f, 0.62f, 0.20f, 1.0f), "%s", demo_.title.c_str());
  ImGui::SameLine();
  ImGui::Text("  t = %.1f us", clock_.time() * 1e6);
  if (!demo_.key_frames.empty()) {
    ImGui::SameLine();
    ImGui::Text("  key frame %d of %d", key_, int(demo_.key_frames.size()));
  }
  for (const auto& line : caption_) ImGui::TextWrapped("%s", line.c_str());
  if (at_key_) {
    if (ImGui::Button(key_ < int(demo_.key_frames.size()) ? "Continue" : "Done")) resume();
  } else {
    if (ImGui::Button(playing_ ? "Pause" : "Play")) playing_ = !playing_;
  }
  ImGui::SameLine();
  float rate = float(clock_.rate() * 1e6);
  ImGui::SetNextItemWidth(220);
  if (ImGui::SliderFloat("us per second", &rate, 0.5f, 200.0f, "%.1f", ImGuiSliderFlags_Logarithmic))
    clock_.set_rate(rate * 1e-6);
  ImGui::SameLine();
  if (ImGui::Button("Exit")) {
    stop(app);
    ImGui::End();
    return;
  }
  // The shared time slider: every run shown at the same kept time.
  ImGui::SameLine();
  if (ImGui::Button(scrubbing_ ? "Live" : "(live)")) go_live();
  ImGui::SameLine();
  float t_us = float((scrubbing_ ? scrub_t_ : clock_.time()) * 1e6);
  ImGui::SetNextItemWidth(std::max(120.0f, ImGui::GetContentRegionAvail().x));
  if (ImGui::SliderFloat("##compare_time", &t_us, 0.0f, float(std::max(1e-3, clock_.time() * 1e6)), "t = %.2f us"))
    scrub_to(double(t_us) * 1e-6);
  std::vector<demos::RunState> runs;
  for (std::size_t i = 0; i < views_.size(); ++i)
    runs.push_back({demo_.runs[i].label, views_[i].frame, views_[i].summary, views_[i].history});
  studies::Chart c = demos::velocity_chart(demo_, runs, std::max(clock_.time() * 1e6, 1.0));
  c.subtitle.clear();
  studies::draw_chart_imgui(c, ImVec2(ImGui::GetContentRegionAvail().x, ImGui::GetContentRegionAvail().y));
  ImGui::End();
}

void CompareMode::blit_view(int x, int y) {
  if (cache_->valid) cache_->target.blit_to_window(x, y);
}

void CompareMode::render_view(GuiApp&, render::Renderer& renderer, int w, int h, float ui_scale, bool, bool) {
  if (!active() || w <= 0 || h <= 0) return;
  Cache& c = *cache_;
  c.resize(w, h);
  if (c.serials.size() != views_.size()) c.serials.assign(views_.size(), ~std::uint64_t(0));
  if (!c.annotator) c.annotator = std::make_unique<render::Annotator>();
  const int n = int(views_.size());
  const int cols = n == 4 ? 2 : n, rows = n == 4 ? 2 : 1;
  render::ViewOptions o;
  render::parse_view_preset(demo_.view, &o.view);
  render::parse_color_field(demo_.field, &o.field);
  // Narrow panes: smaller overlay text, and no axes or scale bar (the run's title sits in
  // the lower left; the scale is the same in every pane).
  const int pane_w = w / (n == 4 ? 2 : std::max(1, n));
  o.ui_scale = std::clamp(std::round(float(pane_w) / 320.0f), 1.0f, std::max(1.0f, ui_scale));
  o.show_axes = o.show_scale_bar = false;
  o.yarn_geometry = render::YarnGeometry::ribbons;
  bool changed = !c.valid;
  // A run's serial: its worker's frame, or the scrubbed frame while the slider holds them.
  auto serial = [&](int i) { return scrubbing_ ? (std::uint64_t(1) << 62) + scrub_serial_ : views_[i].frame_serial; };
  for (int i = 0; i < n; ++i) changed = changed || serial(i) != c.serials[i];
  const double now = wall_now();
  if (changed && (now - c.last_draw > 0.12 || at_key_ || scrubbing_ || !c.valid)) {
    bool have_all = true;
    for (int i = 0; i < n; ++i) have_all = have_all && !shown(std::size_t(i)).node_pos.empty();
    if (have_all) {
      c.target.bind();
      glViewport(0, 0, w, h);
      glClearColor(0.08f, 0.09f, 0.12f, 1);
      glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
      std::vector<const Frame*> frames;
      for (int i = 0; i < n; ++i) frames.push_back(&shown(std::size_t(i)));
      render::share_field_range(frames, &o);  // one colour bar for every pane
      for (int i = 0; i < n; ++i) {
        const int cx = i % cols, ry = i / cols;
        const int vx = cx * w / cols, vw = (cx + 1) * w / cols - vx - (cols > 1 ? 3 : 0);
        const int vy_top = ry * h / rows, vh = (ry + 1) * h / rows - vy_top - (rows > 1 ? 3 : 0);
        const int gl_y = h - vy_top - vh;
        if (int(c.cameras.size()) <= i) {
          render::Camera cam = render::fitted_camera(shown(std::size_t(i)), o.view, float(vw) / float(std::max(1, vh)));
          if (n > 1 && o.view != render::ViewPreset::top) cam.zoom(0.72f);
          c.cameras.push_back(cam);
        }
        render::ViewOptions oi = o;
        oi.show_colorbar = i + 1 == n;
        renderer.draw(shown(std::size_t(i)), c.cameras[i], oi, vx, gl_y, vw, vh);
        std::vector<render::WorldPolyline> lines;
        if (demo_.overlay == demos::Overlay::wave_fronts)
          lines = demos::wave_front_lines(views_[i].scene, shown(std::size_t(i)), shown(std::size_t(i)).time_s);
        render::TextBlock title;
        title.x = 10;
        title.y = -10;
        title.lines = {demo_.runs[i].label};
        title.colors = {render::Vec3{1.0f, 0.75f, 0.35f}};
        title.scale = o.ui_scale + 1;
        c.annotator->draw(c.cameras[i], lines, {title}, vx, gl_y, vw, vh);
        c.serials[i] = serial(i);
      }
      render::RenderTarget::bind_window();
      c.valid = true;
      c.last_draw = now;
    }
  }
}

}  // namespace ravel::app::gui
