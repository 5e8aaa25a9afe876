// Single-yarn pull-out from a patch of the default fabric (issue 37: how much friction does a
// yarn pulled through ravel's weave meet, and how does that depend on the pull's speed?).
//
//   pull_out [--length-mm L] [--width-mm W] [--speed V,...] [--pull-mm D] [--window-mm S]
//            [--chart STEM] [--set key=value ...]
//
// The default scene's fabric, L long along the warps and W wide (defaults 60 x 30 mm; the
// wefts clamped at their ends, x = +-W/2, as the default scene clamps them; the warps free, as
// in the impact), no projectile in reach. The central warp's end node at the +y edge is
// pulled along +y by a spring whose anchor moves at V (a displacement-controlled grip) until
// the anchor has moved D mm (default 6), once per speed V (default 2 m/s). CSV on stdout,
// one row per S mm of anchor travel (default 0.1; the last window may be shorter): the speed,
// the anchor displacement at the window's middle, the mean grip force over the window, the
// ledger's yarn-yarn friction work so far, the number of the pulled yarn's crossings still
// pressing, and the sum of their normal forces. After each speed a line (#): the peak window
// force and where, the mean force over the last half of the pull, the work of the grip and
// the friction work. With --chart, STEM.{png,svg,csv}: force against displacement, one series
// per speed.
//
// A test machine pulls at mm/min; a run here pulls at metres per second so that it ends in a
// minute. The pulled yarn's inertia then adds up to its impedance, mass per length times
// wave speed times V (1.5 N at 2 m/s, 77 N at 100 m/s for a straight yarn of the default
// fabric; its crimp stage lowers it), to the grip force while the yarn is set moving, and the
// tension that takes presses the crossings: a rate effect the impact's pull-out has too.
#include <cerrno>
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

// A positive finite number, the whole of `text`.
bool positive(const char* text, double* v) {
  char* end = nullptr;
  errno = 0;
  *v = std::strtod(text, &end);
  return end != text && *end == '\0' && errno == 0 && std::isfinite(*v) && *v > 0;
}

// One pull at `speed`; CSV rows to stdout. Returns false (message on stderr) when the patch
// has no warp or the run diverges.
bool pull(const ravel::Scene& scene, double speed, double pull_mm, double window_mm, PullResult& r) {
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
    if (m.yarn_family[yy] != ravel::warp || m.yarn_size(yy) < 2) continue;
    const double x = std::abs(m.x0[m.yarn_node(yy, 0)].x());
    if (x < best) best = x, y = yy;
  }
  if (y < 0) {
    std::fprintf(stderr, "pull_out: the patch has no warp yarn to pull\n");
    return false;
  }
  const int a = m.yarn_node(y, 0), b = m.yarn_node(y, m.yarn_size(y) - 1);
  const int end = m.x0[b].y() > m.x0[a].y() ? b : a;
  std::vector<int> mine;
  for (size_t c = 0; c < m.crossings.size(); ++c)
    if (m.crossings[c].warp_yarn == y) mine.push_back(int(c));
  r.crossings = mine.size();
  // Grip stiffness: the pulled yarn's own element stiffness (instantaneous modulus times area
  // over rest length), so that the end node is as stable at the step as an interior one; the
  // grip stretches as much as an element at the same force.
  const int e0 = m.yarn_elem_offset[y];
  const double k = m.modulus_inst * m.elem_area[e0] / m.elem_rest[e0];
  const ravel::Vec3d x0 = so.position(end);
  const double travel = pull_mm * 1e-3, window = window_mm * 1e-3;
  double acc = 0, late = 0, at = 0, window_start = 0;
  long cnt = 0, late_n = 0;
  char name[64];
  std::snprintf(name, sizeof name, "pulled at %.3g m/s", speed);
  r.force = {name, {}, {}, ravel::studies::SeriesStyle::line};
  auto close_window = [&]() {
    const double f = acc / double(cnt), mid_mm = 0.5 * (window_start + at) * 1e3;
    int pressing = 0;
    double nsum = 0;
    for (int c : mine)
      if (so.crossing_active(c) && so.crossing_normal_force(c) > 0) ++pressing, nsum += so.crossing_normal_force(c);
    std::printf("%.4g,%.4f,%.4f,%.5f,%d,%.3f\n", speed, mid_mm, f, so.ledger().friction_work_J, pressing, nsum);
    r.force.x.push_back(mid_mm);
    r.force.y.push_back(f);
    if (f > r.peak) r.peak = f, r.peak_at = mid_mm;
    if (mid_mm > 0.5 * pull_mm) late += f, ++late_n;
    acc = 0, cnt = 0, window_start = at;
  };
  while (at < travel) {
    // The force over the step is the spring's at its start; the anchor then moves V dt.
    const ravel::Vec3d F = k * (x0 + ravel::Vec3d(0, at, 0) - so.position(end));
    so.set_external_force(end, F);
    so.step();
    if (!so.divergence().empty()) {
      std::fprintf(stderr, "pull_out: diverged at %.3g m/s: %s\n", speed, so.divergence().c_str());
      return false;
    }
    const double next = std::min(travel, speed * so.time());
    r.grip_work += F.y() * (next - at);
    at = next;
    acc += F.y();
    ++cnt;
    if (at - window_start >= window * (1 - 1e-9) || at >= travel) close_window();
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
    const bool has_value = i + 1 < argc;
    bool ok = has_value;
    if (!std::strcmp(argv[i], "--length-mm") && has_value) {
      ok = positive(argv[++i], &length_mm);
    } else if (!std::strcmp(argv[i], "--width-mm") && has_value) {
      ok = positive(argv[++i], &width_mm);
    } else if (!std::strcmp(argv[i], "--speed") && has_value) {
      std::stringstream ss(argv[++i]);
      std::string t;
      speeds.clear();
      while (ok && std::getline(ss, t, ',')) {
        double v = 0;
        ok = positive(t.c_str(), &v);
        speeds.push_back(v);
      }
      ok = ok && !speeds.empty();
    } else if (!std::strcmp(argv[i], "--pull-mm") && has_value) {
      ok = positive(argv[++i], &pull_mm);
    } else if (!std::strcmp(argv[i], "--window-mm") && has_value) {
      ok = positive(argv[++i], &window_mm);
    } else if (!std::strcmp(argv[i], "--chart") && has_value) {
      chart_stem = argv[++i];
    } else if (!std::strcmp(argv[i], "--set") && has_value) {
      extra.push_back(argv[++i]);
    } else {
      ok = false;
    }
    if (!ok) {
      std::fprintf(stderr,
                   "pull_out: bad argument '%s'\n"
                   "usage: pull_out [--length-mm L] [--width-mm W] [--speed V,...] [--pull-mm D] [--window-mm S]\n"
                   "                [--chart STEM] [--set key=value ...]   (L, W, V, D, S positive numbers)\n",
                   argv[i]);
      return 2;
    }
  }
  if (speeds.empty()) speeds.push_back(2);
  std::vector<std::string> ov{"output.progress=false", "solver.symmetry=full", "solver.max_balance_error=1000",
                              "fabric.width_mm=" + std::to_string(width_mm),
                              "fabric.length_mm=" + std::to_string(length_mm)};
  ov.insert(ov.end(), extra.begin(), extra.end());  // (a --set of the size wins over the flags)
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
    if (!pull(scene, v, pull_mm, window_mm, r)) return 3;
    std::printf(
        "# length_mm=%.1f width_mm=%.1f speed_mps=%.3g mu=%.3g crossings=%zu peak_N=%.3f at_mm=%.3f "
        "late_mean_N=%.3f grip_work_J=%.5f friction_work_J=%.5f\n",
        scene.fabric.length_m * 1e3, scene.fabric.width_m * 1e3, v, scene.yarn.friction, r.crossings, r.peak, r.peak_at,
        r.late_mean, r.grip_work, r.friction_work);
    c.series.push_back(r.force);
  }
  if (!chart_stem.empty()) {
    c.title = "Single-yarn pull-out, " + scene.name;
    char s[200];
    std::snprintf(s, sizeof s,
                  "the central warp of a %.0f x %.0f mm patch, wefts clamped, mu = %.3g; mean force over %.3g mm "
                  "of grip travel",
                  scene.fabric.length_m * 1e3, scene.fabric.width_m * 1e3, scene.yarn.friction, window_mm);
    c.subtitle = s;
    c.x = {"grip displacement", "mm"};
    c.y = {"pull-out force", "N"};
    c.y.include_zero = true;
    ravel::studies::write_chart(c, chart_stem);
    std::fprintf(stderr, "pull_out: %s.{png,svg,csv}\n", chart_stem.c_str());
  }
  return 0;
}
