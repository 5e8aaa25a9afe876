// The runs of run_paper (paper_internal.h): the velocity sweep, the compression what-if,
// the ballistic-limit searches and the perforation images.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <mutex>
#include <stdexcept>

#include "paper_internal.h"
#include "results.h"
#include "simulation.h"
#include "work_queue.h"

namespace ravel::studies::paper_detail {

namespace fs = std::filesystem;

void run_velocity_stage(PaperState& ps) {
  const PaperOptions& opt = ps.opt;
  const PaperPlan& plan = ps.plan;
  PaperResult& result = ps.result;
  std::vector<Case> cases;
  auto add_case = [&](double mu, double failure, double v) {
    Case c;
    c.index = int(cases.size());
    c.settings = {
        {"yarn.friction", num(mu)}, {"yarn.failure_strain", num(failure)}, {"projectile.velocity_mps", num(v)}};
    cases.push_back(c);
  };
  for (double mu : plan.frictions)
    for (double v : plan.velocities_mps) add_case(mu, kDefaultFailure, v);
  for (double f : plan.failure_strains)
    if (!same(f, kDefaultFailure))
      for (double v : plan.velocities_mps) add_case(kReferenceFriction, f, v);

  SweepOptions& so = ps.velocity_sweep;
  so.scene_path = opt.scene_path;
  so.overrides = ps.with(plan.velocity_overrides);
  so.overrides.push_back("solver.end_time_us=auto");
  so.out_dir = opt.out_dir + "/velocity";
  so.jobs = opt.jobs;
  SweepHooks hooks;
  hooks.on_progress = [&](const SweepProgress& p) { ps.progress("velocity sweep", p.done, p.total, p.skipped); };
  hooks.on_simulation = [&](const Case& c, const Simulation& sim, const std::string&) {
    const Scene& s = sim.scene();
    if (!same(s.yarn.friction, kReferenceFriction) || !same(s.yarn.failure_strain, kDefaultFailure)) return;
    for (double v : plan.image_velocities_mps)
      if (same(v, s.projectile.velocity_mps)) ps.image_frames[v] = sim.frame();
  };
  const std::vector<std::string> varied{"yarn.friction", "yarn.failure_strain", "projectile.velocity_mps"};
  ps.velocity_report = run_sweep(cases, cases, so, varied, hooks, ps.interrupt);
  const SweepReport& vrep = ps.velocity_report;
  if (vrep.interrupted) throw std::runtime_error("interrupted during the velocity sweep (rerun to resume)");
  for (const auto& e : vrep.errors) result.warnings.push_back("velocity sweep: " + e);

  {
    const Csv csv = parse_csv(read_text_file(so.out_dir + "/results.csv"));
    for (const auto& r : csv.rows) {
      VelocityRow w;
      w.case_name = csv.cell(r, "case");
      w.mu = to_d(csv.cell(r, "yarn.friction"));
      w.failure = to_d(csv.cell(r, "yarn.failure_strain"));
      w.v = to_d(csv.cell(r, "projectile.velocity_mps"));
      w.perforated = csv.cell(r, "perforated") == "true";
      w.energy_J = to_d(csv.cell(r, "energy_absorbed_J"));
      w.residual = to_d(csv.cell(r, "residual_velocity_mps"));
      w.perforation_time_s = to_d(csv.cell(r, "perforation_time_s"));
      w.friction_work_J = to_d(csv.cell(r, "friction_work_J"));
      w.wall_s = to_d(csv.cell(r, "wall_time_s"));
      w.broken_warp_yarns = int(to_d(csv.cell(r, "broken_warp_yarns")));
      w.broken_weft_yarns = int(to_d(csv.cell(r, "broken_weft_yarns")));
      w.end_reason = csv.cell(r, "end_reason");
      if (w.end_reason != "perforated" && w.end_reason != "rebounded" && w.end_reason != "caught")
        result.warnings.push_back("velocity sweep case " + w.case_name + " ended by " + w.end_reason +
                                  ": its energy absorbed is not final");
      ps.rows.push_back(w);
    }
  }
  ps.velocity_wall_s = vrep.wall_time_s;
}

void run_compression_stage(PaperState& ps) {
  const PaperOptions& opt = ps.opt;
  const PaperPlan& plan = ps.plan;
  PaperResult& result = ps.result;
  // The crossings' compression law (docs/MODEL.md §4) at 260 m/s, mu = 0 and 0.2: each F_half
  // and each c_min of the plan, the other at the scene's value.
  std::vector<Case> cc;
  auto add = [&](const char* key, double value, double mu) {
    Case c;
    c.index = int(cc.size());
    c.settings = {{key, num(value)}, {"yarn.friction", num(mu)}, {"projectile.velocity_mps", "260"}};
    cc.push_back(c);
  };
  for (double f : plan.compression_forces_n)
    for (double mu : {0.0, kReferenceFriction}) add("fabric.compression_force_n", f, mu);
  for (double g : plan.flattened_gaps_mm)
    for (double mu : {0.0, kReferenceFriction}) add("fabric.flattened_gap_mm", g, mu);
  if (!cc.empty() && ps.base_scene.fabric.crossing_compression == CrossingCompression::hyperbolic) {
    SweepOptions co = ps.velocity_sweep;
    co.out_dir = opt.out_dir + "/compression";
    SweepHooks ch;
    ch.on_progress = [&](const SweepProgress& p) { ps.progress("compression what-if", p.done, p.total, p.skipped); };
    const std::vector<std::string> keys{"fabric.compression_force_n", "fabric.flattened_gap_mm", "yarn.friction",
                                        "projectile.velocity_mps"};
    const SweepReport crep = run_sweep(cc, cc, co, keys, ch, ps.interrupt);
    if (crep.interrupted) throw std::runtime_error("interrupted during the compression what-if (rerun to resume)");
    for (const auto& e : crep.errors) result.warnings.push_back("compression what-if: " + e);
    ps.compression_runs = crep.cases_run;
    ps.compression_resumed = crep.cases_skipped;
    ps.compression_wall_s = crep.wall_time_s;
    const Csv csv = parse_csv(read_text_file(co.out_dir + "/results.csv"));
    for (const auto& r : csv.rows) {
      CompressionRow w;
      const std::string f = csv.cell(r, "fabric.compression_force_n"), g = csv.cell(r, "fabric.flattened_gap_mm");
      w.key = !f.empty() ? "fabric.compression_force_n" : "fabric.flattened_gap_mm";
      w.value = to_d(!f.empty() ? f : g);
      w.mu = to_d(csv.cell(r, "yarn.friction"));
      w.energy_J = to_d(csv.cell(r, "energy_absorbed_J"));
      w.wall_s = to_d(csv.cell(r, "wall_time_s"));
      ps.compression_rows.push_back(w);
    }
  }
}

void run_limit_stage(PaperState& ps) {
  const PaperOptions& opt = ps.opt;
  const PaperPlan& plan = ps.plan;
  PaperResult& result = ps.result;
  const std::atomic<bool>* interrupt = ps.interrupt;
  const auto tl = std::chrono::steady_clock::now();
  std::vector<LimitEntry>& limits = ps.limits;
  for (double mu : plan.limit_frictions) {
    LimitEntry e;
    e.label = "mu=" + num(mu);
    e.mu = mu;
    e.overrides = {"yarn.friction=" + num(mu)};
    for (double m : plan.image_limit_frictions) e.keep_frame = e.keep_frame || same(m, mu);
    limits.push_back(e);
  }
  {
    LimitEntry e;
    e.label = "pin-jointed";
    e.overrides = {"solver.model=pin_jointed"};
    limits.push_back(e);
  }
  LimitOptions lo;
  lo.start_mps = 75;
  lo.growth = 1.25;
  lo.growth_accel = 1.5;
  lo.tolerance_mps = plan.limit_tolerance_mps;
  lo.min_mps = 5;
  lo.max_mps = 1000;
  // Where each search starts. Near the limit a run lasts 0.5-5 ms of simulated time (a
  // minute or more of wall time each), so a search that starts near its limit saves most of
  // its cost. Each search starts at the limit found by its parent in a fixed tree, so the
  // numbers do not depend on --jobs or on which search finished first:
  //   - the reference friction (0.2) and the lowest friction above it (0.4) are roots,
  //     started at the Lambert-Jonas limit fitted to their own velocity runs (180-500 m/s;
  //     within ~10 % for mu >= 0.1: 86 against a bisected 78 m/s at mu = 0.2);
  //   - below the reference, in descending order b0, b1, ...: two chains from the
  //     reference, b0 <- ref, b1 <- b0 and b2 <- ref, b3 <- b2, b4 <- b3, ... (0.1 <- 0.2,
  //     0.06 <- 0.1; 0.02 <- 0.2, 0 <- 0.02), so that both workers search below the
  //     reference at once. Searches here are the longest (runs near the limit creep on for
  //     milliseconds), and the chain 0.2 -> 0.1 -> 0.02 -> 0 of an earlier tree was the
  //     critical path of the whole study (61 of its 76 minutes with --jobs 2). Starting
  //     0.02 from 0.2's limit rather than 0.1's costs about one more run, above the limit,
  //     where runs are short;
  //   - above it each from the next lower (0.6 <- 0.4, ...), the pin-jointed model from the
  //     highest friction.
  // A seeded search takes steps of 15 % that grow (growth_accel) until the outcome flips. A
  // root with no fit, or a search whose parent found no limit, starts at its own fit, else at
  // 75 m/s. The fits are a factor 3 low for mu <= 0.02 (yarns slip aside with little energy
  // at 180-500 m/s and the fit extrapolates from 4x the limit), so those are never roots.
  // Workers take the first ready search in the order: the reference, the frictions below it
  // (their runs near the limit are the longest), then those above, then the pin-jointed model.
  std::map<double, double> fitted_by_mu;  // mu -> fitted limit, where the fit worked
  for (double mu : plan.frictions) {
    std::vector<double> vs, vrs;
    for (const auto& r : ps.rows)
      if (same(r.mu, mu) && same(r.failure, kDefaultFailure) && r.perforated && r.residual > 0) {
        vs.push_back(r.v);
        vrs.push_back(r.residual);
      }
    if (vs.size() < 4) continue;
    const LambertJonas f = fit_lambert_jonas(vs, vrs);
    if (f.ok && f.vbl_mps > lo.min_mps) fitted_by_mu[mu] = f.vbl_mps;
  }
  std::vector<size_t> below, above, order;  // below: descending; above: ascending
  size_t ref = kNoParent, pin = kNoParent;  // kNoParent: not in the plan
  for (size_t i = 0; i < limits.size(); ++i) {
    if (!std::isfinite(limits[i].mu))
      pin = i;
    else if (same(limits[i].mu, kReferenceFriction))
      ref = i;
    else
      (limits[i].mu < kReferenceFriction ? below : above).push_back(i);
  }
  std::sort(below.begin(), below.end(), [&](size_t a, size_t b) { return limits[a].mu > limits[b].mu; });
  std::sort(above.begin(), above.end(), [&](size_t a, size_t b) { return limits[a].mu < limits[b].mu; });
  std::vector<size_t> parent(limits.size(), kNoParent);  // kNoParent: a root
  for (size_t k = 0; k < below.size(); ++k) parent[below[k]] = k == 0 || k == 2 ? ref : below[k - 1];
  for (size_t k = 1; k < above.size(); ++k) parent[above[k]] = above[k - 1];
  if (pin != kNoParent) parent[pin] = !above.empty() ? above.back() : ref;
  if (ref != kNoParent) order.push_back(ref);
  for (size_t i : below) order.push_back(i);
  for (size_t i : above) order.push_back(i);
  if (pin != kNoParent) order.push_back(pin);
  {
    std::mutex mu;
    int done = 0, kept_searches = 0;
    // The start of a search: its parent's limit, else its own fit, else the default (-1).
    auto seed_for = [&](size_t i) -> double {
      const size_t p = parent[i];
      if (p != kNoParent && limits[p].have && limits[p].result.bracketed) {
        limits[i].start_from = "limit of " + limits[p].label;
        return limits[p].result.ballistic_limit_mps;
      }
      if (std::isfinite(limits[i].mu) && fitted_by_mu.count(limits[i].mu)) {
        limits[i].start_from = "fit";
        return fitted_by_mu.at(limits[i].mu);
      }
      limits[i].start_from = "default";
      return -1;
    };
    auto run_entry = [&](LimitEntry& e, double seed) {
      std::string label = e.label;
      for (char& c : label)
        if (c == '=') c = '_';
      e.dir = opt.out_dir + "/limit/" + label;
      std::vector<std::string> ov = ps.with(plan.limit_overrides);
      ov.push_back("solver.end_time_us=auto");
      // The scene rules of the fast search (decide_passing: perforating runs end once the
      // projectile is passing through, MODEL.md §8): a search uses outcomes only, and the
      // decision changed none in the cases measured, so the bisection takes the same path and
      // finds the same limit with fewer steps.
      add_rule_overrides(lo.rules, ov);
      for (const auto& o : e.overrides) ov.push_back(o);
      try {
        prepare_output_dir(e.dir);
        if (fs::exists(e.dir + "/limit.json")) {
          e.result = limit_from_json(read_text_file(e.dir + "/limit.json"));
          e.kept = true;
        } else {
          // The lowest perforating run's last frame, for the images (runs are on their own
          // threads in the fast search: one at a time here, but guarded all the same).
          auto keep = [&e, &mu](const Simulation& sim) {
            if (!e.keep_frame || !sim.summary().perforated) return;
            const double v = sim.scene().projectile.velocity_mps;
            std::lock_guard<std::mutex> lock(mu);
            if (v < e.frame_v) e.frame_v = v, e.frame = sim.frame();
          };
          LimitOptions mine = lo;
          if (seed > 0) {
            mine.start_mps = std::clamp(seed, mine.min_mps, mine.max_mps);
            mine.growth = 1.15;
          }
          e.start_mps = mine.start_mps;
          if (opt.reference_limits) {
            e.result = find_ballistic_limit(scene_shooter(opt.scene_path, ov, interrupt, keep, e.dir), mine, false);
          } else {
            // One run in flight per search (the study runs --jobs searches at once); the
            // search's runs kept in e.dir/runs/ by an interrupted call count as made.
            mine.jobs = 1;
            e.result = find_ballistic_limit_fast(scene_runner(opt.scene_path, ov, keep, e.dir), mine, false, interrupt,
                                                 {}, kept_runs(opt.scene_path, ov, e.dir));
            if (e.result.interrupted) throw std::runtime_error("interrupted");  // no limit.json: a rerun resumes
          }
          std::lock_guard<std::mutex> lock(mu);
          ps.limit_runs += int(e.result.runs.size());
          write_file_atomic(e.dir + "/limit.json", limit_json(e.result, mine, opt.scene_path, ov));
        }
        e.have = true;
      } catch (const std::exception& ex) {
        e.error = ex.what();
      }
    };
    // One queue item per search, taken in `order` once its parent has finished: the parent's
    // limit (written by its item before the queue marks it finished) is read here unlocked.
    auto search = [&](size_t i) {
      double seed;
      {
        std::lock_guard<std::mutex> lock(mu);
        seed = seed_for(i);
      }
      run_entry(limits[i], seed);
      std::lock_guard<std::mutex> lock(mu);
      kept_searches += limits[i].kept;
      ps.progress("ballistic limits", ++done, int(limits.size()), kept_searches);
    };
    run_queue(limits.size(), opt.jobs, interrupt, search, order, parent);
  }
  if (interrupt && interrupt->load())
    throw std::runtime_error("interrupted during the ballistic-limit searches (rerun to resume)");
  for (const auto& e : limits) {
    if (!e.error.empty()) result.warnings.push_back("ballistic limit " + e.label + ": " + e.error);
    for (const auto& w : e.result.warnings) result.warnings.push_back("ballistic limit " + e.label + ": " + w);
  }
  ps.limit_wall_s = seconds_since(tl);
}

void write_images(PaperState& ps) {
  const PaperOptions& opt = ps.opt;
  const PaperPlan& plan = ps.plan;
  PaperResult& result = ps.result;
  const std::atomic<bool>* interrupt = ps.interrupt;
  const auto ti = std::chrono::steady_clock::now();
  auto image = [&](const std::string& rel, const std::string& caption, const Frame* frame,
                   const std::vector<std::string>& rerun_overrides) {
    const std::string path = opt.out_dir + "/" + rel;
    if (!fs::exists(path)) {
      if (!opt.render_png) {
        result.warnings.push_back("no renderer in this build: " + rel + " not drawn");
        return;
      }
      Frame f;
      if (frame) {
        f = *frame;
      } else {  // resumed study: run the case again for its final frame
        auto ov = ps.base;
        for (const auto& o : rerun_overrides) ov.push_back(o);
        Simulation sim(load_scene(opt.scene_path, ov));
        sim.run(interrupt);
        f = sim.frame();
        ++ps.image_runs;
      }
      std::string err;
      if (!opt.render_png(f, path, &err)) {
        result.warnings.push_back(rel + ": " + err);
        return;
      }
    }
    ps.images.emplace_back(caption, rel);
  };
  for (double v : plan.image_velocities_mps) {
    auto it = ps.image_frames.find(v);
    image("images/perforation_" + num(v) + "mps_mu0.2.png", "mu = 0.2 at " + num(v) + " m/s, end of run (Fig. 8 / 12)",
          it == ps.image_frames.end() ? nullptr : &it->second, [&] {
            auto ov = plan.velocity_overrides;
            for (const auto& o : {"yarn.friction=0.2", "yarn.failure_strain=0.052"}) ov.push_back(o);
            ov.push_back("projectile.velocity_mps=" + num(v));
            ov.push_back("solver.end_time_us=auto");
            return ov;
          }());
  }
  for (const auto& e : ps.limits) {
    if (!e.keep_frame || !e.have || !e.result.bracketed) continue;
    image(
        "images/perforation_BL_" + e.label + ".png",
        e.label + " at " + num(e.result.hi_mps, "%.1f") + " m/s, the lowest perforating run of the BL search (Fig. 17)",
        // (a run's scene has its velocity to 6 decimals, scene_runner's "%.6f": the frame of
        // the run at hi_mps carries it rounded, so `same` never matched it and every image
        // was a second run of that velocity to its end, 164 s of a 21 min study)
        std::isfinite(e.frame_v) && std::abs(e.frame_v - e.result.hi_mps) <= 1e-6 ? &e.frame : nullptr, [&] {
          auto ov = plan.limit_overrides;
          ov.push_back(e.overrides[0]);
          ov.push_back("projectile.velocity_mps=" + num(e.result.hi_mps, "%.6f"));
          ov.push_back("solver.end_time_us=auto");
          return ov;
        }());
  }
  ps.image_wall_s = seconds_since(ti);
}

}  // namespace ravel::studies::paper_detail
