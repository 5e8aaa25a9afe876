// Helpers for the headless render tests: images in memory, background masks, regions.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "render/renderer.h"

namespace ravel::testing {

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // top row first
  const std::uint8_t* at(int x, int y) const { return &rgb[(static_cast<size_t>(y) * width + x) * 3]; }
};

// One offscreen renderer shared by every test in the binary (context creation and
// shader compilation cost ~0.1 s each).
inline render::HeadlessRenderer& headless() {
  static std::unique_ptr<render::HeadlessRenderer> h = [] {
    std::string error;
    auto r = render::HeadlessRenderer::create(&error);
    if (!r) ADD_FAILURE() << "no offscreen context: " << error;
    return r;
  }();
  return *h;
}

inline Image render_image(const Frame& frame, const render::ViewOptions& options, int w, int h) {
  Image img{w, h, {}};
  std::string error;
  EXPECT_TRUE(headless().render(frame, options, w, h, &img.rgb, &error)) << error;
  return img;
}

inline Image render_image(const Frame& frame, const render::Camera& camera, const render::ViewOptions& options, int w,
                          int h) {
  Image img{w, h, {}};
  std::string error;
  EXPECT_TRUE(headless().render(frame, camera, options, w, h, &img.rgb, &error)) << error;
  return img;
}

// Options that draw only the fabric (no projectile, clamps, caption or colour bar).
inline render::ViewOptions fabric_only(render::ViewPreset view) {
  render::ViewOptions o;
  o.view = view;
  o.show_projectile = o.show_clamps = o.show_caption = o.show_colorbar = false;
  o.show_scale_bar = o.show_axes = false;
  return o;
}

// The same view with nothing but the background.
inline render::ViewOptions background_only(render::ViewOptions o) {
  o.show_fabric = o.show_projectile = o.show_clamps = o.show_caption = o.show_colorbar = false;
  o.show_scale_bar = o.show_axes = false;
  return o;
}

inline int max_channel_diff(const std::uint8_t* a, const std::uint8_t* b) {
  int d = 0;
  for (int k = 0; k < 3; ++k) d = std::max(d, std::abs(int(a[k]) - int(b[k])));
  return d;
}

// Fraction of pixels in a circle (pixel centre, radius in pixels) that match the
// background image within `tolerance` per channel.
inline double background_fraction_in_circle(const Image& img, const Image& bg, float cx, float cy, float r,
                                            int tolerance = 6) {
  int n = 0, same = 0;
  for (int y = std::max(0, int(cy - r)); y <= std::min(img.height - 1, int(cy + r)); ++y)
    for (int x = std::max(0, int(cx - r)); x <= std::min(img.width - 1, int(cx + r)); ++x) {
      if ((x + 0.5f - cx) * (x + 0.5f - cx) + (y + 0.5f - cy) * (y + 0.5f - cy) > r * r) continue;
      ++n;
      same += max_channel_diff(img.at(x, y), bg.at(x, y)) <= tolerance ? 1 : 0;
    }
  return n ? double(same) / n : 0.0;
}

// Mean colour (0..1) in a circle.
inline render::Vec3 mean_color(const Image& img, float cx, float cy, float r) {
  double s[3] = {0, 0, 0};
  int n = 0;
  for (int y = std::max(0, int(cy - r)); y <= std::min(img.height - 1, int(cy + r)); ++y)
    for (int x = std::max(0, int(cx - r)); x <= std::min(img.width - 1, int(cx + r)); ++x) {
      if ((x + 0.5f - cx) * (x + 0.5f - cx) + (y + 0.5f - cy) * (y + 0.5f - cy) > r * r) continue;
      for (int k = 0; k < 3; ++k) s[k] += img.at(x, y)[k] / 255.0;
      ++n;
    }
  if (n == 0) return {0, 0, 0};
  return {float(s[0] / n), float(s[1] / n), float(s[2] / n)};
}

inline float color_distance(const render::Vec3& a, const render::Vec3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

}  // namespace ravel::testing
