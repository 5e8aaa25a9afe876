// Where the yarn-yarn friction dissipates: the default scene (or any, with --set) run to its
// end, the friction heat of every crossing summed by region, before and after the first yarn
// break. Prints CSV. docs/MODEL.md §10 ("Post-failure friction") quotes it.
//   friction_where [--set k=v ...]
//
// A crossing's heat is the solver's (Solver::crossing_friction_heat: its friction force
// times its slip speed, summed over the steps: the app's "friction" field). The ledger's
// friction_work_J is printed beside it; the heat's sum runs somewhat above it (docs/MODEL.md
// §8). Regions, by the crossing's place at t = 0 measured from the strike point in the
// fabric's plane (R: the projectile's radius):
//   under_projectile   |x| < R and |y| < R
//   primary_yarns      |x| < R or |y| < R, not under the projectile: along the yarns the
//                      projectile strikes, out to the edges
//   elsewhere          the rest
// radial bands (mm) of the same distance, and classes of the largest normal force the
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
  const double R = m.shape.radius, f = m.symmetry_factor;
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

  auto broken_any = [&] {
    for (int e = 0; e < m.element_count; ++e)
      if (s.broken(e)) return true;
    return false;
  };
  std::vector<double> fn_peak(nc, 0.0), at_break(nc, 0.0);
  double t_break = -1, ledger_at_break = 0;
  while (sim.step()) {
    for (int c = 0; c < nc; ++c)
      if (s.crossing_active(c)) fn_peak[c] = std::max(fn_peak[c], s.crossing_normal_force(c));
    if (t_break < 0 && broken_any()) {
      t_break = sim.time_s();
      for (int c = 0; c < nc; ++c) at_break[c] = s.crossing_friction_heat(c);
      ledger_at_break = s.ledger().friction_work_J * f;
    }
  }
  const auto sum = sim.summary();

  std::printf("# %s, mu = %g, V0 = %g m/s: ended %s at %.1f us; first break at %.1f us\n", scene.name.c_str(),
              scene.yarn.friction, scene.projectile.velocity_mps, ravel::to_string(sum.end_reason), sim.time_s() * 1e6,
              t_break * 1e6);
  std::printf("# ledger friction_work_J (whole fabric): %.4f at the first break (the row before it), %.4f at the end\n",
              ledger_at_break, sum.friction_work_J);
  std::printf("phase,group,bin,crossings,heat_J,share\n");
  const char* phase_name[3] = {"before_first_break", "after_first_break", "whole_run"};
  for (int p = 0; p < 3; ++p) {
    auto w = [&](int c) {
      const double end = s.crossing_friction_heat(c);
      return p == 0 ? at_break[c] : p == 1 ? end - at_break[c] : end;
    };
    double total = 0;
    for (int c = 0; c < nc; ++c) total += w(c);
    auto row = [&](const char* group, const char* bin, auto&& in) {
      double x = 0;
      int count = 0;
      for (int c = 0; c < nc; ++c)
        if (in(c)) x += w(c), ++count;
      std::printf("%s,%s,%s,%d,%.4f,%.3f\n", phase_name[p], group, bin, count, x * f, total > 0 ? x / total : 0.0);
    };
    row("all", "all", [](int) { return true; });
    for (int g = 0; g < kRegions; ++g) row("region", region_name[g], [&](int c) { return region[c] == g; });
    for (int b = 0; b < bands; ++b) {
      char bin[32];
      if (b == bands - 1)
        std::snprintf(bin, sizeof bin, ">=%g mm", band_edge_mm[b - 1]);
      else
        std::snprintf(bin, sizeof bin, "%g-%g mm", b == 0 ? 0.0 : band_edge_mm[b - 1], band_edge_mm[b]);
      row("radius", bin, [&](int c) { return band[c] == b; });
    }
    const double fn_edge[] = {1, 10, 50};
    for (int k = 0; k < 4; ++k) {
      const double lo = k == 0 ? 0.0 : fn_edge[k - 1], hi = k == 3 ? 1e300 : fn_edge[k];
      char bin[32];
      if (k == 3)
        std::snprintf(bin, sizeof bin, ">=%g N", lo);
      else
        std::snprintf(bin, sizeof bin, "%g-%g N", lo, hi);
      row("peak_normal_force", bin, [&](int c) { return fn_peak[c] >= lo && fn_peak[c] < hi; });
    }
  }
  return 0;
}
