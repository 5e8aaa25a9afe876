// ravel tradeoff / ravel stability (docs/tradeoff.md): the Pareto front, errors against the
// reference on a tiny scene, the stability classification at a known-diverging time step,
// the suggestion logic on synthetic tradeoff.json files, log axes and grid charts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "chart.h"
#include "results.h"
#include "scene.h"
#include "stability.h"
#include "study_test_util.h"
#include "sweep.h"
#include "tradeoff.h"

namespace ravel::studies {
namespace {

// 24 x 24 mm, 4 mm 1 g sphere at 400 m/s: perforates in a few tens of microseconds.
std::vector<std::string> tiny_scene() {
  return {"fabric.width_mm=24",  "fabric.length_mm=24",         "projectile.diameter_mm=4",
          "projectile.mass_g=1", "projectile.velocity_mps=400", "solver.end_time_us=200"};
}

TEST(Tradeoff, ParetoFrontOnSyntheticPoints) {
  //                          0    1    2    3    4    5    6    7
  const std::vector<double> cost{1.0, 2.0, 3.0, 4.0, 5.0, 0.5, 2.0, NAN};
  const std::vector<double> err{10.0, 5.0, 7.0, 1.0, 1.0, 20.0, 5.0, 0.1};
  const auto f = pareto_front(cost, err);
  ASSERT_EQ(f.size(), 4u);
  EXPECT_EQ(f[0], 5u);  // cheapest
  EXPECT_EQ(f[1], 0u);
  EXPECT_EQ(f[2], 1u);  // (2, 5) twice: kept once, the first
  EXPECT_EQ(f[3], 3u);  // (4, 1) beats (5, 1)
  EXPECT_TRUE(pareto_front({}, {}).empty());
  EXPECT_EQ(pareto_front({3, 2, 1}, {1, 2, 3}).size(), 3u);  // all on the front
  EXPECT_EQ(pareto_front({1, 2, 3}, {1, 2, 3}).size(), 1u);  // the first beats all
}

TEST(Tradeoff, RelativeErrors) {
  EXPECT_DOUBLE_EQ(relative_error(101, 100), 0.01);
  EXPECT_DOUBLE_EQ(relative_error(5, 0, 400), 5.0 / 400);  // reference stopped: relative to V0
  EXPECT_TRUE(std::isnan(relative_error(NAN, 1)));
  EXPECT_EQ(perforation_time_error(-1, -1), 0);
  EXPECT_TRUE(std::isinf(perforation_time_error(1e-5, -1)));
  EXPECT_NEAR(perforation_time_error(1.1e-5, 1e-5), 0.1, 1e-12);
}

TEST(Tradeoff, ReferenceRowIsExactAndErrorsFollowDtFactor) {
  TradeoffOptions opt;
  opt.scene_path = default_scene_path();
  opt.overrides = tiny_scene();
  opt.out_dir = testing::scratch_dir();
  opt.knobs = {{"solver.dt_factor", {"0.1", "0.3", "0.7"}}};
  opt.jobs = 2;
  const auto r = run_tradeoff(opt);
  ASSERT_EQ(r.rows.size(), 4u);
  EXPECT_EQ(r.rows[0].knob, "reference");
  ASSERT_EQ(r.rows[0].status, "completed") << r.rows[0].note;
  EXPECT_TRUE(r.rows[0].perforated);
  // dt 0.1 is the reference setting itself: the same case folder, zero error.
  EXPECT_EQ(r.rows[1].case_name, r.rows[0].case_name);
  EXPECT_EQ(r.runs, 3);
  for (int q = 0; q < 3; ++q) {
    EXPECT_EQ(r.rows[0].error[q], 0.0) << quantity_key(q);
    EXPECT_EQ(r.rows[1].error[q], 0.0) << quantity_key(q);
  }
  // Coarser steps: a nonzero error, and the coarsest step is the least accurate in
  // residual velocity (measured on this scene: 0.1 % at 0.3, 1.2 % at 0.7).
  EXPECT_GT(r.rows[2].error[q_residual_velocity], 0.0);
  EXPECT_GT(r.rows[3].error[q_residual_velocity], r.rows[2].error[q_residual_velocity]);
  // ...and cheaper: fewer steps (CPU time measured for every row).
  for (const auto& row : r.rows) EXPECT_GT(row.cpu_time_s, 0.0) << row.value;
  // Outputs.
  const auto csv = parse_csv(tradeoff_csv(r));
  EXPECT_EQ(csv.rows.size(), 4u);
  EXPECT_GE(csv.column("residual_velocity_error"), 0);
  EXPECT_GE(csv.column("cpu_time_s"), 0);
  const auto j = nlohmann::json::parse(tradeoff_json(r, opt));
  EXPECT_TRUE(j["cheapest"].contains("solver.dt_factor"));
  const auto charts = tradeoff_charts(r, opt);
  ASSERT_EQ(charts.size(), 3u);
  EXPECT_TRUE(charts[0].second.x.log && charts[0].second.y.log);
  // A rerun resumes: nothing runs again.
  const auto again = run_tradeoff(opt);
  EXPECT_EQ(again.runs, 0);
  EXPECT_EQ(again.rows[3].error[q_residual_velocity], r.rows[3].error[q_residual_velocity]);
}

TEST(Stability, DtFactorTwoDivergesHalfIsStable) {
  StabilityOptions opt;
  opt.scene_path = default_scene_path();
  opt.overrides = tiny_scene();
  opt.out_dir = testing::scratch_dir();
  StabilityMapSpec m;
  m.name = "dt_factor";
  m.title = "dt";
  m.x = {"solver.dt_factor", {"0.5", "2"}};
  m.y = {"solver.model", {"sliding"}};
  opt.maps = {m};
  opt.jobs = 2;
  const auto r = run_stability(opt);
  ASSERT_EQ(r.cells.size(), 2u);
  EXPECT_EQ(r.cells[0].x_value, "0.5");
  EXPECT_EQ(r.cells[0].status, "stable") << r.cells[0].diagnosis;
  EXPECT_EQ(r.cells[1].x_value, "2");
  EXPECT_EQ(r.cells[1].status, "diverged") << r.cells[1].diagnosis;
  EXPECT_FALSE(r.cells[1].cause.empty());
  ASSERT_EQ(r.critical_dt.size(), 1u);
  EXPECT_GT(r.critical_dt[0].second, 0.5);
  EXPECT_LT(r.critical_dt[0].second, 2.0);
  // The CSV reads back, and the chart is a grid with the two cells coloured.
  const auto cells = parse_stability_csv(stability_csv(r));
  ASSERT_EQ(cells.size(), 2u);
  EXPECT_EQ(cells[1].status, "diverged");
  const auto charts = stability_charts(cells);
  ASSERT_EQ(charts.size(), 1u);
  const Grid& g = charts[0].second.grid;
  ASSERT_EQ(g.cells.size(), 2u);
  EXPECT_EQ(g.categories[size_t(g.cells[0])], "stable");
  EXPECT_EQ(g.categories[size_t(g.cells[1])], "diverged");
  const auto sentences = stability_sentences(r);
  ASSERT_EQ(sentences.size(), 1u);
  EXPECT_NE(sentences[0].find("stable up to dt_factor = 0.5"), std::string::npos) << sentences[0];
}

TEST(Stability, ClassifiesWarnings) {
  const auto w = classify_summary(
      R"({"status": "completed", "warnings": ["nearest-pair search: yarns slid more than one node in one step 3 times"]})");
  EXPECT_EQ(w.status, "warned");
  EXPECT_EQ(w.cause, "search");
  const auto p = classify_summary(
      R"({"status": "completed", "warnings": ["2 crossings found with yarns passed through each other"]})");
  EXPECT_EQ(p.status, "warned");
  EXPECT_EQ(p.cause, "pass_through");
  const auto f = classify_summary(
      R"({"status": "completed", "warnings": ["yarn-yarn friction work went below zero (-0.208 J at t = 52 us, 0.088 % of the initial energy): ..."]})");
  EXPECT_EQ(f.status, "warned");
  EXPECT_EQ(f.cause, "friction_negative");
  EXPECT_EQ(f.detail, "friction -0.208 J");
  const auto sf = classify_summary(
      R"({"status": "completed", "warnings": ["nearest-pair search: yarns slid more than one node in one step 1 times", "yarn-yarn friction work went below zero (-42.8 J at t = 98 us, 18 % of the initial energy): ..."]})");
  EXPECT_EQ(sf.cause, "search+friction_negative");
  EXPECT_EQ(sf.detail, "search 1, friction -42.8 J");
  const auto ok = classify_summary(R"({"status": "completed", "warnings": ["3 crossings ravelled out"]})");
  EXPECT_EQ(ok.status, "stable");  // ravelling is physics, not a broken method
  const auto d = classify_summary(R"({"status": "diverged", "divergence_cause": "energy_balance", "diagnosis": "x"})");
  EXPECT_EQ(d.status, "diverged");
  EXPECT_EQ(d.cause, "energy_balance");
}

// A synthetic tradeoff.json for scene "tiny".
std::string synthetic_json(double k2_error, const std::string& note = "", double k4_energy_error = 0.3) {
  nlohmann::ordered_json j;
  j["scene"] = "tiny";
  j["date"] = "2026-01-02";
  j["impact_velocity_mps"] = 260;
  j["note"] = note;
  auto row = [](const char* knob, const char* value, double cost, double e_vr, double e_ea) {
    return nlohmann::ordered_json{{"knob", knob},
                                  {"value", value},
                                  {"status", "completed"},
                                  {"cost_s", cost},
                                  {"errors", {{"residual_velocity", e_vr}, {"energy_absorbed", e_ea}}}};
  };
  j["rows"] = {row("fabric.yarns_per_element", "1", 4.0, 0.001, 0.001),
               row("fabric.yarns_per_element", "2", 1.6, k2_error, k2_error),
               row("fabric.yarns_per_element", "3", 1.2, 0.008, 0.2),
               row("fabric.yarns_per_element", "4", 1.0, 0.03, k4_energy_error),
               row("solver.dt_factor", "0.5", 2.0, 0.0, 0.0),
               row("solver.dt_factor", "0.9", 1.1, 0.02, 0.02)};
  return j.dump(2);
}

Scene tiny_named_scene(const std::vector<std::string>& extra = {}) {
  auto ov = tiny_scene();
  ov.push_back("name=tiny");
  for (const auto& e : extra) ov.push_back(e);
  return load_scene(default_scene_path(), ov);
}

TEST(Suggestions, PicksTheCheapestQualifyingSetting) {
  const Scene s = tiny_named_scene();  // yarns_per_element 1, dt_factor 0.5
  const auto out = tradeoff_suggestions(s, synthetic_json(0.004));
  ASSERT_EQ(out.size(), 1u);
  // k = 2 qualifies in both quantities; k = 3 is cheaper but in one only; k = 4 in none.
  EXPECT_NE(out[0].find("fabric.yarns_per_element=2 gives residual velocity and energy absorbed within 1 %"),
            std::string::npos)
      << out[0];
  EXPECT_NE(out[0].find("2.5x less cost"), std::string::npos) << out[0];
  EXPECT_NE(out[0].find("2026-01-02"), std::string::npos) << out[0];
  // k = 3 keeps residual velocity within 1 % but puts energy 20 % off (the run's own setting:
  // 0.1 %): not the same answer, so with k = 2 off by 2 % nothing is suggested at 1 %...
  EXPECT_TRUE(tradeoff_suggestions(s, synthetic_json(0.02)).empty());
  // ... and at 5 % k = 2 is (both within 5 %), not the cheaper k = 3.
  const auto at5 = tradeoff_suggestions(s, synthetic_json(0.02), 0.05);
  ASSERT_EQ(at5.size(), 2u);
  EXPECT_NE(at5[0].find("fabric.yarns_per_element=2 gives residual velocity and energy absorbed within 5 %"),
            std::string::npos)
      << at5[0];
  // A run already at k = 3 (energy 20 % off) may be told about k = 4 only where k = 4 is no
  // worse than that: with its energy 30 % off it is not; with 15 % it is (its residual
  // velocity within 5 %, its energy further off than 5 % but closer than the run's own).
  const Scene k3 = tiny_named_scene({"fabric.yarns_per_element=3"});
  for (const auto& line : tradeoff_suggestions(k3, synthetic_json(0.02), 0.05))
    EXPECT_NE(line.rfind("fabric.yarns_per_element", 0), 0u) << line;
  const auto k4 = tradeoff_suggestions(k3, synthetic_json(0.02, "", 0.15), 0.05);
  EXPECT_TRUE(std::any_of(k4.begin(), k4.end(), [](const std::string& l) {
    return l.rfind("fabric.yarns_per_element=4 gives residual velocity within 5 %", 0) == 0;
  })) << (k4.empty() ? std::string("none") : k4[0]);
  // At 5 %, dt_factor 0.9 qualifies too.
  EXPECT_EQ(tradeoff_suggestions(s, synthetic_json(0.004), 0.05).size(), 2u);
  // No note: the line ends with the measurement's date and velocity.
  EXPECT_NE(out[0].find("2026-01-02, 260 m/s)"), std::string::npos) << out[0];
}

// The measurement's note (what it does not cover) goes with every line it gives.
TEST(Suggestions, CarryTheMeasurementsNote) {
  const Scene s = tiny_named_scene();
  const auto out = tradeoff_suggestions(s, synthetic_json(0.004, "not for ballistic-limit searches"), 0.05);
  ASSERT_EQ(out.size(), 2u);
  for (const auto& line : out)
    EXPECT_NE(line.find("(measured by ravel tradeoff on 2026-01-02, 260 m/s; not for ballistic-limit searches)"),
              std::string::npos)
        << line;
}

// A result that is not a number (the outcome differed from the reference's) is infinitely
// far off: the setting is not suggested for its other, matching results.
TEST(Suggestions, NotWhereAnOutcomeDiffers) {
  auto j = nlohmann::ordered_json::parse(synthetic_json(0.004));
  for (auto& row : j["rows"])
    if (row["knob"] == "fabric.yarns_per_element" && row["value"] == "2") row["errors"]["energy_absorbed"] = "inf";
  for (const auto& line : tradeoff_suggestions(tiny_named_scene(), j.dump(), 0.05))
    EXPECT_NE(line.rfind("fabric.yarns_per_element=2", 0), 0u) << line;
}

TEST(Suggestions, SaysNothingWhenNothingQualifies) {
  // Already the cheapest measured setting.
  EXPECT_TRUE(tradeoff_suggestions(tiny_named_scene({"fabric.yarns_per_element=4", "solver.dt_factor=0.9"}),
                                   synthetic_json(0.004))
                  .empty());
  // Nothing cheaper within 1 %.
  EXPECT_TRUE(tradeoff_suggestions(tiny_named_scene(), synthetic_json(0.5), 0.001).empty());
  // Another scene, a setting that was not measured, a broken file.
  EXPECT_TRUE(tradeoff_suggestions(load_scene(default_scene_path(), tiny_scene()), synthetic_json(0.004)).empty());
  EXPECT_TRUE(tradeoff_suggestions(tiny_named_scene({"fabric.yarns_per_element=5", "solver.dt_factor=0.4"}),
                                   synthetic_json(0.004))
                  .empty());
  EXPECT_TRUE(tradeoff_suggestions(tiny_named_scene(), "{not json").empty());
}

// The shipped measurement varied one knob at a time around the default scene: a run with
// another knob moved (here the pin-jointed model) is not given what a knob did to the
// default (sliding) scene, while the default scene itself is.
TEST(Suggestions, OnlyWhereTheOtherKnobsAreAtTheMeasurementsBase) {
  auto knobs_of = [](const std::vector<std::string>& lines) {
    std::vector<std::string> k;
    for (const auto& l : lines) k.push_back(l.substr(0, l.find('=')));
    return k;
  };
  const auto pin =
      knobs_of(shipped_tradeoff_suggestions(load_scene(default_scene_path(), {"solver.model=pin_jointed"})));
  for (const auto& k : pin) EXPECT_EQ(k, "solver.model") << "a pin-jointed run was told about " << k;
  // With the time step moved, only the time step's own line can hold.
  const auto dt = knobs_of(shipped_tradeoff_suggestions(load_scene(default_scene_path(), {"solver.dt_factor=0.7"})));
  for (const auto& k : dt) EXPECT_EQ(k, "solver.dt_factor");
  // A run of the full model is told about the quarter (4x cheaper, and closer to the
  // reference in every result in the shipped measurement); the same run with the pin-jointed
  // model is not, because the quarter was measured on the sliding model.
  const auto full = knobs_of(shipped_tradeoff_suggestions(load_scene(default_scene_path(), {"solver.symmetry=full"})));
  ASSERT_FALSE(full.empty()) << "the shipped tradeoff suggests the quarter model to a full-model run";
  for (const auto& k : full) EXPECT_EQ(k, "solver.symmetry");
  for (const auto& k : knobs_of(shipped_tradeoff_suggestions(
           load_scene(default_scene_path(), {"solver.symmetry=full", "solver.model=pin_jointed"}))))
    EXPECT_NE(k, "solver.symmetry") << "a pin-jointed run was told what the symmetry did to the sliding model";
  // The default scene: every cheaper measured setting puts some result more than 5 % off.
  EXPECT_TRUE(shipped_tradeoff_suggestions(load_scene(default_scene_path(), {})).empty());
}

TEST(Suggestions, AddedToSummary) {
  const std::string dir = testing::scratch_dir();
  write_file_atomic(dir + "/summary.json", "{\n  \"status\": \"completed\"\n}\n");
  add_suggestions_to_summary(dir + "/summary.json", {"a", "b"});
  const auto j = nlohmann::json::parse(read_text_file(dir + "/summary.json"));
  ASSERT_TRUE(j["suggestions"].is_array());
  EXPECT_EQ(j["suggestions"].size(), 2u);
  EXPECT_EQ(j["status"], "completed");
}

TEST(ChartExtras, LogTicksAndGridChart) {
  const auto t = log_ticks(0.01, 10);
  ASSERT_FALSE(t.empty());
  EXPECT_DOUBLE_EQ(t.front(), 0.01);
  EXPECT_DOUBLE_EQ(t.back(), 10);
  EXPECT_EQ(log_ticks(1, 100).size(), 7u);  // 1 2 5 10 20 50 100
  Chart c;
  c.title = "grid";
  c.x = {"dt_factor", ""};
  c.y = {"model", ""};
  c.grid.x_labels = {"0.5", "1", "2"};
  c.grid.y_labels = {"sliding"};
  c.grid.categories = {"stable", "diverged"};
  c.grid.colors = {{0, 158, 115}, {213, 94, 0}};
  c.grid.cells = {0, 0, 1};
  c.grid.cell_text = {"ok", "ok", "energy"};
  EXPECT_EQ(finite_point_count(c), 3);
  const std::string csv = chart_csv(c);
  EXPECT_NE(csv.find("2,sliding,diverged,energy"), std::string::npos) << csv;
  const auto rgb = chart_rgb(c, 300, 150);
  // The last cell (dt_factor 2) is filled with the diverged colour, the first two with the
  // stable one: a cell's worth of pixels each (a legend swatch is a few dozen), the diverged
  // block right of the stable ones.
  long nd = 0, ns = 0;
  double xd = 0, xs = 0;
  for (size_t i = 0; i + 2 < rgb.size(); i += 3) {
    const double x = double((i / 3) % 300);
    if (rgb[i] == 213 && rgb[i + 1] == 94 && rgb[i + 2] == 0) ++nd, xd += x;
    if (rgb[i] == 0 && rgb[i + 1] == 158 && rgb[i + 2] == 115) ++ns, xs += x;
  }
  ASSERT_GT(nd, 500) << "no diverged cell";
  ASSERT_GT(ns, 2 * 500) << "no stable cells";
  EXPECT_GT(xd / double(nd), xs / double(ns) + 30) << "the diverged cell is not the rightmost";
  EXPECT_NE(chart_svg(c).find("#d55e00"), std::string::npos);
  // Log axes: non-positive values are gaps, not errors.
  Chart l;
  l.x.log = l.y.log = true;
  l.series.push_back({"s", {0.1, 1, 10, -1}, {1, 0, 100, 5}});
  EXPECT_EQ(finite_point_count(l), 2);
  double x0, x1, y0, y1;
  chart_ranges(l, &x0, &x1, &y0, &y1);
  EXPECT_DOUBLE_EQ(x0, 0.1);
  EXPECT_DOUBLE_EQ(x1, 10);
  EXPECT_DOUBLE_EQ(y0, 1);
  EXPECT_DOUBLE_EQ(y1, 100);
  EXPECT_FALSE(chart_svg(l).empty());
}

}  // namespace
}  // namespace ravel::studies
