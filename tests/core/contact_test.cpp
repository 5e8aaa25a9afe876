// Sliding yarn-to-yarn contact (paper §3, SPEC §4): Coulomb friction, momentum of the
// normal correction, interpenetration left after a step, pull-out, the mu limits.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

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

// The warp of crossing_pair pressed with N at the crossing for 20 us, then pulled with T at
// its leading end for 70 us. `moved` is its centre's displacement over the pull; `fn_drift`
// is the displacement a force mu (f_n - N) would give it over the same time, f_n the
// crossing's normal force as it evolves (the pull tilts the pressed warp a little). The
// stick/slip state and the normal force's error are read from 10 us into the pull on,
// when the sudden pull's first waves along the chain (which overshoot T) have passed.
struct Pull {
  double moved = 0, fn_drift = 0, max_fn_error = 0;
  bool always_sliding = true, ever_sliding = false;
};
Pull pull_pressed_warp(double mu, double T, double N, int n, int iterations = 1) {
  Model m = crossing_pair(mu, n);
  m.contact_iterations = iterations;
  auto solver = make_solver(m, Precision::double_precision, 1);
  solver->set_external_force(n / 2, Vec3d(0, 0, -N));
  while (solver->time() < 20e-6) solver->step();
  EXPECT_NEAR(solver->crossing_normal_force(0), N, 1e-3 * N);
  solver->set_external_force(n - 1, Vec3d(0, T, 0));
  const double y0 = warp_centre_y(*solver, n), t0 = solver->time(), dt = solver->model().dt;
  Pull p;
  double v = 0;
  while (solver->time() < t0 + 70e-6) {
    solver->step();
    const double fn = solver->crossing_normal_force(0);
    v += mu * (fn - N) / (n * kMass) * dt;
    p.fn_drift += v * dt;
    if (solver->time() > t0 + 10e-6) {  // after the pull's first waves have rung out
      p.max_fn_error = std::max(p.max_fn_error, std::abs(fn - N));
      const bool sliding = solver->crossing_sliding(0);
      p.always_sliding &= sliding;
      p.ever_sliding |= sliding;
    }
  }
  p.moved = warp_centre_y(*solver, n) - y0;
  return p;
}

// Coulomb's law checked by the motion it produces. The warp is pressed onto the clamped weft
// with N and pulled along its length with T. Below mu N it sticks: it creeps by at most
// mu N / K (nanometres) where free it would move tens of micrometres. Above, it slides, and
// a sliding friction of mu f_n makes it move exactly as a frictionless pull of T - mu N
// would (the same path, so the same geometric forces of the sagging warp on the crossing),
// apart from mu (f_n - N), whose effect `fn_drift` is added back (at T = 3 mu N the pressed
// node passes the crossing within the 70 us and f_n strays from N by up to N). What remains is the
// friction force's own error, bounded at 2 % of what friction takes away (mu N t^2 / 2M):
// friction acts along the slip at the contact, which the sag tilts a few degrees out of the
// pull's line (cos 10 deg = 0.985); measured 0.2-0.7 %. A friction force wrong by 5 % in
// magnitude, or acting on the wrong side of the stick/slip threshold, fails it.
// The same with N = 4 contact passes per step (Eq 16-17): the passes refine the normal
// correction and the bound is still mu f_n per step (friction applied in every pass with the
// pass's fraction, bounded pass by pass, failed this: the sliding contacts stuck at times).
TEST(Friction, FollowsCoulombsLaw) {
  const int n = 5;
  const double N = 0.1, t = 70e-6, M = n * kMass;
  for (int iterations : {1, 4}) {
    for (double mu : {0.1, 0.3, 0.6}) {
      SCOPED_TRACE("mu " + std::to_string(mu) + ", contact passes " + std::to_string(iterations));
      {  // stuck
        const double T = 0.5 * mu * N;
        const Pull p = pull_pressed_warp(mu, T, N, n, iterations);
        EXPECT_FALSE(p.ever_sliding);
        // Only the pulled chain's elastic ringing moves its centre (tens of nm).
        EXPECT_LT(std::abs(p.moved), 0.02 * 0.5 * T / M * t * t);
      }
      for (double ratio : {1.5, 3.0}) {  // sliding
        SCOPED_TRACE("T / (mu N) " + std::to_string(ratio));
        const double T = ratio * mu * N;
        const Pull p = pull_pressed_warp(mu, T, N, n, iterations),
                   free = pull_pressed_warp(0, T - mu * N, N, n, iterations);
        EXPECT_TRUE(p.always_sliding);
        const double friction_takes = 0.5 * mu * N / M * t * t;
        EXPECT_NEAR(p.moved + p.fn_drift, free.moved, 0.02 * friction_takes)
            << "moved " << p.moved << " m, frictionless at T - mu N " << free.moved << " m, |f_n - N| up to "
            << p.max_fn_error << " N";
      }
    }
  }
}

// Transverse compression (docs/MODEL.md §4): a crossing pressed with a normal force N
// settles where the hyperbolic law puts it, c(N) = c_min + (D - c_min) / (1 + N / F_half),
// and the ledger's compression_J is the law's integral from c to D. The implicit update
// solves the law exactly at the end of each step, so once the pressed warp has settled
// (its ringing dies out through the update's own dissipation) the only differences are the
// free flight within a step (N dt^2 / m: nanometres) and rounding: 1e-3 of the compressible
// distance bounds both. The settled normal force is N (a static balance), to the same order.
TEST(Compression, PressedCrossingClosesByTheLawAndStoresItsIntegral) {
  const double cmin = 0.1e-3, Fh = 1.0, span = kL1 - cmin;
  for (double N : {0.3, 1.0, 3.0, 10.0}) {
    SCOPED_TRACE("N = " + std::to_string(N) + " N");
    Model m = crossing_pair(0.0, 5, true);
    m.compression = CrossingCompression::hyperbolic;
    m.crossings[0].flattened_distance = cmin;
    m.crossings[0].compression_force = Fh;
    auto s = make_solver(m, Precision::double_precision, 1);
    // The warp's middle node is pressed onto the weft with a force ramped up over 150 us (a
    // sudden load would ring the undamped elastic chain for far longer than the test runs).
    while (s->time() < 250e-6) {
      s->set_external_force(2, Vec3d(0, 0, -N * std::min(1.0, s->time() / 150e-6)));
      s->step();
    }
    // crossing_gap is measured before the step's correction, after the free flight has
    // pressed the pair together by up to N dt^2 / m (the warp node alone): within that, and
    // 1e-3 of the compressible distance, the law.
    const double c = kL1 + s->crossing_gap(0);
    const double expect = cmin + span / (1 + N / Fh);
    EXPECT_NEAR(c, expect, N * m.dt * m.dt / kMass + 1e-3 * span);
    EXPECT_NEAR(s->crossing_normal_force(0), N, 1e-3 * N);
    // The stored energy is the law's at the distance the correction enforced.
    const double se = expect - cmin, stored = Fh * (span * std::log(span / se) - (span - se));
    EXPECT_NEAR(s->ledger().compression_J, stored, 1e-3 * stored);
    EXPECT_GE(s->ledger().compression_loss_J, 0.0);  // the implicit update only dissipates
  }
}

// The two-stage law (fabric.packed_gap_mm > fabric.flattened_gap_mm): the pressed crossing
// settles at c(N) = c_min + B / (1 + N / F_flat) + A / (1 + N / F_half) with B = c_pack -
// c_min, A = D - c_pack, and stores the law's integral, sum over the stages of
// span F (ln(1 + N / F) - (N / F) / (1 + N / F)). Same tolerances as the one-stage test: the
// Newton solve converges to rounding, so only the free flight within a step remains. The
// forces span both stages (F_half = 1 N, F_flat = 20 N): at 30 N the packing stage is
// nearly closed and the flattening stage half.
TEST(Compression, TwoStageCrossingClosesByTheLawAndStoresItsIntegral) {
  const double cmin = 0.1e-3, cpack = 0.13e-3, Fh = 1.0, Ff = 20.0;
  const double A = kL1 - cpack, B = cpack - cmin;
  for (double N : {0.3, 3.0, 30.0}) {
    SCOPED_TRACE("N = " + std::to_string(N) + " N");
    Model m = crossing_pair(0.0, 5, true);
    m.compression = CrossingCompression::hyperbolic;
    m.crossings[0].flattened_distance = cmin;
    m.crossings[0].packed_distance = cpack;
    m.crossings[0].compression_force = Fh;
    m.crossings[0].flattening_force = Ff;
    auto s = make_solver(m, Precision::double_precision, 1);
    while (s->time() < 250e-6) {
      s->set_external_force(2, Vec3d(0, 0, -N * std::min(1.0, s->time() / 150e-6)));
      s->step();
    }
    // The law at the crossing's own settled force f: the pressed warp's elements take a
    // little of N through their slope (0.3 % at 0.3 N, where this law leaves the crossing
    // 6 um further open than the one-stage test's), so f is N within 1 %, and the distance and
    // the stored energy are the law's at f to the one-stage test's tolerances.
    const double f = s->crossing_normal_force(0);
    EXPECT_NEAR(f, N, 1e-2 * N);
    const double c = kL1 + s->crossing_gap(0);
    const double expect = cmin + B / (1 + f / Ff) + A / (1 + f / Fh);
    EXPECT_NEAR(c, expect, N * m.dt * m.dt / kMass + 1e-3 * (A + B));
    auto stage = [f](double span, double F) { return span * F * (std::log1p(f / F) - (f / F) / (1 + f / F)); };
    const double stored = stage(A, Fh) + stage(B, Ff);
    EXPECT_NEAR(s->ledger().compression_J, stored, 1e-3 * stored);
    EXPECT_GE(s->ledger().compression_loss_J, 0.0);
    // And it is not the one-stage law with the same c_min: at 30 N that one would sit within
    // a micrometre of c_min, the two-stage law ~11 um above it.
    if (N > 10) {
      EXPECT_GT(c - cmin, 0.5 * B / (1 + N / Ff));
    }
  }
}

// The same press on a rigid crossing keeps the rest distance D, whatever the force.
TEST(Compression, RigidCrossingKeepsItsDistance) {
  Model m = crossing_pair(0.0, 5, true);
  auto s = make_solver(m, Precision::double_precision, 1);
  s->set_external_force(2, Vec3d(0, 0, -10.0));
  while (s->time() < 100e-6) s->step();
  EXPECT_NEAR(kL1 + s->crossing_gap(0), kL1, 10.0 * m.dt * m.dt / kMass + 1e-4 * kL1);
  EXPECT_EQ(s->ledger().compression_J, 0.0);
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

// After every step no crossing is left interpenetrating by more than a fraction of D for
// long. One Jacobi pass resolves each rigid crossing exactly; what is left comes from
// neighbouring crossings sharing a node: about 9 um at worst here, bounded at 10 % of D
// (20 um) through impact, failure and perforation. A compressible crossing's closure below its
// flattened distance c_min is removed at a pace (compressed_shift, 0.02 D per step): a broken
// end snapping through a crossing here leaves it 236 um below c_min, through its partner but
// by less than D (a crossing through by more than D is released), and the pace takes it below
// 60 um within 25 steps (measured; removing all but half of c_min at once, the rule until
// 2026-12-05, kept it at 50 um but stretched unloaded yarns to failure on larger plies:
// EndOfEvent.NoYarnIsBrokenByAContactShift). Bounds: never through by more than D, and
// deeper than half of c_min plus the neighbours' 10 % of D for at most 8 samples (64 steps).
TEST(Contact, InterpenetrationAfterEachStepIsBounded) {
  const double D = 0.2e-3, c_min = 0.1e-3;
  for (const char* law : {"fabric.crossing_compression=rigid", "fabric.crossing_compression=hyperbolic"}) {
    SCOPED_TRACE(law);
    Simulation sim(
        test::scene_with(test::small_patch() + std::vector<std::string>{"projectile.velocity_mps=300", law}));
    const bool rigid = std::string(law).find("rigid") != std::string::npos;
    const double deep = (rigid ? 0.0 : 0.5 * c_min) + 0.1 * D;
    int streak = 0, longest = 0;
    while (!sim.finished()) {
      sim.step();
      if (sim.solver().steps() % 8) continue;  // sampled every 8th step
      streak = sim.solver().diagnostics().last_penetration > deep ? streak + 1 : 0;
      longest = std::max(longest, streak);
    }
    EXPECT_GT(sim.summary().broken_weft, 0);
    EXPECT_GT(sim.solver().diagnostics().max_penetration, 0.0);
    EXPECT_LT(sim.solver().diagnostics().max_penetration, (rigid ? D : c_min + D));
    EXPECT_LE(longest, rigid ? 0 : 8) << "samples in a row deeper than " << deep;
  }
}

// Very large mu: (almost) nothing slides, and the answer moves towards the pin-jointed
// model's. Coulomb: the stuck points move only where mu f_n is exceeded, so the total slip
// of the crossings before failure (30 us) at mu = 10 is a small fraction of mu = 0.2's (only
// crossings that barely touch, f_n near 0, can still slip). The robust measure of the answer
// is the damage to the clamped (weft) yarns: when crossings cannot slide, load concentrates
// under the projectile as in the pin-jointed network.
TEST(Friction, VeryLargeMuSticksAndApproachesPinJointed) {
  const std::vector<std::string> base{"fabric.width_mm=36", "fabric.length_mm=36", "projectile.diameter_mm=6",
                                      "projectile.mass_g=2", "projectile.velocity_mps=200"};
  auto run = [&](const char* mu, double& slip) {
    Simulation sim(test::scene_with(base + std::vector<std::string>{mu}));
    const Solver& so = sim.solver();
    const int nc = int(so.model().crossings.size());
    slip = 0;
    while (!sim.finished()) {
      sim.step();
      if (sim.time_s() > 30e-6) continue;  // before failure starts releasing crossings
      for (int c = 0; c < nc; ++c) slip += so.crossing_slip_rate(c) * so.model().dt;
    }
    return sim.summary();
  };
  double slip_big, slip_mid;
  const Summary s_big = run("yarn.friction=10", slip_big);
  const Summary s_mid = run("yarn.friction=0.2", slip_mid);
  EXPECT_GT(slip_mid, 0.0);
  EXPECT_LT(slip_big, 0.05 * slip_mid) << slip_big << " m of slip at mu = 10 vs " << slip_mid << " at mu = 0.2";
  const Summary s_pin = test::simulate(test::scene_with(base + std::vector<std::string>{"solver.model=pin_jointed"}));
  EXPECT_LT(std::abs(s_big.broken_weft_yarns - s_pin.broken_weft_yarns),
            std::abs(s_mid.broken_weft_yarns - s_pin.broken_weft_yarns))
      << "broken weft yarns: mu=10 " << s_big.broken_weft_yarns << ", mu=0.2 " << s_mid.broken_weft_yarns
      << ", pin-jointed " << s_pin.broken_weft_yarns;
}

// The classic yarn pull-out test: a 10 x 10 mm patch held at its left and right edges (the
// weft ends), the projectile parked far away, the central warp pulled out at its top end
// at 10 m/s through a stiff spring (booked as external work). The force (mean over 50 us
// windows) rises while the crossings hold, peaks in the first few mm, and falls as the
// yarn's tail passes the crossings and they let go. Alongside, the normal forces of the
// pulled yarn's crossings (Eq 11) are summed over the same windows: their ratio, the
// lateral resistance, is what friction and the crimp interlock make of the crossings' grip.
struct PullOut {
  double peak_N = 0, peak_at_mm = 0, last_N = 0;
  double resistance = 0;  // pull force / sum of the pulled yarn's normal forces, over the first 2 mm
  int released = 0, crossings = 0;
  double crimp_slope = 0;  // rest crossing distance over the in-plane node spacing: c0 / L0
};
PullOut pull_out(double mu, const char* compression = "fabric.crossing_compression=hyperbolic") {
  Scene sc = test::scene_with({"fabric.width_mm=10", "fabric.length_mm=10", "solver.symmetry=full",
                               "yarn.breakable=false", "projectile.diameter_mm=2", "projectile.mass_g=0.1",
                               "yarn.friction=" + std::to_string(mu), compression});
  Simulation sim(sc);
  Solver& so = sim.solver();
  const Model& m = so.model();
  so.set_projectile_position(Vec3d(0, 0, 1.0));
  so.set_projectile_velocity(Vec3d::Zero());
  so.set_max_balance_error(1e30);  // the ledger's reference (the projectile's energy) is gone
  const int y = m.warp_count / 2, end = m.yarn_node(y, m.yarn_size(y) - 1);
  std::vector<int> mine;
  for (size_t c = 0; c < m.crossings.size(); ++c)
    if (m.crossings[c].warp_yarn == y) mine.push_back(int(c));
  const Vec3d x0 = so.position(end);
  const double V = 10, k = 2e5, pull = 14e-3;
  PullOut r;
  double acc = 0, t = 0, pulled = 0, gripped = 0;
  long cnt = 0;
  std::vector<double> windows;
  while (t < pull / V) {
    const Vec3d F = k * (x0 + Vec3d(0, V * t, 0) - so.position(end));
    so.set_external_force(end, F);
    so.step();
    t = so.time();
    acc += F.y();
    if (V * t < 2e-3) {
      double n = 0;
      for (int c : mine) n += so.crossing_normal_force(c);
      pulled += F.y(), gripped += n;
    }
    if (++cnt == long(50e-6 / m.dt)) {
      windows.push_back(acc / double(cnt));
      if (windows.back() > r.peak_N) r.peak_N = windows.back(), r.peak_at_mm = V * t * 1e3;
      acc = 0, cnt = 0;
    }
  }
  EXPECT_TRUE(so.divergence().empty()) << so.divergence();
  r.last_N = windows.back();
  r.resistance = gripped > 0 ? pulled / gripped : 0;
  r.crossings = int(mine.size());
  const Vec3d a = m.x0[m.yarn_node(y, 0)], b = m.x0[m.yarn_node(y, 1)];
  r.crimp_slope = m.crossings[mine[0]].contact_distance / std::hypot(b.x() - a.x(), b.y() - a.y());
  // Let go: released, or (a crossing whose partner left past a folded free end, so that the
  // slip-off test does not see it leave along the yarn) still tracked but pressing no more.
  for (int c : mine) r.released += !so.crossing_active(c) || so.crossing_normal_force(c) == 0;
  return r;
}

TEST(Friction, PullOutForceRisesPeaksAndDropsAndThePeakGrowsWithMu) {
  double previous = 0;
  for (double mu : {0.0, 0.1, 0.2, 0.4}) {
    SCOPED_TRACE("mu " + std::to_string(mu));
    const PullOut r = pull_out(mu);
    EXPECT_LT(r.peak_at_mm, 4.0);         // the grip is strongest while every crossing still holds
    EXPECT_EQ(r.released, r.crossings);   // every crossing of the pulled yarn let go
    EXPECT_LT(r.last_N, 0.1 * r.peak_N);  // and the force is gone with them
    EXPECT_GT(r.peak_N, previous);        // Coulomb: the grip grows with mu
    previous = r.peak_N;
    // Lateral resistance (pull force over the sum of the yarn's crossing normal forces). Coulomb
    // friction alone resists mu N, so mu is a floor. The crimp adds a geometric part: the yarn's
    // kinks climb the partners' zig-zags, an inclined plane whose slope is at most the rest
    // crimp slope g = c / L0 (compression only flattens it). On a plane of slope g friction and
    // slope combine to at most (mu + g) / (1 - mu g): the ceiling.
    const double g = r.crimp_slope, ceiling = (mu + g) / (1 - mu * g);
    EXPECT_GE(r.resistance, mu);
    EXPECT_LE(r.resistance, ceiling);
    if (mu == 0) {
      EXPECT_GT(r.resistance, 0.0);  // the interlock alone resists
    }
  }
}

// Compressible crossings flatten under the pull, so the interlock a sliding yarn must climb
// is lower than between rigid rods of diameter D (SPEC §4): the lateral resistance at mu = 0
// falls. (Measured: 0.11 against 0.17, and the peak pull-out force 0.95 N against 5.2 N.)
TEST(Friction, CompressionLowersTheCrimpInterlock) {
  const PullOut soft = pull_out(0.0), rigid = pull_out(0.0, "fabric.crossing_compression=rigid");
  EXPECT_LT(soft.resistance, 0.8 * rigid.resistance) << soft.resistance << " vs " << rigid.resistance;
  EXPECT_LT(soft.peak_N, rigid.peak_N);
}

// Low friction at 260 m/s (paper Fig. 12, 14): the primary yarns slip aside off the
// projectile instead of holding it. Of the yarns it struck first (touching at 10 us), those
// not touching it at 40 us and not broken have slipped off: at mu = 0 most of them, at
// mu = 0.2 the ones that leave it break first. The projectile is hardly slowed at mu = 0: the
// patch absorbs far less (paper Fig. 13; measured 4.2 J against 10.5 J). On a 40 mm patch
// struck by a 6 mm sphere of the default scene's mass per presented area.
struct SlipOff {
  int struck = 0, slipped = 0;  // (modelled part) yarns touching at 10 us; of those, gone unbroken by 40 us
  Summary summary;
};
SlipOff slip_off(const char* mu) {
  Simulation sim(test::scene_with(
      {"fabric.width_mm=40", "fabric.length_mm=40", "projectile.diameter_mm=6", "projectile.mass_g=1.75", mu}));
  const Solver& so = sim.solver();
  const Model& m = so.model();
  std::vector<int> node_yarn(m.node_count);
  for (int y = 0; y < m.yarn_count(); ++y)
    for (int k = 0; k < m.yarn_size(y); ++k) node_yarn[m.yarn_node(y, k)] = y;
  auto touching = [&] {
    std::vector<char> on(m.yarn_count(), 0);
    for (int i = 0; i < m.node_count; ++i) {
      Vec3d nrm;
      if (m.shape.sdf(Vec3d(so.position(i) - so.projectile_position()), nrm) < 1e-6) on[node_yarn[i]] = 1;
    }
    return on;
  };
  test::run_until(sim, 10e-6);
  const std::vector<char> first = touching();
  test::run_until(sim, 40e-6);
  const std::vector<char> later = touching();
  std::vector<char> broken(m.yarn_count(), 0);
  for (int e = 0; e < m.element_count; ++e) broken[m.elem_yarn[e]] |= so.broken(e);
  SlipOff r;
  for (int y = 0; y < m.yarn_count(); ++y) {
    r.struck += first[y];
    r.slipped += first[y] && !later[y] && !broken[y];
  }
  sim.run();
  r.summary = sim.summary();
  return r;
}

TEST(Friction, LowFrictionYarnsSlipOffTheProjectile) {
  const SlipOff low = slip_off("yarn.friction=0"), mid = slip_off("yarn.friction=0.2");
  ASSERT_GT(low.struck, 2);
  EXPECT_GE(2 * low.slipped, low.struck) << low.slipped << " of " << low.struck << " slipped off at mu = 0";
  EXPECT_LT(mid.slipped, low.slipped) << mid.slipped << " of " << mid.struck << " at mu = 0.2";
  EXPECT_LT(low.summary.broken_weft_yarns + low.summary.broken_warp_yarns,
            mid.summary.broken_weft_yarns + mid.summary.broken_warp_yarns);
  EXPECT_LT(low.summary.energy_absorbed_J, 0.5 * mid.summary.energy_absorbed_J);
}

}  // namespace
}  // namespace ravel
