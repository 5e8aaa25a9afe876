#include <glad/gl.h>

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "modes.h"

namespace ravel::app::gui {

namespace {
double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

void SingleRunMode::update(GuiApp& app) {
  update_timeline(app);
}

void SingleRunMode::draw_panels(GuiApp& app) {
  draw_timeline_bar(app);
  draw_charts_panel(app);
  draw_status_panel(app);
  draw_picked_window(app);
}

std::string SingleRunMode::view_key(const GuiApp& app) {
  const render::Camera& c = app.camera;
  const render::ViewOptions& o = app.view_options;
  char b[400];
  std::snprintf(b, sizeof b, "%g %g %g %g %g %g %g %d %d %d %d %d %d %d %d %d %g %g %d %g %d %d %g %g %d %d",
                c.target[0], c.target[1], c.target[2], c.distance_m, c.yaw_deg, c.pitch_deg, c.fov_y_deg, int(o.view),
                int(o.field), int(o.map), o.mirror, o.show_projectile, o.show_clamps, o.section_cut, o.show_caption,
                o.show_colorbar, o.range_min, o.range_max, int(o.yarn_geometry), app.playing_render_scale,
                o.highlight_element, o.highlight_crossing, o.highlight_mirror[0], o.highlight_mirror[1],
                o.show_scale_bar, o.show_axes);
  return b;
}

void SingleRunMode::render_view(GuiApp& app, render::Renderer& renderer, int w, int h, float overlay_scale, bool busy,
                                bool force_hq) {
  const double now = now_s();
  if (target_.resize(w, h)) valid_ = false;
  const std::string key = view_key(app);
  const bool new_frame = app.shown_serial() != drawn_serial_;
  const bool view_changed = key != drawn_key_;
  // Scrubbing is drawn like a playing run: cheaper yarns and at most the redraw budget, so the
  // slider stays smooth under a software GL; full quality once the slider rests.
  if (new_frame && !app.live) busy = true;
  if (busy || new_frame || view_changed) last_change_s_ = now;
  const bool still = now - last_change_s_ > 0.25;
  // Budget: at most about a quarter of wall time on the fabric while a run plays.
  const double min_gap_s = std::max(0.066, 3.0 * last_ms_ * 1e-3);
  bool draw = !valid_ || view_changed || force_hq;
  if (!draw && new_frame && now - last_draw_s_ >= min_gap_s) draw = true;
  if (!draw && still && !hq_) draw = true;  // settle to full quality
  if (!draw || app.shown().node_pos.empty()) return;

  const bool hq = force_hq || (still && !busy && !new_frame && !view_changed) ||
                  (!busy && app.view.state != WorkerState::running && !new_frame);
  render::ViewOptions o = app.view_options;
  o.ui_scale = overlay_scale;
  o.tube_sides = hq ? std::max(8, o.tube_sides) : 4;
  // Lower internal resolution while busy (View panel); projectile and caption stay sharp.
  o.render_scale = hq ? 1.0f : app.playing_render_scale;
  // Close-ups use real tubes when still; while busy ribbons are always good enough.
  if (!hq && o.yarn_geometry == render::YarnGeometry::automatic) o.yarn_geometry = render::YarnGeometry::ribbons;
  // ...and consecutive elements merge where the result is within half a pixel.
  if (!hq) o.merge_px = 0.5f;
  const double t0 = now_s();
  target_.bind();
  renderer.draw(app.shown(), app.camera, o, 0, 0, w, h);
  render::RenderTarget::bind_window();
  glFinish();  // make the cost visible here, where it is budgeted
  last_ms_ = (now_s() - t0) * 1e3;
  last_draw_s_ = now_s();
  drawn_serial_ = app.shown_serial();
  drawn_key_ = key;
  hq_ = hq;
  valid_ = true;
  ++draws_;
}

void SingleRunMode::blit_view(int x, int y) {
  if (valid_) target_.blit_to_window(x, y);
}

void SingleRunMode::release() {
  target_.release();
  valid_ = false;
}

}  // namespace ravel::app::gui
