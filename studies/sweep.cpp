#include "sweep.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "results.h"
#include "run_record.h"
#include "version.h"
#include "work_queue.h"

namespace ravel::studies {

namespace fs = std::filesystem;

namespace {

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  const auto b = s.find_last_not_of(" \t");
  return s.substr(a, b - a + 1);
}

bool parse_number(const std::string& s, double* v) {
  char* end = nullptr;
  *v = std::strtod(s.c_str(), &end);
  return !s.empty() && *end == 0 && std::isfinite(*v);
}

std::string format_number(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}

std::string host_name() {
  char h[256] = {0};
  if (gethostname(h, sizeof h - 1) != 0) return "host";
  std::string s(h);
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

}  // namespace

Vary parse_vary(const std::string& text, const std::string& base_scene_path,
                const std::vector<std::string>& base_overrides) {
  const auto eq = text.find('=');
  if (eq == std::string::npos) throw StudyError("--vary '" + text + "': expected key=start:stop:step or key=v1,v2,...");
  Vary v;
  v.key = trim(text.substr(0, eq));
  const std::string spec = trim(text.substr(eq + 1));
  const auto& keys = scene_keys();
  if (std::none_of(keys.begin(), keys.end(), [&](const SceneKeyInfo& k) { return k.key == v.key; }))
    throw StudyError("--vary " + v.key + ": unknown scene key (see 'ravel keys')");
  if (v.key == "name" || v.key == "solver.threads" || v.key == "output.progress")
    throw StudyError("--vary " + v.key + ": this key does not change the physics; vary a physical key");
  if (spec.empty()) throw StudyError("--vary " + v.key + ": no values given");
  if (spec.find(':') != std::string::npos) {
    std::vector<std::string> parts;
    std::stringstream ss(spec);
    std::string p;
    while (std::getline(ss, p, ':')) parts.push_back(trim(p));
    double a, b, step;
    if (parts.size() != 3 || !parse_number(parts[0], &a) || !parse_number(parts[1], &b) ||
        !parse_number(parts[2], &step))
      throw StudyError("--vary " + v.key + ": range '" + spec + "' is not start:stop:step with three numbers");
    if (step <= 0) throw StudyError("--vary " + v.key + ": step must be > 0 in '" + spec + "'");
    if (b < a) throw StudyError("--vary " + v.key + ": stop < start in '" + spec + "'");
    const double n = std::floor((b - a) / step + 1e-9);
    if (n > 100000) throw StudyError("--vary " + v.key + ": range '" + spec + "' has more than 100000 values");
    for (int i = 0; i <= int(n); ++i) v.values.push_back(format_number(a + i * step));
  } else {
    std::stringstream ss(spec);
    std::string p;
    while (std::getline(ss, p, ',')) {
      p = trim(p);
      if (p.empty()) throw StudyError("--vary " + v.key + ": empty value in list '" + spec + "'");
      if (std::find(v.values.begin(), v.values.end(), p) != v.values.end())
        throw StudyError("--vary " + v.key + ": value '" + p + "' listed twice");
      v.values.push_back(p);
    }
  }
  // Validate every value as the scene loader would (ranges, types), before running anything.
  for (const auto& val : v.values) {
    auto ov = base_overrides;
    ov.push_back(v.key + "=" + val);
    try {
      load_scene(base_scene_path, ov);
    } catch (const SceneError& e) {
      throw StudyError("--vary " + v.key + ": value '" + val + "' is not accepted: " + e.problem());
    }
  }
  return v;
}

std::string Case::name() const {
  std::string n;
  for (const auto& [k, v] : settings) {
    if (!n.empty()) n += "__";
    n += k + "=" + v;
  }
  if (n.empty()) n = "base";
  for (char& c : n)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '=' || c == '-' || c == '+' || c == '_'))
      c = '_';
  if (n.size() > 200) {  // keep folder names legal; the settings are in case.json
    n = n.substr(0, 180) + "_" + std::to_string(std::hash<std::string>{}(n) % 100000000);
  }
  return n;
}

std::vector<std::string> Case::overrides() const {
  std::vector<std::string> o;
  for (const auto& [k, v] : settings) o.push_back(k + "=" + v);
  return o;
}

std::vector<Case> expand_cases(const std::vector<Vary>& vary) {
  std::vector<Case> out(1);
  for (const auto& v : vary) {
    std::vector<Case> next;
    for (const auto& c : out)
      for (const auto& val : v.values) {
        Case d = c;
        d.settings.emplace_back(v.key, val);
        next.push_back(d);
      }
    out = std::move(next);
  }
  for (size_t i = 0; i < out.size(); ++i) out[i].index = int(i);
  return out;
}

Shard parse_shard(const std::string& text) {
  Shard s;
  char slash = 0, rest = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &s.index, &slash, &s.count, &rest) != 3 || slash != '/' || s.count < 1 ||
      s.index < 1 || s.index > s.count)
    throw StudyError("--shard: expected i/n with 1 <= i <= n (e.g. 3/8), got '" + text + "'");
  return s;
}

std::vector<Case> shard_cases(const std::vector<Case>& all, Shard shard) {
  std::vector<Case> out;
  for (const auto& c : all)
    if (shard.contains(c.index)) out.push_back(c);
  return out;
}

std::string case_dir(const std::string& out_dir, const Case& c) {
  return out_dir + "/" + c.name();
}

bool case_finished(const std::string& out_dir, const Case& c) {
  std::error_code ec;
  return fs::exists(case_dir(out_dir, c) + "/summary.json", ec);
}

std::string read_text_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw OutputError(path + ": cannot read");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

namespace {

std::string csv_cell(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string o = "\"";
  for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c);
  return o + "\"";
}

std::string json_cell(const nlohmann::json& v) {
  if (v.is_null()) return "";
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_integer()) return std::to_string(v.get<long long>());
  if (v.is_number()) {
    char b[40];
    std::snprintf(b, sizeof b, "%.9g", v.get<double>());
    return b;
  }
  if (v.is_string()) return v.get<std::string>();
  if (v.is_array()) return std::to_string(v.size());
  return v.dump();
}

// Remove temporary case folders left by killed runs of this host (the process is gone).
void remove_stale_temporaries(const std::string& out_dir) {
  const std::string mine = "-" + host_name() + "-";
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(out_dir, ec)) {
    const std::string n = e.path().filename().string();
    if (n.rfind(".tmp-", 0) != 0) continue;
    const auto at = n.rfind(mine);
    if (at == std::string::npos) continue;
    const long pid = std::strtol(n.c_str() + at + mine.size(), nullptr, 10);
    if (pid > 0 && ::kill(pid_t(pid), 0) != 0 && errno == ESRCH) fs::remove_all(e.path(), ec);
  }
}

// A chart over the first varied key (with the key's unit), one series per combination of
// the others: point() adds to the series of that name, sorted() orders each series by x.
struct SeriesChart {
  Chart c;
  std::map<std::string, size_t> index;
  SeriesChart(const std::string& title, const std::string& x_key) {
    c.title = title;
    c.x = {x_key, ""};
    for (const auto& k : scene_keys())
      if (k.key == x_key) c.x.unit = k.unit;
  }
  void point(const std::string& name, double x, double y) {
    auto [it, added] = index.emplace(name, c.series.size());
    if (added) {
      Series s;
      s.name = name;
      c.series.push_back(s);
    }
    c.series[it->second].x.push_back(x);
    c.series[it->second].y.push_back(y);
  }
  Chart sorted() {
    for (auto& s : c.series) {
      std::vector<size_t> o(s.x.size());
      for (size_t i = 0; i < o.size(); ++i) o[i] = i;
      std::sort(o.begin(), o.end(), [&](size_t a, size_t b) { return s.x[a] < s.x[b]; });
      Series t = s;
      for (size_t i = 0; i < o.size(); ++i) t.x[i] = s.x[o[i]], t.y[i] = s.y[o[i]];
      s = t;
    }
    return c;
  }
};

}  // namespace

std::string results_csv(const std::string& out_dir, const std::vector<Case>& cases,
                        const std::vector<std::string>& varied_keys) {
  std::vector<std::string> summary_keys;
  std::vector<std::pair<const Case*, nlohmann::ordered_json>> rows;
  for (const auto& c : cases) {
    if (!case_finished(out_dir, c)) continue;
    RunRecord r = read_run_record(case_dir(out_dir, c));
    if (!r.ok) throw OutputError(case_dir(out_dir, c) + "/summary.json: " + r.error);
    nlohmann::ordered_json j = std::move(r.json);
    for (auto it = j.begin(); it != j.end(); ++it) {
      const std::string k = it.value().is_array() ? it.key() + "_count" : it.key();
      if (std::find(summary_keys.begin(), summary_keys.end(), k) == summary_keys.end()) summary_keys.push_back(k);
    }
    rows.emplace_back(&c, std::move(j));
  }
  std::string out = "case";
  for (const auto& k : varied_keys) out += "," + csv_cell(k);
  for (const auto& k : summary_keys) out += "," + csv_cell(k);
  out += "\n";
  for (const auto& [c, j] : rows) {
    out += csv_cell(c->name());
    for (const auto& k : varied_keys) {
      std::string v;
      for (const auto& [sk, sv] : c->settings)
        if (sk == k) v = sv;
      out += "," + csv_cell(v);
    }
    for (const auto& k : summary_keys) {
      std::string v;
      if (j.contains(k))
        v = json_cell(j[k]);
      else if (k.size() > 6 && k.substr(k.size() - 6) == "_count" && j.contains(k.substr(0, k.size() - 6)))
        v = json_cell(j[k.substr(0, k.size() - 6)]);
      out += "," + csv_cell(v);
    }
    out += "\n";
  }
  return out;
}

int Csv::column(const std::string& name) const {
  for (size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return int(i);
  return -1;
}

std::string Csv::cell(const std::vector<std::string>& row, const std::string& name) const {
  const int i = column(name);
  return i >= 0 && i < int(row.size()) ? row[size_t(i)] : std::string();
}

Csv parse_csv(const std::string& text) {
  Csv csv;
  std::vector<std::string> row;
  std::string cell;
  bool quoted = false, any = false;
  auto end_row = [&] {
    row.push_back(cell);
    cell.clear();
    if (csv.header.empty())
      csv.header = row;
    else
      csv.rows.push_back(row);
    row.clear();
    any = false;
  };
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        cell += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cell += c;
      }
      continue;
    }
    if (c == '"')
      quoted = true, any = true;
    else if (c == ',')
      row.push_back(cell), cell.clear(), any = true;
    else if (c == '\n')
      end_row();
    else if (c != '\r')
      cell += c, any = true;
  }
  if (any || !cell.empty() || !row.empty()) end_row();
  return csv;
}

bool put_chart_x_first(std::vector<std::string>* keys, const std::string& x_key) {
  const auto it = std::find(keys->begin(), keys->end(), x_key);
  if (it == keys->end()) return false;
  std::rotate(keys->begin(), it, it + 1);
  return true;
}

std::string joined_keys(const std::vector<std::string>& keys) {
  std::string s;
  for (const auto& k : keys) s += (s.empty() ? "" : ", ") + k;
  return s;
}

std::string column_unit(const std::string& column) {
  static const std::pair<const char*, const char*> units[] = {{"_mps", "m/s"}, {"_mm", "mm"}, {"_J", "J"},
                                                              {"_N", "N"},     {"_us", "us"}, {"_s", "s"}};
  for (const auto& [suffix, unit] : units) {
    const std::string s = suffix;
    if (column.size() > s.size() && column.compare(column.size() - s.size(), s.size(), s) == 0) return unit;
  }
  return "";
}

std::string column_label(const std::string& column) {
  std::string c = column;
  const std::string unit = column_unit(column);
  if (!unit.empty()) c = c.substr(0, c.rfind('_'));
  std::replace(c.begin(), c.end(), '_', ' ');
  return c;
}

std::vector<std::pair<std::string, Chart>> sweep_charts(const Csv& results, const std::vector<std::string>& varied_keys,
                                                        const std::vector<std::string>& extra_y) {
  std::vector<std::pair<std::string, Chart>> out;
  if (varied_keys.empty() || results.rows.empty()) return out;
  const int xc = results.column(varied_keys[0]);
  if (xc < 0) return out;
  double tmp;
  for (const auto& r : results.rows)
    if (!parse_number(r[size_t(xc)], &tmp)) return out;  // not a numeric key: no x axis
  struct Y {
    std::string column, label, unit;
  };
  std::vector<Y> ys = {{"energy_absorbed_J", "energy absorbed", "J"},
                       {"residual_velocity_mps", "residual velocity", "m/s"}};
  for (const auto& col : extra_y)
    if (std::none_of(ys.begin(), ys.end(), [&](const Y& y) { return y.column == col; }))
      ys.push_back({col, column_label(col), column_unit(col)});
  for (const auto& y : ys) {
    const int yc = results.column(y.column);
    if (yc < 0) continue;
    SeriesChart sc(y.label + " vs " + varied_keys[0], varied_keys[0]);
    Chart& c = sc.c;
    c.y = {y.label, y.unit};
    c.y.include_zero = true;
    int c_left_out = 0;
    for (const auto& r : results.rows) {
      std::string name;
      for (size_t k = 1; k < varied_keys.size(); ++k) {
        const int kc = results.column(varied_keys[k]);
        name += (name.empty() ? "" : ", ") + varied_keys[k] + " = " + (kc >= 0 ? r[size_t(kc)] : "");
      }
      if (name.empty()) name = y.label;
      double xv, yv;
      parse_number(r[size_t(xc)], &xv);
      if (!parse_number(r[size_t(yc)], &yv)) yv = NAN;
      const int stc = results.column("status");
      if (stc >= 0 && r[size_t(stc)] != "completed") yv = NAN, ++c_left_out;  // diverged: no answer
      sc.point(name, xv, yv);
    }
    if (c_left_out)
      c.subtitle = std::to_string(c_left_out) + " case(s) left out: the run diverged (see results.csv, status)";
    out.emplace_back(y.column + "_vs_" + varied_keys[0], sc.sorted());
  }
  return out;
}

void apply_repeats(std::vector<Vary>& vary, int repeats, std::map<std::string, std::string>* base_of) {
  const auto it =
      std::find_if(vary.begin(), vary.end(), [](const Vary& v) { return v.key == "projectile.velocity_mps"; });
  if (it == vary.end())
    throw StudyError(
        "--repeats needs --vary projectile.velocity_mps=...: it runs each of those velocities N times, 1e-6 m/s "
        "apart");
  if (repeats != 1) *it = repeat_velocities(*it, repeats, base_of);  // (which refuses N outside [1, 1000])
}

std::vector<std::string> write_perforation_outputs(const std::string& out_dir, const Csv& results,
                                                   const std::vector<std::string>& varied_keys,
                                                   const std::map<std::string, std::string>& base_of, int repeats,
                                                   int* groups) {
  std::vector<std::string> written;
  if (groups) *groups = 0;
  if (varied_keys.empty()) return written;
  const std::string stem = out_dir + "/charts/perforation_probability_vs_" + varied_keys[0];
  if (repeats <= 1) {
    std::error_code ec;
    std::filesystem::remove(out_dir + "/perforation.csv", ec);
    for (const char* ext : {".png", ".svg", ".csv"}) std::filesystem::remove(stem + ext, ec);
    return written;
  }
  if (results.rows.empty()) return written;
  const PerforationTable table = perforation_table(results, varied_keys, base_of);
  write_file_atomic(out_dir + "/perforation.csv", table.csv);
  written.push_back(out_dir + "/perforation.csv");
  if (groups) *groups = table.groups;
  if (finite_point_count(table.chart) > 0) {
    prepare_output_dir(out_dir + "/charts");
    write_chart(table.chart, stem);
    written.push_back(stem);
  }
  return written;
}

Vary repeat_velocities(const Vary& velocities, int repeats, std::map<std::string, std::string>* base_of) {
  if (repeats < 1 || repeats > 1000)
    throw StudyError("--repeats " + std::to_string(repeats) + ": expected a whole number from 1 to 1000");
  Vary out{velocities.key, {}};
  std::vector<double> vs;
  for (const auto& text : velocities.values) {
    double v;
    if (!parse_number(text, &v))
      throw StudyError("--vary " + velocities.key + ": value '" + text + "' is not a number");
    vs.push_back(v);
  }
  std::vector<double> sorted = vs;
  std::sort(sorted.begin(), sorted.end());
  for (size_t i = 0; i + 1 < sorted.size(); ++i)
    if ((sorted[i + 1] - sorted[i]) / kRepeatStep_mps < repeats - 1e-3)  // (in steps, beside rounding)
      throw StudyError("--repeats " + std::to_string(repeats) + ": the velocities " + format_number(sorted[i]) +
                       " and " + format_number(sorted[i + 1]) + " m/s lie closer than " + std::to_string(repeats) +
                       " x 1e-6 m/s, so their repeats would overlap");
  // Repeat 0 keeps the value as given, so that a sweep rerun with --repeats reuses its runs.
  for (size_t i = 0; i < vs.size(); ++i)
    for (int k = 0; k < repeats; ++k) {
      char b[64];
      std::snprintf(b, sizeof b, "%.6f", vs[i] + k * kRepeatStep_mps);
      const std::string text = k == 0 ? velocities.values[i] : std::string(b);
      out.values.push_back(text);
      if (base_of) (*base_of)[text] = velocities.values[i];
    }
  return out;
}

PerforationTable perforation_table(const Csv& results, const std::vector<std::string>& varied_keys,
                                   const std::map<std::string, std::string>& base_of) {
  PerforationTable t;
  struct Group {
    std::vector<std::string> keys;  // the varied keys' values, velocities at their base
    int runs = 0, decided = 0, perforated = 0, undecided = 0, diverged = 0;
    double residual_sum = 0, energy_sum = 0;
    int energy_n = 0, residual_n = 0;
  };
  std::vector<Group> groups;
  std::map<std::vector<std::string>, size_t> index;
  for (const auto& r : results.rows) {
    std::vector<std::string> keys;
    for (const auto& k : varied_keys) {
      std::string v = results.cell(r, k);
      if (const auto it = base_of.find(v); k == "projectile.velocity_mps" && it != base_of.end()) v = it->second;
      keys.push_back(v);
    }
    if (!index.count(keys)) index[keys] = groups.size(), groups.push_back(Group{keys});
    Group& g = groups[index[keys]];
    ++g.runs;
    if (results.cell(r, "status") != "completed") {
      ++g.diverged;
      continue;
    }
    if (results.cell(r, "end_reason") == "end_time") {
      ++g.undecided;
      continue;
    }
    ++g.decided;
    double x;
    if (parse_number(results.cell(r, "energy_absorbed_J"), &x)) g.energy_sum += x, ++g.energy_n;
    if (results.cell(r, "perforated") == "true") {
      ++g.perforated;
      if (parse_number(results.cell(r, "residual_velocity_mps"), &x)) g.residual_sum += x, ++g.residual_n;
    }
  }
  t.groups = int(groups.size());
  for (const auto& k : varied_keys) t.csv += csv_cell(k) + ",";
  t.csv +=
      "runs,decided,perforated,perforation_probability,undecided,diverged,residual_velocity_mps,energy_absorbed_J\n";
  auto num = [](double v) {
    char b[40];
    std::snprintf(b, sizeof b, "%.6g", v);
    return std::string(b);
  };
  for (const auto& g : groups) {
    for (const auto& v : g.keys) t.csv += csv_cell(v) + ",";
    t.csv += std::to_string(g.runs) + "," + std::to_string(g.decided) + "," + std::to_string(g.perforated) + "," +
             (g.decided ? num(double(g.perforated) / g.decided) : "") + "," + std::to_string(g.undecided) + "," +
             std::to_string(g.diverged) + "," + (g.residual_n ? num(g.residual_sum / g.residual_n) : "") + "," +
             (g.energy_n ? num(g.energy_sum / g.energy_n) : "") + "\n";
  }
  // The chart: probability against the first key, a series per combination of the others.
  if (varied_keys.empty() || groups.empty()) return t;
  for (const auto& g : groups) {
    double x;
    if (!parse_number(g.keys[0], &x)) return t;
  }
  SeriesChart sc("perforation probability vs " + varied_keys[0], varied_keys[0]);
  Chart& c = sc.c;
  c.subtitle = "share of the decided runs that perforated";
  c.y = {"perforation probability", ""};
  c.y.fixed_range = true;  // 0 and 1 a little inside the frame, where the points show
  c.y.min = -0.05;
  c.y.max = 1.05;
  for (const auto& g : groups) {
    std::string name;
    for (size_t k = 1; k < varied_keys.size(); ++k)
      name += (name.empty() ? "" : ", ") + varied_keys[k] + " = " + g.keys[k];
    double x;
    parse_number(g.keys[0], &x);
    sc.point(name.empty() ? "perforation probability" : name, x, g.decided ? double(g.perforated) / g.decided : NAN);
  }
  t.chart = sc.sorted();
  return t;
}

SweepReport run_sweep(const std::vector<Case>& all_cases, const std::vector<Case>& to_run, const SweepOptions& opt,
                      const std::vector<std::string>& varied_keys, const SweepHooks& hooks,
                      const std::atomic<bool>* interrupt) {
  // Cases are named by their varied settings only: a folder that holds cases of another
  // base scene, --set, scene file content or ravel build would be silently mixed in.
  // Refuse it, naming what changed (or, with opt.restart, remove those cases first).
  const std::string base_toml = scene_to_toml(load_scene(opt.scene_path, opt.overrides));
  const std::string build = std::string(version()) + " (source " + source_commit() + ")";
  for (const auto& c : all_cases) {
    if (!case_finished(opt.out_dir, c)) continue;
    std::string text;
    try {
      text = read_text_file(case_dir(opt.out_dir, c) + "/case.json");
    } catch (const OutputError&) {
      continue;  // made by hand: nothing to compare
    }
    const auto cj = nlohmann::json::parse(text, nullptr, false);
    if (cj.is_discarded()) continue;
    const auto ov = cj.value("base_overrides", std::vector<std::string>{});
    const auto scene = cj.value("base_scene", std::string());
    const auto toml = cj.value("base_scene_toml", std::string());
    const auto made_by = cj.value("ravel", std::string("an older ravel"));
    std::string changed;
    if (ov != opt.overrides || scene != opt.scene_path) {
      std::string had;
      for (const auto& o : ov) had += " --set " + o;
      changed = "scene " + scene + (had.empty() ? ", no --set" : "," + had);
    } else if (toml != base_toml) {
      // Name the keys whose lines differ (scene_to_toml writes one key per line).
      auto keys_of = [](const std::string& t) {
        std::map<std::string, std::string> m;
        std::istringstream in(t);
        std::string section;
        for (std::string line; std::getline(in, line);) {
          if (line.rfind("[", 0) == 0) section = line.substr(1, line.find(']') - 1) + ".";
          const auto eq = line.find(" = ");
          if (eq != std::string::npos && line[0] != '#') m[section + line.substr(0, eq)] = line.substr(eq + 3);
        }
        return m;
      };
      const auto a = keys_of(toml), b = keys_of(base_toml);
      std::string keys;
      for (const auto& [k, v] : b)
        if (!a.count(k) || a.at(k) != v) keys += (keys.empty() ? "" : ", ") + k;
      changed = "the scene file's content changed since (" + (keys.empty() ? std::string("its text") : keys) + ")";
    } else if (made_by != build) {
      changed = "made by ravel " + made_by + ", this is ravel " + build;
    }
    if (!changed.empty()) {
      if (!opt.restart)
        throw StudyError(
            "--out " + opt.out_dir + ": holds finished cases of a different sweep (" + changed +
            "); rerun with the same scene, --set and ravel to resume, " +
            std::string(opt.offers_restart ? "--restart to start over, " : "remove the folder to start over, ") +
            "or use another folder");
      std::error_code ec;
      for (const auto& d : all_cases)
        if (fs::exists(case_dir(opt.out_dir, d) + "/case.json", ec)) fs::remove_all(case_dir(opt.out_dir, d), ec);
      fs::remove(opt.out_dir + "/results.csv", ec);
    }
    break;  // one finished case tells
  }
  prepare_output_dir(opt.out_dir);
  remove_stale_temporaries(opt.out_dir);
  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };

  SweepReport rep;
  rep.cases_total = int(all_cases.size());
  rep.cases_in_shard = int(to_run.size());
  SweepProgress prog;
  prog.total = int(to_run.size());
  std::mutex mu;
  std::atomic<long> tmp_counter{0};
  const std::string host = host_name();

  auto report_case = [&](const CaseResult& r) {
    std::lock_guard<std::mutex> lock(mu);
    ++prog.done;
    if (r.skipped)
      ++prog.skipped, ++rep.cases_skipped;
    else if (!r.ok)
      ++prog.failed, ++rep.cases_failed, rep.errors.push_back(r.c.name() + ": " + r.error);
    else
      ++rep.cases_run;
    prog.wall_time_s = elapsed();
    if (hooks.on_case) hooks.on_case(r);
    if (hooks.on_progress) hooks.on_progress(prog);
  };

  // One item per case; an interrupted case returns without a result (a rerun resumes it).
  auto run_case = [&](size_t i) {
    const Case& c = to_run[i];
    CaseResult r;
    r.c = c;
    const std::string final_dir = case_dir(opt.out_dir, c);
    if (case_finished(opt.out_dir, c)) {
      r.skipped = true;
      report_case(r);
      return;
    }
    const std::string tmp = opt.out_dir + "/.tmp-" + c.name().substr(0, 120) + "-" + host + "-" +
                            std::to_string(::getpid()) + "-" + std::to_string(tmp_counter.fetch_add(1));
    std::error_code ec;
    try {
      auto ov = opt.overrides;
      for (const auto& o : c.overrides()) ov.push_back(o);
      ov.push_back("solver.threads=" + std::to_string(opt.solver_threads));
      ov.push_back("output.progress=false");
      Scene scene = load_scene(opt.scene_path, ov);
      fs::remove_all(tmp, ec);
      fs::create_directories(tmp, ec);
      if (ec) throw OutputError(tmp + ": cannot create (" + ec.message() + ")");
      Simulation sim(scene);
      sim.run(interrupt);
      if (opt.extend_undecided && sim.extend_to(scene.solver.max_end_time_s)) sim.run(interrupt);
      if (sim.summary().status == RunStatus::interrupted) {
        fs::remove_all(tmp, ec);
        return;  // not finished: a rerun resumes it
      }
      if (sim.summary().status == RunStatus::diverged) {
        std::lock_guard<std::mutex> lock(mu);
        ++rep.cases_diverged;
      }
      nlohmann::ordered_json cj;
      cj["index"] = c.index;
      cj["name"] = c.name();
      cj["settings"] = nlohmann::ordered_json::object();
      for (const auto& [k, v] : c.settings) cj["settings"][k] = v;
      cj["base_scene"] = opt.scene_path;
      cj["base_overrides"] = opt.overrides;
      cj["base_scene_toml"] = base_toml;  // the resolved scene a resume must match
      cj["ravel"] = build;
      write_file_atomic(tmp + "/case.json", cj.dump(2) + "\n");
      if (hooks.on_simulation) {
        std::lock_guard<std::mutex> lock(mu);
        hooks.on_simulation(c, sim, tmp);
      }
      write_run_outputs(tmp, sim);  // summary.json last
      r.summary_json_text = summary_json(sim.summary(), sim.scene());
      // Publish the whole folder at once. Another shard may have finished it meanwhile.
      if (case_finished(opt.out_dir, c)) {
        fs::remove_all(tmp, ec);
      } else {
        fs::remove_all(final_dir, ec);  // an incomplete folder not made by ravel
        fs::rename(tmp, final_dir, ec);
        if (ec) throw OutputError(final_dir + ": cannot move the finished case into place (" + ec.message() + ")");
      }
    } catch (const std::exception& e) {
      fs::remove_all(tmp, ec);
      r.ok = false;
      r.error = e.what();
    }
    report_case(r);
  };

  const int jobs = std::max(1, std::min<int>(opt.jobs, std::max<int>(1, int(to_run.size()))));
  run_queue(to_run.size(), jobs, interrupt, run_case);

  rep.interrupted = interrupt && interrupt->load();
  rep.wall_time_s = elapsed();
  rep.cases_per_hour = rep.wall_time_s > 0 ? rep.cases_run / (rep.wall_time_s / 3600.0) : 0;

  write_file_atomic(opt.out_dir + "/results.csv", results_csv(opt.out_dir, all_cases, varied_keys));
  nlohmann::ordered_json sj;
  sj["scene"] = opt.scene_path;
  sj["overrides"] = opt.overrides;
  sj["varied_keys"] = varied_keys;
  sj["shard"] = std::to_string(opt.shard.index) + "/" + std::to_string(opt.shard.count);
  sj["jobs"] = jobs;
  sj["cases_total"] = rep.cases_total;
  sj["cases_in_shard"] = rep.cases_in_shard;
  sj["cases_run"] = rep.cases_run;
  sj["cases_skipped"] = rep.cases_skipped;
  sj["cases_failed"] = rep.cases_failed;
  sj["cases_diverged"] = rep.cases_diverged;
  sj["interrupted"] = rep.interrupted;
  sj["wall_time_s"] = rep.wall_time_s;
  sj["cases_per_hour"] = rep.cases_per_hour;
  sj["errors"] = rep.errors;
  const std::string name = opt.shard.count == 1 ? "sweep.json"
                                                : "sweep_shard" + std::to_string(opt.shard.index) + "of" +
                                                      std::to_string(opt.shard.count) + ".json";
  write_file_atomic(opt.out_dir + "/" + name, sj.dump(2) + "\n");
  return rep;
}

namespace {
double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
std::string left_text(double s) {
  char b[64];
  if (s >= 120)
    std::snprintf(b, sizeof b, "  (about %.0f min left)", s / 60);
  else
    std::snprintf(b, sizeof b, s < 10 ? "  (about %.1f s left)" : "  (about %.0f s left)", s);
  return b;
}
}  // namespace

TimeLeft::TimeLeft(int total) : total_(total), t0_s_(now_s()) {}

void TimeLeft::step(bool skipped) {
  ++ended_;
  if (!skipped) ++ran_;
}

std::string TimeLeft::counter() const {
  return "[" + std::to_string(ended_) + "/" + std::to_string(total_) + "]";
}

std::string TimeLeft::left() const {
  return ran_ > 0 && ended_ < total_ ? left_text((now_s() - t0_s_) / ran_ * double(total_ - ended_)) : "";
}

std::string TimeLeft::at(int done, int total, int kept) const {
  std::string s = "[" + std::to_string(done) + "/" + std::to_string(total) + "]";
  const int ran = done - kept;  // kept ones took no time: the pace is of the ones run now
  if (ran > 0 && done < total) s += left_text((now_s() - t0_s_) / ran * double(total - done));
  return s;
}

}  // namespace ravel::studies
