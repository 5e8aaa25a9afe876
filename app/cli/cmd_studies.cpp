// The studies on the command line (docs/studies.md):
//   ravel sweep [SCENE] --vary key=start:stop:step|v1,v2,... [--vary ...] --out DIR
//               [--jobs N] [--shard i/n] [--set k=v ...] [--quiet]
//   ravel limit [SCENE] [--set k=v ...] --out DIR [--tolerance MPS] [--start MPS] [--no-fit]
//               [--reference] [--jobs N]
//   ravel paper [--quick] [--jobs N] --out DIR
// The logic lives in studies/ (ravel_studies); this file parses flags and prints.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <nlohmann/json.hpp>

#include "chart.h"
#include "cli.h"
#include "commands.h"
#include "limit.h"
#include "paper.h"
#include "results.h"
#include "run_record.h"
#include "sweep.h"
#ifdef RAVEL_HAVE_RENDER
#include "render/renderer.h"
#endif

namespace ravel::app {

// app/cli/cmd_run.cpp
std::atomic<bool>& interrupt_flag();
void install_signal_handlers();

namespace {

std::string fmt1(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", v);
  return b;
}

double parse_positive(const CommonArgs& a, const std::string& flag, double fallback) {
  auto it = a.flags.find(flag);
  if (it == a.flags.end()) return fallback;
  char* end = nullptr;
  const double v = std::strtod(it->second.c_str(), &end);
  if (it->second.empty() || *end || !std::isfinite(v) || v <= 0)
    throw UsageError("--" + flag + ": expected a positive number, got '" + it->second + "'");
  return v;
}

// Fail before anything is written when --out cannot be used.
void check_out_dir(const std::string& dir) {
  if (dir.empty()) throw UsageError("needs --out DIR");
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(dir, ec)) {
    if (!fs::is_directory(dir, ec)) throw OutputError("--out " + dir + ": exists and is not a folder");
    if (::access(dir.c_str(), W_OK | X_OK) != 0) throw OutputError("--out " + dir + ": the folder is not writable");
    return;
  }
  fs::path parent = fs::absolute(dir, ec).parent_path();
  while (!parent.empty() && !fs::exists(parent, ec)) parent = parent.parent_path();
  if (!parent.empty() && ::access(parent.c_str(), W_OK | X_OK) != 0)
    throw OutputError("--out " + dir + ": cannot create it (" + parent.string() + " is not writable)");
}

bool progress_wanted(const CommonArgs& a) {
  return !has_switch(a, "quiet");
}

}  // namespace

int cmd_sweep(const Args& args) {
  try {
    CommonArgs a = parse_args(args, "sweep");
    if (!a.multi.count("vary"))
      throw UsageError("sweep needs at least one --vary key=start:stop:step or key=v1,v2,...");
    check_out_dir(a.out_dir);
    studies::SweepOptions opt;
    opt.scene_path = scene_path_from(a);
    opt.overrides = a.overrides;
    load_scene(opt.scene_path, opt.overrides);  // bad scene / --set: fail now
    opt.out_dir = a.out_dir;
    opt.jobs = jobs_from(a);
    opt.solver_threads = a.threads >= 0 ? a.threads : 1;
    opt.extend_undecided = !has_switch(a, "no-extend");
    opt.restart = has_switch(a, "restart");
    opt.offers_restart = true;
    if (a.flags.count("shard")) opt.shard = studies::parse_shard(a.flags["shard"]);
    std::vector<studies::Vary> vary;
    std::vector<std::string> keys;
    for (const auto& v : a.multi["vary"]) {
      vary.push_back(studies::parse_vary(v, opt.scene_path, opt.overrides));
      if (std::find(keys.begin(), keys.end(), vary.back().key) != keys.end())
        throw UsageError("--vary " + vary.back().key + ": key varied twice");
      keys.push_back(vary.back().key);
    }
    // --repeats: each velocity N times, 1e-6 m/s apart (studies::repeat_velocities).
    std::map<std::string, std::string> base_of;
    int repeats = 1;
    if (a.flags.count("repeats")) {
      const std::string& text = a.flags["repeats"];
      char* end = nullptr;
      const long n = std::strtol(text.c_str(), &end, 10);
      if (text.empty() || *end != 0 || n < 1 || n > 1000)
        throw UsageError("--repeats: expected a whole number from 1 to 1000, got '" + text + "'");
      repeats = int(n);
      studies::apply_repeats(vary, repeats, &base_of);
    }
    // The charts' x axis: the first --vary key unless --chart-x names another (cases keep their names).
    std::vector<std::string> chart_keys = keys;
    if (a.flags.count("chart-x") && !studies::put_chart_x_first(&chart_keys, a.flags["chart-x"]))
      throw UsageError("--chart-x " + a.flags["chart-x"] + ": not a --vary key of this sweep (it varies " +
                       studies::joined_keys(keys) + ")");
    std::vector<std::string> chart_y;
    if (a.flags.count("chart-y")) {
      std::stringstream ss(a.flags["chart-y"]);
      for (std::string col; std::getline(ss, col, ',');) {
        col.erase(std::remove_if(col.begin(), col.end(), ::isspace), col.end());  // "a, b" as "a,b"
        if (!col.empty()) chart_y.push_back(col);
      }
      if (chart_y.empty()) throw UsageError("--chart-y: give one or more results.csv columns, comma-separated");
    }
    const auto all = studies::expand_cases(vary);
    const auto mine = studies::shard_cases(all, opt.shard);
    const bool verbose = progress_wanted(a);
    if (verbose)
      std::printf("sweep: %zu cases (%zu in shard %d/%d), %d jobs, out %s\n", all.size(), mine.size(), opt.shard.index,
                  opt.shard.count, opt.jobs, opt.out_dir.c_str());
    std::fflush(stdout);
    install_signal_handlers();
    studies::SweepHooks hooks;
    if (verbose && mine.size() > 1000)
      std::printf(
          "  a large sweep: %zu cases; the time left is shown after each case (Ctrl-C keeps what "
          "finished, a rerun resumes)\n",
          mine.size());
    // Each case as it ends: k of N, its outcome, and the time left at the rate so far.
    studies::TimeLeft pace(int(mine.size()));
    hooks.on_case = [&](const studies::CaseResult& r) {
      pace.step(r.skipped);
      if (r.skipped || !verbose) return;
      if (!r.ok) {
        std::fprintf(stderr, "  %s failed: %s: %s\n", pace.counter().c_str(), r.c.name().c_str(), r.error.c_str());
        return;
      }
      std::string outcome = "?";
      const studies::RunRecord rec = studies::parse_run_record(r.summary_json_text);
      if (rec.ok) {
        if (rec.status == "diverged")
          outcome = "DIVERGED: " + rec.diagnosis;
        else if (rec.perforated)
          outcome = "perforated, residual " + fmt1(rec.residual_velocity_mps) + " m/s";
        else
          outcome = rec.end_reason.empty() ? "stopped" : rec.end_reason;
      }
      std::printf("  %s %s: %s%s\n", pace.counter().c_str(), r.c.name().c_str(), outcome.c_str(), pace.left().c_str());
      std::fflush(stdout);
    };
    hooks.on_progress = [&](const studies::SweepProgress& p) {
      if (verbose && isatty(fileno(stderr)))
        std::fprintf(stderr, "\r  [%d/%d] %.0f s  ", p.done, p.total, p.wall_time_s);
    };
    const auto rep = studies::run_sweep(all, mine, opt, keys, hooks, &interrupt_flag());
    if (verbose && isatty(fileno(stderr))) std::fprintf(stderr, "\r%*s\r", 40, "");
    std::printf("sweep: %d run, %d already finished, %d failed, %d diverged in %.1f s (%.0f cases/hour)\n",
                rep.cases_run, rep.cases_skipped, rep.cases_failed, rep.cases_diverged, rep.wall_time_s,
                rep.cases_per_hour);
    std::printf("  %s/results.csv\n", opt.out_dir.c_str());
    // Charts of what is finished so far (all shards), with their CSVs.
    const studies::Csv results = studies::parse_csv(studies::read_text_file(opt.out_dir + "/results.csv"));
    for (const auto& col : chart_y)
      if (!results.rows.empty() && results.column(col) < 0)  // (no finished case yet: nothing to chart)
        throw UsageError("--chart-y " + col + ": no such column in " + opt.out_dir +
                         "/results.csv (its runs are kept: rerun with a column it has, e.g. energy_absorbed_J, "
                         "first_break_distance_mm, clamp_friction_J)");
    const auto charts = studies::sweep_charts(results, chart_keys, chart_y);
    if (!charts.empty()) prepare_output_dir(opt.out_dir + "/charts");
    for (const auto& [stem, chart] : charts) {
      if (studies::finite_point_count(chart) == 0) {
        std::printf("  (no chart of %s: no numbers in it yet)\n", stem.c_str());
        continue;
      }
      studies::write_chart(chart, opt.out_dir + "/charts/" + stem);
      std::printf("  %s/charts/%s.{png,svg,csv}\n", opt.out_dir.c_str(), stem.c_str());
    }
    // The perforation probability per velocity (and per combination of the other keys); a
    // rerun without --repeats removes what one with it left (it would disagree with results.csv).
    int groups = 0;
    const auto written =
        studies::write_perforation_outputs(opt.out_dir, results, chart_keys, base_of, repeats, &groups);
    for (size_t i = 0; i < written.size(); ++i)
      if (i == 0)
        std::printf("  %s (%d rows of %d repeats)\n", written[i].c_str(), groups, repeats);
      else
        std::printf("  %s.{png,svg,csv}\n", written[i].c_str());
    if (rep.interrupted) return exit_interrupted;
    return rep.cases_failed ? exit_failure : exit_ok;
  } catch (const std::exception& e) {
    return report_error(e);
  }
}

namespace {

// One run's outcome as the limit command prints it.
std::string shot_outcome(const studies::Shot& s) {
  std::string o = s.cancelled         ? "cancelled (" + s.cancel_reason + ")"
                  : s.decided_passing ? "perforated (passing, decided at " + fmt1(s.perforation_time_s * 1e6) + " us)"
                  : s.perforated      ? "perforated"
                  : s.decided         ? "stopped"
                                      : "undecided at its end time (left out)";
  if (s.perforated) o += ", residual " + fmt1(s.residual_velocity_mps) + " m/s";
  if (s.failed) o += " -- FAILED: " + s.error;
  return o;
}

// The residual-velocity chart (every run, and the fit where there is one) and the closing
// lines of `ravel limit`, for either search.
int limit_report(const CommonArgs& a, const Scene& scene, const studies::LimitResult& r, int resumed) {
  studies::Chart c;
  c.title = "Residual velocity vs impact velocity";
  c.subtitle = scene.name;
  c.x = {"impact velocity", "m/s"};
  c.y = {"residual velocity", "m/s"};
  studies::Series runs{"runs", {}, {}, studies::SeriesStyle::markers};
  auto sorted = r.runs;
  std::sort(sorted.begin(), sorted.end(), [](const auto& x, const auto& y) { return x.velocity_mps < y.velocity_mps; });
  for (const auto& s : sorted) {
    if (s.failed || s.cancelled) continue;  // no outcome to show
    runs.x.push_back(s.velocity_mps);
    runs.y.push_back(s.perforated ? s.residual_velocity_mps : 0.0);
  }
  c.series.push_back(runs);
  if (r.fit.ok && !runs.x.empty()) {
    studies::Series fit{"Lambert-Jonas fit", {}, {}, studies::SeriesStyle::line};
    const double v1 = runs.x.back();
    for (int i = 0; i <= 200; ++i) {
      const double v = r.fit.vbl_mps + (v1 - r.fit.vbl_mps) * i / 200.0;
      fit.x.push_back(v);
      fit.y.push_back(r.fit.residual_at(v));
    }
    c.series.push_back(fit);
  }
  studies::write_chart(c, a.out_dir + "/residual_velocity");
  for (const auto& w : r.warnings) std::fprintf(stderr, "ravel: warning: %s\n", w.c_str());
  const bool any_failed = std::any_of(r.runs.begin(), r.runs.end(), [](const auto& s) { return s.failed; });
  if (!r.bracketed) {
    std::printf("limit: no bracket found in %zu runs (%.1f s); see %s/limit.json\n", r.runs.size(), r.wall_time_s,
                a.out_dir.c_str());
    return any_failed ? exit_diverged : exit_failure;
  }
  const size_t full = r.runs.size() - size_t(r.runs_cancelled);
  std::printf("limit: ballistic limit %.2f m/s (bracket %.2f - %.2f m/s) from %zu runs in %.1f s (%.0f runs/hour)\n",
              r.ballistic_limit_mps, r.lo_mps, r.hi_mps, full, r.wall_time_s,
              r.wall_time_s > 0 ? full / (r.wall_time_s / 3600) : 0.0);
  std::printf("  %s search, %d job%s, %d rounds; error estimate +-%.2f m/s%s\n", r.method.c_str(), r.jobs,
              r.jobs == 1 ? "" : "s", r.rounds, r.error_mps,
              r.runs_cancelled ? (", " + std::to_string(r.runs_cancelled) + " moot runs stopped early").c_str() : "");
  std::printf(
      "  (near the limit one run is one draw of a random outcome: another search can land elsewhere in the zone of "
      "mixed results; ravel sweep --repeats N measures the perforation probability, docs/studies.md)\n");
  if (resumed)
    std::printf("  %d of the runs kept from an earlier, interrupted search (%s/runs/)\n", resumed, a.out_dir.c_str());
  if (!r.converged) std::printf("  NOT converged to the tolerance (see the warnings)\n");
  const auto band = studies::outcome_band(r);
  if (!band.threshold)
    std::printf("  no threshold: outcomes alternate from %.2f (lowest perforation) to %.2f m/s (highest stop)\n",
                band.lowest_perforation, band.highest_stop);
  if (band.v50 >= 0)
    std::printf("  V50 %.2f m/s: mean of the %d highest stop%s and %d lowest perforation%s (spread %.2f m/s)\n",
                band.v50, band.v50_pairs, band.v50_pairs == 1 ? "" : "s", band.v50_pairs,
                band.v50_pairs == 1 ? "" : "s", band.v50_spread);
  if (r.fit.ok)
    std::printf("  Lambert-Jonas: a = %.3f, p = %.3f, Vbl = %.2f m/s (rms %.2f m/s over %d points)\n", r.fit.a, r.fit.p,
                r.fit.vbl_mps, r.fit.rms_mps, r.fit.points);
  else if (!has_switch(a, "no-fit"))
    std::printf("  Lambert-Jonas: %s\n", r.fit.note.c_str());
  std::printf("  %s/limit.json, %s/residual_velocity.{png,svg,csv}\n", a.out_dir.c_str(), a.out_dir.c_str());
  return r.converged ? exit_ok : any_failed ? exit_diverged : exit_failure;
}

// `ravel limit` without --reference: the fast search (studies/limit_fast.cpp).
int limit_fast(const CommonArgs& a, const Scene& scene, const std::string& scene_path,
               const std::vector<std::string>& ov, const studies::LimitOptions& lo, bool verbose) {
  const bool with_fit = !has_switch(a, "no-fit");
  // Runs kept in DIR/runs/ by an earlier (interrupted) search count as made.
  const auto prior = studies::kept_runs(scene_path, ov, a.out_dir);
  if (verbose) {
    std::printf(
        "limit: %s, tolerance %.3g m/s, fast search: %d runs in flight, one solver thread each unless "
        "--threads; runs end at perforation or rebound (at most %.0f us), moot ones are stopped\n",
        scene.name.c_str(), lo.tolerance_mps, lo.jobs, scene.solver.max_end_time_s * 1e6);
    for (const auto& s : prior)
      std::printf("  kept    %8.2f m/s: %s  [kept from an earlier run, %.1f s]\n", s.velocity_mps,
                  shot_outcome(s).c_str(), s.wall_time_s);
    std::fflush(stdout);
  }
  studies::LimitHooks hooks;
  hooks.on_finish = [&](const studies::Shot& s, const studies::LimitProgress& p) {
    if (!verbose) return;
    std::printf("  %-7s %8.2f m/s: %s  [%.1f s]\n", s.purpose.c_str(), s.velocity_mps, shot_outcome(s).c_str(),
                s.wall_time_s);
    std::printf("    %s\n", p.line().c_str());
    std::fflush(stdout);
  };
  studies::LimitResult r = studies::find_ballistic_limit_fast(studies::scene_runner(scene_path, ov, {}, a.out_dir), lo,
                                                              with_fit, &interrupt_flag(), hooks, prior);
  if (const std::string w = studies::lumped_mesh_warning(scene); !w.empty()) r.warnings.push_back(w);
  write_file_atomic(a.out_dir + "/limit.json", studies::limit_json(r, lo, scene_path, ov));
  if (r.interrupted) {
    std::fprintf(stderr,
                 "ravel: interrupted; %zu finished runs kept in %s/limit.json and %s/runs/ (rerun the same command "
                 "to resume)\n",
                 r.runs.size() - size_t(r.runs_cancelled), a.out_dir.c_str(), a.out_dir.c_str());
    return exit_interrupted;
  }
  return limit_report(a, scene, r, int(prior.size()));
}

}  // namespace

int cmd_limit(const Args& args) {
  try {
    CommonArgs a = parse_args(args, "limit");
    check_out_dir(a.out_dir);
    const std::string scene_path = scene_path_from(a);
    const bool reference = has_switch(a, "reference");
    std::vector<std::string> ov = overrides_from(a);
    // The fast search runs several runs at once, each on one thread (unless --threads).
    if (!reference && a.threads < 0) ov.push_back("solver.threads=1");
    const Scene scene = load_scene(scene_path, ov);
    studies::LimitOptions lo;
    lo.tolerance_mps = parse_positive(a, "tolerance", 1.0);
    if (lo.tolerance_mps < 1e-4)  // (the bisection would split gaps of a few 1e-6 m/s steps onto their ends)
      throw UsageError("--tolerance: at least 0.0001 m/s, got " + a.flags["tolerance"] +
                       " (the searches run velocities to 1e-6 m/s)");
    lo.start_mps = parse_positive(a, "start", 100.0);
    lo.max_runs = int(parse_positive(a, "max-runs", 60));
    lo.jobs = reference ? 1 : jobs_from(a);
    if (auto it = a.flags.find("without"); it != a.flags.end()) {
      if (reference) throw UsageError("--without: the reference search has no rules to leave out");
      std::stringstream ss(it->second);
      for (std::string rule; std::getline(ss, rule, ',');) {
        if (!studies::leave_out_rule(lo.rules, rule))
          throw UsageError("--without: unknown rule '" + rule +
                           "' (the fast search's rules: " + studies::fast_rule_names() + ")");
      }
    }
    if (!reference) studies::add_rule_overrides(lo.rules, ov);
    prepare_output_dir(a.out_dir);
    install_signal_handlers();
    const bool verbose = progress_wanted(a);
    if (!reference) return limit_fast(a, scene, scene_path, ov, lo, verbose);
    // Finished runs are kept in DIR/runs/: an interrupted search resumes from them.
    auto shoot = studies::scene_shooter(scene_path, ov, &interrupt_flag(), {}, a.out_dir);
    std::vector<studies::Shot> finished;
    int resumed = 0;
    const bool with_fit = !has_switch(a, "no-fit");
    auto logged = [&](double v, const std::string& why) {
      auto s = shoot(v, why);
      s.purpose = why;
      finished.push_back(s);
      resumed += s.resumed;
      if (verbose) {
        std::printf("  %-7s %8.2f m/s: %s", why.c_str(), v,
                    s.perforated ? "perforated"
                    : s.decided  ? "stopped"
                                 : "undecided at its end time (left out)");
        if (s.perforated) std::printf(", residual %.1f m/s", s.residual_velocity_mps);
        if (s.failed) std::printf(" -- FAILED: %s", s.error.c_str());
        std::printf(s.resumed ? "  [kept from an earlier run, %.1f s]\n" : "  [%.1f s]\n", s.wall_time_s);
        std::printf("    %s\n", studies::limit_progress(finished, lo, with_fit).c_str());
        std::fflush(stdout);
      }
      return s;
    };
    if (verbose)
      std::printf(
          "limit: %s, tolerance %.3g m/s, reference search (bisection, one run at a time), runs end at "
          "perforation or rebound (at most %.0f us)\n",
          scene.name.c_str(), lo.tolerance_mps, scene.solver.max_end_time_s * 1e6);
    studies::LimitResult r;
    try {
      r = studies::find_ballistic_limit(logged, lo, with_fit);
      if (const std::string w = studies::lumped_mesh_warning(scene); !w.empty()) r.warnings.push_back(w);
    } catch (const std::exception& e) {
      if (interrupt_flag().load()) {
        // Keep what finished: limit.json lists the finished runs (no limit yet), and DIR/runs/
        // lets the same command resume without redoing them.
        studies::LimitResult part;
        part.runs = finished;
        part.interrupted = true;
        part.warnings.push_back("interrupted after " + std::to_string(finished.size()) +
                                " runs; rerun the same command to resume");
        write_file_atomic(a.out_dir + "/limit.json", studies::limit_json(part, lo, scene_path, ov));
        std::fprintf(stderr,
                     "ravel: interrupted; %zu finished runs kept in %s/limit.json and %s/runs/ (rerun the same "
                     "command to resume)\n",
                     finished.size(), a.out_dir.c_str(), a.out_dir.c_str());
        return exit_interrupted;
      }
      throw;
    }
    write_file_atomic(a.out_dir + "/limit.json", studies::limit_json(r, lo, scene_path, ov));
    return limit_report(a, scene, r, resumed);
  } catch (const std::exception& e) {
    return report_error(e);
  }
}

int cmd_paper(const Args& args) {
  try {
    CommonArgs a = parse_args(args, "paper");
    check_out_dir(a.out_dir);
    studies::PaperOptions opt;
    opt.scene_path = scene_path_from(a);
    opt.overrides = overrides_from(a);
    load_scene(opt.scene_path, opt.overrides);
    opt.out_dir = a.out_dir;
    opt.jobs = jobs_from(a);
    opt.quick = has_switch(a, "quick");
    opt.reference_limits = has_switch(a, "reference-limits");
    const bool verbose = progress_wanted(a);
#ifdef RAVEL_HAVE_RENDER
    std::unique_ptr<render::HeadlessRenderer> renderer;
    opt.render_png = [&renderer](const Frame& f, const std::string& path, std::string* err) {
      if (!renderer) renderer = render::HeadlessRenderer::create(err);
      if (!renderer) return false;
      render::ViewOptions v;
      v.view = render::ViewPreset::top;
      return renderer->render_png(f, v, 1200, 1200, path, err);
    };
#endif
    std::mutex mu;
    std::string last_stage;
    std::unique_ptr<studies::TimeLeft> pace;  // per stage: its pace so far
    opt.on_progress = [&](const std::string& stage, int done, int total, int kept) {
      if (!verbose) return;
      std::lock_guard<std::mutex> lock(mu);
      if (stage != last_stage && !last_stage.empty() && !isatty(fileno(stderr))) std::fprintf(stderr, "\n");
      if (stage != last_stage || !pace) pace = std::make_unique<studies::TimeLeft>(total);
      last_stage = stage;
      std::string at = pace->at(done, total, kept);
      if (kept > 0) at += " (" + std::to_string(kept) + " kept from an earlier run)";
      if (isatty(fileno(stderr)))
        std::fprintf(stderr, "\r  %s: %s      ", stage.c_str(), at.c_str());
      else if (done == total || done % 10 == 0 || total <= 20)  // a log: each of a few long items
        std::fprintf(stderr, "  %s: %s\n", stage.c_str(), at.c_str());
    };
    install_signal_handlers();
    if (verbose)
      std::printf("paper: %s mode, %d jobs, %s ballistic-limit searches, out %s\n", opt.quick ? "quick" : "full",
                  opt.jobs, opt.reference_limits ? "reference" : "fast", opt.out_dir.c_str());
    std::fflush(stdout);
    studies::PaperResult r;
    try {
      r = studies::run_paper(opt, &interrupt_flag());
    } catch (const std::exception& e) {
      if (interrupt_flag().load()) {
        std::fprintf(stderr,
                     "\nravel: interrupted; finished runs are kept in %s/ (velocity/, compression/, limit/); rerun "
                     "the same command to resume\n",
                     opt.out_dir.c_str());
        return exit_interrupted;
      }
      throw;
    }
    if (verbose && isatty(fileno(stderr))) std::fprintf(stderr, "\n");
    std::printf("paper: %d runs in %.0f s (%.0f runs/hour); claims: %d agree, %d partly, %d differ, %d not measured\n",
                r.runs, r.wall_time_s, r.runs_per_hour, r.claims_agree, r.claims_partly, r.claims_differ,
                r.claims_unknown);
    std::printf("  %s\n", r.report_path.c_str());
    if (!r.warnings.empty()) std::printf("  %zu warnings (listed in the report)\n", r.warnings.size());
    return exit_ok;
  } catch (const std::exception& e) {
    return report_error(e);
  }
}

}  // namespace ravel::app
