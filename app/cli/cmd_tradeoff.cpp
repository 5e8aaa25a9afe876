// Speed against accuracy and where the methods fail (docs/tradeoff.md):
//   ravel tradeoff  [SCENE] [--set k=v ...] --out DIR [--quick] [--knob KEY=v1,v2 ...] [--only KEY,KEY]
//                   [--reference KEY=VALUE ...] [--around scene|reference] [--cost wall|cpu] [--limit]
//                   [--searches all|none|RULE,...] [--jobs N] [--threads N] [--note TEXT] [--date YYYY-MM-DD]
//   ravel stability [SCENE] [--set k=v ...] --out DIR [--quick] [--map NAME ...] [--jobs N] [--threads N]
// The logic lives in studies/tradeoff.* and studies/stability.*; this file parses flags and prints.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "chart.h"
#include "cli.h"
#include "commands.h"
#include "results.h"
#include "stability.h"
#include "sweep.h"
#include "tradeoff.h"

namespace ravel::app {

// app/cli/cmd_run.cpp
std::atomic<bool>& interrupt_flag();
void install_signal_handlers();

namespace {

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string p;
  while (std::getline(ss, p, sep))
    if (!p.empty()) out.push_back(p);
  return out;
}

void progress_line(bool verbose, const std::string& s) {
  if (!verbose) return;
  std::printf("  %s\n", s.c_str());
  std::fflush(stdout);
}

}  // namespace

int cmd_tradeoff(const Args& args) {
  try {
    CommonArgs a = parse_args(args, "tradeoff");
    if (a.out_dir.empty()) throw UsageError("tradeoff needs --out DIR");
    studies::TradeoffOptions opt;
    opt.scene_path = scene_path_from(a);
    opt.overrides = a.overrides;
    load_scene(opt.scene_path, opt.overrides);  // bad scene / --set: fail now
    opt.out_dir = a.out_dir;
    opt.jobs = jobs_from(a);
    opt.solver_threads = a.threads >= 0 ? a.threads : 1;
    opt.knobs = studies::default_tradeoff_knobs(has_switch(a, "quick"));
    for (const auto& k : a.multi["knob"]) {
      // --knob KEY=v1,v2: replaces that knob's list (checked like --vary).
      const auto v = studies::parse_vary(k, opt.scene_path, opt.overrides);
      if (!studies::is_tradeoff_knob(v.key))
        throw UsageError("--knob " + v.key +
                         ": not a speed/accuracy knob (solver.dt_factor, solver.contact_iterations, "
                         "solver.precision, solver.model, solver.symmetry, fabric.yarns_per_element, "
                         "fabric.far_yarns_per_element)");
      for (auto& kn : opt.knobs)
        if (kn.key == v.key) kn.values = v.values;
    }
    if (a.flags.count("searches")) {
      // --searches RULES: the reference and the fast ballistic-limit searches, and the fast
      // search without each rule named ("all": every rule, "none": no rule left out).
      opt.searches = true;
      const std::string list = a.flags["searches"];
      if (list == "all") {
        for (const auto& info : studies::fast_rule_table()) opt.search_rules.push_back(info.name);
      } else if (list != "none") {
        for (const auto& rule : split(list, ',')) {
          studies::FastRules scratch;
          if (!studies::leave_out_rule(scratch, rule))
            throw UsageError("--searches: unknown rule '" + rule +
                             "' (all, none, or some of: " + studies::fast_rule_names() + ")");
          if (std::find(opt.search_rules.begin(), opt.search_rules.end(), rule) == opt.search_rules.end())
            opt.search_rules.push_back(rule);
        }
      }
    }
    if (a.flags.count("only")) {
      std::vector<studies::TradeoffKnob> keep;
      for (const auto& key : split(a.flags["only"], ',')) {
        if (key == "searches") {  // no knob rows: the searches alone (and the reference run)
          if (!opt.searches) throw UsageError("--only searches: needs --searches");
          continue;
        }
        bool found = false;
        for (const auto& kn : opt.knobs)
          if (kn.key == key || kn.key.substr(kn.key.find('.') + 1) == key) keep.push_back(kn), found = true;
        if (!found) throw UsageError("--only " + key + ": not a speed/accuracy knob");
      }
      opt.knobs = keep;
      opt.searches_only = keep.empty();
    }
    for (const auto& r : a.multi["reference"]) {
      // --reference KEY=VALUE: the reference's value of a knob, instead of the finest.
      const auto v = studies::parse_vary(r, opt.scene_path, opt.overrides);
      if (v.values.size() != 1) throw UsageError("--reference " + v.key + ": expected one value");
      opt.reference_overrides.emplace_back(v.key, v.values[0]);
    }
    const std::string around = a.flags.count("around") ? a.flags["around"] : "scene";
    if (around != "scene" && around != "reference") throw UsageError("--around: expected scene or reference");
    opt.around_reference = around == "reference";
    opt.cost = a.flags.count("cost") ? a.flags["cost"] : "wall";
    if (opt.cost != "wall" && opt.cost != "cpu") throw UsageError("--cost: expected wall or cpu");
    opt.limit = has_switch(a, "limit");
    if (a.flags.count("tolerance")) opt.limit_options.tolerance_mps = std::atof(a.flags["tolerance"].c_str());
    if (!(opt.limit_options.tolerance_mps > 0)) throw UsageError("--tolerance: expected a positive number");
    opt.note = a.flags.count("note") ? a.flags["note"] : "";
    opt.date = a.flags.count("date") ? a.flags["date"] : "";
    const bool verbose = !has_switch(a, "quiet");
    opt.on_progress = [verbose](const std::string& s) { progress_line(verbose, s); };
    prepare_output_dir(opt.out_dir);
    install_signal_handlers();
    size_t settings = 1;
    for (const auto& k : opt.knobs) settings += k.values.size();
    if (verbose)
      std::printf("tradeoff: %zu knobs, %zu settings (+ reference), %d jobs, cost = %s time, out %s\n",
                  opt.knobs.size(), settings - 1, opt.jobs, opt.cost.c_str(), opt.out_dir.c_str());
    std::fflush(stdout);
    const auto r = studies::run_tradeoff(opt, &interrupt_flag());
    if (r.interrupted) {
      std::fprintf(stderr,
                   "ravel: interrupted; finished runs are kept in %s/cases/ and finished searches in %s/search/ "
                   "(rerun the same command to resume)\n",
                   opt.out_dir.c_str(), opt.out_dir.c_str());
      return exit_interrupted;
    }
    write_file_atomic(opt.out_dir + "/tradeoff.csv", studies::tradeoff_csv(r));
    write_file_atomic(opt.out_dir + "/tradeoff.json", studies::tradeoff_json(r, opt));
    write_file_atomic(opt.out_dir + "/tradeoff.md", studies::tradeoff_markdown(r, opt));
    for (const auto& [stem, chart] : studies::tradeoff_charts(r, opt))
      studies::write_chart(chart, opt.out_dir + "/" + stem);
    if (!r.searches.empty()) {
      write_file_atomic(opt.out_dir + "/searches.csv", studies::searches_csv(r.searches));
      studies::write_chart(studies::searches_chart(r.searches, opt, r.scene_name), opt.out_dir + "/tradeoff_searches");
    }
    // The verdict.
    std::printf("tradeoff: %d runs (%d already finished) in %.0f s\n", r.runs, r.runs_skipped, r.wall_time_s);
    if (!r.rows.empty())
      std::printf("  reference (%s): residual velocity %.2f m/s, energy absorbed %.2f J, cost %.2f s\n",
                  r.rows[0].status.c_str(), r.rows[0].value_q[0], r.rows[0].value_q[1], r.rows[0].cost_s);
    const int nq = std::any_of(r.rows.begin(), r.rows.end(),
                               [](const auto& x) { return !std::isnan(x.value_q[studies::q_ballistic_limit]); })
                       ? 4
                       : 3;
    std::vector<std::string> knobs;
    for (const auto& k : opt.knobs) knobs.push_back(k.key);
    if (!opt.searches_only) {
      std::printf("  cheapest setting within 1 %% / 5 %% of the reference (%s cost):\n", opt.cost.c_str());
      knobs.push_back("");
    }
    for (const auto& k : knobs) {
      std::printf("    %-27s", k.empty() ? "any knob" : k.c_str());
      for (int q = 0; q < nq; ++q) {
        std::string cellv;
        for (double tol : {0.01, 0.05}) {
          const auto e = studies::cheapest_within(r, k, q, tol);
          char b[96];
          if (e.found)
            std::snprintf(b, sizeof b, "%s%s%s", k.empty() ? e.knob.substr(e.knob.find('.') + 1).c_str() : "",
                          k.empty() ? "=" : "", e.value.c_str());
          else
            std::snprintf(b, sizeof b, "none");
          cellv += (cellv.empty() ? "" : " / ") + std::string(b);
        }
        std::printf("  %s: %-18s", studies::quantity_words(q), cellv.c_str());
      }
      std::printf("\n");
    }
    if (!r.searches.empty()) {
      std::printf("  ballistic-limit searches (tolerance %.3g m/s):\n", opt.limit_options.tolerance_mps);
      for (const auto& q : r.searches) {
        if (std::isnan(q.ballistic_limit_mps))
          std::printf("    %-27s %s", q.name.c_str(), q.status.c_str());
        else
          std::printf("    %-27s %.2f m/s", q.name.c_str(), q.ballistic_limit_mps);
        if (!std::isnan(q.diff_mps) && q.name != "reference") std::printf(" (%+.2f from the reference)", q.diff_mps);
        std::printf(", %d runs", q.runs);
        if (!std::isnan(q.wall_time_s)) std::printf(", %.0f s", q.wall_time_s);
        if (!std::isnan(q.rule_saves_s)) std::printf("; the rule saves %+.0f s", q.rule_saves_s);
        std::printf("%s\n", q.kept ? " (kept)" : "");
      }
      std::printf("  %s/searches.csv, %s/tradeoff_searches.{png,svg,csv}, %s/search/\n", opt.out_dir.c_str(),
                  opt.out_dir.c_str(), opt.out_dir.c_str());
    }
    for (const auto& w : r.warnings) std::fprintf(stderr, "ravel: warning: %s\n", w.c_str());
    std::printf("  %s/tradeoff.{csv,json,md}, %s/tradeoff_*.{png,svg,csv}\n", opt.out_dir.c_str(), opt.out_dir.c_str());
    // A failed search (the reference's or another's) fails the command as a failed reference run does.
    const bool search_failed = std::any_of(r.searches.begin(), r.searches.end(),
                                           [](const studies::SearchRow& q) { return q.status == "failed"; });
    return r.rows.empty() || r.rows[0].status == "failed" || r.rows[0].status == "missing" || search_failed
               ? exit_failure
               : exit_ok;
  } catch (const std::exception& e) {
    return report_error(e);
  }
}

int cmd_stability(const Args& args) {
  try {
    CommonArgs a = parse_args(args, "stability");
    if (a.out_dir.empty()) throw UsageError("stability needs --out DIR");
    studies::StabilityOptions opt;
    opt.scene_path = scene_path_from(a);
    opt.overrides = a.overrides;
    const Scene scene = load_scene(opt.scene_path, opt.overrides);
    opt.out_dir = a.out_dir;
    opt.jobs = jobs_from(a);
    opt.solver_threads = a.threads >= 0 ? a.threads : 1;
    opt.maps = studies::default_stability_maps(has_switch(a, "quick"));
    if (a.multi.count("map")) {
      std::vector<studies::StabilityMapSpec> keep;
      for (const auto& name : a.multi["map"]) {
        bool found = false;
        for (const auto& m : opt.maps)
          if (m.name == name) keep.push_back(m), found = true;
        if (!found) throw UsageError("--map " + name + ": expected dt_factor, friction, friction_penalty or velocity");
      }
      opt.maps = keep;
    }
    const bool verbose = !has_switch(a, "quiet");
    opt.on_progress = [verbose](const std::string& s) { progress_line(verbose, s); };
    prepare_output_dir(opt.out_dir);
    install_signal_handlers();
    size_t cells = 0;
    for (const auto& m : opt.maps) cells += m.x.values.size() * m.y.values.size();
    if (verbose)
      std::printf("stability: %zu maps, %zu runs, %d jobs, out %s\n", opt.maps.size(), cells, opt.jobs,
                  opt.out_dir.c_str());
    std::fflush(stdout);
    const auto r = studies::run_stability(opt, &interrupt_flag());
    if (r.interrupted) {
      std::fprintf(stderr, "ravel: interrupted; %d finished runs are kept in %s/ (rerun the same command to resume)\n",
                   r.runs_made + r.runs_kept, opt.out_dir.c_str());
      return exit_interrupted;
    }
    write_file_atomic(opt.out_dir + "/stability.csv", studies::stability_csv(r));
    write_file_atomic(opt.out_dir + "/stability.md", studies::stability_markdown(r, opt));
    char sub[160];
    std::snprintf(sub, sizeof sub, "%s at %.0f m/s unless varied", scene.name.c_str(), scene.projectile.velocity_mps);
    for (const auto& [stem, chart] : studies::stability_charts(r.cells, sub))
      studies::write_chart(chart, opt.out_dir + "/" + stem, 900, 420);
    std::printf("stability: %zu cells in %.0f s", r.cells.size(), r.wall_time_s);
    if (r.runs_kept > 0) std::printf(" (%d run now, %d kept from an earlier run)", r.runs_made, r.runs_kept);
    std::printf("\n");
    for (const auto& s : studies::stability_sentences(r)) std::printf("  %s\n", s.c_str());
    for (const auto& e : r.errors) std::fprintf(stderr, "ravel: %s\n", e.c_str());
    std::printf("  %s/stability.{csv,md}, %s/stability_*.{png,svg,csv}\n", opt.out_dir.c_str(), opt.out_dir.c_str());
    return r.errors.empty() ? exit_ok : exit_failure;
  } catch (const std::exception& e) {
    return report_error(e);
  }
}

}  // namespace ravel::app
