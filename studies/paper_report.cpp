// The charts and DIR/report.md of run_paper (paper_internal.h).
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "paper_internal.h"
#include "results.h"

namespace ravel::studies::paper_detail {

namespace {
// A search's outcomes: a threshold in velocity, or the band where they alternate.
std::string outcomes_cell(const LimitResult& r) {
  const OutcomeBand b = outcome_band(r);
  if (b.threshold) return "threshold";
  return "alternate " + num(b.lowest_perforation, "%.1f") + " - " + num(b.highest_stop, "%.1f");
}
// The V50 of its decided runs (limit.json's v50_mps), with the pairs averaged.
std::string v50_cell(const LimitResult& r) {
  const OutcomeBand b = outcome_band(r);
  if (b.v50 < 0) return "-";
  return num(b.v50, "%.1f") + " (" + std::to_string(b.v50_pairs) + "+" + std::to_string(b.v50_pairs) + ")";
}
}  // namespace

void make_charts(PaperState& ps) {
  const PaperOptions& opt = ps.opt;
  const PaperPlan& plan = ps.plan;
  PaperResult& result = ps.result;
  const std::string sub = std::string(plan.quick ? "quick: " : "full: ") + plan.description;
  auto put = [&](const Chart& c, const std::string& stem, const std::string& caption) {
    if (finite_point_count(c) == 0) {
      result.warnings.push_back("chart " + stem + " has no data and was not drawn");
      return;
    }
    write_chart(c, opt.out_dir + "/charts/" + stem);
    ps.charts.emplace_back(caption, "charts/" + stem);
  };
  // The paper's stated values, drawn on its figures: dashed grey reference lines.
  auto paper_line = [](const std::string& name, std::vector<double> x, std::vector<double> y) {
    Series s;
    s.name = name;
    s.x = std::move(x);
    s.y = std::move(y);
    s.style = SeriesStyle::line;
    s.dashed = true;
    s.color = 7;
    return s;
  };
  double energy_max = 0;
  for (const auto& r : ps.rows)
    if (std::isfinite(r.energy_J)) energy_max = std::max(energy_max, r.energy_J);
  {
    Chart c;
    c.title = "Energy absorbed vs impact velocity, mu = 0.2 (Fig. 11)";
    c.subtitle = sub;
    c.x = {"impact velocity", "m/s"};
    c.y = {"energy absorbed", "J"};
    c.y.include_zero = true;
    for (double f : plan.failure_strains)
      c.series.push_back(ps.energy_series(kReferenceFriction, f, "failure strain " + num(f * 100) + " %"));
    put(c, "fig11_energy_vs_velocity_failure_strain",
        "Energy absorbed vs impact velocity for two failure strains (Fig. 11)");
  }
  {
    Chart c;
    c.title = "Energy absorbed vs impact velocity (Fig. 13)";
    c.subtitle = sub;
    c.x = {"impact velocity", "m/s"};
    c.y = {"energy absorbed", "J"};
    c.y.include_zero = true;
    for (double mu : plan.frictions) c.series.push_back(ps.energy_series(mu, kDefaultFailure, "mu = " + num(mu)));
    c.series.push_back(paper_line("paper: sudden fall near 250 m/s", {250, 250}, {0, energy_max}));
    put(c, "fig13_energy_vs_velocity_friction",
        "Energy absorbed vs impact velocity for each yarn-yarn friction (Fig. 13)");
  }
  // Histories at the history velocity (make_claims reads them too).
  for (double mu : plan.frictions)
    if (const VelocityRow* r = ps.find_row(mu, kDefaultFailure, plan.history_velocity_mps))
      ps.histories[mu] = parse_csv(read_text_file(ps.velocity_sweep.out_dir + "/" + r->case_name + "/history.csv"));
  auto history_series = [&](const Csv& h, const std::string& column, const std::string& name, double scale = 1) {
    Series s;
    s.name = name;
    s.style = SeriesStyle::line;
    const int tc = h.column("t_s"), yc = h.column(column);
    if (tc < 0 || yc < 0) return s;
    for (const auto& r : h.rows) {
      s.x.push_back(to_d(r[size_t(tc)]) * 1e6);
      s.y.push_back(to_d(r[size_t(yc)]) * scale);
    }
    return s;
  };
  {
    Chart c;
    c.title = "Projectile velocity at " + num(plan.history_velocity_mps) + " m/s impact (Fig. 14)";
    c.subtitle = sub;
    c.x = {"time", "us"};
    c.y = {"projectile velocity", "m/s"};
    double vmin = plan.history_velocity_mps;
    for (const auto& [mu, h] : ps.histories) {
      c.series.push_back(history_series(h, "projectile_velocity_mps", "mu = " + num(mu)));
      for (double v : c.series.back().y) vmin = std::min(vmin, v);
    }
    c.series.push_back(paper_line("paper: mu = 1.0 perforates at 73 us", {73, 73}, {vmin, plan.history_velocity_mps}));
    put(c, "fig14_velocity_history",
        "Projectile velocity histories at " + num(plan.history_velocity_mps) + " m/s (Fig. 14)");
  }
  if (ps.histories.count(kReferenceFriction)) {
    const Csv& h = ps.histories[kReferenceFriction];
    Chart c;
    c.title = "Energy histories, mu = 0.2 at " + num(plan.history_velocity_mps) + " m/s (Fig. 15)";
    c.subtitle = sub;
    c.x = {"time", "us"};
    c.y = {"energy", "J"};
    c.y.include_zero = true;
    c.series.push_back(history_series(h, "projectile_ke_J", "projectile kinetic"));
    c.series.push_back(history_series(h, "fabric_ke_J", "fabric kinetic"));
    c.series.push_back(history_series(h, "strain_energy_J", "strain energy"));
    c.series.push_back(history_series(h, "viscous_J", "viscous dissipation"));
    c.series.push_back(history_series(h, "friction_work_J", "yarn friction work"));
    c.series.push_back(history_series(h, "projectile_friction_J", "projectile friction work"));
    c.series.push_back(history_series(h, "released_J", "released by failure"));
    c.series.push_back(history_series(h, "compression_J", "crossing compression (stored)"));
    {
      const Series t = history_series(h, "t_s", "");
      if (!t.x.empty())
        c.series.push_back(paper_line("paper: friction losses about 1 J", {t.x.front(), t.x.back()}, {1, 1}));
    }
    put(c, "fig15_energy_history_mu0.2", "Energy ledger histories for mu = 0.2 (Fig. 15)");
    Chart d;
    d.title = "Kinetic + strain energy of the fabric at " + num(plan.history_velocity_mps) + " m/s (Fig. 15)";
    d.subtitle = sub;
    d.x = {"time", "us"};
    d.y = {"fabric kinetic + strain energy", "J"};
    d.y.include_zero = true;
    for (const auto& [mu, hh] : ps.histories) {
      Series ke = history_series(hh, "fabric_ke_J", "mu = " + num(mu));
      const Series se = history_series(hh, "strain_energy_J", "");
      for (size_t i = 0; i < ke.y.size() && i < se.y.size(); ++i) ke.y[i] += se.y[i];
      d.series.push_back(ke);
    }
    put(d, "fig15_fabric_energy_by_friction", "Fabric kinetic + strain energy histories for each friction (Fig. 15)");
  }
  {
    Chart c;
    c.title = "Ballistic limit vs yarn-yarn friction (Fig. 16)";
    c.subtitle = sub + ", tolerance " + num(plan.limit_tolerance_mps) + " m/s";
    c.x = {"yarn-yarn friction mu", ""};
    c.y = {"ballistic limit", "m/s"};
    c.y.include_zero = true;
    Series s{"sliding model (bracket midpoint; bars: the bracket)", {}, {}};
    Series pin{"pin-jointed model", {}, {}, SeriesStyle::line, -1, true};
    for (const auto& e : ps.limits) {
      if (!e.have || !e.result.bracketed) continue;
      if (std::isnan(e.mu)) {
        pin.x = {plan.limit_frictions.front(), plan.limit_frictions.back()};
        pin.y = {e.result.ballistic_limit_mps, e.result.ballistic_limit_mps};
      } else {
        s.x.push_back(e.mu);
        s.y.push_back(e.result.ballistic_limit_mps);
        s.y_lo.push_back(e.result.lo_mps);
        s.y_hi.push_back(e.result.hi_mps);
      }
    }
    // The paper's text: 71 m/s at mu = 0.1, 70 at 0.2, and about half of BL(0.1) at mu = 0.
    Series paper{"paper (stated in the text)",
                 {0.0, 0.1, 0.2},
                 {paper_limit(0.1) / 2, paper_limit(0.1), paper_limit(0.2)},
                 SeriesStyle::markers,
                 7,
                 false};
    c.series = {s, pin, paper};
    put(c, "fig16_ballistic_limit_vs_friction", "Ballistic limit vs friction, with the pin-jointed model (Fig. 16)");
  }

  for (const char* key : {"fabric.compression_force_n", "fabric.flattened_gap_mm"}) {
    const bool force = std::string(key) == "fabric.compression_force_n";
    Chart c;
    c.title = std::string("Energy absorbed at 260 m/s vs ") + (force ? "F_half" : "c_min") +
              " of the crossings' compression (what-if)";
    c.subtitle = sub + "; the other parameter at the scene's value";
    c.x = force ? Axis{"F_half, force closing half the compressible distance", "N"}
                : Axis{"c_min, centre distance of flattened crossings", "mm"};
    c.x.log = force;
    c.y = {"energy absorbed", "J"};
    c.y.include_zero = true;
    for (double mu : {0.0, kReferenceFriction}) {
      Series sr;
      sr.name = "mu = " + num(mu);
      for (const auto& r : ps.compression_rows)
        if (r.key == key && same(r.mu, mu)) sr.x.push_back(r.value), sr.y.push_back(r.energy_J);
      c.series.push_back(sr);
    }
    put(c, force ? "compression_force_whatif" : "compression_gap_whatif",
        std::string("What-if: energy absorbed at 260 m/s against the crossings' ") +
            (force ? "half-closing force F_half" : "flattened distance c_min"));
  }
}

void write_report(PaperState& ps) {
  const PaperOptions& opt = ps.opt;
  const PaperPlan& plan = ps.plan;
  PaperResult& result = ps.result;
  const SweepReport& vrep = ps.velocity_report;
  result.runs = vrep.cases_run + ps.limit_runs + ps.image_runs + ps.compression_runs;
  result.wall_time_s = seconds_since(ps.t0);
  result.runs_per_hour = result.wall_time_s > 0 ? result.runs / (result.wall_time_s / 3600) : 0;
  std::ostringstream md;
  md << "# ravel: the paper's studies reproduced\n\n"
     << "Zeng, Tan & Shim, *Modelling inter-yarn friction in woven fabric armour* (SPEC §9), rerun with ravel's "
        "default "
        "scene (`"
     << ps.base_scene.name << "`, " << (ps.base_scene.source.empty() ? "built-in" : ps.base_scene.source) << ").\n\n"
     << "- Mode: **" << (plan.quick ? "quick" : "full") << "**: " << plan.description << ".\n";
  if (plan.quick)
    md << "- What quick changes: 8 impact velocities instead of 17; the ballistic-limit searches run on a coarsened "
          "mesh (`fabric.yarns_per_element=2`: every modelled yarn lumps two real yarns, with the crossing geometry "
          "scaled so the crimp angle is kept; about 4x fewer nodes and a 2x larger stable step), to a 4 m/s "
          "tolerance, for 6 friction values instead of 9; the compression what-if at 3 forces and 2 distances. The "
          "velocity studies (Fig. 8, 11-15) use the full mesh. The coarsened BL numbers (Fig. 16, 17) are a "
          "preview; run without `--quick` for the model's answer.\n";
  if (!opt.overrides.empty()) {
    md << "- User overrides:";
    for (const auto& o : opt.overrides) md << " `" << o << "`";
    md << "\n";
  }
  md << "- Every run ends at perforation or rebound (`solver.end_time_us = auto`, at most "
     << num(ps.base_scene.solver.max_end_time_s * 1e6) << " us); a run still undecided there is left out of its "
     << "bracket or marked, never counted as stopped.\n";
  md << "- Wall time " << num(result.wall_time_s, "%.0f") << " s for " << result.runs << " runs made now ("
     << num(result.runs_per_hour, "%.0f") << " runs per hour, " << opt.jobs << " jobs); velocity sweep "
     << num(ps.velocity_wall_s, "%.0f") << " s (" << vrep.cases_run << " run, " << vrep.cases_skipped << " resumed, "
     << num(vrep.cases_per_hour, "%.0f") << " cases/h); compression what-if " << num(ps.compression_wall_s, "%.0f")
     << " s (" << ps.compression_runs << " run, " << ps.compression_resumed << " resumed); ballistic limits "
     << num(ps.limit_wall_s, "%.0f") << " s (" << ps.limit_runs << " runs); images " << num(ps.image_wall_s, "%.0f")
     << " s (" << ps.image_runs << " runs).\n";
  {  // what every run cost, including runs made by earlier (resumed) invocations
    double run_s = 0;
    int n = 0;
    for (const auto& r : ps.rows)
      if (std::isfinite(r.wall_s)) run_s += r.wall_s, ++n;
    for (const auto& r : ps.compression_rows)
      if (std::isfinite(r.wall_s)) run_s += r.wall_s, ++n;
    for (const auto& e : ps.limits)
      for (const auto& s : e.result.runs) run_s += s.wall_time_s, ++n;
    // (the image stage re-runs a resumed case only for its final frame: counted in the line above)
    md << "- All " << n << " runs behind this report (including resumed ones) took " << num(run_s, "%.0f")
       << " s of single-run wall time, " << num(n > 0 ? run_s / n : 0, "%.1f") << " s per run on average.\n";
  }
  md << "\n";

  md << "## The paper's statements beside ravel's numbers\n\n"
     << "Verdicts use stated thresholds (below the table) and are computed, not chosen: " << result.claims_agree
     << " agree, " << result.claims_partly << " partly, " << result.claims_differ << " differ, "
     << result.claims_unknown << " not measured.\n\n"
     << "| Fig. | the paper | ravel (this run) | verdict |\n|---|---|---|---|\n";
  for (const auto& c : ps.claims)
    md << "| " << c.figure << " | " << c.paper << " | " << (c.ravel.empty() ? "(no data)" : c.ravel) << " | **"
       << c.verdict << "** |\n";
  md << "\nThresholds: peak = the first velocity whose energy (mu = 0.2, failure strain 5.2 %) is a local maximum and "
        "falls by at least 15 % within the next 60 m/s; *agrees* if it lies between 220 and 280 m/s and no higher "
        "velocity reaches its energy again (*partly*: one does, or the peak is elsewhere); mu = 0.2 highest at every "
        "velocity (*partly*: at least half); steep rise = mean slope "
        "below mu = 0.06 more than 3x the mean fall above 0.2; perforation time within 15 us of 73 us and earlier than "
        "mu = 0.2; gentle = less than half the velocity lost at mu = 0.2; friction work within a factor 3 of 1 J; BL "
        "within 10 % of the paper; half = ratio 0.4-0.6; flat = within 10 %, lower = below by more than the tolerance; "
        "slit = broken warp yarns at most a third of broken weft yarns; square = warp/weft ratio 0.7-1.4.\n\n"
     << "Where a verdict is *partly* or *differs*, docs/MODEL.md §9 says why, with the runs that isolate the "
        "mechanism.\n\n";

  md << "## Charts\n\nEach chart is a PNG (shown), an SVG and the CSV of exactly the plotted numbers.\n\n";
  for (const auto& [caption, stem] : ps.charts)
    md << "### " << caption << "\n\n![" << caption << "](" << stem << ".png)\n\n[SVG](" << stem << ".svg) · [CSV]("
       << stem << ".csv)\n\n";

  md << "## Ballistic limits\n\n| model | BL (m/s) | bracket (m/s) | runs | search wall time (s) | started at (m/s) "
        "| search | outcomes | V50 (m/s) |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& e : ps.limits) {
    std::string lab = e.label;
    for (char& ch : lab)
      if (ch == '=') ch = '_';
    md << "| [" << e.label << "](limit/" << lab << "/limit.json) | ";
    if (e.have && e.result.bracketed)
      md << num(e.result.ballistic_limit_mps, "%.1f") << " | " << num(e.result.lo_mps, "%.1f") << " - "
         << num(e.result.hi_mps, "%.1f") << (e.result.converged ? "" : " (not converged: see warnings)") << " | "
         << e.result.runs.size() << " | " << num(e.result.wall_time_s, "%.0f") << " | "
         << (std::isfinite(e.start_mps) ? num(e.start_mps, "%.1f") + " (" + e.start_from + ")"
                                        : std::string("(resumed)"))
         << " | " << e.result.method << " | " << outcomes_cell(e.result) << " | " << v50_cell(e.result) << " |\n";
    else
      md << "not found: "
         << (!e.error.empty()             ? e.error
             : !e.result.warnings.empty() ? e.result.warnings.front()
                                          : "")
         << " | | " << e.result.runs.size() << " | " << num(e.result.wall_time_s, "%.0f") << " | | " << e.result.method
         << " | | |\n";
  }
  md << "\nBL = midpoint of the final bracket (highest velocity that did not perforate, lowest that did). V50 = the "
        "V50 of ballistic testing (MIL-STD-662F): the mean of the k highest stops and k lowest perforations of the "
        "search's runs, (k+k), up to 3 of each; no run is placed for it. The searches "
        "start from a fixed tree, so the numbers do not depend on --jobs: mu = 0.2 and 0.4 at the Lambert-Jonas limit "
        "fitted to their velocity-study runs; below 0.2, two chains from 0.2's limit (0.1, then 0.06 from 0.1; 0.02, "
        "then 0 from 0.02); above, each from the next lower friction, the pin-jointed model from the highest (with no "
        "parent limit, at its own fit, "
        "else 75 m/s). Each search steps by 15 % from its start (25 % from 75 m/s) until the outcome flips, then "
        "narrows the bracket. The fast search (`ravel limit`, one run in flight per search) places its points from "
        "the residual velocities and, once the bracket is narrow, makes sure its stopped runs sample the 20 % below it "
        "in steps of at most 5 % (probes fill the gaps): the limit is "
        "the lowest velocity that perforates (SPEC section 8), and where outcomes alternate near it a bracket of two "
        "runs cannot see a perforation below. The reference search (`--reference-limits`) bisects, its steps growing "
        "(23, 37, 60 %). *outcomes*: threshold when every stopped run of the search lies below every perforating "
        "one, else the band where they alternate (lowest perforation - highest stop).\n\n";

  md << "## Perforation images\n\n";
  if (ps.images.empty()) md << "No images (this build has no offscreen renderer).\n\n";
  for (const auto& [caption, rel] : ps.images) md << "### " << caption << "\n\n![" << caption << "](" << rel << ")\n\n";

  md << "## Data\n\n- `velocity/results.csv`: one row per velocity run (every summary.json key); each run's folder "
        "holds history.csv, summary.json, scene.toml.\n- `limit/*/limit.json`: every run of each ballistic-limit "
        "search.\n- `claims.json`: the statements' verdicts and the ballistic limits above, for scripts "
        "(scripts/nightly).\n\n";
  if (!result.warnings.empty()) {
    md << "## Warnings\n\n";
    for (const auto& w : result.warnings) md << "- " << w << "\n";
    md << "\n";
  }
  // claims.json first: a report.md in the folder means its claims.json is there too.
  write_file_atomic(opt.out_dir + "/claims.json", claims_json(ps));
  result.report_path = opt.out_dir + "/report.md";
  write_file_atomic(result.report_path, md.str());
}

// DIR/claims.json: the report's verdicts and ballistic limits for scripts (scripts/nightly):
// each claim as in the table, and each search's limit with its bracket and its health.
std::string claims_json(const PaperState& ps) {
  using nlohmann::json;
  const PaperResult& r = ps.result;
  json j;
  j["mode"] = ps.plan.quick ? "quick" : "full";
  j["counts"] = {{"agrees", r.claims_agree},
                 {"partly", r.claims_partly},
                 {"differs", r.claims_differ},
                 {"not_measured", r.claims_unknown}};
  j["claims"] = json::array();
  for (const auto& c : ps.claims)
    j["claims"].push_back({{"figure", c.figure}, {"paper", c.paper}, {"ravel", c.ravel}, {"verdict", c.verdict}});
  j["limits"] = json::array();
  for (const auto& e : ps.limits) {
    json l = {{"label", e.label}, {"found", e.have && e.result.bracketed}};
    l["mu"] = std::isfinite(e.mu) ? json(e.mu) : json(nullptr);  // null: pin-jointed
    // The paper's stated limit, where it states one (kPaperLimits), and the agreement bound.
    if (std::isfinite(e.mu) && std::isfinite(paper_limit(e.mu))) {
      l["paper_mps"] = paper_limit(e.mu);
      l["paper_tolerance"] = kPaperLimitTolerance;
    }
    int undecided = 0;
    for (const auto& s : e.result.runs) undecided += !s.decided;
    l["runs"] = e.result.runs.size();
    l["undecided_runs"] = undecided;
    if (e.have && e.result.bracketed) {
      l["ballistic_limit_mps"] = e.result.ballistic_limit_mps;
      l["lo_mps"] = e.result.lo_mps;
      l["hi_mps"] = e.result.hi_mps;
      l["converged"] = e.result.converged;
      const OutcomeBand b = outcome_band(e.result);
      l["threshold"] = b.threshold;  // false: outcomes alternate from the lowest perforation to the highest stop
      if (!b.threshold) l["band_mps"] = {b.lowest_perforation, b.highest_stop};
      // The V50 of ballistic testing (limit.json's v50_mps: MIL-STD-662F, up to 3 + 3 runs).
      l["v50_mps"] = b.v50 >= 0 ? json(b.v50) : json(nullptr);
    }
    l["method"] = e.result.method;
    if (!e.error.empty()) l["error"] = e.error;
    j["limits"].push_back(l);
  }
  j["warnings"] = r.warnings;
  return j.dump(2) + "\n";
}

}  // namespace ravel::studies::paper_detail
