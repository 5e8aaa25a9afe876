// Where the yarn-yarn friction dissipates: the default scene (or any, with --set) run to its
// end, the friction of every crossing summed by region, before and after the first yarn
// break. Prints CSV. docs/MODEL.md §10 ("Friction work") quotes it.
//   friction_where [--set k=v ...]
//
// A crossing's dissipation per step is estimated as |f_t| v_slip dt: its friction force
// (the resultant, last step) times the speed of its stuck point. That counts the work the
// stick springs store and give back as well, so the sum runs somewhat above the ledger's
// friction_work_J (which is the impulses' work less the springs' energy, §4); both are
// printed. Regions, by the crossing's place at t = 0 measured from the strike point in the
// fabric's plane (R: the projectile's radius):
//   under_projectile   |x| < R and |y| < R
//   primary_yarns      |x| < R or |y| < R, not under the projectile: along the yarns the
//                      projectile strikes, out to the edges
//   elsewhere          the rest
// and radial bands (mm) of the same distance, and classes of the largest normal force the
// crossing had (N, the modelled crossing's).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "model.h"
#include "scene.h"
#include "simulation.h"
#include "solver.h"

int main(int argc, char** argv) {
  std::vector<std::string> ov{"output.progress=false"};
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--set") && i + 1 < argc) {
      ov.push_back(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: friction_where [--set key=value ...]\n");
      return 2;
    }
  }
  ravel::Scene scene;
  try {
    scene = ravel::load_scene(ravel::default_scene_path(), ov);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "friction_where: %s\n", e.what());
    return 2;
  }
  ravel::Simulation sim(scene);
  const ravel::Solver& s = sim.solver();
  const ravel::Model& m = s.model();
  const int nc = int(m.crossings.size());
  const double R = m.shape.radius, dt = m.dt, f = m.symmetry_factor;
  const ravel::Vec3d strike = s.projectile_position();

  enum { kUnder, kPrimary, kElsewhere, kRegions };
  const char* region_name[kRegions] = {"under_projectile", "primary_yarns", "elsewhere"};
  const double band_edge_mm[] = {6, 15, 30, 45};
  const int bands = 5;
  std::vector<int> region(nc), band(nc);
  for (int c = 0; c < nc; ++c) {
    const auto& cr = m.crossings[c];
    const ravel::Vec3d d = m.x0[m.yarn_node(cr.warp_yarn, cr.warp_node)] - strike;
    const double ax = std::abs(d.x()), ay = std::abs(d.y()), r_mm = std::hypot(d.x(), d.y()) * 1e3;
    region[c] = ax < R && ay < R ? kUnder : ax < R || ay < R ? kPrimary : kElsewhere;
    int b = 0;
    while (b < bands - 1 && r_mm >= band_edge_mm[b]) ++b;
    band[c] = b;
  }

  // [phase][crossing]: 0 before the first break, 1 after it.
  std::vector<double> work[2] = {std::vector<double>(nc, 0.0), std::vector<double>(nc, 0.0)};
  std::vector<double> fn_peak(nc, 0.0);
  int phase = 0;
  double t_break = -1, ledger_at_break = 0;
  auto broken_any = [&] {
    for (int e = 0; e < m.element_count; ++e)
      if (s.broken(e)) return true;
    return false;
  };
  while (sim.step()) {
    for (int c = 0; c < nc; ++c)
      if (s.crossing_active(c)) {
        work[phase][c] += s.crossing_friction_force(c) * s.crossing_slip_rate(c) * dt;
        fn_peak[c] = std::max(fn_peak[c], s.crossing_normal_force(c));
      }
    if (phase == 0 && broken_any()) {
      phase = 1;
      t_break = sim.time_s();
      ledger_at_break = s.ledger().friction_work_J * f;
    }
  }
  const auto sum = sim.summary();

  std::printf("# %s, mu = %g, V0 = %g m/s: ended %s at %.1f us; first break at %.1f us\n", scene.name.c_str(),
              scene.yarn.friction, scene.projectile.velocity_mps, ravel::to_string(sum.end_reason), sim.time_s() * 1e6,
              t_break * 1e6);
  std::printf("# ledger friction_work_J: %.3f at the first break, %.3f at the end\n", ledger_at_break,
              sum.friction_work_J);
  std::printf("phase,group,bin,crossings,work_J,share\n");
  const char* phase_name[3] = {"before_first_break", "after_first_break", "whole_run"};
  for (int p = 0; p < 3; ++p) {
    auto w = [&](int c) { return p == 2 ? work[0][c] + work[1][c] : work[p][c]; };
    double total = 0;
    for (int c = 0; c < nc; ++c) total += w(c);
    std::printf("%s,all,all,%d,%.4f,1.000\n", phase_name[p], nc, total * f);
    for (int g = 0; g < kRegions; ++g) {
      double x = 0;
      int n = 0;
      for (int c = 0; c < nc; ++c)
        if (region[c] == g) x += w(c), ++n;
      std::printf("%s,region,%s,%d,%.4f,%.3f\n", phase_name[p], region_name[g], n, x * f, total > 0 ? x / total : 0.0);
    }
    for (int b = 0; b < bands; ++b) {
      double x = 0;
      int n = 0;
      for (int c = 0; c < nc; ++c)
        if (band[c] == b) x += w(c), ++n;
      char bin[32];
      if (b == bands - 1)
        std::snprintf(bin, sizeof bin, ">=%g mm", band_edge_mm[b - 1]);
      else
        std::snprintf(bin, sizeof bin, "%g-%g mm", b == 0 ? 0.0 : band_edge_mm[b - 1], band_edge_mm[b]);
      std::printf("%s,radius,%s,%d,%.4f,%.3f\n", phase_name[p], bin, n, x * f, total > 0 ? x / total : 0.0);
    }
    const double fn_edge[] = {1, 10, 50};
    for (int k = 0; k < 4; ++k) {
      const double lo = k == 0 ? 0.0 : fn_edge[k - 1], hi = k == 3 ? 1e300 : fn_edge[k];
      double x = 0;
      int n = 0;
      for (int c = 0; c < nc; ++c)
        if (fn_peak[c] >= lo && fn_peak[c] < hi) x += w(c), ++n;
      char bin[32];
      if (k == 3)
        std::snprintf(bin, sizeof bin, ">=%g N", lo);
      else
        std::snprintf(bin, sizeof bin, "%g-%g N", lo, hi);
      std::printf("%s,peak_normal_force,%s,%d,%.4f,%.3f\n", phase_name[p], bin, n, x * f, total > 0 ? x / total : 0.0);
    }
  }
  return 0;
}
