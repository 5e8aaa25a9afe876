// `ravel tradeoff --searches`: what each of the fast ballistic-limit search's rules saves and
// what it may cost in accuracy, measured on the user's scene (issue 36; docs/tradeoff.md).
// The reference search (plain bisection, one run at a time, every run to its end), the fast
// search with every rule, and the fast search without each rule, one after another.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "results.h"
#include "sweep.h"
#include "tradeoff.h"

namespace ravel::studies {

namespace fs = std::filesystem;

namespace {

std::string f(const char* format, double v) {
  if (std::isnan(v)) return "";
  char b[64];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

// One search's row from its result.
SearchRow row_from(const LimitResult& r, const std::string& name, const std::string& rule) {
  SearchRow row;
  row.name = name;
  row.rule = rule;
  row.wall_time_s = r.wall_time_s;
  for (const auto& s : r.runs) {
    if (s.cancelled) {
      ++row.runs_cancelled;
      continue;
    }
    ++row.runs;
    row.runs_decided_passing += s.decided_passing;
  }
  row.rounds = r.rounds;
  if (r.bracketed) {
    row.ballistic_limit_mps = r.ballistic_limit_mps;
    row.lo_mps = r.lo_mps;
    row.hi_mps = r.hi_mps;
  }
  if (r.error_mps >= 0) row.error_mps = r.error_mps;
  row.status = r.converged ? "converged" : "not converged";  // (an interrupted search is never kept)
  if (!r.converged && !r.warnings.empty()) row.note = r.warnings.back();
  // A failed run spoils a search only when it was part of the bracket (both searches leave a
  // failed fit run out of the fit).
  for (const auto& s : r.runs)
    if (s.failed && s.purpose != "fit" && !r.converged) row.status = "failed", row.note = s.error;
  return row;
}

}  // namespace

std::vector<SearchRow> run_limit_searches(const TradeoffOptions& opt, const std::atomic<bool>* interrupt,
                                          std::vector<std::string>* warnings) {
  struct Plan {
    std::string name, rule;
    bool reference;
  };
  std::vector<Plan> plan{{"reference", "", true}, {"fast", "", false}};
  for (const auto& rule : opt.search_rules) plan.push_back({"without " + rule, rule, false});
  prepare_output_dir(opt.out_dir + "/search");
  std::vector<SearchRow> rows;
  for (const auto& p : plan) {
    if (interrupt && interrupt->load()) break;
    const std::string dir = opt.out_dir + "/search/" + (p.rule.empty() ? p.name : p.rule);
    const std::string path = dir + "/limit.json";
    LimitOptions lo = opt.limit_options;
    lo.jobs = p.reference ? 1 : std::max(1, opt.jobs);
    lo.rules = FastRules{};
    if (!p.rule.empty() && !leave_out_rule(lo.rules, p.rule))
      throw std::runtime_error("--searches: unknown rule '" + p.rule + "' (" + fast_rule_names() + ")");
    std::vector<std::string> ov = opt.overrides;
    // The reference runs one run at a time on every core the fast search uses; the fast
    // search one thread per run, jobs runs at once (as `ravel limit` does).
    ov.push_back("solver.threads=" + std::to_string(p.reference ? std::max(1, opt.jobs) : 1));
    ov.push_back("output.progress=false");
    if (!p.reference) add_rule_overrides(lo.rules, ov);
    if (fs::exists(path)) {
      try {
        const std::string text = read_text_file(path);
        const LimitResult kept = limit_from_json(text);
        // Only a search made with the same scene, overrides (the threads and rules among
        // them), tolerance and start stands for this one; any other is searched again.
        const auto j = nlohmann::json::parse(text);
        const bool same = j.value("scene", "") == opt.scene_path &&
                          j.value("overrides", std::vector<std::string>{}) == ov &&
                          j.value("tolerance_mps", -1.0) == lo.tolerance_mps &&
                          j.value("start_mps", -1.0) == lo.start_mps && j.value("jobs", 0) == lo.jobs;
        if (!kept.interrupted && same) {
          SearchRow row = row_from(kept, p.name, p.rule);
          row.kept = true;
          rows.push_back(row);
          if (opt.on_progress)
            opt.on_progress("search " + p.name + ": kept from an earlier run (" + f("%.2f", row.ballistic_limit_mps) +
                            " m/s)");
          continue;
        }
      } catch (const std::exception&) {  // unreadable: searched again
      }
    }
    prepare_output_dir(dir);
    const auto t0 = std::chrono::steady_clock::now();
    LimitResult r;
    try {
      if (p.reference)
        r = find_ballistic_limit(scene_shooter(opt.scene_path, ov, interrupt), lo, true);
      else
        r = find_ballistic_limit_fast(scene_runner(opt.scene_path, ov), lo, true, interrupt);
    } catch (const std::exception& e) {
      if (interrupt && interrupt->load()) break;
      SearchRow row;
      row.name = p.name;
      row.rule = p.rule;
      row.status = "failed";
      row.note = e.what();
      rows.push_back(row);
      if (warnings) warnings->push_back("search " + p.name + ": " + e.what());
      continue;
    }
    if (r.interrupted) break;  // (a finished search is kept even if the interruption came after it)
    // The whole search as the user waits for it (the fast search's own clock starts with its
    // first run; the reference's is the sum of its runs).
    r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    write_file_atomic(path, limit_json(r, lo, opt.scene_path, ov));
    SearchRow row = row_from(r, p.name, p.rule);
    rows.push_back(row);
    if (opt.on_progress)
      opt.on_progress("search " + p.name + ": " +
                      (std::isnan(row.ballistic_limit_mps) ? std::string("no limit")
                                                           : f("%.2f", row.ballistic_limit_mps) + " m/s") +
                      ", " + std::to_string(row.runs) + " runs, " + f("%.0f", row.wall_time_s) + " s");
  }
  // Against the reference and the fast search.
  const SearchRow* ref = nullptr;
  const SearchRow* fast = nullptr;
  for (const auto& r : rows) {
    if (r.name == "reference") ref = &r;
    if (r.name == "fast") fast = &r;
  }
  for (auto& r : rows) {
    if (ref) {
      // Distances only between converged searches (a bracket that never closed is no answer).
      if (r.status == "converged" && ref->status == "converged")
        r.diff_mps = r.ballistic_limit_mps - ref->ballistic_limit_mps;
      r.time_ratio = r.wall_time_s / ref->wall_time_s;
    }
    if (fast && !r.rule.empty()) r.rule_saves_s = r.wall_time_s - fast->wall_time_s;
  }
  return rows;
}

std::string searches_csv(const std::vector<SearchRow>& rows) {
  std::string out =
      "search,rule_left_out,status,wall_time_s,time_vs_reference,rule_saves_s,runs,runs_cancelled,rounds,"
      "runs_decided_passing,ballistic_limit_mps,bracket_lo_mps,bracket_hi_mps,error_estimate_mps,"
      "diff_from_reference_mps,kept\n";
  for (const auto& r : rows) {
    out += r.name + "," + r.rule + "," + r.status + "," + f("%.1f", r.wall_time_s) + "," + f("%.3f", r.time_ratio) +
           "," + f("%.1f", r.rule_saves_s) + "," + std::to_string(r.runs) + "," + std::to_string(r.runs_cancelled) +
           "," + std::to_string(r.rounds) + "," + std::to_string(r.runs_decided_passing) + "," +
           f("%.3f", r.ballistic_limit_mps) + "," + f("%.3f", r.lo_mps) + "," + f("%.3f", r.hi_mps) + "," +
           f("%.3f", r.error_mps) + "," + f("%.3f", r.diff_mps) + "," + (r.kept ? "true" : "false") + "\n";
  }
  return out;
}

std::string searches_markdown(const std::vector<SearchRow>& rows, const TradeoffOptions& opt) {
  std::string md = "\n## Ballistic-limit searches (--searches)\n\n";
  md += "The reference search (bisection, one run at a time on " + std::to_string(std::max(1, opt.jobs)) +
        " solver thread(s), every run to its end), the fast search (`ravel limit`: " +
        std::to_string(std::max(1, opt.jobs)) +
        " runs in flight, one thread each, every rule) and the fast search without each rule, one "
        "after another on the scene's own settings, tolerance " +
        f("%.3g", opt.limit_options.tolerance_mps) +
        " m/s, with the Lambert-Jonas fit's runs as `ravel limit` makes them. *Rule saves*: the "
        "search without the rule took this much longer than the fast search (negative: the rule "
        "cost time on this scene). *From the reference*: the limit minus the reference search's.\n\n";
  md +=
      "| search | limit, m/s (bracket) | from the reference | runs (moot) | rounds | decided passing | wall | "
      "vs reference | rule saves |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : rows) {
    std::string lim = std::isnan(r.ballistic_limit_mps) ? r.status
                                                        : f("%.2f", r.ballistic_limit_mps) + " (" +
                                                              f("%.2f", r.lo_mps) + "-" + f("%.2f", r.hi_mps) + ")";
    if (r.status != "converged" && !std::isnan(r.ballistic_limit_mps)) lim += ", " + r.status;
    md += "| " + r.name + " | " + lim + " | " + (std::isnan(r.diff_mps) ? "-" : f("%+.2f", r.diff_mps) + " m/s") +
          " | " + std::to_string(r.runs) + " (" + std::to_string(r.runs_cancelled) + ") | " + std::to_string(r.rounds) +
          " | " + std::to_string(r.runs_decided_passing) + " | " + f("%.0f", r.wall_time_s) + " s" +
          (r.kept ? " (kept)" : "") + " | " + (std::isnan(r.time_ratio) ? "-" : f("%.2fx", r.time_ratio)) + " | " +
          (std::isnan(r.rule_saves_s) ? "-" : f("%+.0f", r.rule_saves_s) + " s") + " |\n";
  }
  md += "\nThe rules:\n\n";
  for (const auto& info : fast_rule_table()) md += "- `" + std::string(info.name) + "`: " + info.what + "\n";
  md +=
      "\nA search's time depends on its path: a rule that changes where the next run goes changes which "
      "runs follow, so one scene measures what a rule did there, not what it does on average "
      "(tests/studies/limit_fast_test.cpp measures each rule on synthetic targets).\n";
  return md;
}

Chart searches_chart(const std::vector<SearchRow>& rows, const TradeoffOptions& opt, const std::string& scene_name) {
  Chart c;
  c.title = "ballistic-limit searches: distance from the reference's limit against wall time";
  c.subtitle = scene_name + ", tolerance " + f("%.3g", opt.limit_options.tolerance_mps) + " m/s, " +
               std::to_string(std::max(1, opt.jobs)) + " cores";
  c.x = {"wall time of the search", "s"};
  c.x.include_zero = true;
  c.y = {"|limit - reference's limit|", "m/s"};
  c.y.include_zero = true;
  double xmax = 0;
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto& r = rows[i];
    Series s;
    s.name = r.name;
    s.style = SeriesStyle::markers;
    s.color = int(i);
    s.x.push_back(r.wall_time_s);
    s.y.push_back(std::abs(r.diff_mps));
    if (std::isfinite(r.wall_time_s)) xmax = std::max(xmax, r.wall_time_s);
    c.series.push_back(s);
  }
  if (xmax > 0) {
    Series tol{"the tolerance",
               {0, 1.08 * xmax},
               {opt.limit_options.tolerance_mps, opt.limit_options.tolerance_mps},
               SeriesStyle::line};
    tol.color = 7;
    tol.dashed = true;
    c.series.push_back(tol);
  }
  return c;
}

}  // namespace ravel::studies
