// The energy ledger (SPEC §8). Every entry is computed from its own mechanism: kinetic
// energies from velocities, stored energy from element state, dissipations from the
// work of the force or the kinetic-energy change that a correction made. None is the
// remainder of the others, so their sum against the initial energy checks the solver.
#pragma once

namespace ravel {

struct Ledger {
  double projectile_ke_J = 0;  // kinetic energy of the projectile
  double fabric_ke_J = 0;      // kinetic energy of the yarn nodes
  double strain_energy_J = 0;  // stored: elastic springs of the yarn elements + bending springs
  double viscous_J = 0;        // dissipated by the Zener dashpots (integral of mu_d de_v/dt^2)
  double damping_J = 0;        // dissipated by the snap damping of slack elements turning taut (solver.snap_damping)
                               // and the pin-jointed model's crimp damping (yarn.crimp_damping)
  double friction_work_J = 0;  // dissipated by yarn-yarn friction (Eq 12-15): slip beyond the Coulomb limit
  double stick_energy_J = 0;   // stored: the stick penalty springs of yarn-yarn friction (K/2 e^2, Eq 12)
  double projectile_friction_J = 0;  // dissipated by projectile-yarn friction (Eq 20-22)
  double contact_loss_J = 0;         // kinetic energy removed by the normal contact corrections (Eq 9-11, 19)
  // The position shifts that remove penetration left from earlier steps (solver.split_penetration):
  // the energy they take from the yarns' elastic forces (-f . dx, trapezoid rule); either sign.
  double shift_work_J = 0;
  double released_J = 0;          // energy held by elements at the moment they broke
  double compression_J = 0;       // stored: the crossings' transverse compression (the law's integral)
  double compression_loss_J = 0;  // dissipated: work of the compression impulses beyond what the law stores
  double external_work_J = 0;     // work done on the system by external loads (tests, pull-out)
  double clamp_friction_J = 0;    // dissipated by slipping clamps (fabric.clamp = slipping): grip x yarn fed

  // Energy now held or dissipated, less what external loads put in: equals the initial
  // energy for an exact integration.
  double total() const {
    return projectile_ke_J + fabric_ke_J + strain_energy_J + viscous_J + damping_J + friction_work_J +
           projectile_friction_J + contact_loss_J + shift_work_J + released_J + stick_energy_J + compression_J +
           compression_loss_J + clamp_friction_J - external_work_J;
  }
  Ledger scaled(double f) const {
    Ledger l = *this;
    l.projectile_ke_J *= f;
    l.fabric_ke_J *= f;
    l.strain_energy_J *= f;
    l.viscous_J *= f;
    l.damping_J *= f;
    l.friction_work_J *= f;
    l.stick_energy_J *= f;
    l.projectile_friction_J *= f;
    l.contact_loss_J *= f;
    l.shift_work_J *= f;
    l.released_J *= f;
    l.compression_J *= f;
    l.compression_loss_J *= f;
    l.external_work_J *= f;
    l.clamp_friction_J *= f;
    return l;
  }
};

// The energy book: the running sums each mechanism adds its energy or work to during a step
// (in the stage that owns the mechanism), and the one place that turns them into the ledger
// row. Central differences carry velocities at half steps and positions at whole steps, so
// the row is at t - dt/2: kinetic energies of v(t - dt/2) exactly, stored energies and the
// cumulative terms evaluated at whole steps as the mean of their values at t - dt and t
// (core/solver.h, "Energy timing").
struct EnergyBook {
  // Kinetic energy of v(t + dt/2): all of it and the fabric's (finish_step).
  double ke_half = 0, ke_fabric_half = 0;
  // Stored in the elements and bending springs at t (internal_forces) and at t - dt.
  double stored_now = 0, stored_prev = 0;
  // Cumulative dissipation by the Zener dashpots and energy released by broken elements,
  // at t and t - dt (internal_forces).
  double viscous_cum = 0, viscous_prev = 0, released_cum = 0, released_prev = 0;
  double damping_cum = 0;  // snap and crimp damping (internal_forces)
  // Work of the corrections, cumulative (finish_step, release_held; sign: done on the system).
  double pfriction_cum = 0, contact_cum = 0, external_cum = 0;
  double shift_cum = 0;  // the position shifts' work against the yarn forces (shift_energy)
  // Slipping clamps: the energy the yarn fed from a clamp took out of its element, at t and
  // t - dt (internal_forces).
  double clamp_cum = 0, clamp_prev = 0;
  // Yarn-yarn friction: its impulses' work and the stick springs' energy at t and t - dt.
  double friction_work_cum = 0, stick_end = 0, stick_prev = 0;
  // The compression law: its impulses' work and its stored energy at t and t - dt.
  double compress_work_cum = 0, compress_end = 0, compress_prev = 0;

  // Before the first step: the values at t = 0 are the "previous" ones of the first row.
  void start() {
    compress_prev = compress_end;
    stick_prev = stick_end;
    stored_prev = stored_now;
    viscous_prev = viscous_cum;
    released_prev = released_cum;
    clamp_prev = clamp_cum;
  }
  // The ledger row at t - dt/2, then this step's values become the previous ones.
  void close_row(Ledger& l) {
    l.fabric_ke_J = ke_fabric_half;
    l.projectile_ke_J = ke_half - ke_fabric_half;
    l.strain_energy_J = 0.5 * (stored_prev + stored_now);
    l.viscous_J = 0.5 * (viscous_prev + viscous_cum);
    l.damping_J = damping_cum;
    l.released_J = 0.5 * (released_prev + released_cum);
    l.projectile_friction_J = pfriction_cum;
    l.contact_loss_J = contact_cum;
    l.shift_work_J = shift_cum;
    l.compression_J = 0.5 * (compress_prev + compress_end);
    // Dissipated by friction: the work its impulses took from the yarns (and the projectile)
    // less what the stick penalty springs hold (Eq 12: a stuck contact stores K/2 e^2 and
    // gives it back; only the rest is lost).
    l.stick_energy_J = 0.5 * (stick_prev + stick_end);
    l.friction_work_J = 0.0 - (friction_work_cum + l.stick_energy_J);  // (0.0 - : no negative zero)
    l.compression_loss_J = -compress_work_cum - l.compression_J;
    l.external_work_J = external_cum;
    l.clamp_friction_J = 0.5 * (clamp_prev + clamp_cum);
    start();
  }
};

}  // namespace ravel
