// The Studies windows: a sweep and a ballistic-limit search of the scene on screen, run
// in the background with the studies library (the same code as `ravel sweep` and `ravel
// limit`), with their live charts. Each writes into a folder the window names (default:
// the export folder's sweep/ and limit/), with the scene it ran as scene.toml beside it.
#include <imgui.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <thread>

#include "chart_imgui.h"
#include "gui_app.h"
#include "gui_jobs.h"
#include "results.h"

namespace ravel::app::gui {

// ----------------------------------------------------------------------------- LimitRunner

LimitRunner::~LimitRunner() {
  cancel();
  if (thread_.joinable()) thread_.join();
}

bool LimitRunner::start(const std::string& scene_path, const std::vector<std::string>& overrides,
                        const std::string& out_dir, double tolerance_mps, int jobs, std::string* error) {
  if (running()) {
    *error = "a search is running";
    return false;
  }
  if (thread_.joinable()) thread_.join();
  try {
    load_scene(scene_path, overrides);  // bad scene: say so now, start nothing
    prepare_output_dir(out_dir);
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
  interrupt_ = false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    state_ = Snapshot{};
    state_.running = true;
    state_.out_dir = out_dir;
    state_.started = std::chrono::steady_clock::now();
  }
  thread_ = std::thread([this, scene_path, overrides, out_dir, tolerance_mps, jobs] {
    // The same search as `ravel limit` with no flags: the fast search, `jobs` runs in
    // flight, one solver thread each, runs kept in out_dir/runs/ (a cancelled search
    // resumes from them).
    studies::LimitOptions opt;
    opt.tolerance_mps = tolerance_mps;
    opt.start_mps = 100;
    opt.jobs = std::max(1, jobs);
    std::vector<std::string> ov = overrides;
    ov.push_back("solver.end_time_us=auto");
    ov.push_back("solver.threads=1");
    studies::add_rule_overrides(opt.rules, ov);  // as ravel limit does
    try {
      const std::vector<studies::Shot> prior = studies::kept_runs(scene_path, ov, out_dir);
      {
        std::lock_guard<std::mutex> lock(mu_);
        state_.runs = prior;
      }
      studies::LimitHooks hooks;
      hooks.on_start = [&](const studies::Shot& s) {
        std::lock_guard<std::mutex> lock(mu_);
        state_.in_flight.push_back(s);
      };
      hooks.on_finish = [&](const studies::Shot& s, const studies::LimitProgress& p) {
        std::lock_guard<std::mutex> lock(mu_);
        state_.runs.push_back(s);
        state_.progress = p;
        state_.in_flight = p.in_flight;
      };
      studies::LimitResult r = studies::find_ballistic_limit_fast(studies::scene_runner(scene_path, ov, {}, out_dir),
                                                                  opt, true, &interrupt_, hooks, prior);
      if (const std::string w = studies::lumped_mesh_warning(load_scene(scene_path, ov)); !w.empty())
        r.warnings.push_back(w);
      write_file_atomic(out_dir + "/limit.json", studies::limit_json(r, opt, scene_path, ov));
      std::lock_guard<std::mutex> lock(mu_);
      state_.in_flight.clear();
      if (r.interrupted) {
        state_.error = "cancelled; the runs that finished are kept in " + out_dir + "/runs (start again to resume)";
      } else {
        state_.result = r;
        state_.finished = true;
      }
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mu_);
      state_.error = interrupt_ ? "cancelled; the runs that finished are kept in " + out_dir + "/runs" : e.what();
    }
    std::lock_guard<std::mutex> lock(mu_);
    state_.running = false;
  });
  return true;
}

void LimitRunner::cancel() {
  interrupt_ = true;
}

bool LimitRunner::running() const {
  std::lock_guard<std::mutex> lock(mu_);
  return state_.running;
}

LimitRunner::Snapshot LimitRunner::snapshot() const {
  std::lock_guard<std::mutex> lock(mu_);
  return state_;
}

// ----------------------------------------------------------------------------- windows

bool write_sweep_charts(GuiApp& app);  // below: the Sweep window's Save charts

namespace {

// The scene on screen as a file in `dir` (what the study runs), and its path.
std::string write_scene(GuiApp& app, const std::string& dir) {
  prepare_output_dir(dir);
  const std::string path = dir + "/scene.toml";
  write_file_atomic(path, scene_to_toml(app.draft));
  return path;
}

std::string default_dir(const GuiApp& app, const char* sub) {
  return app.export_dir + "/" + sub;
}

bool start_sweep(GuiApp& app, const std::vector<std::string>& vary_lines) {
  StudiesWindow& w = *app.studies;
  if (!*w.sweep_dir) std::snprintf(w.sweep_dir, sizeof w.sweep_dir, "%s", default_dir(app, "sweep").c_str());
  // A running sweep reads its scene file: do not rewrite it under it.
  if (w.sweep.running()) {
    w.sweep_error = "a sweep is running";
    return false;
  }
  try {
    studies::SweepOptions o;
    o.out_dir = w.sweep_dir;
    o.scene_path = write_scene(app, o.out_dir + "/.scene");
    o.jobs = std::max(1, w.jobs);
    w.sweep_error.clear();
    if (!w.sweep.start(o, vary_lines, &w.sweep_error, w.repeats)) return false;
    app.notice = "sweep started into " + o.out_dir;
    app.notice_is_error = false;
    return true;
  } catch (const std::exception& e) {
    w.sweep_error = e.what();
    return false;
  }
}

bool start_limit(GuiApp& app) {
  StudiesWindow& w = *app.studies;
  if (!*w.limit_dir) std::snprintf(w.limit_dir, sizeof w.limit_dir, "%s", default_dir(app, "limit").c_str());
  if (w.limit.running()) {  // it reads its scene file: do not rewrite it under it
    w.limit_error = "a search is running";
    return false;
  }
  try {
    const std::string scene = write_scene(app, std::string(w.limit_dir) + "/.scene");
    w.limit_error.clear();
    if (!w.limit.start(scene, {}, w.limit_dir, w.tolerance_mps, w.limit_jobs, &w.limit_error)) return false;
    app.notice = std::string("ballistic-limit search started into ") + w.limit_dir;
    app.notice_is_error = false;
    return true;
  } catch (const std::exception& e) {
    w.limit_error = e.what();
    return false;
  }
}

std::vector<std::string> lines_of(const char* text) {
  std::vector<std::string> lines;
  std::stringstream ss(text);
  for (std::string line; std::getline(ss, line);)
    if (line.find_first_not_of(" \t") != std::string::npos) lines.push_back(line);
  return lines;
}

const ImVec4 kBad(1.0f, 0.42f, 0.38f, 1.0f);

// The varied keys with the chosen x-axis key first (the first key when none is chosen or it
// is not varied in this sweep).
std::vector<std::string> sweep_chart_keys(const StudiesWindow& w, std::vector<std::string> keys) {
  studies::put_chart_x_first(&keys, w.chart_x);
  return keys;
}

void sweep_window(GuiApp& app) {
  StudiesWindow& w = *app.studies;
  if (!w.show_sweep) return;
  const float fs = ImGui::GetFontSize();
  // (wide and tall enough for a two-key chart and its legend)
  ImGui::SetNextWindowSize(ImVec2(fs * 50, fs * 38), ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Sweep", &w.show_sweep)) {
    ImGui::End();
    return;
  }
  if (!*w.sweep_dir) std::snprintf(w.sweep_dir, sizeof w.sweep_dir, "%s", default_dir(app, "sweep").c_str());
  const studies::SweepRunner::Snapshot s = w.sweep.snapshot();
  ImGui::TextWrapped(
      "Runs of the scene in the panels (its draft) with one or more keys varied, as `ravel sweep` does. One key per "
      "line: key=start:stop:step or key=v1,v2,...");
  ImGui::BeginDisabled(s.running);
  ImGui::InputTextMultiline("##vary", w.vary, sizeof w.vary, ImVec2(-1, ImGui::GetTextLineHeight() * 3.5f));
  ImGui::InputText("folder", w.sweep_dir, sizeof w.sweep_dir);
  ImGui::SliderInt("jobs", &w.jobs, 1, int(std::max(1u, std::thread::hardware_concurrency())));
  ImGui::SetNextItemWidth(fs * 8);
  if (ImGui::InputInt("repeats", &w.repeats)) w.repeats = std::clamp(w.repeats, 1, 1000);
  help_marker(
      "Near the ballistic limit one run is one draw of a random outcome. With repeats N each velocity of the "
      "projectile.velocity_mps line is run N times, 1e-6 m/s apart, and the chart 'perforation probability' shows "
      "the share that perforated (perforation.csv in the folder), as ravel sweep --repeats N does.");
  if (ImGui::Button("Start sweep")) start_sweep(app, lines_of(w.vary));
  ImGui::EndDisabled();
  if (s.running) {
    ImGui::SameLine();
    if (ImGui::Button("Cancel")) w.sweep.cancel();
  }
  ImGui::PushTextWrapPos(0);
  if (!w.sweep_error.empty()) ImGui::TextColored(kBad, "%s", w.sweep_error.c_str());
  if (!s.error.empty()) ImGui::TextColored(kBad, "%s", s.error.c_str());
  ImGui::PopTextWrapPos();
  if (s.progress.total > 0) {
    char label[128];
    std::snprintf(label, sizeof label, "%d / %d cases  (%d resumed, %d failed)  %.0f s", s.progress.done,
                  s.progress.total, s.progress.skipped, s.progress.failed, s.progress.wall_time_s);
    ImGui::ProgressBar(float(s.progress.done) / float(s.progress.total), ImVec2(-1, 0), label);
  }
  if (s.finished)
    ImGui::Text("done: %d run, %d resumed in %.1f s; %s/results.csv", s.report.cases_run, s.report.cases_skipped,
                s.report.wall_time_s, w.sweep_dir);
  // With several varied keys the charts can put any of them on x (the others make the series).
  if (s.varied_keys.size() > 1) {
    const std::string shown = sweep_chart_keys(w, s.varied_keys).front();
    if (ImGui::BeginCombo("x axis", shown.c_str())) {
      for (const auto& k : s.varied_keys)
        if (ImGui::Selectable(k.c_str(), k == shown)) w.chart_x = k;
      ImGui::EndCombo();
    }
  }
  auto charts = studies::sweep_charts(s.results, sweep_chart_keys(w, s.varied_keys));
  // With repeats: the perforation probability per velocity, first (the same table as perforation.csv).
  if (s.repeats > 1 && !s.results.rows.empty()) {
    studies::Chart p = studies::perforation_table(s.results, sweep_chart_keys(w, s.varied_keys), s.base_of).chart;
    if (studies::finite_point_count(p) > 0) charts.insert(charts.begin(), {"perforation_probability", std::move(p)});
  }
  if (!charts.empty()) {
    ImGui::BeginDisabled(s.running);
    if (ImGui::Button("Save charts")) write_sweep_charts(app);
    ImGui::EndDisabled();
    help_marker("PNG, SVG and CSV of the charts into the sweep folder's charts/, as ravel sweep writes them.");
    w.chart_index = std::min(w.chart_index, int(charts.size()) - 1);
    for (int i = 0; i < int(charts.size()); ++i) {
      if (i) ImGui::SameLine();
      ImGui::RadioButton(charts[size_t(i)].second.y.label.c_str(), &w.chart_index, i);
    }
    studies::draw_chart_imgui(
        charts[size_t(w.chart_index)].second,
        ImVec2(ImGui::GetContentRegionAvail().x, std::max(fs * 12, ImGui::GetContentRegionAvail().y)));
  }
  ImGui::End();
}

void limit_window(GuiApp& app) {
  StudiesWindow& w = *app.studies;
  if (!w.show_limit) return;
  const float fs = ImGui::GetFontSize();
  ImGui::SetNextWindowSize(ImVec2(fs * 36, fs * 30), ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Ballistic limit", &w.show_limit)) {
    ImGui::End();
    return;
  }
  if (!*w.limit_dir) std::snprintf(w.limit_dir, sizeof w.limit_dir, "%s", default_dir(app, "limit").c_str());
  const LimitRunner::Snapshot s = w.limit.snapshot();
  ImGui::TextWrapped(
      "The lowest impact velocity that perforates the scene in the panels, found as `ravel limit` finds it: the fast "
      "search, several runs in flight (one solver thread each), runs stopped once their outcome cannot move the "
      "bracket, the next velocities placed from the residual velocities measured. `ravel limit --reference` is the "
      "plain bisection to check it against.");
  ImGui::BeginDisabled(s.running);
  ImGui::InputText("folder", w.limit_dir, sizeof w.limit_dir);
  ImGui::SetNextItemWidth(fs * 8);
  ImGui::InputDouble("tolerance (m/s)", &w.tolerance_mps, 0, 0, "%.2f");
  w.tolerance_mps = std::clamp(w.tolerance_mps, 0.05, 50.0);
  ImGui::SetNextItemWidth(fs * 8);
  ImGui::InputInt("runs in flight", &w.limit_jobs);
  w.limit_jobs = std::clamp(w.limit_jobs, 1, 64);
  if (ImGui::Button("Start search")) start_limit(app);
  ImGui::EndDisabled();
  if (s.running) {
    ImGui::SameLine();
    if (ImGui::Button("Cancel")) w.limit.cancel();
  }
  ImGui::PushTextWrapPos(0);
  if (!w.limit_error.empty()) ImGui::TextColored(kBad, "%s", w.limit_error.c_str());
  if (!s.error.empty()) ImGui::TextColored(kBad, "%s", s.error.c_str());
  ImGui::PopTextWrapPos();
  if (s.finished) {
    if (s.result.bracketed) {
      ImGui::Text("ballistic limit %.1f m/s (bracket %.2f - %.2f, +-%.2f m/s)%s", s.result.ballistic_limit_mps,
                  s.result.lo_mps, s.result.hi_mps, s.result.error_mps, s.result.converged ? "" : ", not converged");
      ImGui::SameLine();
      help_marker(
          "The bracket of this search's runs. Near the limit one run is one draw of a random outcome: a velocity "
          "1e-6 m/s higher can give the other one, and on the default scene at mu = 0.2 the perforation probability "
          "rises from 0 to 1 over about 5 m/s (the zone of mixed results). Another search can land elsewhere in it; "
          "compare limits that differ by more. ravel sweep --repeats N measures the probability (docs/studies.md).");
    } else
      ImGui::TextColored(kBad, "no bracket: %s", s.result.warnings.empty() ? "" : s.result.warnings[0].c_str());
    ImGui::TextDisabled("%s search, %d run%s in flight, %d rounds, %d moot runs stopped, %.0f s",
                        s.result.method.c_str(), s.result.jobs, s.result.jobs == 1 ? "" : "s", s.result.rounds,
                        s.result.runs_cancelled, s.result.wall_time_s);
    const auto band = studies::outcome_band(s.result);
    if (s.result.bracketed && !band.threshold)
      ImGui::TextColored(kBad, "no threshold: outcomes alternate from %.1f to %.1f m/s", band.lowest_perforation,
                         band.highest_stop);
    if (s.result.bracketed && band.v50 >= 0)
      ImGui::TextDisabled("V50 %.1f m/s (mean of %d + %d runs, spread %.1f m/s)", band.v50, band.v50_pairs,
                          band.v50_pairs, band.v50_spread);
    if (s.result.fit.ok)
      ImGui::TextDisabled("Lambert-Jonas fit: %.1f m/s (a %.2f, p %.2f)", s.result.fit.vbl_mps, s.result.fit.a,
                          s.result.fit.p);
    ImGui::TextDisabled("%s/limit.json", s.out_dir.c_str());
  } else if (s.running) {
    const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - s.started).count();
    // The bracket, the guess and the time left as of the last run that ended.
    if (s.progress.finished + s.progress.cancelled > 0)
      ImGui::TextWrapped("%s", s.progress.line().c_str());
    else
      ImGui::Text("bracketing: first runs going");
    if (s.progress.eta_s >= 0) {  // the ETA counts down from the last run that ended
      const double left = std::max(0.0, s.progress.eta_s - (el - s.progress.elapsed_s));
      ImGui::Text("%.0f s elapsed; about %.0f s left", el, left);
    } else {
      ImGui::Text("%.0f s elapsed", el);
    }
    for (const auto& f : s.in_flight) ImGui::TextDisabled("  running %.2f m/s (%s)", f.velocity_mps, f.purpose.c_str());
  }
  if (ImGui::BeginTable("runs", 4, ImGuiTableFlags_RowBg | ImGuiTableFlags_ScrollY,
                        ImVec2(0, std::max(fs * 6, ImGui::GetContentRegionAvail().y)))) {
    ImGui::TableSetupColumn("velocity (m/s)");
    ImGui::TableSetupColumn("outcome");
    ImGui::TableSetupColumn("residual (m/s)");
    ImGui::TableSetupColumn("wall (s)");
    ImGui::TableHeadersRow();
    for (const auto& r : s.runs) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::Text("%.2f", r.velocity_mps);
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(r.failed       ? "failed"
                             : r.cancelled  ? ("stopped: " + r.cancel_reason).c_str()
                             : r.perforated ? (r.decided_passing ? "passing" : "perforated")
                             : r.decided    ? r.end_reason.c_str()
                                            : "undecided");
      if (r.decided_passing && ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "perforated: the run ended at %.1f us, once the projectile was passing through\n"
            "(an element broken, held only by yarns with no intact path to a clamp; rule decide_passing)",
            r.perforation_time_s * 1e6);
      ImGui::TableNextColumn();
      ImGui::Text("%.1f", r.residual_velocity_mps);
      ImGui::TableNextColumn();
      ImGui::Text("%.0f%s", r.wall_time_s, r.resumed ? " (kept)" : "");
    }
    ImGui::EndTable();
  }
  ImGui::End();
}

}  // namespace

void studies_menu_items(GuiApp& app) {
  StudiesWindow& w = *app.studies;
  if (ImGui::MenuItem("Sweep...", nullptr, w.show_sweep)) w.show_sweep = !w.show_sweep;
  if (ImGui::MenuItem("Ballistic limit...", nullptr, w.show_limit)) w.show_limit = !w.show_limit;
}

void draw_studies_windows(GuiApp& app) {
  sweep_window(app);
  limit_window(app);
}

bool studies_running(const GuiApp& app) {
  return app.studies->sweep.running() || app.studies->limit.running();
}

bool write_sweep_charts(GuiApp& app) {
  StudiesWindow& w = *app.studies;
  const studies::SweepRunner::Snapshot s = w.sweep.snapshot();
  try {
    if (s.running) throw std::runtime_error("the sweep is still running");
    const auto charts = studies::sweep_charts(s.results, sweep_chart_keys(w, s.varied_keys));
    const std::string dir = std::string(w.sweep_dir) + "/charts";
    int n = 0;
    for (const auto& [stem, chart] : charts) {
      if (studies::finite_point_count(chart) == 0) continue;
      if (n == 0) prepare_output_dir(dir);
      studies::write_chart(chart, dir + "/" + stem);
      ++n;
    }
    if (n == 0) throw std::runtime_error("no chart has a point to draw yet");
    app.notice = "wrote " + std::to_string(n) + " sweep charts into " + dir;
    app.notice_is_error = false;
    return true;
  } catch (const std::exception& e) {
    app.notice = std::string("sweep charts: ") + e.what();
    app.notice_is_error = true;
    return false;
  }
}

bool write_scripted_sweep_charts(GuiApp& app, const std::string& x_key) {
  StudiesWindow& w = *app.studies;
  auto keys = w.sweep.snapshot().varied_keys;
  if (!x_key.empty() && !studies::put_chart_x_first(&keys, x_key)) {
    app.notice =
        "sweep-charts: " + x_key + " is not a varied key of the sweep (it varies " + studies::joined_keys(keys) + ")";
    app.notice_is_error = true;
    return false;
  }
  if (!x_key.empty()) w.chart_x = x_key;
  return write_sweep_charts(app);
}

bool start_scripted_sweep(GuiApp& app, const std::string& vary) {
  StudiesWindow& w = *app.studies;
  w.show_sweep = true;
  // Several keys: KEY=LIST;KEY=LIST (one line each in the window); repeats=N sets the
  // window's repeats (ravel sweep --repeats N).
  std::vector<std::string> lines;
  std::string text;
  w.repeats = 1;
  for (size_t a = 0; a <= vary.size();) {
    const size_t b = std::min(vary.find(';', a), vary.size());
    const std::string part = vary.substr(a, b - a);
    a = b + 1;
    if (part.rfind("repeats=", 0) == 0) {
      char* end = nullptr;
      const long n = std::strtol(part.c_str() + 8, &end, 10);
      if (*end != '\0' || n < 1 || n > 1000) {
        app.notice = "sweep: repeats must be a whole number from 1 to 1000, got '" + part.substr(8) + "'";
        app.notice_is_error = true;
        return false;
      }
      w.repeats = int(n);
      continue;
    }
    if (!part.empty()) lines.push_back(part);
    text += (text.empty() ? "" : "\n") + part;
  }
  std::snprintf(w.vary, sizeof w.vary, "%s", text.c_str());
  const bool ok = start_sweep(app, lines);
  if (!ok) {
    app.notice = "sweep: " + w.sweep_error;
    app.notice_is_error = true;
  }
  return ok;
}

bool start_scripted_limit(GuiApp& app, const std::string& jobs) {
  app.studies->show_limit = true;
  if (!jobs.empty()) {
    char* end = nullptr;
    const long j = std::strtol(jobs.c_str(), &end, 10);
    if (*end != '\0' || j < 1 || j > 64) {
      app.notice = "limit: runs in flight must be a whole number from 1 to 64, got '" + jobs + "'";
      app.notice_is_error = true;
      return false;
    }
    app.studies->limit_jobs = int(j);
  }
  const bool ok = start_limit(app);
  if (!ok) {
    app.notice = "limit: " + app.studies->limit_error;
    app.notice_is_error = true;
  }
  return ok;
}

}  // namespace ravel::app::gui
