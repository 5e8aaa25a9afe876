// Cheaper fabric drawing (docs/rendering.md, "Speed"): ribbons as tube impostors, the
// automatic choice between them, a lower internal resolution that keeps the projectile
// and the caption sharp, and no re-upload of unchanged instances.
#include <gtest/gtest.h>

#include <memory>

#include "render/renderer.h"
#include "tests/render/render_test_util.h"
#include "tests/render/synthetic_frame.h"

namespace ravel::testing {
namespace {

using render::Camera;
using render::ViewOptions;
using render::ViewPreset;
using render::YarnGeometry;

// Pixels where the fabric differs from the background.
std::vector<bool> fabric_mask(const Image& img, const Image& bg) {
  std::vector<bool> m(static_cast<std::size_t>(img.width) * img.height);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      m[static_cast<std::size_t>(y) * img.width + x] = max_channel_diff(img.at(x, y), bg.at(x, y)) > 6;
  return m;
}

// Ribbons are impostors of the tubes: the same outline, from the top and obliquely.
TEST(RenderLod, RibbonsCoverTheSameOutlineAsTubes) {
  SyntheticFabric s;
  s.yarns = 40;
  s.dent_depth_m = 0.008f;
  s.hole_radius_m = 0.003f;
  s.projectile_z_m = 0.05f;
  const Frame f = make_synthetic_frame(s);
  const int w = 400, h = 300;
  for (ViewPreset v : {ViewPreset::top, ViewPreset::oblique, ViewPreset::back}) {
    ViewOptions o = fabric_only(v);
    const Camera c = render::fitted_camera(f, v, float(w) / h);
    const Image bg = render_image(f, c, background_only(o), w, h);
    o.yarn_geometry = YarnGeometry::tubes;
    const auto tubes = fabric_mask(render_image(f, c, o, w, h), bg);
    EXPECT_FALSE(headless().stats().ribbons);
    o.yarn_geometry = YarnGeometry::ribbons;
    const auto ribbons = fabric_mask(render_image(f, c, o, w, h), bg);
    EXPECT_TRUE(headless().stats().ribbons);
    int covered = 0, differ = 0;
    for (std::size_t i = 0; i < tubes.size(); ++i) {
      covered += tubes[i];
      differ += tubes[i] != ribbons[i];
    }
    ASSERT_GT(covered, w * h / 5) << to_string(v);
    EXPECT_LT(double(differ) / covered, 0.02) << to_string(v);
  }
}

// Automatic: ribbons while the yarn is a few pixels wide, tubes in a close-up.
TEST(RenderLod, AutomaticUsesRibbonsFarAndTubesClose) {
  const Frame f = make_synthetic_frame(SyntheticFabric{});
  const int w = 320, h = 240;
  ViewOptions o = fabric_only(ViewPreset::oblique);
  o.yarn_geometry = YarnGeometry::automatic;
  Camera c = render::fitted_camera(f, o.view, float(w) / h);
  render_image(f, c, o, w, h);
  EXPECT_TRUE(headless().stats().ribbons);
  EXPECT_LT(headless().stats().yarn_width_px, o.tube_min_px);
  c.zoom(0.03f);
  render_image(f, c, o, w, h);
  EXPECT_FALSE(headless().stats().ribbons);
  EXPECT_GE(headless().stats().yarn_width_px, o.tube_min_px);
}

// Merging consecutive elements (level of detail) halves the instances of a small view
// without changing the outline; off by default, and never for a close-up.
TEST(RenderLod, MergedElementsKeepTheOutline) {
  SyntheticFabric s;
  s.yarns = 40;
  s.dent_depth_m = 0.008f;
  s.projectile_z_m = 0.05f;
  const Frame f = make_synthetic_frame(s);
  const int w = 240, h = 180;
  ViewOptions o = fabric_only(ViewPreset::oblique);
  o.yarn_geometry = YarnGeometry::ribbons;
  const Camera c = render::fitted_camera(f, o.view, float(w) / h);
  const Image bg = render_image(f, c, background_only(o), w, h);
  const auto all = fabric_mask(render_image(f, c, o, w, h), bg);
  const int all_tubes = headless().stats().tubes_drawn;
  o.merge_px = 0.5f;
  const auto merged = fabric_mask(render_image(f, c, o, w, h), bg);
  EXPECT_LT(headless().stats().tubes_drawn, 0.7 * all_tubes);
  int covered = 0, differ = 0;
  for (std::size_t i = 0; i < all.size(); ++i) {
    covered += all[i];
    differ += all[i] != merged[i];
  }
  EXPECT_LT(double(differ) / covered, 0.02);
  Camera close = c;
  close.zoom(0.1f);
  render_image(f, close, o, w, h);
  EXPECT_EQ(headless().stats().tubes_drawn, all_tubes);
}

// A second draw of the same frame does not upload the instances again.
TEST(RenderLod, UnchangedInstancesAreNotUploadedAgain) {
  SyntheticFabric s;
  s.yarns = 30;
  Frame f = make_synthetic_frame(s);
  const ViewOptions o = fabric_only(ViewPreset::oblique);
  render_image(f, o, 200, 150);
  render_image(f, o, 200, 150);
  EXPECT_FALSE(headless().stats().instances_uploaded);
  f.elem_strain[5] = 0.04f;  // one colour changes
  render_image(f, o, 200, 150);
  EXPECT_TRUE(headless().stats().instances_uploaded);
}

// render_scale < 1: the fabric is drawn smaller and upscaled, but the caption and the
// projectile are drawn at full resolution (into a single-sampled target, as the app's).
TEST(RenderLod, LowerResolutionKeepsProjectileAndCaptionSharp) {
  SyntheticFabric s;
  s.yarns = 48;
  s.dent_depth_m = 0.006f;
  s.projectile_z_m = 0.004f;
  const Frame f = make_synthetic_frame(s);
  const int w = 480, h = 360;
  std::string error;
  auto ctx = render::OffscreenContext::create(w, h, 0, &error);
  ASSERT_TRUE(ctx) << error;
  ASSERT_TRUE(ctx->make_current());
  std::vector<std::uint8_t> full, low;
  {
    render::Renderer r;
    ViewOptions o;
    o.view = ViewPreset::top;
    const Camera c = render::fitted_camera(f, o.view, float(w) / h);
    r.draw(f, c, o, 0, 0, w, h);
    full = ctx->read_rgb();
    EXPECT_EQ(r.stats().fabric_width, w);
    o.render_scale = 0.5f;
    r.draw(f, c, o, 0, 0, w, h);
    low = ctx->read_rgb();
    EXPECT_EQ(r.stats().fabric_width, w / 2);
    EXPECT_EQ(r.stats().fabric_height, h / 2);
  }
  const Image a{w, h, full}, b{w, h, low};
  auto differing = [&](int x0, int y0, int x1, int y1) {
    int n = 0, d = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x, ++n) d += max_channel_diff(a.at(x, y), b.at(x, y)) > 24;
    return double(d) / n;
  };
  // Caption, top left: its letters are drawn at full resolution, pixel for pixel.
  int letters = 0, kept = 0;
  for (int y = 10; y < 70; ++y)
    for (int x = 10; x < 110; ++x) {
      auto bright = [](const std::uint8_t* p) { return p[0] > 170 && p[1] > 170 && p[2] > 170; };
      if (!bright(a.at(x, y))) continue;
      ++letters;
      kept += bright(b.at(x, y));
    }
  ASSERT_GT(letters, 100);
  EXPECT_GT(double(kept) / letters, 0.98);
  // Projectile, in the middle of the top view: its disc (inside the rim) is unchanged.
  float u = 0, v = 0;
  const Camera c = render::fitted_camera(f, ViewPreset::top, float(w) / h);
  ASSERT_TRUE(c.project({0, 0, s.projectile_z_m}, float(w) / h, &u, &v));
  const int cx = int(u * w), cy = int(v * h), r = 12;
  EXPECT_LT(differing(cx - r, cy - r, cx + r, cy + r), 0.01);
  // The fabric itself is not blank in the upscaled image.
  const render::Vec3 m = mean_color(b, 0.25f * w, 0.5f * h, 20);
  EXPECT_GT(m[0] + m[1] + m[2], 0.1f);
  headless();  // the shared context is made current again by its next render
}

// Into a multisampled target (exported images) render_scale is ignored.
TEST(RenderLod, LowerResolutionIsIgnoredForMultisampledImages) {
  ViewOptions o = fabric_only(ViewPreset::top);
  o.render_scale = 0.5f;
  render_image(make_synthetic_frame(SyntheticFabric{}), o, 200, 150);
  EXPECT_EQ(headless().stats().fabric_width, 200);
}

}  // namespace
}  // namespace ravel::testing
