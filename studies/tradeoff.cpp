#include "tradeoff.h"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <limits>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>

#include "results.h"
#include "run_record.h"
#include "sweep.h"
#include "work_queue.h"

namespace ravel::studies {

namespace fs = std::filesystem;
using ojson = nlohmann::ordered_json;

namespace {

bool parse_num(const std::string& s, double* v) {
  char* end = nullptr;
  *v = std::strtod(s.c_str(), &end);
  return !s.empty() && *end == 0 && std::isfinite(*v);
}

std::string num(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// A numeric value written the way the case names use it ("0.50" -> "0.5").
std::string normalise(const std::string& key, const std::string& v) {
  double d;
  if (key == "solver.dt_factor" && parse_num(v, &d)) return num(d);
  if ((key == "solver.contact_iterations" || key == "fabric.yarns_per_element" ||
       key == "fabric.far_yarns_per_element") &&
      parse_num(v, &d))
    return num(std::round(d));
  return v;
}

std::string today() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  localtime_r(&t, &tm);
  char b[16];
  std::strftime(b, sizeof b, "%Y-%m-%d", &tm);
  return b;
}

std::string short_knob(const std::string& key) {
  const auto dot = key.find('.');
  return dot == std::string::npos ? key : key.substr(dot + 1);
}

double user_cpu_s(int who) {
  rusage ru{};
  getrusage(who, &ru);
  return double(ru.ru_utime.tv_sec) + 1e-6 * double(ru.ru_utime.tv_usec);
}

// Method warnings: the nearest-pair assumption broke (SPEC §4).
bool method_warning(const std::string& w) {
  return w.find("slid more than one node") != std::string::npos || w.find("passed through") != std::string::npos;
}

}  // namespace

std::vector<TradeoffKnob> default_tradeoff_knobs(bool quick) {
  if (quick)
    return {{"solver.dt_factor", {"0.1", "0.3", "0.5", "0.9"}},
            {"solver.contact_iterations", {"1", "2", "8"}},
            {"solver.precision", {"double", "float"}},
            {"solver.model", {"sliding", "pin_jointed"}},
            {"solver.symmetry", {"auto", "full"}},
            {"fabric.yarns_per_element", {"1", "2", "4"}},
            {"fabric.far_yarns_per_element", {"1", "3"}}};
  return {{"solver.dt_factor", {"0.1", "0.2", "0.3", "0.5", "0.7", "0.9"}},
          {"solver.contact_iterations", {"1", "2", "4", "8"}},
          {"solver.precision", {"double", "float"}},
          {"solver.model", {"sliding", "pin_jointed"}},
          {"solver.symmetry", {"auto", "full"}},
          {"fabric.yarns_per_element", {"1", "2", "3", "4"}},
          {"fabric.far_yarns_per_element", {"1", "2", "3", "4"}}};
}

bool is_tradeoff_knob(const std::string& key) {
  for (const auto& k : default_tradeoff_knobs())
    if (k.key == key) return true;
  return false;
}

std::string finest_knob_value(const TradeoffKnob& knob) {
  if (knob.values.empty()) return "";
  const std::string& key = knob.key;
  if (key == "solver.precision") return "double";
  if (key == "solver.model") return "sliding";
  if (key == "solver.symmetry") return "auto";
  const bool smallest =
      key == "solver.dt_factor" || key == "fabric.yarns_per_element" || key == "fabric.far_yarns_per_element";
  const bool largest = key == "solver.contact_iterations";
  if (!smallest && !largest) return "";
  std::string best;
  double bv = smallest ? INFINITY : -INFINITY;
  for (const auto& v : knob.values) {
    double d;
    if (!parse_num(v, &d)) continue;
    if (smallest ? d < bv : d > bv) bv = d, best = normalise(key, v);
  }
  return best;
}

std::string scene_knob_value(const Scene& s, const std::string& key) {
  if (key == "solver.dt_factor") return num(s.solver.dt_factor);
  if (key == "solver.contact_iterations") return std::to_string(s.solver.contact_iterations);
  if (key == "solver.precision") return s.solver.precision == Precision::double_precision ? "double" : "float";
  if (key == "solver.model") return s.solver.model == ContactModel::sliding ? "sliding" : "pin_jointed";
  if (key == "solver.symmetry") return s.solver.symmetry == SymmetryMode::automatic ? "auto" : "full";
  if (key == "fabric.yarns_per_element") return std::to_string(s.fabric.yarns_per_element);
  if (key == "fabric.far_yarns_per_element") return std::to_string(s.fabric.far_yarns_per_element);
  return "";
}

const char* quantity_key(int q) {
  static const char* k[] = {"residual_velocity", "energy_absorbed", "perforation_time", "ballistic_limit"};
  return k[q];
}
const char* quantity_words(int q) {
  static const char* k[] = {"residual velocity", "energy absorbed", "perforation time", "ballistic limit"};
  return k[q];
}

double relative_error(double value, double ref, double scale) {
  if (std::isnan(value) || std::isnan(ref)) return NAN;
  const double d = std::abs(value - ref);
  if (ref != 0) return d / std::abs(ref);
  if (scale != 0) return d / std::abs(scale);
  return d == 0 ? 0 : INFINITY;
}

double perforation_time_error(double value_s, double ref_s) {
  const bool a = value_s >= 0, b = ref_s >= 0;
  if (!a && !b) return 0;
  if (a != b) return INFINITY;
  return relative_error(value_s, ref_s);
}

std::vector<size_t> pareto_front(const std::vector<double>& cost, const std::vector<double>& error) {
  std::vector<size_t> idx;
  for (size_t i = 0; i < std::min(cost.size(), error.size()); ++i)
    if (std::isfinite(cost[i]) && std::isfinite(error[i])) idx.push_back(i);
  // Cheapest first (then most accurate); a point is on the front when it is more
  // accurate than every cheaper one.
  std::sort(idx.begin(), idx.end(), [&](size_t a, size_t b) {
    return cost[a] != cost[b] ? cost[a] < cost[b] : error[a] != error[b] ? error[a] < error[b] : a < b;
  });
  std::vector<size_t> front;
  double best = INFINITY;
  for (size_t i : idx) {
    if (error[i] < best) {
      front.push_back(i);
      best = error[i];
    }
  }
  return front;
}

// ---------------------------------------------------------------------------------------

namespace {

struct Setting {
  std::string knob, value;  // which row
  Case c;                   // every knob's value
};

// Per-case CPU time: the hook runs on the case's worker thread right after the run; the
// thread's user time since the previous hook on that thread (or the thread's start) is
// the case's. With solver threads > 1 (and one job) the process's user time is used, so
// the solver's other threads count too.
class CpuMeter {
 public:
  explicit CpuMeter(bool per_thread) : per_thread_(per_thread), last_process_(user_cpu_s(RUSAGE_SELF)) {}
  double take() {
    if (per_thread_) {
      thread_local double last = 0;
      thread_local const CpuMeter* owner = nullptr;
      if (owner != this) owner = this, last = 0;
      const double now = user_cpu_s(RUSAGE_THREAD);
      const double d = now - last;
      last = now;
      return d;
    }
    std::lock_guard<std::mutex> lock(mu_);
    const double now = user_cpu_s(RUSAGE_SELF);
    const double d = now - last_process_;
    last_process_ = now;
    return d;
  }

 private:
  bool per_thread_;
  double last_process_;
  std::mutex mu_;
};

void fill_row_from_case(TradeoffRow& row, const std::string& dir) {
  const RunRecord r = read_run_record(dir);
  if (!r.ok) {
    row.status = r.error == "missing" ? "missing" : "failed";
    if (r.error != "missing") row.note = "summary.json " + r.error;
    return;
  }
  row.wall_time_s = r.wall_time_s;
  row.node_steps_per_s = r.node_steps_per_s;
  row.perforated = r.perforated;
  row.value_q[q_residual_velocity] = r.residual_velocity_mps;
  row.value_q[q_energy_absorbed] = r.energy_absorbed_J;
  row.value_q[q_perforation_time] = r.perforation_time_s;
  std::string warn;
  bool method = false;
  for (const auto& t : r.warnings) {
    if (method_warning(t)) method = true;
    warn += (warn.empty() ? "" : "; ") + t;
  }
  if (r.status == "diverged") {
    row.status = "diverged";
    row.note = r.diagnosis;
  } else {
    row.status = method ? "warned" : r.status;
    row.note = warn;
  }
  if (fs::exists(dir + "/cost.json")) {
    const auto c = ojson::parse(read_text_file(dir + "/cost.json"), nullptr, false);
    if (!c.is_discarded() && c.contains("cpu_time_s") && c["cpu_time_s"].is_number())
      row.cpu_time_s = c["cpu_time_s"].get<double>();
  }
}

}  // namespace

TradeoffResult run_tradeoff(const TradeoffOptions& opt_in, const std::atomic<bool>* interrupt) {
  TradeoffOptions opt = opt_in;
  if (opt.knobs.empty() && !opt.searches_only) opt.knobs = default_tradeoff_knobs();
  const auto t0 = std::chrono::steady_clock::now();
  const Scene base = load_scene(opt.scene_path, opt.overrides);
  TradeoffResult res;
  res.scene_name = base.name;
  res.impact_velocity_mps = base.projectile.velocity_mps;

  // Every knob's value in the reference and in the "other knobs" of each row.
  std::vector<std::string> keys;
  std::map<std::string, std::string> finest, around;
  for (auto& k : opt.knobs) {
    for (auto& v : k.values) v = normalise(k.key, v);
    keys.push_back(k.key);
    finest[k.key] = finest_knob_value(k);
    around[k.key] = opt.around_reference ? finest[k.key] : scene_knob_value(base, k.key);
  }
  for (const auto& [k, v] : opt.reference_overrides) {
    if (!finest.count(k)) throw StudyError("--reference " + k + ": not one of the knobs of this study");
    finest[k] = normalise(k, v);
    if (opt.around_reference) around[k] = finest[k];
  }
  auto make_case = [&](const std::map<std::string, std::string>& values) {
    Case c;
    for (const auto& k : keys) c.settings.emplace_back(k, values.at(k));
    return c;
  };
  std::vector<Setting> settings;
  settings.push_back({"reference", "finest", make_case(finest)});
  for (const auto& k : opt.knobs)
    for (const auto& v : k.values) {
      auto vals = around;
      vals[k.key] = v;
      settings.push_back({k.key, v, make_case(vals)});
    }
  // Distinct cases, in first-seen order.
  std::vector<Case> cases;
  std::set<std::string> seen;
  for (auto& s : settings)
    if (seen.insert(s.c.name()).second) {
      s.c.index = int(cases.size());
      cases.push_back(s.c);
    }

  SweepOptions so;
  so.scene_path = opt.scene_path;
  so.overrides = opt.overrides;
  so.out_dir = opt.out_dir + "/cases";
  so.jobs = opt.jobs;
  so.solver_threads = opt.solver_threads;
  CpuMeter meter(opt.solver_threads == 1);
  SweepHooks hooks;
  hooks.on_simulation = [&](const Case&, const Simulation&, const std::string& tmp) {
    ojson c;
    c["cpu_time_s"] = meter.take();
    c["cpu_time_measure"] =
        opt.solver_threads == 1 ? "user time of the case's thread" : "user time of the process (one case at a time)";
    write_file_atomic(tmp + "/cost.json", c.dump(2) + "\n");
  };
  TimeLeft pace(int(cases.size()));
  hooks.on_case = [&](const CaseResult& r) {
    pace.step(r.skipped);
    if (r.skipped)
      ++res.runs_skipped;
    else
      ++res.runs;
    if (opt.on_progress && !r.skipped)
      opt.on_progress(pace.counter() + (r.ok ? " done " + r.c.name() : " FAILED " + r.c.name() + ": " + r.error) +
                      pace.left());
  };
  if (opt.solver_threads != 1 && opt.jobs != 1)
    res.warnings.push_back("CPU time per case is only measured with --threads 1 or --jobs 1");
  const auto rep = run_sweep(cases, cases, so, keys, hooks, interrupt);
  res.interrupted = rep.interrupted;
  for (const auto& e : rep.errors) res.warnings.push_back(e);

  // Rows.
  for (const auto& s : settings) {
    TradeoffRow row;
    row.knob = s.knob;
    row.value = s.value;
    row.case_name = s.c.name();
    fill_row_from_case(row, case_dir(so.out_dir, s.c));
    if (opt.solver_threads != 1 && opt.jobs != 1) row.cpu_time_s = NAN;
    res.rows.push_back(row);
  }

  // Ballistic limits (one search per distinct case; resumed from DIR/limit/<case>.json).
  if (opt.limit && !res.interrupted) {
    prepare_output_dir(opt.out_dir + "/limit");
    std::mutex mu;
    std::map<std::string, double> bl;
    auto search = [&](size_t i) {
      const std::string name = cases[i].name();
      const std::string path = opt.out_dir + "/limit/" + name + ".json";
      double v = NAN;
      if (fs::exists(path)) {
        try {
          const LimitResult kept = limit_from_json(read_text_file(path));
          if (kept.converged) v = kept.ballistic_limit_mps;
        } catch (const std::exception&) {  // unreadable: left without a limit, as before
        }
      } else {
        auto ov = opt.overrides;
        for (const auto& o : cases[i].overrides()) ov.push_back(o);
        ov.push_back("solver.threads=" + std::to_string(opt.solver_threads));
        ov.push_back("output.progress=false");
        try {
          auto r =
              find_ballistic_limit(scene_shooter(opt.scene_path, ov, interrupt, {}, opt.out_dir + "/limit/" + name),
                                   opt.limit_options, false);
          if (interrupt && interrupt->load()) return;
          write_file_atomic(path, limit_json(r, opt.limit_options, opt.scene_path, ov));
          if (r.converged) v = r.ballistic_limit_mps;
        } catch (const std::exception& e) {
          std::lock_guard<std::mutex> lock(mu);
          res.warnings.push_back("ballistic limit of " + name + ": " + e.what());
        }
        if (opt.on_progress) {
          std::lock_guard<std::mutex> lock(mu);
          opt.on_progress("ballistic limit " + name + ": " + (std::isnan(v) ? "not found" : num(v) + " m/s"));
        }
      }
      std::lock_guard<std::mutex> lock(mu);
      bl[name] = v;
    };
    run_queue(cases.size(), opt.jobs, interrupt, search);
    for (auto& row : res.rows)
      if (bl.count(row.case_name)) row.value_q[q_ballistic_limit] = bl[row.case_name];
    if (interrupt && interrupt->load()) res.interrupted = true;
  }

  // The ballistic-limit searches, each with the machine to itself (after every other run).
  if (opt.searches && !res.interrupted) {
    res.searches = run_limit_searches(opt, interrupt, &res.warnings);
    if (interrupt && interrupt->load()) res.interrupted = true;
  }

  // Errors against the reference, and the cost measure.
  const TradeoffRow ref = res.rows[0];
  for (auto& row : res.rows) {
    row.cost_s = opt.cost == "cpu" ? row.cpu_time_s : row.wall_time_s;
    if (row.status == "diverged" || row.status == "failed" || row.status == "missing" || ref.status == "diverged" ||
        ref.status == "failed" || ref.status == "missing")
      continue;
    row.error[q_residual_velocity] =
        relative_error(row.value_q[q_residual_velocity], ref.value_q[q_residual_velocity], res.impact_velocity_mps);
    row.error[q_energy_absorbed] = relative_error(row.value_q[q_energy_absorbed], ref.value_q[q_energy_absorbed]);
    row.error[q_perforation_time] =
        perforation_time_error(row.value_q[q_perforation_time], ref.value_q[q_perforation_time]);
    row.error[q_ballistic_limit] = relative_error(row.value_q[q_ballistic_limit], ref.value_q[q_ballistic_limit]);
  }
  if (ref.status != "completed")
    res.warnings.push_back("the reference run is " + ref.status + (ref.note.empty() ? "" : ": " + ref.note));
  res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

TradeoffVerdictEntry cheapest_within(const TradeoffResult& r, const std::string& knob, int q, double tol) {
  TradeoffVerdictEntry best;
  for (size_t i = 1; i < r.rows.size(); ++i) {
    const auto& row = r.rows[i];
    if (!knob.empty() && row.knob != knob) continue;
    if (row.status != "completed" && row.status != "warned") continue;
    if (!(row.error[q] <= tol) || !std::isfinite(row.cost_s)) continue;
    if (!best.found || row.cost_s < best.cost_s) {
      best.found = true;
      best.knob = row.knob;
      best.value = row.value;
      best.cost_s = row.cost_s;
      best.error = row.error[q];
    }
  }
  return best;
}

namespace {

bool has_bl(const TradeoffResult& r) {
  return std::any_of(r.rows.begin(), r.rows.end(),
                     [](const TradeoffRow& x) { return !std::isnan(x.value_q[q_ballistic_limit]); });
}
int quantity_count(const TradeoffResult& r) {
  return has_bl(r) ? 4 : 3;
}

std::string cell(double v, const char* f = "%.6g") {
  if (std::isnan(v)) return "";
  if (std::isinf(v)) return "inf";
  return fmt(f, v);
}

std::string csv_quote(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string o = "\"";
  for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c);
  return o + "\"";
}

const double kTolerances[] = {0.01, 0.05};

std::string pct(double e) {
  if (std::isnan(e)) return "-";
  if (std::isinf(e)) return "outcome differs";
  return fmt(e < 0.001 ? "%.3f %%" : "%.2g %%", 100 * e);
}

}  // namespace

std::string tradeoff_csv(const TradeoffResult& r) {
  std::string out =
      "knob,value,wall_time_s,cpu_time_s,node_steps_per_s,residual_velocity_error,energy_absorbed_error,"
      "perforation_time_error,ballistic_limit_error,status,residual_velocity_mps,energy_absorbed_J,perforation_time_s,"
      "ballistic_limit_mps,cost_s,note,case\n";
  for (const auto& row : r.rows) {
    out += csv_quote(row.knob) + "," + csv_quote(row.value) + "," + cell(row.wall_time_s) + "," + cell(row.cpu_time_s) +
           "," + cell(row.node_steps_per_s) + "," + cell(row.error[0]) + "," + cell(row.error[1]) + "," +
           cell(row.error[2]) + "," + cell(row.error[3]) + "," + row.status + "," + cell(row.value_q[0]) + "," +
           cell(row.value_q[1]) + "," + (row.value_q[2] >= 0 ? cell(row.value_q[2]) : std::string()) + "," +
           cell(row.value_q[3]) + "," + cell(row.cost_s) + "," + csv_quote(row.note) + "," + csv_quote(row.case_name) +
           "\n";
  }
  return out;
}

std::string tradeoff_json(const TradeoffResult& r, const TradeoffOptions& opt) {
  ojson j;
  j["tool"] = "ravel tradeoff";
  j["scene"] = r.scene_name;
  j["scene_path"] = opt.scene_path;
  j["overrides"] = opt.overrides;
  j["date"] = opt.date.empty() ? today() : opt.date;
  j["impact_velocity_mps"] = r.impact_velocity_mps;
  j["around"] = opt.around_reference ? "reference" : "scene";
  j["cost_measure"] = opt.cost == "cpu" ? "cpu_time_s" : "wall_time_s";
  j["jobs"] = opt.jobs;
  j["solver_threads"] = opt.solver_threads;
  j["note"] = opt.note;
  j["study_wall_time_s"] = r.wall_time_s;  // this invocation (small when it resumed finished runs)
  {
    // What the runs behind the table cost, each distinct run once.
    std::set<std::string> seen;
    double wall = 0, cpu = 0;
    for (const auto& row : r.rows)
      if (seen.insert(row.case_name).second) {
        if (std::isfinite(row.wall_time_s)) wall += row.wall_time_s;
        if (std::isfinite(row.cpu_time_s)) cpu += row.cpu_time_s;
      }
    j["runs"] = int(seen.size());
    j["runs_wall_time_s"] = wall;
    j["runs_cpu_time_s"] = cpu;
  }
  j["tolerances"] = {0.01, 0.05};
  j["reference"] = ojson::object();
  if (!r.rows.empty()) {
    const auto& ref = r.rows[0];
    j["reference"]["case"] = ref.case_name;
    j["reference"]["changed_from_finest"] = ojson::object();
    for (const auto& [k, v] : opt.reference_overrides) j["reference"]["changed_from_finest"][k] = v;
    j["reference"]["status"] = ref.status;
    j["reference"]["residual_velocity_mps"] = ref.value_q[0];
    j["reference"]["energy_absorbed_J"] = ref.value_q[1];
    j["reference"]["perforation_time_s"] = ref.value_q[2] >= 0 ? ojson(ref.value_q[2]) : ojson(nullptr);
    if (!std::isnan(ref.value_q[3])) j["reference"]["ballistic_limit_mps"] = ref.value_q[3];
    j["reference"]["cost_s"] = std::isfinite(ref.cost_s) ? ojson(ref.cost_s) : ojson(nullptr);
  }
  auto jnum = [](double v) { return std::isfinite(v) ? ojson(v) : std::isinf(v) ? ojson("inf") : ojson(nullptr); };
  j["rows"] = ojson::array();
  for (size_t i = 1; i < r.rows.size(); ++i) {
    const auto& row = r.rows[i];
    ojson o;
    o["knob"] = row.knob;
    o["value"] = row.value;
    o["status"] = row.status;
    o["cost_s"] = jnum(row.cost_s);
    o["wall_time_s"] = jnum(row.wall_time_s);
    o["cpu_time_s"] = jnum(row.cpu_time_s);
    o["node_steps_per_s"] = jnum(row.node_steps_per_s);
    o["errors"] = ojson::object();
    for (int q = 0; q < quantity_count(r); ++q) o["errors"][quantity_key(q)] = jnum(row.error[q]);
    j["rows"].push_back(o);
  }
  // Per knob, per tolerance: the cheapest value within it, for each quantity.
  j["cheapest"] = ojson::object();
  for (const auto& k : opt.knobs) {
    ojson kj;
    for (double tol : kTolerances) {
      ojson tj;
      for (int q = 0; q < quantity_count(r); ++q) {
        const auto e = cheapest_within(r, k.key, q, tol);
        if (!e.found) {
          tj[quantity_key(q)] = nullptr;
          continue;
        }
        tj[quantity_key(q)] = {{"value", e.value}, {"cost_s", e.cost_s}, {"error", e.error}};
      }
      kj[fmt("%g%%", 100 * tol)] = tj;
    }
    j["cheapest"][k.key] = kj;
  }
  if (!r.searches.empty()) {
    j["searches"] = ojson::array();
    for (const auto& q : r.searches) {
      ojson o;
      o["search"] = q.name;
      o["rule_left_out"] = q.rule.empty() ? ojson(nullptr) : ojson(q.rule);
      o["status"] = q.status;
      if (!q.note.empty()) o["note"] = q.note;
      o["wall_time_s"] = jnum(q.wall_time_s);
      o["time_vs_reference"] = jnum(q.time_ratio);
      o["rule_saves_s"] = jnum(q.rule_saves_s);
      o["runs"] = q.runs;
      o["runs_cancelled"] = q.runs_cancelled;
      o["rounds"] = q.rounds;
      o["runs_decided_passing"] = q.runs_decided_passing;
      o["ballistic_limit_mps"] = jnum(q.ballistic_limit_mps);
      o["bracket_mps"] = {jnum(q.lo_mps), jnum(q.hi_mps)};
      o["error_estimate_mps"] = jnum(q.error_mps);
      o["diff_from_reference_mps"] = jnum(q.diff_mps);
      o["kept"] = q.kept;
      j["searches"].push_back(o);
    }
  }
  j["warnings"] = r.warnings;
  return j.dump(2) + "\n";
}

std::string tradeoff_markdown(const TradeoffResult& r, const TradeoffOptions& opt) {
  std::string md = "# Speed against accuracy: " + r.scene_name + "\n\n";
  std::string ov;
  for (const auto& o : opt.overrides) ov += " --set " + o;
  md += "Scene `" + opt.scene_path + "`" + (ov.empty() ? "" : ov) + ", impact velocity " +
        fmt("%.0f", r.impact_velocity_mps) + " m/s; measured " + (opt.date.empty() ? today() : opt.date) + ". ";
  md += std::string("Each knob is varied alone, the others at ") +
        (opt.around_reference ? "their finest values" : "the scene's values") +
        ". Errors are relative to the reference (every knob at its finest: smallest dt_factor, most contact "
        "iterations, double precision, sliding contact, every yarn modelled, symmetry auto" +
        [&] {
          std::string t;
          for (const auto& [k, v] : opt.reference_overrides) t += (t.empty() ? "; but " : ", ") + k + " = " + v;
          return t;
        }() +
        "). Cost: " + (opt.cost == "cpu" ? "user CPU time" : "wall time") + " of the run, " + std::to_string(opt.jobs) +
        " job(s) at a time, " + std::to_string(opt.solver_threads) + " solver thread(s).";
  if (!opt.note.empty()) md += " " + opt.note;
  md += "\n\n";
  if (!r.rows.empty()) {
    const auto& ref = r.rows[0];
    md += "Reference (`" + ref.case_name + "`): " + ref.status + ", residual velocity " + cell(ref.value_q[0], "%.2f") +
          " m/s, energy absorbed " + cell(ref.value_q[1], "%.2f") + " J, perforation " +
          (ref.value_q[2] >= 0 ? cell(ref.value_q[2] * 1e6, "%.1f") + " us" : std::string("none")) +
          (std::isnan(ref.value_q[3]) ? "" : ", ballistic limit " + cell(ref.value_q[3], "%.1f") + " m/s") + ", cost " +
          cell(ref.cost_s, "%.2f") + " s.\n\n";
  }
  const int nq = quantity_count(r);
  if (!opt.searches_only) {  // (with no knob rows there is nothing to choose between)
    md += "## Verdict: the cheapest setting within 1 % / 5 % of the reference\n\n| knob |";
    for (int q = 0; q < nq; ++q) md += std::string(" ") + quantity_words(q) + " |";
    md += "\n|---|";
    for (int q = 0; q < nq; ++q) md += "---|";
    md += "\n";
    std::vector<std::string> knobs;
    for (const auto& k : opt.knobs) knobs.push_back(k.key);
    knobs.push_back("");
    for (const auto& k : knobs) {
      md += "| " + (k.empty() ? std::string("**any row**") : "`" + k + "`") + " |";
      for (int q = 0; q < nq; ++q) {
        std::string c;
        for (double tol : kTolerances) {
          const auto e = cheapest_within(r, k, q, tol);
          c += (c.empty() ? "" : " / ") + (e.found ? (k.empty() ? short_knob(e.knob) + "=" : std::string()) + e.value +
                                                         " (" + cell(e.cost_s, "%.3g") + " s)"
                                                   : std::string("none"));
        }
        md += " " + c + " |";
      }
      md += "\n";
    }
  }
  md += "\n## Every setting\n\n| knob | value | status | wall s | CPU s | node-steps/s |";
  for (int q = 0; q < nq; ++q) md += std::string(" ") + quantity_words(q) + " error |";
  md += "\n|---|---|---|---|---|---|";
  for (int q = 0; q < nq; ++q) md += "---|";
  md += "\n";
  for (const auto& row : r.rows) {
    md += "| " + short_knob(row.knob) + " | " + row.value + " | " + row.status + " | " + cell(row.wall_time_s, "%.2f") +
          " | " + cell(row.cpu_time_s, "%.2f") + " | " + cell(row.node_steps_per_s, "%.3g") + " |";
    for (int q = 0; q < nq; ++q) md += " " + pct(row.error[q]) + " |";
    md += "\n";
  }
  if (!r.searches.empty()) md += searches_markdown(r.searches, opt);
  if (!r.warnings.empty()) {
    md += "\n## Warnings\n\n";
    for (const auto& w : r.warnings) md += "- " + w + "\n";
  }
  md +=
      "\nCharts: `tradeoff_<quantity>.{png,svg,csv}` (error against cost, log-log, one series per knob, the "
      "Pareto front dashed black). Rows: `tradeoff.csv`; runs: `cases/`.\n";
  return md;
}

std::vector<std::pair<std::string, Chart>> tradeoff_charts(const TradeoffResult& r, const TradeoffOptions& opt) {
  std::vector<std::pair<std::string, Chart>> out;
  const int nq = quantity_count(r);
  for (int q = 0; q < nq; ++q) {
    Chart c;
    c.title = std::string(quantity_words(q)) + ": error against cost";
    c.x = {opt.cost == "cpu" ? "CPU time per run" : "wall time per run", "s"};
    c.x.log = true;
    c.y = {std::string(quantity_words(q)) + " error vs reference", "%"};
    c.y.log = true;
    std::vector<double> all_cost, all_err;
    std::vector<std::string> all_label;
    int zero = 0, off = 0;
    double xmin = INFINITY, xmax = -INFINITY;
    for (size_t ki = 0; ki < opt.knobs.size(); ++ki) {
      const auto& k = opt.knobs[ki];
      Series s;
      s.name = short_knob(k.key);
      s.color = int(ki);
      for (const auto& row : r.rows) {
        if (row.knob != k.key) continue;
        const double e = 100 * row.error[q];
        if (std::isfinite(row.cost_s)) xmin = std::min(xmin, row.cost_s), xmax = std::max(xmax, row.cost_s);
        if (e == 0) ++zero;
        if (!std::isfinite(e)) ++off;
        s.x.push_back(row.cost_s);
        s.y.push_back(e);
        all_cost.push_back(row.cost_s);
        all_err.push_back(e);
      }
      c.series.push_back(s);
    }
    // The front over every row (the reference too: error 0, so it ends the front).
    if (!r.rows.empty()) {
      all_cost.push_back(r.rows[0].cost_s);
      all_err.push_back(0);
      if (std::isfinite(r.rows[0].cost_s))
        xmin = std::min(xmin, r.rows[0].cost_s), xmax = std::max(xmax, r.rows[0].cost_s);
    }
    Series front{"Pareto front", {}, {}, SeriesStyle::line};
    front.color = 7;
    front.dashed = true;
    for (size_t i : pareto_front(all_cost, all_err))
      if (all_err[i] > 0) front.x.push_back(all_cost[i]), front.y.push_back(all_err[i]);
    c.series.push_back(front);
    if (std::isfinite(xmin)) {
      Series one{"1 % and 5 %", {xmin, xmax, NAN, xmin, xmax}, {1, 1, NAN, 5, 5}, SeriesStyle::line};
      one.color = 6;
      c.series.push_back(one);
    }
    std::string sub = r.scene_name + " at " + fmt("%.0f", r.impact_velocity_mps) + " m/s";
    if (zero) sub += "; " + std::to_string(zero) + " row(s) with zero error not shown";
    if (off) sub += "; " + std::to_string(off) + " diverged / outcome differs not shown";
    c.subtitle = sub;
    out.emplace_back(std::string("tradeoff_") + quantity_key(q), c);
  }
  return out;
}

// ---------------------------------------------------------------------------------------

std::string shipped_tradeoff_path(const Scene& scene) {
  const std::string p = assets_dir() + "/tradeoff/" + scene.name + ".json";
  std::error_code ec;
  return fs::exists(p, ec) ? p : "";
}

namespace {

// The scene as a measurement sees it: the speed/accuracy knobs (what a suggestion changes)
// and what does not change the physics (threads, SIMD, outputs, the name) set aside.
std::string physics_of(Scene s) {
  const Scene d;
  s.name = d.name;
  s.solver.dt_factor = d.solver.dt_factor;
  s.solver.contact_iterations = d.solver.contact_iterations;
  s.solver.precision = d.solver.precision;
  s.solver.model = d.solver.model;
  s.solver.symmetry = d.solver.symmetry;
  s.fabric.yarns_per_element = d.fabric.yarns_per_element;
  // (the graded mesh's bands go with its knob: they change nothing while it is 1)
  s.fabric.far_yarns_per_element = d.fabric.far_yarns_per_element;
  s.fabric.full_resolution_m = d.fabric.full_resolution_m;
  s.fabric.clamp_resolution_m = d.fabric.clamp_resolution_m;
  s.solver.threads = d.solver.threads;
  s.solver.simd = d.solver.simd;
  s.output = d.output;
  return scene_to_toml(s);
}

}  // namespace

std::vector<std::string> shipped_tradeoff_suggestions(const Scene& scene) {
  const std::string path = shipped_tradeoff_path(scene);
  if (path.empty()) return {};
  try {
    // Within 1 %; for a knob with nothing there, within 5 % (each line says which).
    const std::string text = read_text_file(path);
    // Only for the scene it was measured on: the shipped scene of that name with the
    // recorded overrides, apart from the knobs themselves.
    const auto j = ojson::parse(text, nullptr, false);
    if (j.is_discarded() || !j.is_object()) return {};
    const auto ov = j.value("overrides", std::vector<std::string>{});
    const Scene measured = load_scene(assets_dir() + "/scenes/" + scene.name + ".toml", ov);
    if (physics_of(measured) != physics_of(scene)) return {};
    auto out = tradeoff_suggestions(scene, text, 0.01);
    for (const auto& s5 : tradeoff_suggestions(scene, text, 0.05)) {
      const std::string knob = s5.substr(0, s5.find('='));
      if (std::none_of(out.begin(), out.end(), [&](const std::string& s1) { return s1.rfind(knob + "=", 0) == 0; }))
        out.push_back(s5);
    }
    // Each row varied one knob with the others at the measurement's base (the measured
    // scene's values, or the reference's with --around reference): a knob's suggestion holds
    // only where the run's other knobs are at that base (a pin-jointed run is not told what
    // a graded mesh did to the sliding model).
    const bool around_reference = j.value("around", std::string("scene")) == "reference";
    const std::string ref_case = j.contains("reference") && j["reference"].is_object()
                                     ? j["reference"].value("case", std::string())
                                     : std::string();
    auto base_value = [&](const std::string& knob) -> std::string {
      if (!around_reference) return scene_knob_value(measured, knob);
      const std::string key = knob + "=";
      for (size_t at = 0; at < ref_case.size();) {
        size_t end = ref_case.find("__", at);
        if (end == std::string::npos) end = ref_case.size();
        const std::string part = ref_case.substr(at, end - at);
        if (part.rfind(key, 0) == 0) return normalise(knob, part.substr(key.size()));
        at = end + 2;
      }
      return "";
    };
    std::vector<std::string> knobs;
    if (j.contains("rows") && j["rows"].is_array())
      for (const auto& row : j["rows"]) {
        const std::string k = row.value("knob", std::string());
        if (!k.empty() && std::find(knobs.begin(), knobs.end(), k) == knobs.end()) knobs.push_back(k);
      }
    std::vector<std::string> kept;
    for (const auto& line : out) {
      const std::string knob = line.substr(0, line.find('='));
      const bool others_at_base = std::all_of(knobs.begin(), knobs.end(), [&](const std::string& k) {
        return k == knob || scene_knob_value(scene, k) == base_value(k);
      });
      if (others_at_base) kept.push_back(line);
    }
    return kept;
  } catch (const std::exception&) {
    return {};
  }
}

void add_suggestions_to_summary(const std::string& summary_path, const std::vector<std::string>& suggestions) {
  auto j = ojson::parse(read_text_file(summary_path));
  j["suggestions"] = suggestions;
  write_file_atomic(summary_path, j.dump(2) + "\n");
}

std::vector<std::string> tradeoff_suggestions(const Scene& scene, const std::string& text, double tolerance,
                                              double min_ratio) {
  std::vector<std::string> out;
  const auto j = ojson::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("rows") || !j["rows"].is_array()) return out;
  if (j.value("scene", std::string()) != scene.name) return out;
  const std::string date = j.value("date", std::string("?"));
  // The measurement's own note (ravel tradeoff --note): what it does not cover, said with each line.
  const std::string note = j.contains("note") && j["note"].is_string() ? j["note"].get<std::string>() : "";
  const double v0 = j.contains("impact_velocity_mps") && j["impact_velocity_mps"].is_number()
                        ? j["impact_velocity_mps"].get<double>()
                        : NAN;
  auto cost_of = [](const ojson& row) {
    return row.contains("cost_s") && row["cost_s"].is_number() ? row["cost_s"].get<double>() : NAN;
  };
  // Knobs in the file's order.
  std::vector<std::string> knobs;
  for (const auto& row : j["rows"]) {
    const std::string k = row.value("knob", std::string());
    if (!k.empty() && std::find(knobs.begin(), knobs.end(), k) == knobs.end()) knobs.push_back(k);
  }
  for (const auto& knob : knobs) {
    const std::string mine = scene_knob_value(scene, knob);
    if (mine.empty()) continue;
    double my_cost = NAN;
    const ojson* my_row = nullptr;
    for (const auto& row : j["rows"])
      if (row.value("knob", std::string()) == knob && normalise(knob, row.value("value", std::string())) == mine)
        my_cost = cost_of(row), my_row = &row;
    if (!std::isfinite(my_cost)) continue;  // the run's own setting was not measured
    // A setting is suggested for the results it keeps within the tolerance only if it puts no
    // other result further off than the tolerance or than the run's own setting does: a
    // coarse mesh whose perforation time happens to match but whose energy is 30 % off is not
    // "the same answer, cheaper". An error that is not a number or is missing (outcome
    // differs) counts as infinite; where the run's own setting has no finite error (its
    // measured run diverged), the tolerance alone is the bound.
    auto error_of = [](const ojson& row, const std::string& q) {
      if (!row.contains("errors") || !row["errors"].contains(q) || !row["errors"][q].is_number())
        return std::numeric_limits<double>::infinity();
      return row["errors"][q].get<double>();
    };
    auto no_worse = [&](const ojson& row) {
      std::vector<std::string> qs;
      for (const ojson* r : {&row, my_row})
        if (r && r->contains("errors") && (*r)["errors"].is_object())
          for (auto it = (*r)["errors"].begin(); it != (*r)["errors"].end(); ++it)
            if (std::find(qs.begin(), qs.end(), it.key()) == qs.end()) qs.push_back(it.key());
      if (qs.empty()) return false;
      for (const auto& q : qs) {
        const double own = error_of(*my_row, q);
        if (!(error_of(row, q) <= std::max(tolerance, std::isfinite(own) ? own : tolerance))) return false;
      }
      return true;
    };
    const ojson* best = nullptr;
    std::vector<std::string> best_q;
    for (const auto& row : j["rows"]) {
      if (row.value("knob", std::string()) != knob) continue;
      const std::string st = row.value("status", std::string());
      if (st != "completed" && st != "warned") continue;
      const double c = cost_of(row);
      if (!(c > 0) || my_cost / c < min_ratio) continue;
      std::vector<std::string> qs;
      if (row.contains("errors"))
        for (auto it = row["errors"].begin(); it != row["errors"].end(); ++it)
          if (it.value().is_number() && it.value().get<double>() <= tolerance) qs.push_back(it.key());
      if (qs.empty() || !no_worse(row)) continue;
      if (!best || qs.size() > best_q.size() || (qs.size() == best_q.size() && c < cost_of(*best))) {
        best = &row;
        best_q = qs;
      }
    }
    if (!best) continue;
    std::string words;
    for (size_t i = 0; i < best_q.size(); ++i) {
      std::string w = best_q[i];
      std::replace(w.begin(), w.end(), '_', ' ');
      words += (i == 0 ? "" : i + 1 == best_q.size() ? " and " : ", ") + w;
    }
    out.push_back(knob + "=" + best->value("value", std::string()) + " gives " + words + " within " +
                  fmt("%g", 100 * tolerance) + " % of the reference at " + fmt("%.1f", my_cost / cost_of(*best)) +
                  "x less cost than " + knob + "=" + mine + " (measured by ravel tradeoff on " + date +
                  (std::isfinite(v0) ? ", " + fmt("%.0f", v0) + " m/s" : std::string()) +
                  (note.empty() ? std::string() : "; " + note) + ")");
  }
  return out;
}

}  // namespace ravel::studies
