// Checkpoints (Simulation::checkpoint / restore, core/state_io.h): a run written out and
// read back into a new Simulation of the same scene continues bit for bit like the run
// that never stopped, through contact, sliding, yarn failure and perforation; bytes of
// another scene or damaged bytes are refused and change nothing.
#include <gtest/gtest.h>

#include <cstring>

#include "fixture.h"

namespace ravel::test {
namespace {

// Everything a history row holds, compared as bytes (bit for bit).
bool same_rows(const std::vector<HistoryRow>& a, const std::vector<HistoryRow>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::memcmp(&a[i], &b[i], sizeof(HistoryRow)) != 0) return false;
  return true;
}

// Run `scene` to t_stop, checkpoint, then (a) go on to the end and (b) restore the bytes into a
// fresh Simulation and go on to the end: the two must agree in every bit.
void expect_resume_is_exact(const Scene& scene, double t_stop, const Scene* resume_scene = nullptr) {
  Simulation a(scene);
  run_until(a, t_stop);
  ASSERT_FALSE(a.finished()) << "stop earlier: the run ended before " << t_stop * 1e6 << " us";
  const std::string bytes = a.checkpoint();
  const long steps_at_stop = a.step_count();
  a.run();

  Simulation b(resume_scene ? *resume_scene : scene);
  b.restore(bytes);
  EXPECT_EQ(b.step_count(), steps_at_stop);
  b.run();

  EXPECT_EQ(a.state_hash(), b.state_hash());
  EXPECT_EQ(a.step_count(), b.step_count());
  EXPECT_TRUE(same_rows(a.history(), b.history())) << "histories differ";
  const Summary sa = a.summary(), sb = b.summary();
  EXPECT_EQ(sa.end_reason, sb.end_reason);
  EXPECT_EQ(sa.perforated, sb.perforated);
  EXPECT_EQ(sa.residual_velocity_mps, sb.residual_velocity_mps);
  EXPECT_EQ(sa.perforation_time_s, sb.perforation_time_s);
  EXPECT_EQ(sa.broken_warp, sb.broken_warp);
  EXPECT_EQ(sa.broken_weft, sb.broken_weft);
  EXPECT_EQ(sa.energy_balance_error, sb.energy_balance_error);
  EXPECT_EQ(sa.warnings, sb.warnings);
}

// A slipping clamp's yarn fed out (State::grip_payout) is state: stopped while the clamps
// feed, the resumed run goes on bit for bit, including the pull-out past the clamp's depth.
TEST(Checkpoint, SlippingClampsResumeBitForBit) {
  const Scene s =
      scene_with({"fabric.width_mm=30", "fabric.length_mm=30", "projectile.diameter_mm=4", "projectile.mass_g=1",
                  "projectile.velocity_mps=300", "fabric.clamp=slipping", "fabric.clamp_grip_n=60"});
  {
    Simulation probe(s);
    run_until(probe, 40e-6);
    ASSERT_GT(probe.summary().clamp_slip_max_m, 1e-4) << "the test needs clamps feeding at the stop";
  }
  expect_resume_is_exact(s, 40e-6);
}

TEST(Checkpoint, ASlidingRunContinuesBitForBitThroughFailureAndPerforation) {
  // 300 m/s on the small patch: contact from the first step, yarns break near 20 us and the
  // projectile perforates by about 60 us. Stopped twice: before and after the first break.
  const Scene s =
      scene_with(small_patch() + std::vector<std::string>{"projectile.velocity_mps=300", "solver.end_time_us=auto"});
  {
    Simulation probe(s);
    probe.run();
    ASSERT_TRUE(probe.summary().perforated) << "the test needs a run that perforates";
    ASSERT_GT(probe.summary().broken_weft + probe.summary().broken_warp, 0);
  }
  expect_resume_is_exact(s, 8e-6);
  expect_resume_is_exact(s, 30e-6);
}

TEST(Checkpoint, PinJointedAndFloatRunsContinueBitForBit) {
  expect_resume_is_exact(
      scene_with(small_patch() + std::vector<std::string>{"solver.model=pin_jointed", "projectile.velocity_mps=300"}),
      15e-6);
  expect_resume_is_exact(
      scene_with(small_patch() + std::vector<std::string>{"solver.precision=float", "projectile.velocity_mps=300"}),
      15e-6);
}

TEST(Checkpoint, AResumeMayUseAnotherThreadCount) {
  // The state a step produces is the same for any thread count (docs/MODEL.md §4, Jacobi
  // sweep), so a run checkpointed on one thread continues on two with the same state bit for
  // bit; the ledger's sums over nodes are reduced per thread, so they agree to rounding.
  const Scene one = scene_with(small_patch() + std::vector<std::string>{"solver.threads=1"});
  const Scene two = scene_with(small_patch() + std::vector<std::string>{"solver.threads=2"});
  Simulation a(one);
  run_until(a, 12e-6);
  const std::string bytes = a.checkpoint();
  a.run();
  Simulation b(two);
  b.restore(bytes);
  b.run();
  EXPECT_EQ(a.state_hash(), b.state_hash());
  ASSERT_EQ(a.history().size(), b.history().size());
  const double e0 = a.history().front().ledger.total();
  for (std::size_t i = 0; i < a.history().size(); ++i) {
    const Ledger& la = a.history()[i].ledger;
    const Ledger& lb = b.history()[i].ledger;
    EXPECT_NEAR(la.fabric_ke_J, lb.fabric_ke_J, 1e-12 * e0) << "row " << i;
    EXPECT_NEAR(la.strain_energy_J, lb.strain_energy_J, 1e-12 * e0) << "row " << i;
    EXPECT_NEAR(la.total(), lb.total(), 1e-12 * e0) << "row " << i;
  }
}

TEST(Checkpoint, AnotherScenesOrDamagedBytesAreRefusedAndChangeNothing) {
  const Scene s = scene_with(small_patch());
  Simulation a(s);
  run_until(a, 5e-6);
  const std::string bytes = a.checkpoint();

  Simulation other(scene_with(small_patch() + std::vector<std::string>{"yarn.friction=0.3"}));
  run_until(other, 2e-6);
  const std::uint64_t before = other.state_hash();
  const long steps = other.step_count();
  try {
    other.restore(bytes);
    FAIL() << "a checkpoint of another scene was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("another scene"), std::string::npos) << e.what();
  }
  EXPECT_EQ(other.state_hash(), before);
  EXPECT_EQ(other.step_count(), steps);

  Simulation same(s);
  run_until(same, 1e-6);
  const std::uint64_t same_before = same.state_hash();
  for (std::size_t cut : {std::size_t(4), bytes.size() / 2, bytes.size() - 1}) {
    EXPECT_THROW(same.restore(bytes.substr(0, cut)), std::runtime_error) << "cut at " << cut;
    EXPECT_EQ(same.state_hash(), same_before);
  }
  EXPECT_THROW(same.restore(bytes + "x"), std::runtime_error);
  std::string flipped = bytes;  // one bit of one node's position
  flipped[flipped.size() / 2] ^= 1;
  try {
    same.restore(flipped);
    FAIL() << "a damaged checkpoint was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("damaged"), std::string::npos) << e.what();
  }
  EXPECT_THROW(same.restore("not a checkpoint at all"), std::runtime_error);
  EXPECT_EQ(same.state_hash(), same_before);
  same.restore(bytes);  // the whole, right bytes
  EXPECT_EQ(same.state_hash(), a.state_hash());
}

}  // namespace
}  // namespace ravel::test
