// The app's Demos menu and "Compare runs": two to four runs in split viewports with
// their time kept in step, slow motion, pauses at a demo's key frames with its caption.
//
// One SimWorker per run (each owns its Simulation on its own thread). A shared clock
// keeps them in step: the clock advances at the slow-motion rate but never more than a
// short lead ahead of the slowest run, and every worker is told to pause when it reaches
// the clock (SimWorker::pause_at) and to play again when the clock moves on. So no run
// is ever ahead of the clock, the slowest run gates the others, and at a key frame every
// run stops at the same simulated time (within one time step). The clock logic is in
// demos::SharedClock (app/demos/demos.h: no GL, no ImGui) so it is unit-tested.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "demos.h"
#include "modes.h"
#include "sim_worker.h"
#include "timeline.h"

namespace ravel::render {
class Renderer;
}

namespace ravel::app::gui {

struct GuiApp;

class CompareMode : public Mode {
 public:
  CompareMode();
  ~CompareMode();
  bool active() const { return !workers_.empty(); }

  // The Demos (the catalogue) and Compare (2-4 runs of the current scene with overrides)
  // menus of the app's menu bar; call between BeginMainMenuBar and EndMainMenuBar.
  void menu_items(GuiApp& app);
  // The Compare runs dialog, when open.
  void draw_dialogs(GuiApp& app);
  // Start a demo by name (false if there is none / its scene is bad; app.notice says why).
  bool start_demo(GuiApp& app, const std::string& name);
  // Start a comparison of the app's current (draft) scene with per-run overrides.
  bool start_compare(GuiApp& app, const std::vector<std::string>& labels,
                     const std::vector<std::vector<std::string>>& overrides);
  void stop(GuiApp& app);
  void resume();  // "Continue" past a key frame
  void set_playing(bool p) { playing_ = p; }

  // Mode: once per UI frame sync the workers, advance the shared clock, gate the workers;
  // the panels (caption and controls over the chart area, the velocity chart of the runs);
  // the runs side by side in a render target, redrawn when they publish new frames.
  bool has_time_slider() const override { return false; }  // its slider is in its panel
  std::string field() const override { return demo_.field; }
  void update(GuiApp& app) override { update(); }
  void update();
  void draw_panels(GuiApp& app) override;
  void render_view(GuiApp& app, render::Renderer& renderer, int w, int h, float overlay_scale, bool busy,
                   bool force_hq) override;
  void blit_view(int x, int y) override;
  void scrub_to(GuiApp&, double t_s) override { scrub_to(t_s); }
  void go_live(GuiApp&) override { go_live(); }

  // Time travel in step: every run keeps its frames (a Timeline each), and the slider in
  // the compare panel (or scrub_to) shows all runs at the same earlier time.
  void scrub_to(double t_s);
  void go_live() { scrubbing_ = false; }
  bool scrubbing() const { return scrubbing_; }
  double scrub_time_s() const { return scrub_t_; }
  const Frame& shown(std::size_t i) const { return scrubbing_ ? scrub_frames_[i] : views_[i].frame; }

  double clock_s() const { return clock_.time(); }
  int key_index() const { return key_; }
  bool at_key() const { return at_key_; }
  // Running: active, playing and not held at a key frame with a run still going (a
  // scripted `wait` waits for this to end).
  bool busy() const;
  const std::vector<WorkerView>& views() const { return views_; }

 private:
  struct Cache;
  void start(GuiApp& app, const demos::Demo& demo, const std::vector<Scene>& scenes);
  double next_stop_s() const;

  demos::Demo demo_;  // the demo (or the comparison as an ad-hoc demo without key frames)
  std::vector<std::unique_ptr<SimWorker>> workers_;
  std::vector<WorkerView> views_;
  demos::SharedClock clock_;
  int key_ = 0;          // next key frame
  bool at_key_ = false;  // paused at key frame key_ - 1
  bool playing_ = true;
  double last_wall_ = -1;
  std::vector<std::string> caption_;
  std::vector<Timeline> timelines_;
  std::vector<std::uint64_t> kept_serial_;
  bool scrubbing_ = false;
  double scrub_t_ = 0;
  std::vector<Frame> scrub_frames_;
  std::uint64_t scrub_serial_ = 0;
  std::unique_ptr<Cache> cache_;
  // Compare dialog state.
  bool show_compare_dialog_ = false;
  int compare_n_ = 3;
  char compare_text_[4][256] = {{"yarn.friction=0.02"}, {"yarn.friction=0.2"}, {"yarn.friction=1.0"}, {""}};
};

}  // namespace ravel::app::gui
