// Time-step convergence of the sliding model through an impact (SPEC §10): the answer must
// not depend on dt_factor beyond the integrator's own error. The paper's projectile on a
// 60 x 60 mm patch at 260 m/s, unbreakable (failure is a threshold: after the first break
// the sequence of breaks scatters; see docs/MODEL.md §4), to 70 us.
#include <gtest/gtest.h>

#include <cmath>

#include "fixture.h"

namespace ravel {
namespace {

using test::operator+;

struct State {
  double v = 0, max_strain = 0, contact_J = 0, normal_J = 0, friction_J = 0;
  double capture_J = 0;  // 1/2 m v0^2 of the nodes within the projectile's radius of its axis (whole fabric)
};

State impact_at_70us(const char* dt_factor) {
  Simulation sim(test::scene_with(
      {"fabric.width_mm=60", "fabric.length_mm=60", "yarn.breakable=false", "solver.end_time_us=70", dt_factor}));
  sim.run();
  State s;
  s.v = sim.solver().projectile_velocity().norm();
  const Model& m = sim.solver().model();
  for (int i = 0; i < m.node_count; ++i)
    if (m.inv_mass[i] > 0 && std::hypot(m.x0[i].x(), m.x0[i].y()) < 6e-3)
      s.capture_J += 0.5 / m.inv_mass[i] * 260.0 * 260.0;
  s.capture_J *= m.symmetry_factor;
  for (int e = 0; e < sim.solver().model().element_count; ++e)
    s.max_strain = std::max(s.max_strain, sim.solver().strain(e));
  const Ledger& l = sim.history().back().ledger;
  s.contact_J = l.contact_loss_J;
  // The normal contact is an ideal constraint: no net work. Its velocity corrections remove
  // kinetic energy (contact_loss) that its position shifts put into the elements (shift_work,
  // negative); the sum, with the compression law's loss, is the method's error.
  s.normal_J = l.contact_loss_J + l.shift_work_J + l.compression_loss_J;
  s.friction_J = sim.history().back().ledger.friction_work_J;
  return s;
}

// The order: leapfrog is second order, but the contact corrections (a projection of positions
// and velocities each step, Eq 9-11) and the stick/slip switch of friction are first order, so
// the projectile's speed converges at first order: halving dt halves its error, and the
// successive differences fall by 2 (measured 0.230 then 0.119 m/s, ratio 1.94). A ratio below
// 2^0.7 would mean it no longer converges at (about) that rate.
// The size: Richardson's extrapolation with p = 1 gives the limit; the default dt's error must
// stay below half the full-mode limit search's tolerance (1 m/s, studies/paper.cpp), or the
// ballistic limit would depend on dt more than on the search (measured 0.46 m/s).
TEST(Convergence, SlidingImpactConvergesInDtAtFirstOrder) {
  const State a = impact_at_70us("solver.dt_factor=0.5");
  const State b = impact_at_70us("solver.dt_factor=0.25");
  const State c = impact_at_70us("solver.dt_factor=0.125");
  const double d1 = std::abs(a.v - b.v), d2 = std::abs(b.v - c.v);
  EXPECT_GT(d1, std::pow(2.0, 0.7) * d2) << d1 << " then " << d2;
  const double limit = c.v - (b.v - c.v);  // Richardson, p = 1
  EXPECT_LT(std::abs(a.v - limit), 1.0);
  // Strain: the same first order (measured 1.1 % between 0.5 and 0.125); 2 % is the
  // Richardson error of 0.5 doubled.
  EXPECT_NEAR(a.max_strain, c.max_strain, 0.02 * c.max_strain);
  // Friction work (~2.5 J): stick/slip chatter is first order; 20 % (measured 12 %).
  EXPECT_NEAR(a.friction_J, c.friction_J, 0.2 * c.friction_J);
  for (const State* s : {&a, &b, &c}) EXPECT_GE(s->contact_J, 0.0);  // corrections only remove energy
  // The normal contact's net work is not a dt error: the projectile picks up the nodes it
  // strikes in perfectly inelastic collisions (paper Eq 19: a struck node takes the
  // projectile's normal speed), which lose 1/2 m v_rel^2 each whatever dt is. It is bounded by
  // the nodes within the projectile's radius struck at the impact speed (relative speed <= v0;
  // about 1.0 J here; measured 0.89, 0.83, 0.76 J) and is positive.
  for (const State* s : {&a, &b, &c}) {
    EXPECT_GT(s->normal_J, 0.0);
    EXPECT_LT(s->normal_J, s->capture_J);
  }
}

}  // namespace
}  // namespace ravel
