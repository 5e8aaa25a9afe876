#include "stability.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>

#include "model.h"
#include "results.h"
#include "run_record.h"

namespace ravel::studies {

namespace fs = std::filesystem;
using ojson = nlohmann::ordered_json;

namespace {

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

std::string csv_quote(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string o = "\"";
  for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c);
  return o + "\"";
}

std::string short_key(const std::string& key) {
  const auto dot = key.find('.');
  return dot == std::string::npos ? key : key.substr(dot + 1);
}

const char* kStatuses[] = {"stable", "warned", "diverged", "failed"};
int status_index(const std::string& s) {
  for (int i = 0; i < 4; ++i)
    if (s == kStatuses[i]) return i;
  return -1;
}

}  // namespace

std::vector<StabilityMapSpec> default_stability_maps(bool quick) {
  std::vector<StabilityMapSpec> m;
  StabilityMapSpec dt;
  dt.name = "dt_factor";
  dt.title = "Time-step factor, per contact model";
  dt.x = {"solver.dt_factor",
          quick ? std::vector<std::string>{"0.25", "0.5", "0.9", "1.1", "1.5", "2"}
                : std::vector<std::string>{"0.1", "0.25", "0.5", "0.75", "0.9", "1", "1.1", "1.25", "1.5", "2"}};
  dt.y = {"solver.model", {"sliding", "pin_jointed"}};
  m.push_back(dt);
  StabilityMapSpec fr;
  fr.name = "friction";
  fr.title = "Contact iterations at high friction (sliding)";
  fr.x = {"solver.contact_iterations",
          quick ? std::vector<std::string>{"1", "2", "8"} : std::vector<std::string>{"1", "2", "4", "8"}};
  fr.y = {"yarn.friction", {"0.2", "1", "10"}};
  fr.fixed = {"solver.model=sliding"};
  m.push_back(fr);
  // The stick penalty alpha_f (docs/MODEL.md §4): stiff springs are less stable at very high
  // friction, soft ones can feed energy into the yarns (friction work below zero: warned).
  StabilityMapSpec fp;
  fp.name = "friction_penalty";
  fp.title = "Stick penalty at low to very high friction (sliding)";
  fp.x = {"solver.friction_penalty", quick ? std::vector<std::string>{"0.25", "0.5", "1"}
                                           : std::vector<std::string>{"0.1", "0.25", "0.5", "0.75", "1"}};
  fp.y = {"yarn.friction", {"0.2", "1", "10"}};
  fp.fixed = {"solver.model=sliding"};
  m.push_back(fp);
  StabilityMapSpec v;
  v.name = "velocity";
  v.title = "Impact velocity and time-step factor (sliding)";
  v.x = {"projectile.velocity_mps", quick ? std::vector<std::string>{"200", "600", "1000"}
                                          : std::vector<std::string>{"200", "400", "600", "800", "1000"}};
  v.y = {"solver.dt_factor",
         quick ? std::vector<std::string>{"0.5", "0.9"} : std::vector<std::string>{"0.25", "0.5", "0.9"}};
  v.fixed = {"solver.model=sliding"};
  m.push_back(v);
  return m;
}

StabilityCell classify_summary(const std::string& text) {
  StabilityCell c;
  const RunRecord r = parse_run_record(text);
  if (!r.ok) {
    c.status = "failed";
    c.diagnosis = "summary.json " + r.error;
    return c;
  }
  c.wall_time_s = r.number("wall_time_s", 0);
  c.end_time_us = r.number("dt_s", 0) * r.number("step_count", 0) * 1e6;
  if (r.status == "diverged") {
    c.status = "diverged";
    c.diagnosis = r.diagnosis;
    c.cause = r.divergence_cause.empty() ? "diverged" : r.divergence_cause;
    return c;
  }
  if (r.status != "completed") {
    c.status = "failed";
    c.diagnosis = "status " + r.status + ": " + r.diagnosis;
    return c;
  }
  std::string search, pass, friction;
  for (const auto& t : r.warnings) {
    if (t.find("slid more than one node") != std::string::npos) search = t;
    if (t.find("passed through") != std::string::npos) pass = t;
    if (t.find("friction work went below zero") != std::string::npos) friction = t;
  }
  if (!search.empty() || !pass.empty() || !friction.empty()) {
    c.status = "warned";
    // "... slid more than one node in one step N times ..." / "N crossings found with yarns passed through ..."
    auto count_after = [](const std::string& t, const std::string& marker) {
      const auto at = t.find(marker);
      return at == std::string::npos ? std::string("?") : std::to_string(std::atol(t.c_str() + at + marker.size()));
    };
    if (!search.empty()) c.detail = "search " + count_after(search, "in one step ");
    if (!pass.empty())
      c.detail += (c.detail.empty() ? "" : ", ") + std::string("pass ") + std::to_string(std::atol(pass.c_str()));
    c.cause = !search.empty() ? (!pass.empty() ? "search+pass" : "search") : !pass.empty() ? "pass_through" : "";
    c.diagnosis = search + (search.empty() || pass.empty() ? "" : "; ") + pass;
    if (!friction.empty()) {
      // "yarn-yarn friction work went below zero (-0.208 J at t = 52 us, ...": the method fed
      // energy in where it should dissipate.
      c.cause += c.cause.empty() ? "friction_negative" : "+friction_negative";
      const auto at = friction.find("below zero (");
      c.detail +=
          (c.detail.empty() ? "" : ", ") +
          (at == std::string::npos ? std::string("friction < 0")
                                   : "friction " + friction.substr(at + 12, friction.find(" J", at) - at - 12) + " J");
      c.diagnosis += (c.diagnosis.empty() ? "" : "; ") + friction;
    }
    return c;
  }
  c.status = "stable";
  c.diagnosis = "completed (" + (r.json.contains("end_reason") ? r.end_reason : std::string("?")) + ")";
  return c;
}

StabilityResult run_stability(const StabilityOptions& opt_in, const std::atomic<bool>* interrupt) {
  StabilityOptions opt = opt_in;
  if (opt.maps.empty()) opt.maps = default_stability_maps();
  const auto t0 = std::chrono::steady_clock::now();
  StabilityResult res;
  res.maps = opt.maps;
  for (auto& m : res.maps) {
    if (interrupt && interrupt->load()) break;
    auto ov = opt.overrides;
    for (const auto& f : m.fixed) ov.push_back(f);
    // Check every value the way --vary does (throws StudyError naming the key).
    auto join = [](const Vary& v) {
      std::string s = v.key + "=";
      for (size_t i = 0; i < v.values.size(); ++i) s += (i ? "," : "") + v.values[i];
      return s;
    };
    m.x = parse_vary(join(m.x), opt.scene_path, ov);
    m.y = parse_vary(join(m.y), opt.scene_path, ov);
    // Rows outer, columns inner.
    const auto cases = expand_cases({m.y, m.x});
    SweepOptions so;
    so.scene_path = opt.scene_path;
    so.overrides = ov;
    so.out_dir = opt.out_dir + "/" + m.name;
    so.jobs = opt.jobs;
    so.solver_threads = opt.solver_threads;
    SweepHooks hooks;
    TimeLeft pace(int(cases.size()));
    hooks.on_case = [&](const CaseResult& r) {
      pace.step(r.skipped);
      if (opt.on_progress && !r.skipped)
        opt.on_progress(m.name + " " + pace.counter() + ": " + r.c.name() + (r.ok ? "" : " FAILED: " + r.error) +
                        pace.left());
    };
    const auto rep = run_sweep(cases, cases, so, {m.y.key, m.x.key}, hooks, interrupt);
    if (rep.interrupted) res.interrupted = true;
    res.runs_made += rep.cases_run;
    res.runs_kept += rep.cases_skipped;
    for (const auto& e : rep.errors) res.errors.push_back(m.name + ": " + e);
    for (const auto& c : cases) {
      StabilityCell cell;
      const std::string dir = case_dir(so.out_dir, c);
      if (case_finished(so.out_dir, c)) {
        cell = classify_summary(read_text_file(dir + "/summary.json"));
      } else {
        cell.status = rep.interrupted ? "" : "failed";
        cell.diagnosis = rep.interrupted ? "not run (interrupted)" : "the run could not start";
        if (rep.interrupted) continue;
      }
      cell.map = m.name;
      cell.y_key = c.settings[0].first;
      cell.y_value = c.settings[0].second;
      cell.x_key = c.settings[1].first;
      cell.x_value = c.settings[1].second;
      res.cells.push_back(cell);
    }
    // Theory for the time-step maps: the model's own estimate of the critical factor.
    if (m.x.key == "solver.dt_factor") {
      for (const auto& yv : m.y.values) {
        auto o = ov;
        o.push_back(m.y.key + "=" + yv);
        try {
          const Model model = build_model(load_scene(opt.scene_path, o));
          res.critical_dt.emplace_back(yv, model.critical_dt_factor);
        } catch (const std::exception&) {
        }
      }
    }
  }
  res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

std::string stability_csv(const StabilityResult& r) {
  std::string out = "map,x_key,x_value,y_key,y_value,status,cause,detail,diagnosis,wall_time_s,simulated_us\n";
  for (const auto& c : r.cells)
    out += csv_quote(c.map) + "," + csv_quote(c.x_key) + "," + csv_quote(c.x_value) + "," + csv_quote(c.y_key) + "," +
           csv_quote(c.y_value) + "," + c.status + "," + csv_quote(c.cause) + "," + csv_quote(c.detail) + "," +
           csv_quote(c.diagnosis) + "," + fmt("%.3f", c.wall_time_s) + "," + fmt("%.2f", c.end_time_us) + "\n";
  return out;
}

std::vector<StabilityCell> parse_stability_csv(const std::string& text) {
  std::vector<StabilityCell> out;
  const Csv csv = parse_csv(text);
  auto col = [&](const char* n) { return csv.column(n); };
  const int cm = col("map"), cxk = col("x_key"), cxv = col("x_value"), cyk = col("y_key"), cyv = col("y_value"),
            cs = col("status"), cc = col("cause"), cdt = col("detail"), cd = col("diagnosis"), cw = col("wall_time_s"),
            ct = col("simulated_us");
  if (cm < 0 || cxv < 0 || cyv < 0 || cs < 0) return out;
  for (const auto& row : csv.rows) {
    auto get = [&](int i) { return i >= 0 && size_t(i) < row.size() ? row[size_t(i)] : std::string(); };
    StabilityCell c;
    c.map = get(cm);
    c.x_key = get(cxk);
    c.x_value = get(cxv);
    c.y_key = get(cyk);
    c.y_value = get(cyv);
    c.status = get(cs);
    c.cause = get(cc);
    c.detail = get(cdt);
    c.diagnosis = get(cd);
    c.wall_time_s = std::atof(get(cw).c_str());
    c.end_time_us = std::atof(get(ct).c_str());
    if (!c.map.empty()) out.push_back(c);
  }
  return out;
}

std::vector<std::pair<std::string, Chart>> stability_charts(const std::vector<StabilityCell>& cells,
                                                            const std::string& subtitle) {
  std::vector<std::pair<std::string, Chart>> out;
  std::vector<std::string> maps;
  for (const auto& c : cells)
    if (std::find(maps.begin(), maps.end(), c.map) == maps.end()) maps.push_back(c.map);
  for (const auto& m : maps) {
    Chart ch;
    Grid& g = ch.grid;
    g.categories = {"stable", "warned", "diverged", "failed"};
    g.colors = {{0, 158, 115}, {230, 159, 0}, {213, 94, 0}, {150, 150, 150}};
    std::string xk, yk;
    for (const auto& c : cells) {
      if (c.map != m) continue;
      xk = c.x_key, yk = c.y_key;
      if (std::find(g.x_labels.begin(), g.x_labels.end(), c.x_value) == g.x_labels.end())
        g.x_labels.push_back(c.x_value);
      if (std::find(g.y_labels.begin(), g.y_labels.end(), c.y_value) == g.y_labels.end())
        g.y_labels.push_back(c.y_value);
    }
    g.cells.assign(g.x_labels.size() * g.y_labels.size(), -1);
    g.cell_text.assign(g.cells.size(), "");
    int counts[4] = {0, 0, 0, 0};
    for (const auto& c : cells) {
      if (c.map != m) continue;
      const size_t xi = size_t(std::find(g.x_labels.begin(), g.x_labels.end(), c.x_value) - g.x_labels.begin());
      const size_t yi = size_t(std::find(g.y_labels.begin(), g.y_labels.end(), c.y_value) - g.y_labels.begin());
      const size_t i = yi * g.x_labels.size() + xi;
      const int k = status_index(c.status);
      g.cells[i] = k;
      if (k >= 0) ++counts[k];
      // Short cell text: what broke (the diagnosis is in stability.csv / .md).
      static const std::map<std::string, std::string> shorter{{"energy_balance", "energy"},
                                                              {"non_finite", "NaN"},
                                                              {"search_lost", "lost"},
                                                              {"node_escaped", "escaped"},
                                                              {"projectile_left_domain", "left"},
                                                              {"search+pass", "search, pass"},
                                                              {"pass_through", "pass"}};
      std::string t = c.status == "stable" ? "ok" : !c.detail.empty() ? c.detail : c.cause.empty() ? c.status : c.cause;
      if (shorter.count(t)) t = shorter.at(t);
      std::replace(t.begin(), t.end(), '_', ' ');
      g.cell_text[i] = t;
    }
    ch.title = "Stability map: " + short_key(yk) + " vs " + short_key(xk);
    ch.subtitle = subtitle.empty() ? "" : subtitle + "; ";
    ch.subtitle += std::to_string(counts[0]) + " stable, " + std::to_string(counts[1]) + " warned, " +
                   std::to_string(counts[2]) + " diverged" +
                   (counts[3] ? ", " + std::to_string(counts[3]) + " failed" : "") +
                   " (warned: slid > 1 node, passed through, or friction < 0)";
    ch.x = {xk, ""};
    ch.y = {yk, ""};
    for (const auto& k : scene_keys()) {
      if (k.key == xk) ch.x.unit = k.unit;
      if (k.key == yk) ch.y.unit = k.unit;
    }
    out.emplace_back("stability_" + m, ch);
  }
  return out;
}

std::vector<std::string> stability_sentences(const StabilityResult& r) {
  std::vector<std::string> out;
  for (const auto& m : r.maps) {
    std::vector<std::string> ys;
    for (const auto& c : r.cells)
      if (c.map == m.name && std::find(ys.begin(), ys.end(), c.y_value) == ys.end()) ys.push_back(c.y_value);
    for (const auto& y : ys) {
      std::vector<const StabilityCell*> row;
      for (const auto& c : r.cells)
        if (c.map == m.name && c.y_value == y) row.push_back(&c);
      std::string s = m.name + ": " + short_key(m.y.key) + " = " + y + ": ";
      size_t first_bad = row.size();
      for (size_t i = 0; i < row.size(); ++i)
        if (row[i]->status != "stable") {
          first_bad = i;
          break;
        }
      if (first_bad == row.size()) {
        s += "stable over the whole range (" + short_key(m.x.key) + " " + row.front()->x_value + " to " +
             row.back()->x_value + ")";
      } else {
        bool all_bad_after = true;
        for (size_t i = first_bad; i < row.size(); ++i)
          if (row[i]->status == "stable") all_bad_after = false;
        if (first_bad > 0)
          s += "stable up to " + short_key(m.x.key) + " = " + row[first_bad - 1]->x_value + "; ";
        else
          s += std::string(row[0]->status == "diverged" ? "diverged" : "not stable") + " already at " +
               short_key(m.x.key) + " = " + row[0]->x_value + "; ";
        std::map<std::string, std::vector<std::string>> by;
        std::vector<std::string> order;
        for (size_t i = first_bad; i < row.size(); ++i) {
          if (row[i]->status == "stable") continue;
          const std::string k = row[i]->status + (row[i]->cause.empty() ? "" : " (" + row[i]->cause + ")");
          if (!by.count(k)) order.push_back(k);
          by[k].push_back(row[i]->x_value);
        }
        std::string parts;
        for (const auto& k : order) {
          std::string vals;
          for (const auto& v : by[k]) vals += (vals.empty() ? "" : ", ") + v;
          parts += (parts.empty() ? "" : "; ") + k + " at " + vals;
        }
        s += parts;
        if (!all_bad_after) s += " (not monotone: stable again further on)";
      }
      for (const auto& [yv, crit] : r.critical_dt)
        if (yv == y && m.x.key == "solver.dt_factor")
          s += " [theory: critical dt_factor about " + fmt("%.2f", crit) +
               " for this mesh, sqrt(3)/2 of it once nodes ride on the projectile in a long run (core/model.h "
               "critical_dt_factor, held_dt_factor)]";
      out.push_back(s);
    }
  }
  return out;
}

std::string stability_markdown(const StabilityResult& r, const StabilityOptions& opt) {
  std::string ov;
  for (const auto& o : opt.overrides) ov += " --set " + o;
  std::string md = "# Stability map\n\nScene `" + opt.scene_path + "`" + ov +
                   ". Every cell is one run to its end "
                   "(perforation, rebound or the scene's end time): **stable** (completed, assumptions held), "
                   "**warned** (completed, but the nearest-pair search saw yarns slide more than one node in a step "
                   "or pass through each other, or the yarn-yarn friction work went below zero), **diverged** (the "
                   "solver stopped it; cause in the cell), "
                   "**failed** (could not run).\n\n";
  for (const auto& m : r.maps) {
    md += "## " + m.title + "\n\n";
    if (!m.fixed.empty()) {
      md += "Fixed:";
      for (const auto& f : m.fixed) md += " `" + f + "`";
      md += ". ";
    }
    md += "Chart: `stability_" + m.name + ".{png,svg,csv}`; runs: `" + m.name + "/`.\n\n";
    for (const auto& s : stability_sentences(r))
      if (s.rfind(m.name + ":", 0) == 0) md += "- " + s.substr(m.name.size() + 2) + "\n";
    md += "\n";
    for (const auto& c : r.cells)
      if (c.map == m.name && c.status != "stable")
        md += "  - " + short_key(c.y_key) + "=" + c.y_value + ", " + short_key(c.x_key) + "=" + c.x_value + ": " +
              c.diagnosis + "\n";
    md += "\n";
  }
  if (!r.errors.empty()) {
    md += "## Errors\n\n";
    for (const auto& e : r.errors) md += "- " + e + "\n";
  }
  md += "Study wall time " + fmt("%.0f", r.wall_time_s) + " s.\n";
  return md;
}

}  // namespace ravel::studies
