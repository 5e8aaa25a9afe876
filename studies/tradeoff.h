// Speed against accuracy (SPEC §10, docs/tradeoff.md): run a scene once per setting of
// each speed/accuracy knob (time-step factor, contact iterations, precision, contact
// model, symmetry, yarns per element), measure its cost (wall time, CPU time, node-steps
// per second) and its error against the finest setting (residual velocity, energy
// absorbed, perforation time and, optionally, the ballistic limit), and say which
// setting is the cheapest within 1 % and 5 %.
//
// The runs go through the sweep machinery (studies/sweep.h): one case folder per
// distinct setting, written atomically, resumed on a rerun, --jobs in parallel. A case's
// name lists every knob's value, so the same setting reached from two knobs (e.g. the
// scene's own values) runs once.
//
// tradeoff.json keeps, per knob, the cheapest setting within each tolerance; `ravel run`
// reads the one shipped for its scene (assets/tradeoff/<scene name>.json) and suggests a
// cheaper setting when one is known to agree (tradeoff_suggestions()).
#pragma once

#include <atomic>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "chart.h"
#include "limit.h"
#include "scene.h"

namespace ravel::studies {

struct TradeoffKnob {
  std::string key;                  // scene key, e.g. solver.dt_factor
  std::vector<std::string> values;  // as for --set
};

// The knobs and their default lists (quick: shorter lists).
std::vector<TradeoffKnob> default_tradeoff_knobs(bool quick = false);
// The finest value of a knob (the reference's): smallest dt_factor, most iterations,
// double, sliding, yarns_per_element 1, symmetry auto (the symmetric model is exact for a
// symmetric scene; the `full` row checks that claim). Empty for an unknown key.
std::string finest_knob_value(const TradeoffKnob& knob);
// The value a scene has for a knob key, written as --set takes it ("0.5", "sliding").
std::string scene_knob_value(const Scene& scene, const std::string& key);
// Is `key` one of the knobs tradeoff knows?
bool is_tradeoff_knob(const std::string& key);

// The quantities compared with the reference.
enum TradeoffQuantity { q_residual_velocity = 0, q_energy_absorbed = 1, q_perforation_time = 2, q_ballistic_limit = 3 };
constexpr int kTradeoffQuantities = 4;
const char* quantity_key(int q);    // residual_velocity | energy_absorbed | perforation_time | ballistic_limit
const char* quantity_words(int q);  // "residual velocity", ...

// Relative error |value - ref| / |ref|; when ref is 0, relative to `scale` (the impact
// velocity for residual velocity). NaN when either is NaN.
double relative_error(double value, double ref, double scale = 0);
// Perforation time error: both absent (< 0): 0; only one: infinity; else relative.
double perforation_time_error(double value_s, double ref_s);

// Indices of the points no other point beats in both cost and error (lower is better;
// ties kept once), sorted by cost. Points with a non-finite cost or error are left out.
std::vector<size_t> pareto_front(const std::vector<double>& cost, const std::vector<double>& error);

struct TradeoffRow {
  std::string knob;       // scene key, or "reference"
  std::string value;      // the knob's value ("finest" for the reference)
  std::string case_name;  // folder under DIR/cases
  std::string status;     // completed | warned | diverged | failed | missing
  std::string note;       // diagnosis / warnings, in words
  double wall_time_s = NAN, cpu_time_s = NAN, node_steps_per_s = NAN;
  double value_q[kTradeoffQuantities] = {NAN, NAN, NAN, NAN};  // the quantities (m/s, J, s, m/s)
  double error[kTradeoffQuantities] = {NAN, NAN, NAN, NAN};    // relative to the reference
  bool perforated = false;
  double cost_s = NAN;  // the chosen cost measure (TradeoffOptions::cost), s
};

struct TradeoffOptions {
  std::string scene_path;  // resolved file
  std::vector<std::string> overrides;
  std::string out_dir;
  std::vector<TradeoffKnob> knobs;  // default_tradeoff_knobs() unless set
  bool around_reference = false;    // other knobs at their finest (true) or the scene's values
  // Knob values of the reference other than the finest (--reference KEY=VALUE), e.g. when
  // the finest setting itself diverges. Said in every output.
  std::vector<std::pair<std::string, std::string>> reference_overrides;
  std::string cost = "wall";  // wall | cpu: the cost the verdict and charts use
  int jobs = 1;
  int solver_threads = 1;
  bool limit = false;          // also the ballistic limit of every setting
  LimitOptions limit_options;  // tolerance etc. (start: 100 m/s)
  // The ballistic-limit searches compared (--searches): on the scene's own settings, the
  // reference search, the fast search, and the fast search without each rule named here
  // (fast_rule_table names). `searches` false: none.
  bool searches = false;
  std::vector<std::string> search_rules;
  bool searches_only = false;  // no knob rows (only the reference run and the searches)
  std::string date;            // YYYY-MM-DD written into tradeoff.json ("" = today)
  // Free text for tradeoff.json (machine load, quick mode, what it does not cover); the
  // suggestions drawn from the file repeat it.
  std::string note;
  std::function<void(const std::string& what)> on_progress;  // one line per finished run
};

// One ballistic-limit search of the --searches comparison: what it found and what it cost.
struct SearchRow {
  std::string name;    // reference | fast | without <rule>
  std::string rule;    // the rule left out ("" for the reference and the fast search)
  std::string status;  // converged | not converged | failed
  std::string note;    // the error, or why it did not converge
  double wall_time_s = NAN;
  int runs = 0, runs_cancelled = 0, rounds = 0, runs_decided_passing = 0;
  double ballistic_limit_mps = NAN, lo_mps = NAN, hi_mps = NAN;
  double error_mps = NAN;  // the search's own error estimate (limit.json's error_mps)
  double diff_mps = NAN;   // ballistic_limit_mps minus the reference search's
  // This search's wall time minus the fast search's (a `without` row: what the rule saved;
  // < 0: it cost), and this search's wall time over the reference's.
  double rule_saves_s = NAN, time_ratio = NAN;
  bool kept = false;  // read back from DIR/search/{reference,fast,<rule>}/limit.json, not searched now
};

struct TradeoffVerdictEntry {
  bool found = false;
  std::string knob, value;
  double cost_s = NAN, error = NAN;
};

struct TradeoffResult {
  std::vector<TradeoffRow> rows;  // rows[0] is the reference
  std::string scene_name;
  double impact_velocity_mps = 0;
  double wall_time_s = 0;  // the whole study
  int runs = 0, runs_skipped = 0;
  bool interrupted = false;
  std::vector<std::string> warnings;
  std::vector<SearchRow> searches;  // --searches: [0] the reference search, [1] the fast one
};

// Run (or resume) every setting; writes DIR/cases/... and returns the rows. The caller
// writes the outputs with the functions below (run_tradeoff does not).
TradeoffResult run_tradeoff(const TradeoffOptions& opt, const std::atomic<bool>* interrupt = nullptr);

// The searches of --searches, one after another on the machine's opt.jobs cores (each
// search has the machine to itself, so their wall times compare): the reference (one run at
// a time, opt.jobs solver threads), the fast search (opt.jobs runs in flight, one thread
// each) and the fast search without each of opt.search_rules, all with the Lambert-Jonas
// fit as `ravel limit` makes it. Each is kept as DIR/search/{reference,fast,<rule>}/limit.json
// and read back on a rerun made with the same scene, overrides, tolerance and jobs; a search cut short by an
// interruption is made again from its start (a resumed search's time would not be its cost). Called by run_tradeoff.
std::vector<SearchRow> run_limit_searches(const TradeoffOptions& opt, const std::atomic<bool>* interrupt,
                                          std::vector<std::string>* warnings);
// The rows' table (searches.csv), their section of tradeoff.md, and the chart (difference from
// the reference's limit against wall time).
std::string searches_csv(const std::vector<SearchRow>& rows);
std::string searches_markdown(const std::vector<SearchRow>& rows, const TradeoffOptions& opt);
Chart searches_chart(const std::vector<SearchRow>& rows, const TradeoffOptions& opt, const std::string& scene_name);

// The cheapest row of `knob` ("" = any row) whose error in quantity q is within tol.
TradeoffVerdictEntry cheapest_within(const TradeoffResult& r, const std::string& knob, int q, double tol);

std::string tradeoff_csv(const TradeoffResult& r);
std::string tradeoff_json(const TradeoffResult& r, const TradeoffOptions& opt);
std::string tradeoff_markdown(const TradeoffResult& r, const TradeoffOptions& opt);
// Error (%) against cost (s), log-log, one series per knob, the Pareto front, 1 % / 5 %
// lines: one chart per quantity (file stem first).
std::vector<std::pair<std::string, Chart>> tradeoff_charts(const TradeoffResult& r, const TradeoffOptions& opt);

// Suggestions for a run with `scene`, from a tradeoff.json text: for each knob, a
// cheaper value (at least `min_ratio` x less cost than the scene's own value in the
// same table) whose error is within `tolerance` for at least one quantity (the one with
// most quantities, then the cheapest). Nothing when the file is for another scene, the
// scene's value was not measured, or nothing cheaper qualifies.
std::vector<std::string> tradeoff_suggestions(const Scene& scene, const std::string& tradeoff_json_text,
                                              double tolerance = 0.01, double min_ratio = 1.2);
// assets/tradeoff/<scene name>.json (empty when there is none).
std::string shipped_tradeoff_path(const Scene& scene);
// The suggestions from the shipped file for `scene` (none when there is no file): within
// 1 %, and within 5 % for knobs with nothing within 1 %.
std::vector<std::string> shipped_tradeoff_suggestions(const Scene& scene);
// Add "suggestions": [...] to a run's summary.json (rewritten atomically).
void add_suggestions_to_summary(const std::string& summary_path, const std::vector<std::string>& suggestions);

}  // namespace ravel::studies
