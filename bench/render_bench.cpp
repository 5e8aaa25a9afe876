// render_bench: time to draw one frame of a default-scene-sized fabric under OSMesa.
//
//   render_bench [--size WxH] [--repeat N] [--sides N] [--samples N] [--view NAME]
//                [--geometry auto|tubes|ribbons] [--scale F] [--merge PX] [--zoom F]
//                [--png PATH] [--sweep]
//
// Prints CSV (header + one row): width,height,elements,tubes,samples,sides,view,geometry,
// scale,yarn_px,ms_per_frame,ms_first_frame,ms_png. ms_per_frame is the median of N draws
// including read-back (what a snapshot pays per image); ms_png is the PNG encode + write.
// `geometry` is what was drawn (tubes or ribbons), yarn_px the yarn width on screen.
// --sweep prints one row per configuration of a fixed matrix (headless 1600x1200 and the
// app's 3D view size, 1200x640, without MSAA), ignoring the other options but --repeat.
// The fabric is a synthetic quarter of 72 x 72 yarns per family (the default scene's
// quarter model), mirrored to the full 143 x 143, dented and strained with a hole.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "render/renderer.h"
#include "tests/render/synthetic_frame.h"

namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

int usage(const char* why) {
  std::fprintf(stderr,
               "render_bench: %s\nusage: render_bench [--size WxH] [--repeat N] [--sides N] "
               "[--samples N] [--view oblique|top|back|section] [--geometry auto|tubes|ribbons] "
               "[--scale F] [--merge PX] [--zoom F] [--png PATH] [--sweep]\n",
               why);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ravel;
  int width = 1600, height = 1200, repeat = 5, samples = 4;
  render::ViewOptions options;
  std::string png;
  bool sweep = false;
  float zoom = 1.0f;  // camera distance factor (< 1 = closer), for close-up comparisons
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--sweep") {
      sweep = true;
      continue;
    }
    const char* v = i + 1 < argc ? argv[i + 1] : nullptr;
    if (!v) return usage(("missing value after " + a).c_str());
    ++i;
    if (a == "--size") {
      if (std::sscanf(v, "%dx%d", &width, &height) != 2) return usage("--size wants WxH");
    } else if (a == "--repeat") {
      repeat = std::max(1, std::atoi(v));
    } else if (a == "--sides") {
      options.tube_sides = std::atoi(v);
    } else if (a == "--samples") {
      samples = std::atoi(v);
    } else if (a == "--view") {
      if (!render::parse_view_preset(v, &options.view)) return usage("unknown view");
    } else if (a == "--geometry") {
      if (!render::parse_yarn_geometry(v, &options.yarn_geometry))
        return usage("--geometry wants auto, tubes or ribbons");
    } else if (a == "--scale") {
      options.render_scale = static_cast<float>(std::atof(v));
    } else if (a == "--merge") {
      options.merge_px = static_cast<float>(std::atof(v));
    } else if (a == "--zoom") {
      zoom = static_cast<float>(std::atof(v));
    } else if (a == "--png") {
      png = v;
    } else {
      return usage(("unknown option " + a).c_str());
    }
  }

  testing::SyntheticFabric s;
  s.yarns = 72;
  s.dent_depth_m = 0.012f;
  s.peak_strain = 1.0f;
  s.hole_radius_m = 0.003f;
  s.projectile_z_m = -0.006f;
  const Frame frame = testing::make_synthetic_frame(s);

  struct Config {
    int width, height, samples;
    render::ViewOptions options;
  };
  std::vector<Config> configs;
  if (!sweep) {
    configs.push_back({width, height, samples, options});
  } else {
    using G = render::YarnGeometry;
    const struct {
      int w, h, samples, sides;
      G geometry;
      float scale;
      float merge = 0;
    } matrix[] = {
        {1600, 1200, 4, 8, G::tubes, 1},        {1600, 1200, 4, 8, G::ribbons, 1},
        {1600, 1200, 0, 8, G::tubes, 1},        {1600, 1200, 0, 4, G::tubes, 1},
        {1600, 1200, 0, 8, G::ribbons, 1},      {1200, 640, 0, 8, G::tubes, 1},
        {1200, 640, 0, 4, G::tubes, 1},         {1200, 640, 0, 8, G::ribbons, 1},
        {1200, 640, 0, 8, G::ribbons, 0.75f},   {1200, 640, 0, 8, G::ribbons, 0.5f},
        {1200, 640, 0, 8, G::ribbons, 1, 0.5f}, {1600, 1200, 0, 8, G::ribbons, 0.5f},
        {160, 120, 0, 8, G::tubes, 1},          {160, 120, 0, 8, G::ribbons, 1},
    };
    for (const auto& m : matrix) {
      render::ViewOptions o = options;
      o.tube_sides = m.sides;
      o.yarn_geometry = m.geometry;
      o.render_scale = m.scale;
      o.merge_px = m.merge;
      configs.push_back({m.w, m.h, m.samples, o});
    }
  }

  std::printf(
      "width,height,elements,tubes,samples,sides,view,geometry,scale,merge_px,yarn_px,"
      "ms_per_frame,ms_first_frame,ms_png\n");
  for (const Config& c : configs) {
    std::string error;
    auto context = render::OffscreenContext::create(c.width, c.height, c.samples, &error);
    if (!context) {
      std::fprintf(stderr, "render_bench: %s\n", error.c_str());
      return 1;
    }
    render::Renderer renderer;
    render::Camera camera = render::fitted_camera(frame, c.options.view, static_cast<float>(c.width) / c.height);
    if (zoom > 0 && zoom != 1.0f) camera.zoom(zoom);

    std::vector<double> times;
    std::vector<std::uint8_t> rgb;
    double first = 0;
    for (int i = 0; i <= repeat; ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      renderer.draw(frame, camera, c.options, 0, 0, c.width, c.height);
      rgb = context->read_rgb();
      (i == 0 ? first : times.emplace_back()) = ms_since(t0);
    }
    std::sort(times.begin(), times.end());
    double png_ms = 0;
    if (!png.empty() && !sweep) {
      const auto t0 = std::chrono::steady_clock::now();
      if (!render::write_png(png, c.width, c.height, rgb, &error)) {
        std::fprintf(stderr, "render_bench: %s\n", error.c_str());
        return 1;
      }
      png_ms = ms_since(t0);
    }
    const render::DrawStats& st = renderer.stats();
    std::printf("%d,%d,%zu,%d,%d,%d,%s,%s,%.2f,%.2f,%.1f,%.1f,%.1f,%.1f\n", c.width, c.height, frame.elem_a.size(),
                st.tubes_drawn, c.samples, c.options.tube_sides, render::to_string(c.options.view),
                st.ribbons ? "ribbons" : "tubes", static_cast<double>(st.fabric_width) / c.width, c.options.merge_px,
                st.yarn_width_px, times[times.size() / 2], first, png_ms);
    std::fflush(stdout);
  }
  return 0;
}
