// Sliding yarn-to-yarn contact (paper §3, SPEC §4): Coulomb friction, momentum of the
// normal correction, interpenetration left after a step, pull-out, the mu limits.
#include <gtest/gtest.h>

#include <cmath>

#include "fixture.h"
#include "geometry.h"

namespace ravel {
namespace {

using test::operator+;

constexpr double kL0 = 0.844e-3, kL1 = 0.2e-3, kMass = 9.4e-8, kE = 7.28e10, kArea = 7.64e-8, kRho = 1440;

// Two straight yarns crossing at their middle nodes, D apart: a warp of n nodes along y on
// top, a weft of n nodes along x below (optionally clamped); elastic, unbreakable, no
// bending springs; the projectile parked far away.
Model crossing_pair(double mu, int n = 5, bool clamp_weft = true) {
  Model m;
  m.symmetry_label = "full";
  m.contact = ContactModel::sliding;
  m.yarn_offset = {0};
  const int c = n / 2;
  auto add = [&](const Vec3d& x, bool fixed) {
    m.x0.push_back(x);
    m.mass.push_back(kMass);
    m.inv_mass.push_back(fixed ? 0.0 : 1.0 / kMass);
    m.fixed.push_back(fixed ? fix_all : 0);
  };
  for (int k = 0; k < n; ++k) {  // warp, along y, on top at the crossing
    add(Vec3d(0, (k - c) * kL0, 0.5 * kL1), false);
    m.yarn_nodes.push_back(k);
  }
  m.yarn_offset.push_back(n);
  for (int k = 0; k < n; ++k) {  // weft, along x, below at the crossing
    add(Vec3d((k - c) * kL0, 0, -0.5 * kL1), clamp_weft);
    m.yarn_nodes.push_back(n + k);
  }
  m.yarn_offset.push_back(2 * n);
  m.node_count = 2 * n;
  m.yarn_family = {warp, weft};
  m.yarn_grid = {0, 0};
  m.yarn_end_free = {3, 3};
  m.yarn_start_mirror = {-1, -1};
  m.warp_count = m.weft_count = 1;
  const double rest = kL0;
  for (int y = 0; y < 2; ++y) {
    m.yarn_elem_offset.push_back(int(m.elem_a.size()));
    for (int k = 0; k + 1 < n; ++k) {
      m.elem_a.push_back(y * n + k);
      m.elem_b.push_back(y * n + k + 1);
      m.elem_yarn.push_back(y);
      m.elem_rest.push_back(rest);
      m.elem_area.push_back(kArea);
      m.elem_stiffness.push_back(kE * kArea / rest);
    }
  }
  m.yarn_elem_offset.push_back(int(m.elem_a.size()));
  m.element_count = int(m.elem_a.size());
  Crossing cr;
  cr.warp_yarn = 0;
  cr.weft_yarn = 1;
  cr.warp_node = cr.weft_node = c;
  cr.side = 1.0;  // warp on top: n points down, from warp to weft
  cr.contact_distance = kL1;
  m.crossings.push_back(cr);
  m.friction = mu;
  m.friction_penalty = 0.5;
  m.contact_iterations = 1;
  m.material = Material::elastic;
  m.modulus_inst = kE;
  m.density = kRho;
  m.breakable = false;
  m.shape.radius = 1e-3;
  m.projectile_mass = m.projectile_mass_full = 1.0;
  m.projectile_x0 = Vec3d(0, 0, 1.0);
  m.wave_speed = std::sqrt(kE / kRho);
  m.dt = 0.5 * rest / m.wave_speed;
  m.half_width = m.half_length = 0.01;
  m.end_time = 1;
  return m;
}

double warp_centre_y(const Solver& s, int n) {
  double y = 0;
  for (int k = 0; k < n; ++k) y += s.position(k).y();
  return y / n;
}

// Pressed with N at the crossing and pulled with T at its leading end. Below mu N the warp
// sticks: it creeps by at most mu N / K (nanometres) and the friction force balances T.
// Above, it slides and the friction force is mu f_n (f_n the normal force of Eq 11, which
// the pressed, slightly sagging warp keeps within a few % of N). mu = 0 slides freely.
// The pull starts after 20 us of pressing; the checks run over the next 60 us.
TEST(Friction, FollowsCoulombsLaw) {
  const int n = 5;
  const double N = 0.1;
  for (double mu : {0.0, 0.1, 0.3, 0.6}) {
    for (double ratio : {0.5, 1.5}) {
      if (mu == 0 && ratio == 0.5) continue;
      SCOPED_TRACE("mu " + std::to_string(mu) + " T/(mu N) " + std::to_string(ratio));
      const double T = mu > 0 ? ratio * mu * N : 0.02;
      auto solver = make_solver(crossing_pair(mu, n), Precision::double_precision, 1);
      solver->set_external_force(n / 2, Vec3d(0, 0, -N));
      while (solver->time() < 20e-6) solver->step();
      ASSERT_NEAR(solver->crossing_normal_force(0), N, 1e-3 * N);
      solver->set_external_force(n - 1, Vec3d(0, T, 0));
      while (solver->time() < 30e-6) solver->step();
      const double y0 = warp_centre_y(*solver, n), t0 = solver->time();
      int samples = 0;
      while (solver->time() < t0 + 60e-6) {
        solver->step();
        if (solver->steps() % 50) continue;
        ++samples;
        const double fn = solver->crossing_normal_force(0), ft = solver->crossing_friction_force(0);
        EXPECT_NEAR(fn, N, 0.15 * N);  // the pull tilts the pressed warp a little
        if (ratio < 1) {
          EXPECT_FALSE(solver->crossing_sliding(0));
          EXPECT_LE(ft, mu * fn * (1 + 1e-9));
        } else {
          EXPECT_TRUE(mu == 0 || solver->crossing_sliding(0));
          EXPECT_NEAR(ft, mu * fn, 1e-9 * N);
        }
      }
      EXPECT_GT(samples, 10);
      const double moved = warp_centre_y(*solver, n) - y0;
      const double free_motion = 0.5 * T / (n * kMass) * 60e-6 * 60e-6;  // T alone, 60 us
      if (ratio < 1) {
        // Stuck: only the pulled chain's elastic ringing moves its centre (tens of nm); free
        // it would move tens of micrometres.
        EXPECT_LT(std::abs(moved), 0.02 * free_motion);
      } else {
        // Sliding: it moves by at least (T - mu N) / T of the free motion (more, because
        // the pressed node sags and the contact normal tilts forward as the contact moves
        // back along the yarn: this test's flexible chain, not friction).
        const double expect = (T - mu * N) / T * free_motion;
        EXPECT_GT(moved, 0.8 * expect);
      }
    }
  }
}

// The normal correction moves the two contact points apart along d with equal and
// opposite impulses on one line through both: starting at rest with the yarns pushed into
// each other, the pair flies apart with zero total linear and angular momentum.
// (Elements and bending springs are central forces, so the whole pair conserves both.)
TEST(Contact, NormalCorrectionConservesMomentum) {
  Model m = crossing_pair(0.0, 5, false);
  // The whole warp 80 um into the weft and off the weft's node, so the impulse has a
  // lever arm; element lengths are unchanged, so only the contact acts in this step.
  for (int k = 0; k < 5; ++k) m.x0[k] += Vec3d(0.3e-3, 0.05e-3, -0.08e-3);
  m.split_penetration = false;  // the paper's velocity-only correction (Eq 9-10)
  auto s = make_solver(m, Precision::double_precision, 1);
  s->step();
  ASSERT_GT(s->crossing_normal_force(0), 0.0);  // the correction did act
  Vec3d p = Vec3d::Zero(), L = Vec3d::Zero();
  double pscale = 0, lscale = 0;
  for (int i = 0; i < m.node_count; ++i) {
    // Angular momentum about the origin with the positions the impulses were computed at.
    const Vec3d x = s->position(i) - m.dt * s->velocity(i), v = s->velocity(i);
    p += m.mass[i] * v;
    L += m.mass[i] * x.cross(v);
    pscale += m.mass[i] * v.norm();
    lscale += m.mass[i] * x.norm() * v.norm();
  }
  ASSERT_GT(pscale, 0.0);
  EXPECT_LT(p.norm(), 1e-12 * pscale);
  EXPECT_LT(L.norm(), 1e-12 * lscale);
}

// With solver.split_penetration, penetration that was there before the step is removed by
// moving the nodes: the pair ends the step touching, at rest relative to each other, and
// no momentum is created.
TEST(Contact, SplitRemovesOldPenetrationWithoutVelocity) {
  Model m = crossing_pair(0.0, 5, false);
  for (int k = 0; k < 5; ++k) m.x0[k] += Vec3d(0.3e-3, 0.05e-3, -0.08e-3);
  m.split_penetration = true;
  auto s = make_solver(m, Precision::double_precision, 1);
  s->step();
  double vmax = 0;
  for (int i = 0; i < m.node_count; ++i) vmax = std::max(vmax, s->velocity(i).norm());
  EXPECT_LT(vmax, 1e-9);  // no separating velocity
  // Touching again at the crossing: the closest distance of the 2 x 2 segment pairs is D.
  double closest = 1e9;
  for (int a = 1; a <= 2; ++a)
    for (int b = 6; b <= 7; ++b) {
      double sa, sb;
      Vec3d pa, pb;
      closest_points_segments(s->position(a), s->position(a + 1), s->position(b), s->position(b + 1), sa, sb, pa, pb);
      closest = std::min(closest, (pb - pa).norm());
    }
  // (The shift tilts the warp, which moves its closest point a little: 1 % of D.)
  EXPECT_NEAR(closest, kL1, 1e-2 * kL1);
}

// After every step no crossing is left interpenetrating by more than a fraction of D.
// One Jacobi pass resolves each crossing exactly; what is left comes from neighbouring
// crossings sharing a node: about 13 um at worst here, bounded at 10 % of D (20 um)
// through impact, failure and perforation.
TEST(Contact, InterpenetrationAfterEachStepIsBounded) {
  Simulation sim(test::scene_with(test::small_patch() + std::vector<std::string>{"projectile.velocity_mps=300"}));
  sim.run();
  const double D = 0.2e-3;
  EXPECT_GT(sim.summary().broken_weft, 0);
  EXPECT_GT(sim.solver().diagnostics().max_penetration, 0.0);
  EXPECT_LT(sim.solver().diagnostics().max_penetration, 0.1 * D);
}

// Very large mu: (almost) nothing slides, and the answer moves towards the pin-jointed
// model's. Only crossings that barely touch (f_n near 0, so mu f_n / K is sub-nanometre)
// can still slip. The robust measure of the answer is the damage to the clamped (weft)
// yarns: when crossings cannot slide, load concentrates under the projectile and many more
// of them break, as in the pin-jointed network (measured on this patch: 13 broken weft
// yarns at mu = 0.2 and 1, 21 at mu = 3, 25 at mu = 10, 43 pin-jointed).
TEST(Friction, VeryLargeMuSticksAndApproachesPinJointed) {
  const std::vector<std::string> base{"fabric.width_mm=36",  "fabric.length_mm=36",         "projectile.diameter_mm=6",
                                      "projectile.mass_g=2", "projectile.velocity_mps=200", "solver.end_time_us=150"};
  auto count = [&](const char* mu, long& sliding, long& stuck) {
    Simulation sim(test::scene_with(base + std::vector<std::string>{mu}));
    sliding = stuck = 0;
    while (!sim.finished()) {
      sim.step();
      if (sim.time_s() > 30e-6) continue;  // before failure starts releasing crossings
      sliding += sim.solver().sliding_crossings();
      stuck += sim.solver().stuck_crossings();
    }
    return sim.summary();
  };
  long slide_big, stuck_big, slide_mid, stuck_mid;
  const Summary s_big = count("yarn.friction=10", slide_big, stuck_big);
  const Summary s_mid = count("yarn.friction=0.2", slide_mid, stuck_mid);
  EXPECT_LT(slide_big, 0.05 * stuck_big) << slide_big << " sliding, " << stuck_big << " stuck";
  EXPECT_LT(slide_big, 0.2 * slide_mid) << slide_big << " vs " << slide_mid << " at mu = 0.2";
  const Summary s_pin = test::simulate(test::scene_with(base + std::vector<std::string>{"solver.model=pin_jointed"}));
  EXPECT_LT(std::abs(s_big.broken_weft_yarns - s_pin.broken_weft_yarns),
            std::abs(s_mid.broken_weft_yarns - s_pin.broken_weft_yarns))
      << "broken weft yarns: mu=10 " << s_big.broken_weft_yarns << ", mu=0.2 " << s_mid.broken_weft_yarns
      << ", pin-jointed " << s_pin.broken_weft_yarns;
}

// The classic yarn pull-out test: a 10 x 10 mm patch held at its left and right edges (the
// weft ends), the projectile parked far away, the central warp pulled out at its top end
// at 10 m/s through a stiff spring (booked as external work). The force (mean over 50 us
// windows) rises while the crossings hold, peaks in the first few mm, and drops to nearly
// nothing as the yarn's tail passes the crossings and they let go. Even mu = 0 resists a
// little (the crimp has to straighten the crossing wefts); the peak grows with mu.
struct PullOut {
  double peak_N = 0, peak_at_mm = 0, last_N = 0;
  int released = 0, crossings = 0;
};
PullOut pull_out(double mu) {
  Scene sc =
      test::scene_with({"fabric.width_mm=10", "fabric.length_mm=10", "solver.symmetry=full", "yarn.breakable=false",
                        "projectile.diameter_mm=2", "projectile.mass_g=0.1", "yarn.friction=" + std::to_string(mu)});
  Simulation sim(sc);
  Solver& so = sim.solver();
  const Model& m = so.model();
  so.set_projectile_position(Vec3d(0, 0, 1.0));
  so.set_projectile_velocity(Vec3d::Zero());
  so.set_max_balance_error(1e30);  // the ledger's reference (the projectile's energy) is gone
  const int y = m.warp_count / 2, end = m.yarn_node(y, m.yarn_size(y) - 1);
  const Vec3d x0 = so.position(end);
  const double V = 10, k = 2e5, pull = 10e-3;
  PullOut r;
  double acc = 0, t = 0;
  long cnt = 0;
  std::vector<double> windows;
  while (t < pull / V) {
    const Vec3d F = k * (x0 + Vec3d(0, V * t, 0) - so.position(end));
    so.set_external_force(end, F);
    so.step();
    t = so.time();
    acc += F.y();
    if (++cnt == long(50e-6 / m.dt)) {
      windows.push_back(acc / double(cnt));
      if (windows.back() > r.peak_N) r.peak_N = windows.back(), r.peak_at_mm = V * t * 1e3;
      acc = 0, cnt = 0;
    }
  }
  EXPECT_TRUE(so.divergence().empty()) << so.divergence();
  r.last_N = windows.back();
  for (size_t c = 0; c < m.crossings.size(); ++c)
    if (m.crossings[c].warp_yarn == y) ++r.crossings, r.released += !so.crossing_active(int(c));
  return r;
}

TEST(Friction, PullOutForceRisesPeaksAndDropsAndThePeakGrowsWithMu) {
  double previous = 0;
  for (double mu : {0.0, 0.1, 0.2, 0.4}) {
    SCOPED_TRACE("mu " + std::to_string(mu));
    const PullOut r = pull_out(mu);
    EXPECT_GT(r.peak_N, 1.0);                        // measured 5 N at mu = 0 .. 31 N at 0.4
    EXPECT_LT(r.peak_at_mm, 4.0);                    // rises to the peak within the first crossings
    EXPECT_LT(std::abs(r.last_N), 0.05 * r.peak_N);  // and drops once the yarn is out
    EXPECT_GE(r.crossings, 10);
    EXPECT_EQ(r.released, r.crossings);    // every crossing of the pulled yarn let go
    EXPECT_GT(r.peak_N, 1.15 * previous);  // the peak grows with mu
    previous = r.peak_N;
  }
}

// Low friction at a low impact velocity (paper Fig. 12, 17): the projectile pushes the
// yarns aside instead of breaking them, and the free edges ravel. At 40 m/s mu = 0.02
// breaks nothing while mu = 0.2 breaks several clamped yarns. At 60 m/s mu = 0.02 slips
// through (perforates) while mu = 0.2 stops the projectile, and more crossings ravel out
// (measured 105 vs 79). (How many elements break on the way through at 60 m/s is not
// robust: near the limit it changes with rounding.)
TEST(Friction, LowFrictionPushesYarnsAsideAndRavels) {
  const std::vector<std::string> base{"fabric.width_mm=36", "fabric.length_mm=36", "projectile.diameter_mm=6",
                                      "projectile.mass_g=2", "solver.end_time_us=800"};
  auto run = [&](const char* v, const char* mu, long& ravelled) {
    Simulation sim(test::scene_with(base + std::vector<std::string>{v, mu}));
    sim.run();
    ravelled = sim.solver().diagnostics().ravelled;
    return sim.summary();
  };
  long r_low, r_mid;
  const Summary low = run("projectile.velocity_mps=40", "yarn.friction=0.02", r_low);
  const Summary mid = run("projectile.velocity_mps=40", "yarn.friction=0.2", r_mid);
  EXPECT_EQ(low.broken_warp + low.broken_weft, 0);
  EXPECT_GE(mid.broken_weft_yarns, 3);
  EXPECT_GE(r_low, 10);  // with nothing broken, every release is at a free edge
  const Summary low60 = run("projectile.velocity_mps=60", "yarn.friction=0.02", r_low);
  const Summary mid60 = run("projectile.velocity_mps=60", "yarn.friction=0.2", r_mid);
  EXPECT_TRUE(low60.perforated);
  EXPECT_FALSE(mid60.perforated);  // at 61 m/s it just perforates: 16 m/s against 36 for mu = 0.02
  EXPECT_GT(r_low, r_mid) << r_low << " vs " << r_mid;
}

}  // namespace
}  // namespace ravel
