// Graded lumping (fabric.far_yarns_per_element, docs/MODEL.md §1): every real yarn near the
// strike point and along the clamps is modelled, one modelled yarn stands for k real ones
// elsewhere. It must be the same fabric (mass, yarn count, crimp), start at rest, and give
// the fine mesh's response where nothing is lumped better than a uniformly lumped mesh does.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "fixture.h"

namespace ravel {
namespace {

using test::operator+;

double total_mass(const Model& m) {
  double s = 0;
  for (double x : m.mass) s += x;
  return s * m.symmetry_factor;
}

// Real yarns modelled: each yarn's cross-section over the real one, summed (a yarn on a
// mirror plane counts its modelled half twice over the whole fabric, like every other).
double yarn_count(const Model& m, Family fam, double area) {
  double s = 0;
  for (int y = 0; y < m.yarn_count(); ++y)
    if (m.yarn_family[y] == fam) s += m.elem_area[m.yarn_elem_offset[y]] / area;
  return s;
}

TEST(Graded, KeepsTheFabricsMassAndYarns) {
  const Model full = build_model(test::scene_with({}));
  const Scene gs = test::scene_with({"fabric.far_yarns_per_element=3"});
  const Model g = build_model(gs);
  // 72 modelled yarns each way in the quarter; graded: 0..15 mm (18) and 45..60 mm (19 with
  // the clamped edge's) for x, 0..15 mm and every third beyond for y (free edges).
  EXPECT_LT(g.node_count, 0.6 * full.node_count);
  EXPECT_GT(g.node_count, 0.2 * full.node_count);
  // Each modelled yarn weighs its spacing to its neighbours: the fabric's mass and the
  // number of real yarns it stands for are the full mesh's (to rounding).
  EXPECT_NEAR(total_mass(g) / total_mass(full), 1.0, 1e-12);
  const double A = gs.yarn.area_m2;
  EXPECT_NEAR(yarn_count(g, warp, A), yarn_count(full, warp, A), 1e-9);
  EXPECT_NEAR(yarn_count(g, weft, A), yarn_count(full, weft, A), 1e-9);
  EXPECT_LT(g.warp_count, full.warp_count);
  EXPECT_LT(g.weft_count, full.weft_count);
  // The time step is the fine band's.
  EXPECT_NEAR(g.dt / full.dt, 1.0, 1e-12);
}

TEST(Graded, EveryYarnZigZagsAndStartsAtRest) {
  const Scene s = test::scene_with({"fabric.far_yarns_per_element=3"});
  const Model m = build_model(s);
  const double slope = s.fabric.crossing_gap_m / s.fabric.spacing_m;  // L1 / L0: the crimp
  int uniform = 0, transition = 0;
  for (int y = 0; y < m.yarn_count(); ++y) {
    for (int k = 0; k + 1 < m.yarn_size(y); ++k) {
      const Vec3d a = m.x0[m.yarn_node(y, k)], b = m.x0[m.yarn_node(y, k + 1)];
      ASSERT_LT(a.z() * b.z(), 0.0) << "yarn " << y << " node " << k << ": no zig-zag";
      const Vec3d d = b - a;
      const double run = std::hypot(d.x(), d.y()), rise = std::abs(d.z());
      // Where both nodes stand for the same spacing the crimp angle is the real fabric's;
      // across a change of spacing it lies between the two sides' (within 50 %).
      const double r = rise / run / slope;
      const double za = std::abs(a.z()), zb = std::abs(b.z());
      if (std::abs(za - zb) < 1e-12 && std::abs(run - 2 * za / s.fabric.crossing_gap_m * s.fabric.spacing_m) < 1e-9) {
        EXPECT_NEAR(r, 1.0, 1e-9);
        ++uniform;
      } else {
        EXPECT_GE(r, 0.5 - 1e-9);
        EXPECT_LE(r, 1.5 + 1e-9);
        ++transition;
      }
      // Every element starts unstretched.
      EXPECT_NEAR(m.elem_rest[m.yarn_elem_offset[y] + k], d.norm(), 1e-15);
    }
  }
  // A change of spacing tilts the two elements beside it, and a free edge yarn (weight
  // (1 + k) / 2) its last one: at most three changes, six elements, per yarn.
  EXPECT_GT(uniform, 4 * transition);
  EXPECT_LE(transition, 6 * m.yarn_count());
  // Every crossing starts touching or apart, never pressed.
  for (const Crossing& c : m.crossings) {
    EXPECT_GT(c.contact_distance, 0.0);
    EXPECT_LE(c.flattened_distance, c.contact_distance);
  }
  // The projectile starts touching the fabric under it, not the higher crimp of the lumped
  // yarns far away.
  const Model full = build_model(test::scene_with({}));
  EXPECT_DOUBLE_EQ(m.projectile_x0.z(), full.projectile_x0.z());
}

// The projectile's speed at 60 us on a 60 mm ply (no failure): a graded mesh, fine within
// 8 mm of the strike and 4 mm of the clamps, is much closer to the full mesh than a mesh
// lumped everywhere by the same k (measured: 0.045 against 0.45 m/s at 150 m/s; the full mesh 144.73 m/s).
TEST(Graded, FollowsTheFullMeshWhereTheProjectileIs) {
  const std::vector<std::string> base{"fabric.width_mm=60", "fabric.length_mm=60", "projectile.velocity_mps=150",
                                      "solver.end_time_us=60", "yarn.breakable=false"};
  auto v_end = [&](const std::vector<std::string>& more) {
    Simulation sim(test::scene_with(base + more));
    sim.run();
    EXPECT_LT(std::abs(sim.summary().energy_balance_error), 2e-3);
    return sim.history().back().projectile_velocity_mps;
  };
  const double full = v_end({});
  const double uniform = v_end({"fabric.yarns_per_element=3"});
  const double graded =
      v_end({"fabric.far_yarns_per_element=3", "fabric.full_resolution_mm=8", "fabric.clamp_resolution_mm=4"});
  EXPECT_LT(std::abs(graded - full), 0.25 * std::abs(uniform - full))
      << "full " << full << " uniform " << uniform << " graded " << graded;
}

TEST(Graded, RefusesToLumpTwice) {
  try {
    test::scene_with({"fabric.far_yarns_per_element=3", "fabric.yarns_per_element=2"});
    FAIL() << "accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("fabric.far_yarns_per_element"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cannot be combined"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ravel
