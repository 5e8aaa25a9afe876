// render_bench: time to draw one frame of a default-scene-sized fabric under OSMesa.
//
//   render_bench [--size WxH] [--repeat N] [--sides N] [--samples N] [--view NAME]
//                [--png PATH]
//
// Prints CSV (header + one row): width,height,elements,tubes,samples,sides,view,
// ms_per_frame,ms_first_frame,ms_png. ms_per_frame is the median of N draws including
// read-back (what a snapshot pays per image); ms_png is stb_image_write's encode + write.
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
               "[--samples N] [--view oblique|top|back|section] [--png PATH]\n",
               why);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ravel;
  int width = 1600, height = 1200, repeat = 5, samples = 4;
  render::ViewOptions options;
  std::string png;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
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

  std::string error;
  auto context = render::OffscreenContext::create(width, height, samples, &error);
  if (!context) {
    std::fprintf(stderr, "render_bench: %s\n", error.c_str());
    return 1;
  }
  render::Renderer renderer;
  const render::Camera camera =
      render::fitted_camera(frame, options.view, static_cast<float>(width) / height);

  std::vector<double> times;
  std::vector<std::uint8_t> rgb;
  double first = 0;
  for (int i = 0; i <= repeat; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    renderer.draw(frame, camera, options, 0, 0, width, height);
    rgb = context->read_rgb();
    (i == 0 ? first : times.emplace_back()) = ms_since(t0);
  }
  std::sort(times.begin(), times.end());
  double png_ms = 0;
  if (!png.empty()) {
    const auto t0 = std::chrono::steady_clock::now();
    if (!render::write_png(png, width, height, rgb, &error)) {
      std::fprintf(stderr, "render_bench: %s\n", error.c_str());
      return 1;
    }
    png_ms = ms_since(t0);
  }
  std::printf(
      "width,height,elements,tubes,samples,sides,view,ms_per_frame,ms_first_frame,ms_png\n");
  std::printf("%d,%d,%zu,%d,%d,%d,%s,%.1f,%.1f,%.1f\n", width, height, frame.elem_a.size(),
              renderer.stats().tubes_drawn, samples, options.tube_sides,
              render::to_string(options.view), times[times.size() / 2], first, png_ms);
  return 0;
}
