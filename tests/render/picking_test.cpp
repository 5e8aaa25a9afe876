// Picking (render/picking.h): the element or crossing under a pixel of the 3D view, in the
// modelled part or a mirrored copy, with the view's camera. No GL needed.
#include "render/picking.h"

#include <gtest/gtest.h>

#include <cmath>

#include "synthetic_frame.h"

namespace ravel::render {
namespace {

struct Px {
  float x, y;
};

Px project(const Camera& cam, const std::array<float, 3>& p, const std::array<float, 3>& m, int w, int h) {
  float u = 0, v = 0;
  EXPECT_TRUE(cam.project(Vec3{p[0] * m[0], p[1] * m[1], p[2] * m[2]}, float(w) / float(h), &u, &v));
  return {u * float(w), v * float(h)};
}

Px element_mid(const Frame& f, const Camera& cam, int e, const std::array<float, 3>& m, int w, int h) {
  const auto& a = f.node_pos[f.elem_a[std::size_t(e)]];
  const auto& b = f.node_pos[f.elem_b[std::size_t(e)]];
  return project(cam, {0.5f * (a[0] + b[0]), 0.5f * (a[1] + b[1]), 0.5f * (a[2] + b[2])}, m, w, h);
}

TEST(Picking, FindsTheElementUnderThePixelInEachMirroredCopy) {
  testing::SyntheticFabric s;
  s.yarns = 24;
  const Frame f = testing::make_synthetic_frame(s);
  ViewOptions o;
  o.view = ViewPreset::top;
  const int w = 1000, h = 800;
  const Camera cam = fitted_camera(f, o.view, float(w) / float(h));
  const auto copies = view_copies(f, o);
  ASSERT_EQ(copies.size(), 4u);  // a quarter: the modelled part and three mirror images
  // Elements away from the symmetry planes (on a plane a copy coincides with its mirror), in
  // every copy.
  int tested = 0;
  for (int e : {40, 333, 700, 901, int(f.elem_a.size()) - 5}) {
    const auto& a = f.node_pos[f.elem_a[std::size_t(e)]];
    if (std::abs(a[0]) < 2 * s.spacing_m || std::abs(a[1]) < 2 * s.spacing_m) continue;
    ++tested;
    for (std::size_t c = 0; c < copies.size(); ++c) {
      const Px p = element_mid(f, cam, e, copies[c], w, h);
      const Pick k = pick_element(f, cam, o, w, h, p.x, p.y);
      EXPECT_EQ(k.element, e) << "copy " << c;
      EXPECT_EQ(k.copy, int(c));
      EXPECT_EQ(k.mirror, copies[c]);
      EXPECT_LT(k.distance_px, 1.0f);
    }
  }
  EXPECT_GE(tested, 3);
  // Off the fabric: nothing.
  EXPECT_EQ(pick_element(f, cam, o, w, h, 2.0f, 2.0f).element, -1);
  // Without mirroring only the modelled quarter is there.
  o.mirror = false;
  const Px p = element_mid(f, cam, 333, {-1, 1, 1}, w, h);
  const Pick k = pick_element(f, cam, o, w, h, p.x, p.y);
  EXPECT_NE(k.element, 333);
}

TEST(Picking, BrokenAndCutAwayElementsAreNotPickable) {
  testing::SyntheticFabric s;
  s.yarns = 24;
  s.hole_radius_m = 3e-3f;
  const Frame f = testing::make_synthetic_frame(s);
  ViewOptions o;
  o.view = ViewPreset::top;
  const int w = 900, h = 900;
  const Camera cam = fitted_camera(f, o.view, 1.0f);
  int broken = -1;
  for (std::size_t e = 0; e < f.elem_broken.size() && broken < 0; ++e)
    if (f.elem_broken[e]) broken = int(e);
  ASSERT_GE(broken, 0);
  const Px p = element_mid(f, cam, broken, {1, 1, 1}, w, h);
  EXPECT_NE(pick_element(f, cam, o, w, h, p.x, p.y, 2.0f).element, broken);
  // The section cut removes y < projectile y: the mirror copy below the cut is gone.
  o.section_cut = true;
  const Px below = element_mid(f, cam, 333, {1, -1, 1}, w, h);
  const Pick k = pick_element(f, cam, o, w, h, below.x, below.y, 1.0f);
  EXPECT_FALSE(k.element == 333 && k.mirror[1] < 0);
}

TEST(Picking, FindsTheCrossingUnderThePixel) {
  testing::SyntheticFabric s;
  s.yarns = 16;
  Frame f = testing::make_synthetic_frame(s);
  // Crossings at every grid point: warp node (0, i, j) over weft node (1, i, j).
  const std::uint32_t n = std::uint32_t(s.yarns);
  for (std::uint32_t i = 0; i < n; ++i)
    for (std::uint32_t j = 0; j < n; ++j) {
      f.crossing_warp_node.push_back(i * n + j);
      f.crossing_weft_node.push_back(n * n + i * n + j);
      f.crossing_i.push_back(int(i));
      f.crossing_j.push_back(int(j));
      f.crossing_normal_force_n.push_back(float(i + j));
      f.crossing_slip_rate.push_back(0);
      f.crossing_active.push_back(1);
    }
  ViewOptions o;
  o.view = ViewPreset::top;
  const int w = 800, h = 800;
  const Camera cam = fitted_camera(f, o.view, 1.0f);
  const int target = int(5 * n + 9);
  const auto& a = f.node_pos[f.crossing_warp_node[std::size_t(target)]];
  const Px p = project(cam, {a[0], a[1], 0}, {-1, 1, 1}, w, h);
  const Pick k = pick_crossing(f, cam, o, w, h, p.x, p.y);
  EXPECT_EQ(k.crossing, target);
  EXPECT_EQ(k.mirror[0], -1.0f);
  f.crossing_active[std::size_t(target)] = 0;  // released crossings are not contacts
  EXPECT_NE(pick_crossing(f, cam, o, w, h, p.x, p.y, 2.0f).crossing, target);
}

}  // namespace
}  // namespace ravel::render
