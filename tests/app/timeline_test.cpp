// The app's timeline (app/worker/timeline.h): frames kept within a memory budget, evenly thinned,
// found by time and rebuilt whole.
#include "timeline.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ravel::app {
namespace {

// A small frame whose every per-frame array carries its time, so a rebuilt frame can be
// checked value by value.
Frame make_frame(double t_s, int nodes = 50, int elems = 40, int crossings = 20) {
  Frame f;
  f.scene_name = "t";
  f.time_s = t_s;
  const float v = float(t_s * 1e6);
  for (int i = 0; i < nodes; ++i) {
    f.node_pos.push_back({v, float(i), 0});
    f.node_vel.push_back({0, v, float(i)});
    f.node_slip_rate.push_back(v + i);
  }
  for (int e = 0; e < elems; ++e) {
    f.elem_a.push_back(std::uint32_t(e));
    f.elem_b.push_back(std::uint32_t(e + 1));
    f.elem_family.push_back(std::uint8_t(e % 2));
    f.elem_yarn.push_back(std::uint32_t(e / 10));
    f.elem_broken.push_back(std::uint8_t(v > 5 && e == 3));
    f.elem_strain.push_back(1e-3f * v + 1e-6f * float(e));
    f.elem_stress_pa.push_back(1e6f * v);
  }
  for (int c = 0; c < crossings; ++c) {
    f.crossing_warp_node.push_back(std::uint32_t(c));
    f.crossing_weft_node.push_back(std::uint32_t(c + 1));
    f.crossing_i.push_back(c);
    f.crossing_j.push_back(-c);
    f.crossing_normal_force_n.push_back(v * float(c));
    f.crossing_slip_rate.push_back(v);
    f.crossing_active.push_back(1);
  }
  f.projectile_pos = {0, 0, v};
  return f;
}

TEST(Timeline, KeepsEveryFrameWithinTheBudgetAndRebuildsThemWhole) {
  Timeline tl(std::size_t(64) << 20);
  tl.reset(1);
  for (int k = 0; k <= 100; ++k) tl.add(make_frame(k * 1e-6), k * 10);
  ASSERT_EQ(tl.size(), 101u);
  EXPECT_EQ(tl.spacing_s(), 0.0);
  const Frame f = tl.frame(37);
  const Frame ref = make_frame(37e-6);
  EXPECT_EQ(f.time_s, ref.time_s);
  EXPECT_EQ(tl.step(37), 370);
  EXPECT_EQ(f.node_pos, ref.node_pos);
  EXPECT_EQ(f.node_vel, ref.node_vel);
  EXPECT_EQ(f.elem_strain, ref.elem_strain);
  EXPECT_EQ(f.elem_stress_pa, ref.elem_stress_pa);
  EXPECT_EQ(f.elem_broken, ref.elem_broken);
  EXPECT_EQ(f.elem_a, ref.elem_a);  // from the run's first frame (does not change)
  EXPECT_EQ(f.elem_yarn, ref.elem_yarn);
  EXPECT_EQ(f.crossing_normal_force_n, ref.crossing_normal_force_n);
  EXPECT_EQ(f.crossing_i, ref.crossing_i);
  EXPECT_EQ(f.projectile_pos, ref.projectile_pos);
  EXPECT_EQ(tl.strain(37, 5), ref.elem_strain[5]);
  EXPECT_EQ(tl.crossing_force(37, 7), ref.crossing_normal_force_n[7]);
  EXPECT_EQ(tl.crossing_force(37, 700), 0.0f);  // a crossing the frame does not have
}

TEST(Timeline, FindsTheLastFrameAtOrBeforeATime) {
  Timeline tl;
  tl.reset(1);
  for (int k = 0; k < 10; ++k) tl.add(make_frame(2e-6 * k), k);
  EXPECT_EQ(tl.index_at(-1), 0u);
  EXPECT_EQ(tl.index_at(0), 0u);
  EXPECT_EQ(tl.index_at(3.9e-6), 1u);
  EXPECT_EQ(tl.index_at(4e-6), 2u);
  EXPECT_EQ(tl.index_at(1.0), 9u);
  // A frame no later than the newest is not new: ignored.
  tl.add(make_frame(18e-6), 99);
  tl.add(make_frame(5e-6), 99);
  EXPECT_EQ(tl.size(), 10u);
}

TEST(Timeline, ThinsEvenlyToStayWithinItsBudgetAndKeepsBothEnds) {
  const std::size_t per_frame = [] {
    Timeline probe;
    probe.reset(0);
    probe.add(make_frame(0), 0);
    return probe.bytes();
  }();
  // Room for 40 frames; feed 1000, 0.1 us apart (a 100 us run).
  Timeline tl(40 * per_frame);
  tl.reset(7);
  for (int k = 0; k < 1000; ++k) {
    tl.add(make_frame(k * 1e-7), k);
    ASSERT_LE(tl.bytes(), tl.budget_bytes()) << "after frame " << k;
  }
  EXPECT_EQ(tl.frames_seen(), 1000);
  EXPECT_GE(tl.size(), 20u);  // thinning halves at most: at least half the budget is used
  EXPECT_LE(tl.size(), 40u);
  EXPECT_DOUBLE_EQ(tl.first_time(), 0.0);
  EXPECT_DOUBLE_EQ(tl.last_time(), 999e-7);  // the newest frame is always kept
  // Evenly spread: every gap but the last is at least the spacing and at most twice it.
  ASSERT_GT(tl.spacing_s(), 0.0);
  for (std::size_t i = 1; i + 1 < tl.size(); ++i) {
    const double gap = tl.time(i) - tl.time(i - 1);
    EXPECT_GE(gap, tl.spacing_s() - 1e-15) << i;
    EXPECT_LE(gap, 2 * tl.spacing_s() + 1e-7 + 1e-15) << i;
  }
  // A new run starts empty.
  tl.reset(8);
  EXPECT_TRUE(tl.empty());
  EXPECT_EQ(tl.bytes(), 0u);
  EXPECT_EQ(tl.run_id(), 8);
}

TEST(Timeline, TheDefaultBudgetHoldsA300UsDefaultRunAtEveryMicrosecond) {
  // The default scene's quarter model: 10,368 nodes, 10,224 elements, 5,112 crossings.
  Timeline tl;  // 256 MB
  tl.reset(1);
  for (int k = 0; k <= 300; ++k) tl.add(make_frame(k * 1e-6, 10368, 10224, 5112), k);
  EXPECT_EQ(tl.size(), 301u) << "thinned to " << tl.size() << " frames, " << tl.bytes() / (1 << 20) << " MB";
  EXPECT_LT(tl.bytes(), std::size_t(160) << 20);  // about 0.47 MB a frame
}

}  // namespace
}  // namespace ravel::app
