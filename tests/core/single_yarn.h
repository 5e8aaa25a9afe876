// One straight elastic yarn struck transversely (fabric.weave = single_yarn) and classical
// single-yarn theory (Smith et al.): shared by the wave tests and the slipping-clamp tests.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace ravel::test::single {

constexpr double kE = 7.28e10, kRho = 1440, kA = 7.64e-8, kL0 = 0.844e-3;

// A 300 mm yarn struck at v by a heavy flat-fronted load (1 kg: its speed barely changes),
// for 20 us. Lumped mass = rho A L0, so the discrete chain's wave speed L0 sqrt(k/m) equals
// c = sqrt(E / rho).
inline std::vector<std::string> single_yarn(double v) {
  char mass[64], vel[64];
  std::snprintf(mass, sizeof mass, "fabric.node_mass_g=%.9g", kRho * kA * kL0 * 1e3);
  std::snprintf(vel, sizeof vel, "projectile.velocity_mps=%g", v);
  return {"fabric.weave=single_yarn",
          "fabric.length_mm=300",
          "yarn.material=elastic",
          "yarn.modulus_pa=7.28e10",
          "yarn.breakable=false",
          "projectile.mass_g=1000",
          "projectile.friction=0",
          "solver.end_time_us=20",
          mass,
          vel};
}

// Smith's relation V = c sqrt(2 eps sqrt(eps (1 + eps)) - eps^2) solved for eps.
inline double smith_strain(double v, double c) {
  double lo = 0, hi = 0.5;
  for (int i = 0; i < 200; ++i) {
    const double m = 0.5 * (lo + hi);
    (c * std::sqrt(2 * m * std::sqrt(m * (1 + m)) - m * m) < v ? lo : hi) = m;
  }
  return lo;
}

}  // namespace ravel::test::single
