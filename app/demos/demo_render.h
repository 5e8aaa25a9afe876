// Headless rendering of the guided demos (app/demos/demos.h) for handouts and slides:
// `ravel demo NAME --out DIR` writes DIR/NN_<name>_<t>us.png for every key frame (the runs
// side by side in split viewports, the two-line caption, the theory overlay, the velocity
// chart so far), the charts (PNG + SVG + CSV through studies/chart.h) and DIR/index.md.
#pragma once

#include <cstdint>
#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "demos.h"
#include "render/annotate.h"
#include "render/renderer.h"
#include "chart.h"

namespace ravel::app::demos {

// Where each run's viewport sits in an image (pixels, origin top-left) and its camera.
struct ViewportLayout {
  int x = 0, y = 0, w = 0, h = 0;
  render::Camera camera;
};

struct ImageLayout {
  int width = 0, height = 0;
  std::vector<ViewportLayout> viewports;
  int chart_y = 0, chart_h = 0;    // the velocity chart strip (0 = none)
  int banner_y = 0, banner_h = 0;  // the caption banner
};

// Split a w x h image for n runs (1..4 side by side; 4 as 2 x 2), leaving room for the
// caption banner and, when `chart`, a chart strip under the viewports. Cameras are fitted
// to `first_frames` (t = 0), so the framing does not change from key frame to key frame.
ImageLayout layout_image(int w, int h, const std::vector<Frame>& first_frames, render::ViewPreset view, bool chart);

// The theoretical wave fronts of a scene at time t as polylines in the fabric plane,
// around the strike point: diamonds |x| + |y| = R (fronts that run along the yarns
// through the impact point), longitudinal (cyan) and transverse (yellow). A front larger
// than the fabric is clipped to it.
std::vector<render::WorldPolyline> wave_front_lines(const Scene& scene, const Frame& frame, double t_s);
// The overlay colours, for tests that find them on the image.
render::Vec3 longitudinal_color();
render::Vec3 transverse_color();

// Projectile speed histories of the runs (up to each run's last row), as a chart.
studies::Chart velocity_chart(const Demo& demo, const std::vector<RunState>& runs, double x_max_us);
studies::Chart broken_chart(const Demo& demo, const std::vector<RunState>& runs);

// Draw one key frame: every run in its viewport, overlays, caption banner, chart strip.
// `hr` must be current. Returns RGB, top row first.
std::vector<std::uint8_t> compose_key_frame(render::HeadlessRenderer& hr, render::Annotator& annotator,
                                            const Demo& demo, const std::vector<std::string>& caption_lines,
                                            const std::vector<RunState>& runs, const ImageLayout& layout,
                                            double chart_x_max_us);

struct DemoImage {
  std::string path;  // DIR/NN_<name>_<t>us.png
  double t_us = 0;   // the time shown (the slowest run's)
  std::vector<std::string> caption;
  std::vector<RunState> runs;  // the state drawn
  ImageLayout layout;
};

struct DemoResult {
  std::vector<DemoImage> images;
  std::vector<std::string> charts;  // path stems (STEM.png / .svg / .csv)
  std::string index_path;
  double wall_time_s = 0;
};

struct DemoRenderOptions {
  int width = 1600, height = 1000;
  int solver_threads = 1;
  bool quick = false;
  std::function<void(const std::string&)> progress;  // one line per step ("" = quiet)
  const std::atomic<bool>* interrupt = nullptr;      // Ctrl-C: the demo stops and throws "interrupted"
};

// Run the demo and write its images, charts and index.md into out_dir (created).
// Throws std::runtime_error (no OSMesa context, unwritable folder) or SceneError.
DemoResult render_demo(const Demo& demo, const std::string& out_dir, const DemoRenderOptions& options);

}  // namespace ravel::app::demos
