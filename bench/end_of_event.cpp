// The end of the event (issue 37, docs/MODEL.md §10 "After the first break"): where and when
// the yarn-yarn friction dissipates, and what holds the projectile, on the default scene.
//
//   end_of_event --series DT_US [--chart STEM] [--set key=value ...]
//       CSV on stdout every DT_US: the ledger's friction work and the friction heat of the
//       crossings summed by class -- on a yarn that touches the projectile now (hooked), on
//       a yarn with a broken element (broken), all others -- with the yarns in each class,
//       the strain and fabric kinetic energy. With --chart, STEM.{png,svg,csv}: the three
//       classes and the ledger's figure against time.
//   end_of_event --at T_US,... [--set ...] [--profile] [--warp I]
//       a report at each time: the yarns touching the projectile (their nodes, strains and
//       broken elements), the friction heat since the last time by warp and weft grid line;
//       --profile the strain along the yarns of grid lines 0, 1 and 3; --warp I every
//       crossing along warp grid line I (normal and friction force, gap, slip rate).
// The heat of a crossing is its friction force times the speed of its stuck point (the
// ledger's friction work takes out what the stick springs give back, so the classes sum a
// little above it). Node counts and energies are the whole fabric's (the quarter times 4).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "chart.h"
#include "model.h"
#include "scene.h"
#include "simulation.h"
#include "solver.h"

int main(int argc, char** argv) {
  std::vector<std::string> ov{"output.progress=false"};
  std::vector<double> at;
  int warp_detail = -1;
  bool profile = false;
  double series_every = 0;
  std::string chart_stem;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--set") && i + 1 < argc) {
      ov.push_back(argv[++i]);
    } else if (!std::strcmp(argv[i], "--at") && i + 1 < argc) {
      std::stringstream ss(argv[++i]);
      std::string t;
      while (std::getline(ss, t, ',')) at.push_back(std::stod(t) * 1e-6);
    } else if (!std::strcmp(argv[i], "--series") && i + 1 < argc) {
      series_every = std::stod(argv[++i]) * 1e-6;
    } else if (!std::strcmp(argv[i], "--chart") && i + 1 < argc) {
      chart_stem = argv[++i];
    } else if (!std::strcmp(argv[i], "--profile")) {
      profile = true;
    } else if (!std::strcmp(argv[i], "--warp") && i + 1 < argc) {
      warp_detail = std::atoi(argv[++i]);
    } else {
      std::fprintf(stderr,
                   "usage: end_of_event --series DT_US [--chart STEM] [--set key=value ...]\n"
                   "       end_of_event --at T_US,... [--profile] [--warp I] [--set key=value ...]\n");
      return 2;
    }
  }
  ravel::Scene scene = ravel::load_scene(ravel::default_scene_path(), ov);
  ravel::Simulation sim(scene);
  const ravel::Solver& s = sim.solver();
  const ravel::Model& m = s.model();
  const int nc = int(m.crossings.size());
  const double f = m.symmetry_factor;
  std::vector<double> heat_prev(nc, 0.0);
  double tprev = 0;
  size_t next = 0;
  std::vector<int> node_yarn(m.node_count, -1), node_k(m.node_count, -1);
  for (int y = 0; y < m.yarn_count(); ++y)
    for (int k = 0; k < m.yarn_size(y); ++k) node_yarn[m.yarn_node(y, k)] = y, node_k[m.yarn_node(y, k)] = k;
  std::vector<int> node_elem_first(m.node_count, -1);
  if (series_every > 0) {
    // Friction heat by class of crossing, cumulative, every series_every: crossings on a yarn
    // touching the projectile now (hooked), on a yarn with a broken element (broken), others.
    std::vector<double> cls(3, 0.0), prev(nc, 0.0);
    std::vector<char> yarn_broken(m.yarn_count(), 0), yarn_touch(m.yarn_count(), 0);
    double next_t = series_every;
    std::printf(
        "t_us,v_mps,fw_ledger_J,heat_hooked_J,heat_broken_J,heat_other_J,hooked_yarns,broken_yarns,"
        "strain_energy_J,fabric_ke_J\n");
    ravel::studies::Series sh{"on yarns touching the projectile", {}, {}, ravel::studies::SeriesStyle::line},
        sb{"on broken yarns", {}, {}, ravel::studies::SeriesStyle::line},
        so{"all other crossings", {}, {}, ravel::studies::SeriesStyle::line},
        sl{"ledger friction work (total)", {}, {}, ravel::studies::SeriesStyle::line};
    sl.dashed = true;

    int step = 0;
    while (sim.step()) {
      if (++step % 4) continue;
      std::fill(yarn_touch.begin(), yarn_touch.end(), 0);
      const ravel::Vec3d xp = s.projectile_position();
      for (int i = 0; i < m.node_count; ++i) {
        ravel::Vec3d n;
        const ravel::Vec3d rel = s.position(i) - xp;
        if (m.shape.sdf(rel, n) < 5e-6) yarn_touch[node_yarn[i]] = 1;
      }
      for (int y = 0; y < m.yarn_count(); ++y)
        if (!yarn_broken[y])
          for (int e = 0; e < m.yarn_size(y) - 1; ++e)
            if (s.broken(m.yarn_elem_offset[y] + e)) {
              yarn_broken[y] = 1;
              break;
            }
      for (int c = 0; c < nc; ++c) {
        const double h = s.crossing_friction_heat(c), dh = (h - prev[c]) * f;
        prev[c] = h;
        if (dh == 0) continue;
        const auto& cr = m.crossings[c];
        const int k = yarn_touch[cr.warp_yarn] || yarn_touch[cr.weft_yarn]     ? 0
                      : yarn_broken[cr.warp_yarn] || yarn_broken[cr.weft_yarn] ? 1
                                                                               : 2;
        cls[k] += dh;
      }
      if (sim.time_s() >= next_t) {
        next_t += series_every;
        int nh = 0, nb = 0;
        for (int y = 0; y < m.yarn_count(); ++y) nh += yarn_touch[y], nb += yarn_broken[y];
        const auto& L = s.ledger();
        const double t_us = sim.time_s() * 1e6;
        std::printf("%.1f,%.2f,%.4f,%.4f,%.4f,%.4f,%d,%d,%.3f,%.3f\n", t_us, -s.projectile_velocity().z(),
                    L.friction_work_J * f, cls[0], cls[1], cls[2], nh, nb, L.strain_energy_J * f, L.fabric_ke_J * f);
        for (auto* q : {&sh, &sb, &so, &sl}) q->x.push_back(t_us);
        sh.y.push_back(cls[0]);
        sb.y.push_back(cls[1]);
        so.y.push_back(cls[2]);
        sl.y.push_back(L.friction_work_J * f);
      }
    }
    if (!chart_stem.empty()) {
      ravel::studies::Chart c;
      c.title = "Where yarn-yarn friction dissipates, " + scene.name;
      char b[160];
      const ravel::Summary sum = sim.summary();
      std::snprintf(b, sizeof b, "mu = %.3g, %.0f m/s; first break %.1f us; %s at %.1f us (sampled every %.3g us)",
                    scene.yarn.friction, scene.projectile.velocity_mps, sum.first_break_time_s * 1e6,
                    sum.perforated ? "perforated" : "ended",
                    (sum.perforated ? sum.perforation_time_s : sim.time_s()) * 1e6, series_every * 1e6);
      c.subtitle = b;
      c.x = {"time", "us"};
      c.y = {"friction heat, cumulative", "J"};
      c.y.include_zero = true;
      c.series = {sh, sb, so, sl};
      ravel::studies::write_chart(c, chart_stem);
      std::fprintf(stderr, "end_of_event: %s.{png,svg,csv}\n", chart_stem.c_str());
    }
    return 0;
  }
  while (next < at.size() && sim.step()) {
    if (sim.time_s() + 0.5 * sim.dt_s() < at[next]) continue;
    const double t = sim.time_s();
    const ravel::Vec3d xp = s.projectile_position(), vp = s.projectile_velocity();
    std::printf("=== t = %.1f us  proj z = %.3f mm  v = %.2f m/s  Fproj = %.1f N (quarter)  fw = %.3f J\n", t * 1e6,
                xp.z() * 1e3, vp.z(), s.projectile_contact_force(), s.ledger().friction_work_J * f);
    // nodes touching (sdf <= 5 um)
    std::map<int, std::vector<int>> touch;  // yarn -> k
    for (int i = 0; i < m.node_count; ++i) {
      ravel::Vec3d n;
      const ravel::Vec3d rel = s.position(i) - xp;
      const double sd = m.shape.sdf(rel, n);
      if (sd < 5e-6) touch[node_yarn[i]].push_back(node_k[i]);
    }
    for (auto& [y, ks] : touch) {
      const int fam = m.yarn_family[y];
      const int e0 = m.yarn_elem_offset[y];
      const int ne = m.yarn_size(y) - 1;
      double smax = 0, smin = 1e9;
      int nb = 0;
      for (int e = 0; e < ne; ++e) {
        if (s.broken(e0 + e)) {
          ++nb;
          continue;
        }
        smax = std::max(smax, s.strain(e0 + e));
      }
      // strain of elements next to the touching nodes
      std::string kl;
      for (int k : ks) {
        char b[64];
        const double sl = k > 0 && !s.broken(e0 + k - 1) ? s.strain(e0 + k - 1) : -1;
        const double sr = k < ne && !s.broken(e0 + k) ? s.strain(e0 + k) : -1;
        smin = std::min(smin, std::max(sl, sr));
        const ravel::Vec3d x = s.position(m.yarn_node(y, k));
        std::snprintf(b, sizeof b, " %d(%.1f,%.1f|%.2f%%)", k, x.x() * 1e3, x.y() * 1e3, 100 * std::max(sl, sr));
        kl += b;
      }
      std::printf("  %s %d (grid %d): %zu nodes, yarn max strain %.2f%%, broken elems %d:%s\n", fam ? "weft" : "warp",
                  y, m.yarn_grid[y], ks.size(), 100 * smax, nb, kl.c_str());
    }
    // friction heat by yarn in the interval
    std::map<int, double> hw, hf;
    double tot = 0;
    for (int c = 0; c < nc; ++c) {
      const double dh = (s.crossing_friction_heat(c) - heat_prev[c]) * f;
      heat_prev[c] = s.crossing_friction_heat(c);
      hw[m.crossings[c].grid_i] += dh;
      hf[m.crossings[c].grid_j] += dh;
      tot += dh;
    }
    std::printf("  heat %.1f-%.1f us: %.3f J; by warp grid I (top):", tprev * 1e6, t * 1e6, tot);
    std::vector<std::pair<double, int>> v;
    for (auto& [k, h] : hw) v.push_back({h, k});
    std::sort(v.rbegin(), v.rend());
    for (int i = 0; i < 8 && i < int(v.size()); ++i) std::printf(" %d:%.2f", v[i].second, v[i].first);
    std::printf("\n   by weft grid J (top):");
    v.clear();
    for (auto& [k, h] : hf) v.push_back({h, k});
    std::sort(v.rbegin(), v.rend());
    for (int i = 0; i < 8 && i < int(v.size()); ++i) std::printf(" %d:%.2f", v[i].second, v[i].first);
    std::printf("\n");
    if (profile) {
      for (int y = 0; y < m.yarn_count(); ++y) {
        const int g = m.yarn_grid[y];
        if (g != 0 && g != 1 && g != 3) continue;
        const int e0 = m.yarn_elem_offset[y], ne = m.yarn_size(y) - 1;
        std::printf("  %s grid %d strain %%:", m.yarn_family[y] ? "weft" : "warp", g);
        for (int e = 0; e < ne; e += (e < 12 ? 1 : 6))
          std::printf(" %s%.2f", s.broken(e0 + e) ? "X" : "", 100 * s.strain(e0 + e));
        std::printf("\n");
      }
    }
    if (warp_detail >= 0) {
      std::printf("  crossings along warp I=%d: J fn ft gap_um slip active | warp strain at kw, weft strain at kf\n",
                  warp_detail);
      for (int c = 0; c < nc; ++c) {
        const auto& cr = m.crossings[c];
        if (cr.grid_i != warp_detail || cr.grid_j > 40) continue;
        const int kw = s.crossing_warp_node(c), kf = s.crossing_weft_node(c);
        const int ew = m.yarn_elem_offset[cr.warp_yarn] + std::min(kw, m.yarn_size(cr.warp_yarn) - 2);
        const int ef = m.yarn_elem_offset[cr.weft_yarn] + std::min(kf, m.yarn_size(cr.weft_yarn) - 2);
        std::printf("   J=%2d kw=%2d kf=%2d fn=%7.2f ft=%6.2f gap=%6.1f slip=%6.1f act=%d | %.2f%% %.2f%%\n", cr.grid_j,
                    kw, kf, s.crossing_normal_force(c), s.crossing_friction_force(c), s.crossing_gap(c) * 1e6,
                    s.crossing_slip_rate(c), int(s.crossing_active(c)), 100 * s.strain(ew), 100 * s.strain(ef));
      }
    }
    tprev = t;
    ++next;
  }
  return 0;
}
