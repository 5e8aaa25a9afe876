// The app's modes: what fills the 3D view and the panels around it.
//
//   single run   one SimWorker (GuiApp::worker): the fabric of the run on screen, the time
//                slider, the velocity and energy charts, the status, the picked item
//   compare      two to four runs side by side with their time in step (gui_demos.h), the
//                same for the guided demos
//
// The main loop (cmd_gui.cpp) asks the active mode, once per UI frame, to update, to draw
// its panels, to draw its 3D view into a render target when due and to copy it into the
// window; scripted scrubbing goes to the active mode. Everything else (the menu bar, the
// left panel, the windows) is the same in every mode.
#pragma once

#include <cstdint>
#include <string>

#include "gui_app.h"
#include "render/render_target.h"
#include "render/renderer.h"

namespace ravel::app::gui {

class Mode {
 public:
  virtual ~Mode() = default;
  virtual bool has_time_slider() const = 0;  // the single run's slider under the 3D view
  // The colour field the mode imposes on its views ("" = the View panel's choice).
  virtual std::string field() const { return {}; }
  // Once per UI frame, before the panels.
  virtual void update(GuiApp& app) = 0;
  // The panels below the 3D view (and over it, such as the picked item).
  virtual void draw_panels(GuiApp& app) = 0;
  // Redraw the 3D view into the mode's render target when due (w x h framebuffer pixels);
  // `busy`: the run plays or the mouse drags (cheaper geometry), `force_hq`: a screenshot.
  virtual void render_view(GuiApp& app, render::Renderer& renderer, int w, int h, float overlay_scale, bool busy,
                           bool force_hq) = 0;
  // Copy the view into the window's back buffer with its lower-left corner at (x, y).
  virtual void blit_view(int x, int y) = 0;
  virtual void scrub_to(GuiApp& app, double t_s) = 0;
  virtual void go_live(GuiApp& app) = 0;
};

// The single run: the fabric drawn into a texture and redrawn only when something changed
// (a new frame, the camera, the view options, the size). Drawing the whole fabric costs
// tens of milliseconds under a software GL, so while the run plays a new frame is drawn at
// most at a rate that leaves most of each second to the UI (panels, charts and input stay
// at 30+ fps); camera moves redraw at once, with cheaper yarns while the mouse drags or the
// run plays, and full quality once everything is still.
class SingleRunMode : public Mode {
 public:
  bool has_time_slider() const override { return true; }
  void update(GuiApp& app) override;
  void draw_panels(GuiApp& app) override;
  void render_view(GuiApp& app, render::Renderer& renderer, int w, int h, float overlay_scale, bool busy,
                   bool force_hq) override;
  void blit_view(int x, int y) override;
  void scrub_to(GuiApp& app, double t_s) override { app.scrub_to(t_s); }
  void go_live(GuiApp& app) override { app.go_live(); }

  void release();  // the render target, with the context current
  double last_draw_ms() const { return last_ms_; }
  long draws() const { return draws_; }

 private:
  static std::string view_key(const GuiApp& app);
  render::RenderTarget target_;
  bool valid_ = false, hq_ = false;
  std::uint64_t drawn_serial_ = ~std::uint64_t(0);
  std::string drawn_key_;
  double last_draw_s_ = -1, last_change_s_ = -1;
  double last_ms_ = 0;
  long draws_ = 0;
};

}  // namespace ravel::app::gui
