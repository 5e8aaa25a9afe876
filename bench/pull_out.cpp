// Single-yarn pull-out from a patch of the default fabric (issue 37: is the friction of a yarn
// pulled through ravel's weave the size measured for aramid fabrics?).
//
//   pull_out [--length-mm L] [--width-mm W] [--speed V,...] [--pull-mm D] [--window-mm S]
//            [--chart STEM] [--set key=value ...]
//
// The default scene's fabric, L long along the warps and W wide (the wefts clamped at their
// ends, x = +-W/2, as the default scene clamps them; the warps free, as in the impact), no
// projectile in reach. The central warp's end node at y = +L/2 is pulled along +y by a stiff
// spring whose anchor moves at V (a displacement-controlled grip, as in a tensile machine)
// for D mm, once per speed V. CSV on stdout, one row per S mm of pull: the speed, the grip
// displacement, the mean grip force over the window, the ledger's yarn-yarn friction work,
// the number of the pulled yarn's crossings still pressing, and the sum of their normal
// forces. After each speed a line (#): the peak force and where, the mean force over the
// last half of the pull, the work of the grip and the friction work. With --chart,
// STEM.{png,svg,csv}: force against displacement, one series per speed.
//
// A test machine pulls at mm/min; the run pulls at V (default 2 m/s) so that it ends in a
// minute: the pulled yarn's inertia adds about rho A V c (0.3 N at 2 m/s, c the yarn's wave
// speed) to the grip force, and the tension it makes presses the crossings (a rate effect
// that the impact's pull-out at 100-200 m/s has too).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "chart.h"
#include "model.h"
#include "scene.h"
#include "simulation.h"
#include "solver.h"

namespace {

struct PullResult {
  ravel::studies::Series force;
  double peak = 0, peak_at = 0, late_mean = 0, grip_work = 0, friction_work = 0;
  size_t crossings = 0;
};

// One pull at `speed`; CSV rows to stdout. Returns false (message on stderr) on a divergence.
bool pull(const ravel::Scene& scene, double speed, double length_mm, double pull_mm, double window_mm, PullResult& r) {
  ravel::Simulation sim(scene);
  ravel::Solver& so = sim.solver();
  const ravel::Model& m = so.model();
  // Out of reach: the projectile rests 1 m above the fabric (the ledger's reference, its
  // kinetic energy, is then zero: main() lifts the balance bound).
  so.set_projectile_position(ravel::Vec3d(0, 0, 1.0));
  so.set_projectile_velocity(ravel::Vec3d::Zero());
  // The warp nearest x = 0 and its end node at the +y edge.
  int y = -1;
  double best = 1e9;
  for (int yy = 0; yy < m.yarn_count(); ++yy) {
    if (m.yarn_family[yy] != ravel::warp) continue;
    const double x = std::abs(m.x0[m.yarn_node(yy, 0)].x());
    if (x < best) best = x, y = yy;
  }
  const int a = m.yarn_node(y, 0), b = m.yarn_node(y, m.yarn_size(y) - 1);
  const int end = m.x0[b].y() > m.x0[a].y() ? b : a;
  std::vector<int> mine;
  for (size_t c = 0; c < m.crossings.size(); ++c)
    if (m.crossings[c].warp_yarn == y) mine.push_back(int(c));
  r.crossings = mine.size();
  // Grip stiffness: one element's E A / L0, so that the end node is as stable at the step as
  // an interior one (the grip stretches as much as an element at the same force; the
  // displacement column is the anchor's).
  const double L0 = length_mm * 1e-3 / (m.yarn_size(y) - 1);
  const double k = scene.yarn.modulus_pa * scene.yarn.area_m2 / L0;
  const ravel::Vec3d x0 = so.position(end);
  const double T = pull_mm * 1e-3 / speed;
  const long per_window = std::max(1L, long(window_mm * 1e-3 / speed / m.dt));
  double acc = 0, late = 0, pulled_prev = 0;
  long cnt = 0, late_n = 0;
  char name[64];
  std::snprintf(name, sizeof name, "pulled at %.3g m/s", speed);
  r.force = {name, {}, {}, ravel::studies::SeriesStyle::line};
  while (so.time() < T) {
    const double pulled = speed * so.time();
    const ravel::Vec3d F = k * (x0 + ravel::Vec3d(0, pulled, 0) - so.position(end));
    so.set_external_force(end, F);
    so.step();
    if (!so.divergence().empty()) {
      std::fprintf(stderr, "pull_out: diverged at %.3g m/s: %s\n", speed, so.divergence().c_str());
      return false;
    }
    acc += F.y();
    r.grip_work += F.y() * (speed * so.time() - pulled_prev);
    pulled_prev = speed * so.time();
    if (++cnt < per_window) continue;
    const double f = acc / double(cnt), d_mm = pulled_prev * 1e3;
    acc = 0, cnt = 0;
    int pressing = 0;
    double nsum = 0;
    for (int c : mine)
      if (so.crossing_active(c) && so.crossing_normal_force(c) > 0) ++pressing, nsum += so.crossing_normal_force(c);
    std::printf("%.4g,%.4f,%.4f,%.5f,%d,%.3f\n", speed, d_mm, f, so.ledger().friction_work_J, pressing, nsum);
    r.force.x.push_back(d_mm);
    r.force.y.push_back(f);
    if (f > r.peak) r.peak = f, r.peak_at = d_mm;
    if (d_mm > 0.5 * pull_mm) late += f, ++late_n;
  }
  r.late_mean = late_n ? late / double(late_n) : 0.0;
  r.friction_work = so.ledger().friction_work_J;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  double length_mm = 60, width_mm = 30, pull_mm = 6, window_mm = 0.1;
  std::vector<double> speeds;
  std::string chart_stem;
  std::vector<std::string> extra;
  for (int i = 1; i < argc; ++i) {
    auto num = [&](double* v) {
      if (i + 1 >= argc) return false;
      *v = std::atof(argv[++i]);
      return *v > 0;
    };
    bool ok = true;
    if (!std::strcmp(argv[i], "--length-mm")) {
      ok = num(&length_mm);
    } else if (!std::strcmp(argv[i], "--width-mm")) {
      ok = num(&width_mm);
    } else if (!std::strcmp(argv[i], "--speed") && i + 1 < argc) {
      std::stringstream ss(argv[++i]);
      std::string t;
      while (ok && std::getline(ss, t, ',')) {
        speeds.push_back(std::atof(t.c_str()));
        ok = speeds.back() > 0;
      }
    } else if (!std::strcmp(argv[i], "--pull-mm")) {
      ok = num(&pull_mm);
    } else if (!std::strcmp(argv[i], "--window-mm")) {
      ok = num(&window_mm);
    } else if (!std::strcmp(argv[i], "--chart") && i + 1 < argc) {
      chart_stem = argv[++i];
    } else if (!std::strcmp(argv[i], "--set") && i + 1 < argc) {
      extra.push_back(argv[++i]);
    } else {
      ok = false;
    }
    if (!ok) {
      std::fprintf(stderr,
                   "usage: pull_out [--length-mm L] [--width-mm W] [--speed V,...] [--pull-mm D] [--window-mm S]\n"
                   "                [--chart STEM] [--set key=value ...]   (positive numbers)\n");
      return 2;
    }
  }
  if (speeds.empty()) speeds.push_back(2);
  std::vector<std::string> ov{"output.progress=false", "solver.symmetry=full", "solver.max_balance_error=1000",
                              "fabric.width_mm=" + std::to_string(width_mm),
                              "fabric.length_mm=" + std::to_string(length_mm)};
  ov.insert(ov.end(), extra.begin(), extra.end());
  ravel::Scene scene;
  try {
    scene = ravel::load_scene(ravel::default_scene_path(), ov);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pull_out: %s\n", e.what());
    return 2;
  }
  std::printf("speed_mps,pull_mm,force_N,friction_work_J,crossings_pressing,normal_sum_N\n");
  ravel::studies::Chart c;
  for (double v : speeds) {
    PullResult r;
    if (!pull(scene, v, length_mm, pull_mm, window_mm, r)) return 3;
    std::printf(
        "# length_mm=%.1f width_mm=%.1f speed_mps=%.3g mu=%.3g crossings=%zu peak_N=%.3f at_mm=%.3f "
        "late_mean_N=%.3f grip_work_J=%.5f friction_work_J=%.5f\n",
        length_mm, width_mm, v, scene.yarn.friction, r.crossings, r.peak, r.peak_at, r.late_mean, r.grip_work,
        r.friction_work);
    c.series.push_back(r.force);
  }
  if (!chart_stem.empty()) {
    c.title = "Single-yarn pull-out, " + scene.name;
    char s[200];
    std::snprintf(s, sizeof s,
                  "the central warp of a %.0f x %.0f mm patch, wefts clamped, mu = %.3g; mean force over %.3g mm "
                  "of pull",
                  length_mm, width_mm, scene.yarn.friction, window_mm);
    c.subtitle = s;
    c.x = {"grip displacement", "mm"};
    c.y = {"pull-out force", "N"};
    c.y.include_zero = true;
    ravel::studies::write_chart(c, chart_stem);
    std::fprintf(stderr, "pull_out: %s.{png,svg,csv}\n", chart_stem.c_str());
  }
  return 0;
}
