// Yarn element constitutive laws (SPEC §2, paper Eq 23-25).
//
// Zener: spring K1 in series with a Kelvin-Voigt unit (K2 || mu_d). With e_v the strain of
// the Kelvin-Voigt unit: sigma = K1 (eps - e_v), mu_d de_v/dt = K1 eps - (K1 + K2) e_v.
// Over a step the total strain is taken linear in time (eps0 -> eps1); the ODE for e_v is
// then solved exactly, so the update is stable for any dt and reproduces Eq 24 at a
// constant strain rate to rounding. The dashpot dissipation over the step is the exact
// integral of mu_d (de_v/dt)^2 along that solution.
//
// Tension only: a yarn cannot carry compression (it buckles). When K1 (eps - e_v) would
// be negative the element is slack: sigma = 0 and the Kelvin-Voigt unit relaxes on its
// own, mu_d de_v/dt = -K2 e_v.
#pragma once

#include <algorithm>
#include <cmath>

namespace ravel {

struct ZenerConstants {
  double k1, k2, mu;  // Pa, Pa, Pa s
  double tau() const { return mu / (k1 + k2); }
};

struct ZenerStep {
  double ev;          // new internal strain
  double stress;      // Pa, >= 0
  double dissipated;  // J per m^3 over the step
};

// The update for a fixed step dt, with everything that does not depend on the element
// precomputed (the solver makes one per run).
struct ZenerStepper {
  ZenerConstants c;
  double dt, inv_dt, lam, g, decay, slack_decay;
  ZenerStepper(const ZenerConstants& z, double step)
      : c(z),
        dt(step),
        inv_dt(1.0 / step),
        lam(1.0 / z.tau()),
        g(z.k1 / (z.k1 + z.k2)),
        decay(std::exp(-step / z.tau())),
        slack_decay(std::exp(-step * z.k2 / z.mu)) {}

  // Advance one element from (eps0, ev0) to eps1.
  ZenerStep step(double eps0, double eps1, double ev0) const {
    const double r = (eps1 - eps0) * inv_dt;
    const double C = ev0 - g * (eps0 - r / lam);
    const double ev1 = g * (eps1 - r / lam) + C * decay;
    const double stress = c.k1 * (eps1 - ev1);
    const bool taut0 = c.k1 * (eps0 - ev0) >= 0.0;  // taut at the start of the step
    if (stress >= 0.0) {
      if (!taut0) return slack_then_taut(eps0, eps1, ev0);
      // integral of (g r - lam C e^{-lam s})^2 ds over [0, dt]
      const double diss =
          c.mu * (g * g * r * r * dt - 2.0 * g * r * C * (1.0 - decay) + 0.5 * lam * C * C * (1.0 - decay * decay));
      return {ev1, stress, diss};
    }
    if (taut0) return taut_then_slack(eps0, eps1, ev0, stress);
    // Slack: sigma = 0, Kelvin-Voigt unit relaxes: e_v = ev0 exp(-K2 s / mu).
    const double evs = ev0 * slack_decay;
    return {evs, 0.0, 0.5 * c.k2 * (ev0 * ev0 - evs * evs)};
  }

 private:
  // A step that starts slack and ends taut, or the reverse, is taken in two parts, each on
  // its own branch. One formula for the whole step would run the taut ODE through the slack
  // part with the series spring in compression, a state a tension-only yarn cannot hold:
  // the energy of that compression (K1/2 (eps - e_v)^2 per volume, never booked) went into
  // the Kelvin-Voigt unit. Loose broken yarn pieces flapping between slack and taut gained
  // energy that way (4 J over 4 ms of a slowly caught projectile at 73 m/s).
  //
  // Taut over a part of length h from (eps0, ev0) at strain rate r: e_v and the dashpot's
  // dissipation (the same solution as step's).
  void taut_part(double eps0, double r, double ev0, double h, double& ev1, double& diss) const {
    const double C = ev0 - g * (eps0 - r / lam), dec = std::exp(-lam * h);
    ev1 = g * (eps0 + r * h - r / lam) + C * dec;
    diss = c.mu * (g * g * r * r * h - 2.0 * g * r * C * (1.0 - dec) + 0.5 * lam * C * C * (1.0 - dec * dec));
  }
  // Slack until the strain reaches e_v (which barely relaxes meanwhile: dt K2 / mu ~ 1e-4),
  // then taut.
  ZenerStep slack_then_taut(double eps0, double eps1, double ev0) const {
    if (!(eps1 > ev0)) {  // the strain never reaches e_v: slack throughout
      const double evs = ev0 * slack_decay;
      return {evs, 0.0, 0.5 * c.k2 * (ev0 * ev0 - evs * evs)};
    }
    const double f = (ev0 - eps0) / (eps1 - eps0), h1 = f * dt, r = (eps1 - eps0) * inv_dt;
    const double evm = ev0 * std::exp(-h1 * c.k2 / c.mu);
    double ev1, diss;
    taut_part(eps0 + r * h1, r, evm, dt - h1, ev1, diss);
    return {ev1, std::max(0.0, c.k1 * (eps1 - ev1)), 0.5 * c.k2 * (ev0 * ev0 - evm * evm) + diss};
  }
  // Taut until the stress falls to zero (found on the straight line between its values at the
  // ends of the whole-step taut solution, sigma0 >= 0 > sigma1), then slack.
  ZenerStep taut_then_slack(double eps0, double eps1, double ev0, double sigma1) const {
    const double sigma0 = c.k1 * (eps0 - ev0), f = sigma0 / (sigma0 - sigma1), h1 = f * dt;
    const double r = (eps1 - eps0) * inv_dt;
    double evm, diss;
    taut_part(eps0, r, ev0, h1, evm, diss);
    const double evs = evm * std::exp(-(dt - h1) * c.k2 / c.mu);
    return {evs, 0.0, diss + 0.5 * c.k2 * (evm * evm - evs * evs)};
  }
};

// Advance one element from (eps0, ev0) to eps1 over dt (decay and slack_decay as in
// ZenerStepper; kept for callers that step with varying dt).
template <class R>
inline ZenerStep zener_update(const ZenerConstants& c, R eps0, R eps1, R ev0, double dt, double /*decay*/,
                              double /*slack_decay*/) {
  return ZenerStepper(c, dt).step(double(eps0), double(eps1), double(ev0));
}

// Stored energy per unit volume.
inline double zener_stored(const ZenerConstants& c, double stress, double ev) {
  return stress * stress / (2.0 * c.k1) + 0.5 * c.k2 * ev * ev;
}

// Eq 24: stress at strain eps under a constant strain rate from rest.
inline double zener_constant_rate_stress(const ZenerConstants& c, double eps, double rate) {
  const double s = c.k1 + c.k2;
  return c.k1 * c.k2 / s * eps - c.k1 * c.k1 * c.mu / (s * s) * rate * std::expm1(-s / c.mu * eps / rate);
}

}  // namespace ravel
