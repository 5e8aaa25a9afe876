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

  // Energy now held or dissipated, less what external loads put in: equals the initial
  // energy for an exact integration.
  double total() const {
    return projectile_ke_J + fabric_ke_J + strain_energy_J + viscous_J + damping_J + friction_work_J +
           projectile_friction_J + contact_loss_J + shift_work_J + released_J + stick_energy_J + compression_J +
           compression_loss_J - external_work_J;
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
    return l;
  }
};

}  // namespace ravel
