// Headless render checks on synthetic Frames: context, camera, coverage, mirroring,
// broken elements, colours, warp / weft, overlay.
#include <gtest/gtest.h>

#include <cstdio>

#include "render/renderer.h"
#include "tests/render/render_test_util.h"
#include "tests/render/synthetic_frame.h"

namespace ravel::testing {
namespace {

using render::Camera;
using render::ViewOptions;
using render::ViewPreset;

TEST(RenderContext, OsmesaGivesCoreProfileOf33OrLater) {
  auto& h = headless();
  const std::string version = h.context().gl_version();
  int major = 0, minor = 0;
  ASSERT_EQ(std::sscanf(version.c_str(), "%d.%d", &major, &minor), 2) << version;
  EXPECT_GE(major * 10 + minor, 33) << version;
  EXPECT_NE(version.find("Core"), std::string::npos) << version;
}

TEST(RenderCamera, TopViewShowsXRightAndYUp) {
  Frame f = make_synthetic_frame({});
  const Camera c = render::fitted_camera(f, ViewPreset::top, 4.0f / 3.0f);
  float u0, v0, ux, vx, uy, vy;
  ASSERT_TRUE(c.project({0, 0, 0}, 4.0f / 3.0f, &u0, &v0));
  ASSERT_TRUE(c.project({0.01f, 0, 0}, 4.0f / 3.0f, &ux, &vx));
  ASSERT_TRUE(c.project({0, 0.01f, 0}, 4.0f / 3.0f, &uy, &vy));
  EXPECT_NEAR(u0, 0.5f, 1e-3f);
  EXPECT_NEAR(v0, 0.5f, 1e-3f);
  EXPECT_GT(ux, u0 + 0.01f);  // +x to the right
  EXPECT_NEAR(vx, v0, 1e-4f);
  EXPECT_LT(vy, v0 - 0.01f);  // +y up (image rows run down)
  const Camera back = render::fitted_camera(f, ViewPreset::back, 4.0f / 3.0f);
  ASSERT_TRUE(back.project({0.01f, 0, 0}, 4.0f / 3.0f, &ux, &vx));
  EXPECT_LT(ux, 0.49f);  // seen from behind, +x is on the left
}

TEST(RenderCamera, FitPutsEveryFabricCornerInsideTheView) {
  Frame f = make_synthetic_frame({});
  for (ViewPreset v : {ViewPreset::oblique, ViewPreset::top, ViewPreset::back}) {
    const Camera c = render::fitted_camera(f, v, 1.5f);
    float umin = 1, umax = 0, vmin = 1, vmax = 0;
    for (float x : {-f.half_width_m, f.half_width_m})
      for (float y : {-f.half_length_m, f.half_length_m}) {
        float u, w;
        ASSERT_TRUE(c.project({x, y, 0}, 1.5f, &u, &w));
        umin = std::min(umin, u), umax = std::max(umax, u), vmin = std::min(vmin, w), vmax = std::max(vmax, w);
      }
    EXPECT_GE(umin, 0.0f) << to_string(v);
    EXPECT_LE(umax, 1.0f) << to_string(v);
    EXPECT_GE(vmin, 0.0f) << to_string(v);
    EXPECT_LE(vmax, 1.0f) << to_string(v);
    // Fitted, not lost in the distance: the fabric spans most of one image dimension.
    EXPECT_GT(std::max(umax - umin, vmax - vmin), 0.7f) << to_string(v);
  }
}

// The flat fabric seen from the top covers exactly its projected rectangle.
TEST(RenderCoverage, FabricCoversItsProjectedRectangle) {
  SyntheticFabric s;
  s.projectile_z_m = 0.05f;
  const Frame f = make_synthetic_frame(s);
  const int w = 400, h = 300;
  const ViewOptions o = fabric_only(ViewPreset::top);
  const Camera c = render::fitted_camera(f, ViewPreset::top, float(w) / h);
  const Image img = render_image(f, c, o, w, h);
  const Image bg = render_image(f, c, background_only(o), w, h);
  float u0, v0, u1, v1;
  ASSERT_TRUE(c.project({-f.half_width_m, f.half_length_m, 0}, float(w) / h, &u0, &v0));
  ASSERT_TRUE(c.project({f.half_width_m, -f.half_length_m, 0}, float(w) / h, &u1, &v1));
  const float x0 = u0 * w, x1 = u1 * w, y0 = v0 * h, y1 = v1 * h;
  const float slack = 3.0f;  // pixels: yarn half-width beyond the outermost nodes + edge AA
  int inside = 0, inside_fabric = 0, outside = 0, outside_fabric = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float px = x + 0.5f, py = y + 0.5f;
      const bool fabric = max_channel_diff(img.at(x, y), bg.at(x, y)) > 6;
      if (px > x0 + slack && px < x1 - slack && py > y0 + slack && py < y1 - slack) {
        ++inside;
        inside_fabric += fabric;
      } else if (px < x0 - slack || px > x1 + slack || py < y0 - slack || py > y1 + slack) {
        ++outside;
        outside_fabric += fabric;
      }
    }
  ASSERT_GT(inside, w * h / 3);
  EXPECT_GT(double(inside_fabric) / inside, 0.97);  // yarns 0.92 L0 wide: an opaque weave
  EXPECT_LT(double(outside_fabric) / outside, 0.002);
}

TEST(RenderCoverage, QuarterModelIsMirroredToTheFullFabric) {
  SyntheticFabric s;
  s.yarns = 40;
  s.projectile_z_m = 0.05f;
  const Frame f = make_synthetic_frame(s);
  ASSERT_TRUE(f.mirror_x && f.mirror_y);
  const int w = 200, h = 200;
  ViewOptions o = fabric_only(ViewPreset::top);
  const Camera c = render::fitted_camera(f, ViewPreset::top, 1.0f);
  const Image bg = render_image(f, c, background_only(o), w, h);
  const Image full = render_image(f, c, o, w, h);
  o.mirror = false;
  const Image quarter = render_image(f, c, o, w, h);
  // Quadrant centres in the image: +x right, +y up.
  const float q = 0.25f * w;
  const float centres[4][2] = {{3 * q, q}, {q, q}, {q, 3 * q}, {3 * q, 3 * q}};  // (+,+) first
  for (int i = 0; i < 4; ++i) {
    EXPECT_LT(background_fraction_in_circle(full, bg, centres[i][0], centres[i][1], 10), 0.02)
        << "quadrant " << i << " of the mirrored fabric is empty";
    const double expected_bg = i == 0 ? 0.0 : 1.0;
    EXPECT_NEAR(background_fraction_in_circle(quarter, bg, centres[i][0], centres[i][1], 10), expected_bg, 0.02)
        << "quadrant " << i << " without mirroring";
  }
  EXPECT_EQ(headless().stats().mirror_copies, 1);
}

TEST(RenderBroken, BrokenElementsLeaveAHoleShowingTheBackground) {
  SyntheticFabric s;
  s.projectile_z_m = 0.05f;
  s.hole_radius_m = 0.005f;
  const Frame holed = make_synthetic_frame(s);
  s.hole_radius_m = 0;
  const Frame intact = make_synthetic_frame(s);
  const int w = 320, h = 240;
  const ViewOptions o = fabric_only(ViewPreset::top);
  const Camera c = render::fitted_camera(intact, ViewPreset::top, float(w) / h);
  const Image bg = render_image(intact, c, background_only(o), w, h);
  float u, v, ur, vr;
  ASSERT_TRUE(c.project({0, 0, 0}, float(w) / h, &u, &v));
  ASSERT_TRUE(c.project({0.003f, 0, 0}, float(w) / h, &ur, &vr));
  const float r = (ur - u) * w;  // 3 mm in pixels
  ASSERT_GT(r, 4.0f);
  const Image a = render_image(holed, c, o, w, h);
  const Image b = render_image(intact, c, o, w, h);
  EXPECT_GT(background_fraction_in_circle(a, bg, u * w, v * h, r), 0.6);
  EXPECT_LT(background_fraction_in_circle(b, bg, u * w, v * h, r), 0.02);
  EXPECT_GT(headless().stats().tubes_drawn, 0);
}

TEST(RenderColor, StrainedRegionDiffersFromUnstrained) {
  SyntheticFabric s;
  s.projectile_z_m = 0.05f;
  s.peak_strain = 0.95f;
  s.strain_decay_m = 0.01f;
  const Frame f = make_synthetic_frame(s);
  const int w = 320, h = 240;
  const ViewOptions o = fabric_only(ViewPreset::top);
  const Camera c = render::fitted_camera(f, ViewPreset::top, float(w) / h);
  const Image img = render_image(f, c, o, w, h);
  float uc, vc, ue, ve;
  ASSERT_TRUE(c.project({0, 0, 0}, float(w) / h, &uc, &vc));
  ASSERT_TRUE(c.project({0.8f * f.half_width_m, 0.8f * f.half_length_m, 0}, float(w) / h, &ue, &ve));
  const render::Vec3 hot = mean_color(img, uc * w, vc * h, 4);
  const render::Vec3 cold = mean_color(img, ue * w, ve * h, 4);
  EXPECT_GT(color_distance(hot, cold), 0.35f);
  // The colour map runs blue -> red: the strained centre is redder than it is blue,
  // the unstrained corner the other way round.
  EXPECT_GT(hot[0], hot[2]);
  EXPECT_GT(cold[2], cold[0]);
}

TEST(RenderColor, VelocityFieldUsesImpactVelocityRangeWithUnits) {
  SyntheticFabric s;
  s.dent_depth_m = 0.01f;
  const Frame f = make_synthetic_frame(s);
  ViewOptions o;
  o.field = render::ColorField::velocity;
  float lo, hi;
  render::field_range(f, o, &lo, &hi);
  EXPECT_EQ(lo, 0.0f);
  EXPECT_EQ(hi, 260.0f);
  EXPECT_STREQ(render::field_title(o.field), "yarn speed (m/s)");
  EXPECT_STREQ(render::field_title(render::ColorField::strain), "strain / failure strain");
  o.field = render::ColorField::sliding;
  render::field_range(f, o, &lo, &hi);
  EXPECT_GT(hi, 0.0f);  // automatic: a nice number at or above the largest slip rate
  float max_slip = 0;
  for (float v : f.node_slip_rate) max_slip = std::max(max_slip, v);
  EXPECT_GE(hi, max_slip);
  EXPECT_LT(hi, 2.6f * max_slip);
}

// The friction field: per element the mean of its nodes' friction heat; the scale's top at
// the 98th percentile of the nodes with any (a few hot crossings must not make the rest one
// colour), rounded up to a nice number; values above it take the top colour.
TEST(RenderColor, FrictionFieldTopsAtTheNinetyEighthPercentile) {
  SyntheticFabric s;
  Frame f = make_synthetic_frame(s);
  f.node_friction_j_per_g.assign(f.node_pos.size(), 0.0f);
  const std::size_t n = std::min<std::size_t>(1000, f.node_pos.size());
  ASSERT_EQ(n, 1000u);
  for (std::size_t i = 0; i < n; ++i) f.node_friction_j_per_g[i] = float(i + 1) * 0.1f;  // 0.1 .. 100 J/g
  f.node_friction_j_per_g[0] = 1e4f;                                                     // one hot node: above the top
  ViewOptions o;
  render::ColorField parsed;
  ASSERT_TRUE(render::parse_color_field("friction", &parsed));
  o.field = parsed;
  EXPECT_STREQ(render::to_string(o.field), "friction");
  EXPECT_STREQ(render::field_title(o.field), "friction heat (J/g)");
  float lo, hi;
  render::field_range(f, o, &lo, &hi);
  EXPECT_EQ(lo, 0.0f);
  EXPECT_EQ(hi, 100.0f);  // the 980th of 1000 values is 98.1 J/g; nice_ceil(98.1) = 100
  f.node_friction_j_per_g.assign(f.node_pos.size(), 0.0f);  // nothing yet: a small positive top
  render::field_range(f, o, &lo, &hi);
  EXPECT_GT(hi, 0.0f);
  EXPECT_LE(hi, 1e-3f);
}

// Side by side (demos, compare) a data-scaled field gets one range, the largest of the
// frames' own; strain keeps its fixed range, and a range already set stays.
TEST(RenderColor, SideBySideFramesShareTheDataScaledRange) {
  SyntheticFabric s;
  Frame cool = make_synthetic_frame(s), hot = cool;
  cool.node_friction_j_per_g.assign(cool.node_pos.size(), 2.0f);
  hot.node_friction_j_per_g.assign(hot.node_pos.size(), 40.0f);
  ViewOptions o;
  o.field = render::ColorField::friction;
  render::share_field_range({&cool, &hot}, &o);
  EXPECT_EQ(o.range_min, 0.0f);
  EXPECT_EQ(o.range_max, 50.0f);  // nice_ceil(40): the hotter frame's own top
  ViewOptions set;
  set.field = render::ColorField::friction;
  set.range_min = 0, set.range_max = 7;
  render::share_field_range({&cool, &hot}, &set);
  EXPECT_EQ(set.range_max, 7.0f);
  ViewOptions strain;
  render::share_field_range({&cool, &hot}, &strain);
  EXPECT_EQ(strain.range_max, strain.range_min);  // left to field_range (0 .. 1)
}

TEST(RenderColor, WarpAndWeftAreDistinguishable) {
  SyntheticFabric s;
  s.projectile_z_m = 0.05f;
  s.peak_strain = 0.5f;
  s.strain_decay_m = 1.0f;  // nearly uniform strain: only the family differs
  Frame warp = make_synthetic_frame(s), weft = warp;
  for (auto& fam : warp.elem_family) fam = 0;
  for (auto& fam : weft.elem_family) fam = 1;
  const int w = 160, h = 120;
  const ViewOptions o = fabric_only(ViewPreset::top);
  const Camera c = render::fitted_camera(warp, ViewPreset::top, float(w) / h);
  const render::Vec3 a = mean_color(render_image(warp, c, o, w, h), w / 2.f, h / 2.f, 20);
  const render::Vec3 b = mean_color(render_image(weft, c, o, w, h), w / 2.f, h / 2.f, 20);
  const float la = a[0] + a[1] + a[2], lb = b[0] + b[1] + b[2];
  EXPECT_GT(la, 1.2f * lb) << "warp should be drawn lighter than weft";
}

TEST(RenderOverlay, CaptionNamesSceneFrictionVelocityTimeAndModel) {
  Frame f = make_synthetic_frame({});
  f.scene_name = "twaron_ct716";
  f.time_s = 42.5e-6;
  f.friction = 0.35;
  f.impact_velocity_mps = 360;
  f.model_label = "quarter, sliding";
  std::string all;
  for (const auto& l : render::caption_lines(f, {})) all += l + "\n";
  EXPECT_NE(all.find("twaron_ct716"), std::string::npos) << all;
  EXPECT_NE(all.find("t = 42.5 us"), std::string::npos) << all;
  EXPECT_NE(all.find("mu = 0.35"), std::string::npos) << all;
  EXPECT_NE(all.find("V0 = 360 m/s"), std::string::npos) << all;
  EXPECT_NE(all.find("quarter, sliding"), std::string::npos) << all;
}

TEST(RenderOverlay, CaptionAndColourBarAreDrawn) {
  SyntheticFabric s;
  s.projectile_z_m = 0.05f;
  const Frame f = make_synthetic_frame(s);
  const int w = 640, h = 480;
  ViewOptions o = fabric_only(ViewPreset::top);
  const Camera c = render::fitted_camera(f, ViewPreset::top, float(w) / h);
  const Image plain = render_image(f, c, o, w, h);
  o.show_caption = o.show_colorbar = true;
  const Image with = render_image(f, c, o, w, h);
  auto changed = [&](int x0, int y0, int x1, int y1) {
    int n = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) n += max_channel_diff(plain.at(x, y), with.at(x, y)) > 20;
    return double(n) / ((x1 - x0) * (y1 - y0));
  };
  EXPECT_GT(changed(0, 0, 60, 40), 0.1);                          // caption, top left
  EXPECT_GT(changed(w - 30, 0, w, h / 3), 0.1);                   // colour bar, top right
  EXPECT_LT(changed(w / 3, h / 3, 2 * w / 3, 2 * h / 3), 0.001);  // the fabric is left alone
  // The bar runs from the map's low end (bottom) to its high end (top): find the most
  // saturated red and the bluest pixel in the bar's column strip.
  int red_y = -1, blue_y = -1, best_red = 0, best_blue = 0;
  for (int y = 0; y < h / 2; ++y)
    for (int x = w - 30; x < w; ++x) {
      const auto* p = with.at(x, y);
      if (p[0] - p[2] > best_red) best_red = p[0] - p[2], red_y = y;
      if (p[2] - p[0] > best_blue) best_blue = p[2] - p[0], blue_y = y;
    }
  EXPECT_GT(best_red, 100);
  EXPECT_GT(best_blue, 100);
  EXPECT_LT(red_y, blue_y);
}

// The scale bar is as long on screen as its label says (true at the fabric plane in the top
// view, where the camera's target lies), the axes triad shows x to the right and y up in the
// top view, and a highlighted element is marked where it is.
TEST(RenderOverlay, ScaleBarIsTrueToTheFabricAxesPointTheRightWayAndThePickIsMarked) {
  SyntheticFabric s;
  s.projectile_z_m = 0.05f;
  const Frame f = make_synthetic_frame(s);
  const int w = 640, h = 480;
  ViewOptions o = fabric_only(ViewPreset::top);
  const Camera c = render::fitted_camera(f, ViewPreset::top, float(w) / h);
  const Image plain = render_image(f, c, o, w, h);

  // Scale bar: the longest horizontal run of near-white pixels in the lower left quarter.
  ViewOptions bar = o;
  bar.show_scale_bar = true;
  const Image with_bar = render_image(f, c, bar, w, h);
  int longest = 0;
  for (int y = h / 2; y < h; ++y) {
    int run = 0;
    for (int x = 0; x < w / 2; ++x) {
      const auto* p = with_bar.at(x, y);
      run = (p[0] > 230 && p[1] > 230 && p[2] > 230) ? run + 1 : 0;
      longest = std::max(longest, run);
    }
  }
  float u0, v0, u1, v1;
  ASSERT_TRUE(c.project({0, 0, 0}, float(w) / h, &u0, &v0));
  ASSERT_TRUE(c.project({0.01f, 0, 0}, float(w) / h, &u1, &v1));
  const double px_per_mm = (u1 - u0) * w / 10.0;
  const double mm = longest / px_per_mm;
  // A round length: 1, 2 or 5 x 10^k mm, to the bar's pixel rounding.
  const double mant = mm / std::pow(10.0, std::floor(std::log10(mm) + 1e-9));
  EXPECT_TRUE(std::abs(mant - 1) < 0.05 || std::abs(mant - 2) < 0.05 || std::abs(mant - 5) < 0.05)
      << longest << " px = " << mm << " mm";
  EXPECT_GT(longest, 40);

  // Axes: in the top view x (red) points right of the triad's centre, y (green) up.
  ViewOptions axes = o;
  axes.show_axes = true;
  const Image with_axes = render_image(f, c, axes, w, h);
  double rx = 0, ry = 0, gx = 0, gy = 0;
  int nr = 0, ng = 0;
  for (int y = h / 2; y < h; ++y)
    for (int x = 0; x < w / 3; ++x) {
      const auto* p = with_axes.at(x, y);
      if (max_channel_diff(p, plain.at(x, y)) < 40) continue;
      if (p[0] > 180 && p[1] < 130) rx += x, ry += y, ++nr;
      if (p[1] > 180 && p[0] < 150 && p[2] < 150) gx += x, gy += y, ++ng;
    }
  ASSERT_GT(nr, 10);
  ASSERT_GT(ng, 10);
  EXPECT_GT(rx / nr, gx / ng + 5);  // the x axis' pixels lie right of the y axis'
  EXPECT_LT(gy / ng, ry / nr - 5);  // the y axis' above the x axis'

  // The highlighted element: magenta pixels where it projects.
  const int e = 777;
  ViewOptions hl = o;
  hl.highlight_element = e;
  const Image with_hl = render_image(f, c, hl, w, h);
  const auto& a = f.node_pos[f.elem_a[e]];
  const auto& b = f.node_pos[f.elem_b[e]];
  float um, vm;
  ASSERT_TRUE(c.project({0.5f * (a[0] + b[0]), 0.5f * (a[1] + b[1]), 0.5f * (a[2] + b[2])}, float(w) / h, &um, &vm));
  int magenta = 0;
  for (int y = int(vm * h) - 12; y <= int(vm * h) + 12; ++y)
    for (int x = int(um * w) - 12; x <= int(um * w) + 12; ++x) {
      const auto* p = with_hl.at(x, y);
      magenta += p[0] > 200 && p[2] > 150 && p[1] < 120;
    }
  EXPECT_GT(magenta, 20);
}

TEST(RenderSection, SectionCutRemovesTheNearHalf) {
  SyntheticFabric s;
  s.dent_depth_m = 0.012f;
  s.projectile_z_m = -0.006f;
  const Frame f = make_synthetic_frame(s);
  const int w = 320, h = 240;
  ViewOptions o = fabric_only(ViewPreset::section);
  const Camera c = render::fitted_camera(f, ViewPreset::section, float(w) / h);
  // A node on the near side (y < 0, mirrored) at the dent's bottom would be drawn in front
  // of the cut; with the cut the pixel where the apex projects shows the far side only.
  const Image cut = render_image(f, c, o, w, h);
  o.view = ViewPreset::oblique;  // same camera, no cut
  const Image whole = render_image(f, c, o, w, h);
  int differ = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) differ += max_channel_diff(cut.at(x, y), whole.at(x, y)) > 20;
  EXPECT_GT(differ, w * h / 50);
  // The apex of the dent is at the centre of the cut: the fabric is drawn there.
  float u, v;
  ASSERT_TRUE(c.project({0, 0, -0.012f}, float(w) / h, &u, &v));
  const Image bg = render_image(f, c, background_only(o), w, h);
  EXPECT_LT(background_fraction_in_circle(cut, bg, u * w, v * h - 3, 3), 0.5);
}

// The cut removes the near half (y below the impact point, towards the section camera at
// -y), not the far one: a whole fabric with only its near half left shows nothing in the
// section view, and with only its far half left shows that half.
TEST(RenderSection, TheCutIsOnTheCameraSide) {
  SyntheticFabric s;
  s.quarter = false;
  s.dent_depth_m = 0.012f;
  s.projectile_z_m = -0.006f;
  const int w = 320, h = 240;
  const ViewOptions o = fabric_only(ViewPreset::section);
  auto drawn_fraction = [&](bool keep_near) {
    Frame f = make_synthetic_frame(s);
    for (std::size_t e = 0; e < f.elem_a.size(); ++e) {
      const float y = 0.5f * (f.node_pos[f.elem_a[e]][1] + f.node_pos[f.elem_b[e]][1]);
      if ((y < 0) != keep_near) f.elem_broken[e] = 1;  // broken elements are not drawn
    }
    const Camera c = render::fitted_camera(f, ViewPreset::section, float(w) / h);
    const Image img = render_image(f, c, o, w, h);
    const Image bg = render_image(f, c, background_only(o), w, h);
    int differ = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) differ += max_channel_diff(img.at(x, y), bg.at(x, y)) > 20;
    return double(differ) / (w * h);
  };
  EXPECT_LT(drawn_fraction(true), 0.002);  // only the near half: all of it is cut away
  EXPECT_GT(drawn_fraction(false), 0.05);  // only the far half: it is what the section shows
}

}  // namespace
}  // namespace ravel::testing
