// Headless render checks on real runs of the default scene (the paper's ballistic test).
#include <gtest/gtest.h>

#include <filesystem>

#include "core/scene.h"
#include "core/simulation.h"
#include "render/renderer.h"
#include "tests/render/render_test_util.h"

namespace ravel::testing {
namespace {

using render::Camera;
using render::ViewOptions;
using render::ViewPreset;

// Run the default scene with overrides to `until_us` (or to its end), return the frame.
Frame run_default(const std::vector<std::string>& overrides, double until_us, Summary* summary) {
  Simulation sim(load_scene(default_scene_path(), overrides));
  while (sim.time_s() < until_us * 1e-6 && sim.step()) {
  }
  if (summary) *summary = sim.summary();
  return sim.frame();
}

// Fraction of background pixels within `radius_m` of the strike point, seen from the top
// with the projectile hidden, the camera zoomed onto a 30 mm wide patch around it.
// The rendered image is kept in the build folder (render_run_out/NAME.png) for a look.
double background_at_impact(const Frame& f, const std::string& name, float radius_m = 2e-3f) {
  const int w = 400, h = 300;
  const ViewOptions o = fabric_only(ViewPreset::top);
  Camera c = Camera::preset(ViewPreset::top);
  // The strike point in the fabric plane (the projectile itself may have flown on).
  const float px = f.projectile_pos[0], py = f.projectile_pos[1];
  c.fit_box({px - 0.015f, py - 0.011f, 0}, {px + 0.015f, py + 0.011f, 0}, float(w) / h, 1.0f);
  const Image img = render_image(f, c, o, w, h);
  const Image bg = render_image(f, c, background_only(o), w, h);
  float u, v, ur, vr;
  EXPECT_TRUE(c.project({px, py, 0}, float(w) / h, &u, &v));
  EXPECT_TRUE(c.project({px + radius_m, py, 0}, float(w) / h, &ur, &vr));
  const std::string dir = std::string(RAVEL_RENDER_OUTPUT_DIR) + "/render_run_out";
  std::filesystem::create_directories(dir);
  render::write_png(dir + "/" + name + ".png", w, h, img.rgb);
  return background_fraction_in_circle(img, bg, u * w, v * h, (ur - u) * w);
}

TEST(RenderRun, DefaultSceneRendersAndIsNotBlank) {
  const Frame f = run_default({}, 20.0, nullptr);
  ASSERT_GT(f.elem_a.size(), 1000u);
  const int w = 400, h = 300;
  ViewOptions o;  // oblique, strain, everything shown
  const Camera c = render::fitted_camera(f, o.view, float(w) / h);
  const Image img = render_image(f, c, o, w, h);
  const Image bg = render_image(f, c, background_only(o), w, h);
  int drawn = 0;
  std::vector<int> seen(1 << 15, 0);
  int distinct = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      drawn += max_channel_diff(img.at(x, y), bg.at(x, y)) > 6;
      const auto* p = img.at(x, y);
      const int key = (p[0] >> 3) << 10 | (p[1] >> 3) << 5 | (p[2] >> 3);
      distinct += seen[key]++ == 0;
    }
  EXPECT_GT(double(drawn) / (w * h), 0.35);  // the fabric fills much of the view
  EXPECT_GT(distinct, 200);                  // shaded and coloured, not flat
  // The full fabric is shown although a quarter was simulated.
  EXPECT_TRUE(f.mirror_x && f.mirror_y) << "default scene expected to run as a quarter";
  EXPECT_EQ(headless().stats().mirror_copies, 4);
}

TEST(RenderRun, PerforatedRunShowsAHoleAtTheImpactPoint) {
  Summary s;
  const Frame f = run_default({"projectile.velocity_mps=360"}, 1e9, &s);
  ASSERT_TRUE(s.perforated) << "360 m/s should perforate the default fabric";
  int broken = 0;
  for (auto b : f.elem_broken) broken += b;
  EXPECT_GT(broken, 0);
  EXPECT_GT(background_at_impact(f, "perforated_360", 3.5e-3f), 0.25);
}

TEST(RenderRun, UnperforatedRunShowsNoHole) {
  // A run that is really stopped (thrown back or caught, not merely unfinished): 40 m/s on
  // the default scene lumped two yarns to one (so it decides in about a second of CPU),
  // drawn at its end.
  Summary s;
  const Frame f =
      run_default({"projectile.velocity_mps=40", "fabric.yarns_per_element=2", "solver.end_time_us=auto"}, 1e9, &s);
  ASSERT_FALSE(s.perforated);
  ASSERT_TRUE(s.end_reason == EndReason::rebounded || s.end_reason == EndReason::caught) << to_string(s.end_reason);
  EXPECT_LT(background_at_impact(f, "unperforated_40", 3.5e-3f), 0.02);
}

TEST(RenderRun, StrainedRegionColourDiffersFromUnstrained) {
  const Frame f = run_default({}, 30.0, nullptr);
  const int w = 480, h = 360;
  const ViewOptions o = fabric_only(ViewPreset::top);
  const Camera c = render::fitted_camera(f, ViewPreset::top, float(w) / h);
  const Image img = render_image(f, c, o, w, h);
  // Most strained and least strained intact elements of the modelled part.
  std::size_t hi = 0, lo = 0;
  for (std::size_t e = 0; e < f.elem_strain.size(); ++e) {
    if (f.elem_broken[e]) continue;
    if (f.elem_strain[e] > f.elem_strain[hi]) hi = e;
    if (std::abs(f.elem_strain[e]) < std::abs(f.elem_strain[lo])) lo = e;
  }
  ASSERT_GT(f.elem_strain[hi], 0.3f * f.failure_strain);
  auto centre_px = [&](std::size_t e, float* x, float* y) {
    const auto& a = f.node_pos[f.elem_a[e]];
    const auto& b = f.node_pos[f.elem_b[e]];
    float u, v;
    EXPECT_TRUE(c.project({0.5f * (a[0] + b[0]), 0.5f * (a[1] + b[1]), 0.5f * (a[2] + b[2])}, float(w) / h, &u, &v));
    *x = u * w, *y = v * h;
  };
  float xh, yh, xl, yl;
  centre_px(hi, &xh, &yh);
  centre_px(lo, &xl, &yl);
  const auto hot = mean_color(img, xh, yh, 1.5f), cold = mean_color(img, xl, yl, 1.5f);
  EXPECT_GT(color_distance(hot, cold), 0.2f) << "strain " << f.elem_strain[hi] << " vs " << f.elem_strain[lo];
}

}  // namespace
}  // namespace ravel::testing
