#include "limit.h"
#include "limit_internal.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <filesystem>
#include <stdexcept>

#include "results.h"
#include "sweep.h"
#include "version.h"

namespace ravel::studies {

double LambertJonas::residual_at(double v) const {
  if (v <= vbl_mps) return 0;
  return a * std::pow(std::pow(v, p) - std::pow(vbl_mps, p), 1.0 / p);
}

namespace {

// Sum of squares for (p, Vbl) with the best a; returns +inf outside the allowed region.
double sse_best_a(const std::vector<double>& v, const std::vector<double>& vr, double p, double vbl, double vmin,
                  double* a_out) {
  if (!(p >= 1.0 && p <= 10.0) || !(vbl >= 0 && vbl < vmin)) return std::numeric_limits<double>::infinity();
  // Scale velocities by vmin so pow() stays well conditioned for large p.
  double sg = 0, sgg = 0;
  std::vector<double> g(v.size());
  for (size_t i = 0; i < v.size(); ++i) {
    const double x = std::pow(v[i] / vmin, p) - std::pow(vbl / vmin, p);
    g[i] = x > 0 ? vmin * std::pow(x, 1.0 / p) : 0.0;
    sg += g[i] * vr[i];
    sgg += g[i] * g[i];
  }
  if (sgg <= 0) return std::numeric_limits<double>::infinity();
  const double a = sg / sgg;
  double sse = 0;
  for (size_t i = 0; i < v.size(); ++i) sse += (vr[i] - a * g[i]) * (vr[i] - a * g[i]);
  if (a_out) *a_out = a;
  return sse;
}

}  // namespace

LambertJonas fit_lambert_jonas(const std::vector<double>& v_in, const std::vector<double>& vr_in, double vbl_hint) {
  LambertJonas fit;
  std::vector<double> v, vr;
  for (size_t i = 0; i < std::min(v_in.size(), vr_in.size()); ++i)
    if (std::isfinite(v_in[i]) && std::isfinite(vr_in[i]) && vr_in[i] > 0 && v_in[i] > 0) {
      v.push_back(v_in[i]);
      vr.push_back(vr_in[i]);
    }
  fit.points = int(v.size());
  if (v.size() < 3) {
    fit.note = "fewer than 3 perforating runs with a residual velocity: no fit";
    return fit;
  }
  const double vmin = *std::min_element(v.begin(), v.end());
  // Nelder-Mead over (p, Vbl) from several starts (the surface has long flat valleys).
  auto f = [&](const std::array<double, 2>& q) { return sse_best_a(v, vr, q[0], q[1], vmin, nullptr); };
  std::array<double, 2> best{2.0, 0.5 * vmin};
  double best_f = std::numeric_limits<double>::infinity();
  std::vector<double> vbl_starts{0.3 * vmin, 0.6 * vmin, 0.9 * vmin};
  if (vbl_hint > 0 && vbl_hint < vmin) vbl_starts.push_back(vbl_hint);
  for (double p0 : {1.5, 2.0, 3.0, 5.0})
    for (double b0 : vbl_starts) {
      std::array<std::array<double, 2>, 3> s{{{p0, b0}, {p0 * 1.2, b0}, {p0, b0 + 0.05 * (vmin - b0) + 0.01 * vmin}}};
      std::array<double, 3> fs{f(s[0]), f(s[1]), f(s[2])};
      for (int it = 0; it < 600; ++it) {
        std::array<int, 3> o{0, 1, 2};
        std::sort(o.begin(), o.end(), [&](int x, int y) { return fs[x] < fs[y]; });
        const auto b = s[o[0]], m = s[o[1]], w = s[o[2]];
        const double fb = fs[o[0]], fm = fs[o[1]], fw = fs[o[2]];
        if (std::abs(fw - fb) <= 1e-14 * (1 + fb) && std::abs(w[0] - b[0]) < 1e-9 &&
            std::abs(w[1] - b[1]) < 1e-9 * vmin)
          break;
        const std::array<double, 2> c{(b[0] + m[0]) / 2, (b[1] + m[1]) / 2};
        auto along = [&](double t) {
          return std::array<double, 2>{c[0] + t * (w[0] - c[0]), c[1] + t * (w[1] - c[1])};
        };
        const auto r = along(-1);
        const double fr = f(r);
        if (fr < fb) {
          const auto e = along(-2);
          const double fe = f(e);
          if (fe < fr)
            s[o[2]] = e, fs[o[2]] = fe;
          else
            s[o[2]] = r, fs[o[2]] = fr;
        } else if (fr < fm) {
          s[o[2]] = r, fs[o[2]] = fr;
        } else {
          const auto k = fr < fw ? along(-0.5) : along(0.5);
          const double fk = f(k);
          if (fk < std::min(fr, fw)) {
            s[o[2]] = k, fs[o[2]] = fk;
          } else {  // shrink towards the best
            for (int j : {o[1], o[2]}) {
              s[j] = {(s[j][0] + b[0]) / 2, (s[j][1] + b[1]) / 2};
              fs[j] = f(s[j]);
            }
          }
        }
      }
      for (int j = 0; j < 3; ++j)
        if (fs[j] < best_f) best_f = fs[j], best = s[j];
    }
  if (!std::isfinite(best_f)) {
    fit.note = "the fit did not converge";
    return fit;
  }
  fit.p = best[0];
  fit.vbl_mps = best[1];
  sse_best_a(v, vr, fit.p, fit.vbl_mps, vmin, &fit.a);
  fit.rms_mps = std::sqrt(best_f / double(v.size()));
  fit.ok = true;
  if (v.size() == 3) fit.note = "3 points for 3 parameters: the fit interpolates, it does not test the law";
  return fit;
}

namespace {
// A run whose outcome contradicts the bracket [lo, hi]: a perforation below lo or a stop
// above hi (failed, cancelled and undecided runs have no outcome and contradict nothing).
bool against_bracket(const Shot& s, double lo, double hi) {
  if (s.failed || s.cancelled || (!s.decided && !s.perforated)) return false;
  return (s.perforated && s.velocity_mps < lo) || (!s.perforated && s.velocity_mps > hi);
}
}  // namespace

void warn_non_monotone(LimitResult& res) {
  const double lo = res.lo_mps, hi = res.hi_mps;
  for (const auto& s : res.runs) {
    if (against_bracket(s, lo, hi)) {
      char b[200];
      std::snprintf(b, sizeof b, "non-monotone outcome: %.2f m/s %s although the bracket is [%.2f, %.2f] m/s",
                    s.velocity_mps, s.perforated ? "perforated" : "did not perforate", lo, hi);
      res.warnings.push_back(b);
    }
  }
}

void describe_error(LimitResult& res) {
  if (!res.bracketed) {
    res.error_mps = -1;
    res.error_note = "no bracket: no answer";
    return;
  }
  res.error_mps = 0.5 * (res.hi_mps - res.lo_mps);
  std::string note =
      "half the final bracket: its ends are full runs that stopped (lo) and perforated (hi), so the limit lies in it "
      "when perforation is a threshold in velocity; the rules add 0 m/s. Near the limit one run is a draw from a zone "
      "of mixed results (on the default scene at mu = 0.2 a velocity 1e-6 m/s higher can give the other outcome, and "
      "the perforation probability rises from 0 to 1 over about 5 m/s): another search path can land elsewhere in "
      "that zone; `ravel sweep --repeats N` measures the probability per velocity (docs/studies.md)";
  bool non_monotone = false;
  for (const auto& w : res.warnings) non_monotone |= w.rfind("non-monotone", 0) == 0;
  if (non_monotone) note += "; but some runs contradict a threshold (see warnings): the error is larger";
  if (res.runs_cancelled > 0)
    note += "; " + std::to_string(res.runs_cancelled) + " runs stopped as moot, none of them a bracket end";
  int decided = 0;
  for (const auto& s : res.runs) decided += s.decided_passing && !s.cancelled;
  if (decided > 0)
    note += "; " + std::to_string(decided) +
            " perforating runs ended once the projectile was passing through (decide_passing), an early end "
            "that running on never reversed in the cases measured (docs/MODEL.md section 8)";
  res.error_note = note;
}

LimitResult find_ballistic_limit(const ShootFn& shoot, const LimitOptions& opt, bool with_fit) {
  const auto t0 = std::chrono::steady_clock::now();
  LimitResult res;
  bool failed = false;
  // Outcome of one run: perforated, stopped (rebounded), or undecided (still moving forward
  // and not through at its end time, even after the shooter extended it): an undecided run
  // never counts as stopped; it is left out of the bracket with a warning (SPEC §8).
  enum Outcome { stopped, perforated, undecided };
  auto fire = [&](double v, const char* why) {
    v = run_velocity(v);
    Shot s = shoot(v, why);
    s.velocity_mps = v;
    s.purpose = why;
    char b[400];
    if (s.failed) {
      std::snprintf(b, sizeof b, "the run at %.2f m/s failed (%s)", v, s.error.c_str());
      res.warnings.push_back(b);
      failed = true;
    } else if (!s.decided && !s.perforated) {
      std::snprintf(b, sizeof b,
                    "the run at %.2f m/s reached its end time (%s) undecided, neither perforated nor stopped: left "
                    "out of the bracket; raise solver.max_end_time_us",
                    v, s.end_reason.c_str());
      res.warnings.push_back(b);
    }
    res.runs.push_back(s);
    return s.perforated ? perforated : s.decided ? stopped : undecided;
  };
  auto budget_left = [&] { return int(res.runs.size()) < opt.max_runs && !failed; };

  // Bracket: walk from the start velocity by the growth factor until the outcome flips
  // (downwards from a perforation, upwards from a stop or an undecided run).
  double v = run_velocity(std::clamp(opt.start_mps, opt.min_mps, opt.max_mps));
  double step = opt.growth;
  Outcome o = fire(v, "bracket");
  double lo = -1, hi = -1;
  bool down = o == perforated;
  if (!failed && o != undecided) (o == perforated ? hi : lo) = v;
  while (budget_left() && (lo < 0 || hi < 0)) {
    const double prev = v;
    v = down ? v / step : v * step;
    step = std::pow(step, std::max(1.0, opt.growth_accel));
    // A step past a bound fires once at the bound (growing steps overshoot it quickly);
    // the search gives up only when the bound itself has been fired.
    v = run_velocity(std::clamp(v, opt.min_mps, opt.max_mps));
    if (v == prev) break;
    o = fire(v, "bracket");
    if (failed) break;
    if (o == perforated) {
      hi = hi < 0 ? v : std::min(hi, v);
      if (lo < 0) down = true;
    } else if (o == stopped) {
      lo = std::max(lo, v);
      if (hi < 0) down = false;
    }
  }
  if (lo < 0 || hi < 0) {
    if (!failed)
      res.warnings.push_back(lo < 0 ? "no velocity down to the minimum failed to perforate"
                                    : "no velocity up to the maximum perforated");
    res.lo_mps = lo;
    res.hi_mps = hi;
    res.rounds = int(res.runs.size());
    describe_error(res);
    res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return res;
  }
  res.bracketed = true;
  // Bisection. An undecided run is left out: the next velocity is the middle of the widest
  // gap between the bracket's ends and the undecided velocities inside it, so the search goes
  // on beside them, and stops (not converged) when no gap is wider than half the tolerance.
  std::vector<double> undecided_at;
  auto next_try = [&] {
    std::vector<double> pts{lo, hi};
    for (double u : undecided_at)
      if (u > lo && u < hi) pts.push_back(u);
    std::sort(pts.begin(), pts.end());
    double best = -1, gap = 0;
    for (size_t i = 0; i + 1 < pts.size(); ++i)
      if (pts[i + 1] - pts[i] > gap) gap = pts[i + 1] - pts[i], best = 0.5 * (pts[i] + pts[i + 1]);
    return gap > 0.5 * opt.tolerance_mps ? best : -1.0;
  };
  for (const auto& r : res.runs)
    if (!r.failed && !r.decided && !r.perforated) undecided_at.push_back(r.velocity_mps);
  while (hi - lo > opt.tolerance_mps && budget_left()) {
    const double mid = run_velocity(next_try());
    if (mid <= lo || mid >= hi) break;  // (none left: next_try's -1, or a gap under 1e-6 m/s)
    const Outcome om = fire(mid, "bisect");
    if (failed) break;
    if (om == perforated)
      hi = mid;
    else if (om == stopped)
      lo = mid;
    else
      undecided_at.push_back(mid);
  }
  res.lo_mps = lo;
  res.hi_mps = hi;
  res.converged = hi - lo <= opt.tolerance_mps;
  res.ballistic_limit_mps = 0.5 * (lo + hi);
  if (!res.converged)
    res.warnings.push_back(failed          ? "search stopped by a failed run before the bracket reached the tolerance"
                           : budget_left() ? "undecided runs inside the bracket left nothing to bisect"
                                           : "run budget exhausted before the bracket reached the tolerance");
  if (with_fit && !failed) {
    for (double f : opt.fit_factors) {
      const double vf = run_velocity(res.ballistic_limit_mps * f);
      if (vf > opt.max_mps) continue;
      fire(vf, "fit");
      failed = false;  // a failed fit run only loses that point
    }
    std::vector<double> vs, vrs;
    for (const auto& s : res.runs)
      if (!s.failed && s.perforated && s.velocity_mps >= hi) {
        vs.push_back(s.velocity_mps);
        vrs.push_back(s.residual_velocity_mps);
      }
    res.fit = fit_lambert_jonas(vs, vrs, res.ballistic_limit_mps);
  }
  // Monotonicity check over every run made, the fit's runs among them (a run well above the
  // bracket that stops says the outcome is not a threshold in velocity).
  warn_non_monotone(res);
  res.rounds = int(res.runs.size());
  describe_error(res);
  res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

std::string limit_progress(const std::vector<Shot>& runs, const LimitOptions& opt, bool with_fit) {
  double lo = -1, hi = -1, run_time = 0;
  int perforated = 0, stopped = 0, fits = 0, timed = 0;
  for (const auto& s : runs) {
    if (s.purpose == "fit") ++fits;
    if (!s.resumed) run_time += s.wall_time_s, ++timed;
    if (s.failed || s.purpose == "fit") continue;
    if (s.perforated) {
      ++perforated;
      hi = hi < 0 ? s.velocity_mps : std::min(hi, s.velocity_mps);
    } else if (s.decided) {
      ++stopped;
      lo = std::max(lo, s.velocity_mps);
    }
  }
  const int k = int(runs.size());
  char b[200];
  if (lo < 0 || hi < 0 || lo >= hi) {
    std::snprintf(b, sizeof b, "run %d, bracketing (%d perforated, %d stopped)", k, perforated, stopped);
    return b;
  }
  // Each bisection halves the bracket; the fit's runs follow at the limit times each factor.
  int left = hi - lo > opt.tolerance_mps ? int(std::ceil(std::log2((hi - lo) / opt.tolerance_mps))) : 0;
  if (with_fit) {
    int planned = 0;
    for (double f : opt.fit_factors) planned += 0.5 * (lo + hi) * f <= opt.max_mps;
    left += std::max(0, planned - fits);
  }
  if (left == 0) {
    std::snprintf(b, sizeof b, "run %d of %d, bracket %.2f - %.2f m/s", k, k, lo, hi);
    return b;
  }
  const double mean = timed > 0 ? run_time / timed : 0;
  const double t = left * mean;
  if (mean <= 0)
    std::snprintf(b, sizeof b, "run %d of about %d, bracket %.2f - %.2f m/s", k, k + left, lo, hi);
  else if (t < 120)
    std::snprintf(b, sizeof b, "run %d of about %d, bracket %.2f - %.2f m/s, ~%.0f s left", k, k + left, lo, hi, t);
  else
    std::snprintf(b, sizeof b, "run %d of about %d, bracket %.2f - %.2f m/s, ~%.1f min left", k, k + left, lo, hi,
                  t / 60);
  return b;
}

namespace {

nlohmann::ordered_json shot_to_json(const Shot& s) {
  nlohmann::ordered_json q;
  q["velocity_mps"] = s.velocity_mps;
  q["purpose"] = s.purpose;
  q["perforated"] = s.perforated;
  q["residual_velocity_mps"] = s.residual_velocity_mps;
  q["energy_absorbed_J"] = s.energy_absorbed_J;
  q["perforation_time_s"] =
      s.perforation_time_s >= 0 ? nlohmann::ordered_json(s.perforation_time_s) : nlohmann::ordered_json(nullptr);
  q["end_reason"] = s.end_reason;
  if (s.decided_passing) q["decided_passing"] = true;
  q["decided"] = s.decided;
  q["failed"] = s.failed;
  if (s.failed) q["error"] = s.error;
  q["broken_warp_yarns"] = s.broken_warp_yarns;
  q["broken_weft_yarns"] = s.broken_weft_yarns;
  q["broken_warp_lines"] = s.broken_warp_lines;
  q["broken_weft_lines"] = s.broken_weft_lines;
  q["friction_work_J"] = s.friction_work_J;
  q["friction_work_to_first_break_J"] = s.friction_work_to_first_break_J;
  q["first_break_distance_mm"] = s.first_break_distance_mm >= 0 ? nlohmann::ordered_json(s.first_break_distance_mm)
                                                                : nlohmann::ordered_json(nullptr);
  q["wall_time_s"] = s.wall_time_s;
  if (s.cancelled) {
    q["cancelled"] = true;
    q["cancel_reason"] = s.cancel_reason;
  }
  if (s.started_s >= 0) {
    q["started_s"] = s.started_s;
    q["ended_s"] = s.ended_s;
    q["round"] = s.round;
  }
  return q;
}

}  // namespace

Shot shot_from_json(const nlohmann::json& q) {
  Shot s;
  auto num = [&](const char* k, double d) { return q.contains(k) && q[k].is_number() ? q[k].get<double>() : d; };
  s.velocity_mps = num("velocity_mps", 0);
  s.purpose = q.value("purpose", "");
  s.perforated = q.value("perforated", false);
  s.residual_velocity_mps = num("residual_velocity_mps", 0);
  s.energy_absorbed_J = num("energy_absorbed_J", 0);
  s.perforation_time_s = num("perforation_time_s", -1);
  s.end_reason = q.value("end_reason", "");
  s.decided_passing = q.value("decided_passing", false);
  s.decided = q.value("decided", true);
  s.failed = q.value("failed", false);
  s.error = q.value("error", "");
  s.broken_warp_yarns = q.value("broken_warp_yarns", 0);
  s.broken_weft_yarns = q.value("broken_weft_yarns", 0);
  // (absent in files written before 2026-12-06; a non-list is read as none)
  auto lines = [&](const char* k) {
    std::vector<int> out;
    if (q.contains(k) && q[k].is_array())
      for (const auto& v : q[k])
        if (v.is_number_integer()) out.push_back(v.get<int>());
    return out;
  };
  s.broken_warp_lines = lines("broken_warp_lines");
  s.broken_weft_lines = lines("broken_weft_lines");
  s.friction_work_J = num("friction_work_J", 0);
  s.friction_work_to_first_break_J = num("friction_work_to_first_break_J", 0);
  s.first_break_distance_mm = num("first_break_distance_mm", -1);
  s.wall_time_s = num("wall_time_s", 0);
  s.cancelled = q.value("cancelled", false);
  s.cancel_reason = q.value("cancel_reason", "");
  s.started_s = num("started_s", -1);
  s.ended_s = num("ended_s", -1);
  s.round = q.value("round", 0);
  return s;
}

LimitResult limit_from_json(const std::string& text) {
  const auto j = nlohmann::json::parse(text);
  LimitResult r;
  r.bracketed = j.value("bracketed", false);
  r.converged = j.value("converged", false);
  if (j.contains("bracket_mps")) {
    r.lo_mps = j["bracket_mps"][0].is_number() ? j["bracket_mps"][0].get<double>() : -1.0;
    r.hi_mps = j["bracket_mps"][1].is_number() ? j["bracket_mps"][1].get<double>() : -1.0;
  }
  if (j["ballistic_limit_mps"].is_number()) r.ballistic_limit_mps = j["ballistic_limit_mps"].get<double>();
  const auto& f = j["lambert_jonas"];
  r.fit.ok = f.value("ok", false);
  r.fit.a = f.value("a", 0.0);
  r.fit.p = f.value("p", 0.0);
  r.fit.vbl_mps = f.value("vbl_mps", 0.0);
  r.fit.rms_mps = f.value("rms_mps", 0.0);
  r.fit.points = f.value("points", 0);
  r.fit.note = f.value("note", "");
  for (const auto& q : j["runs"]) r.runs.push_back(shot_from_json(q));
  for (const auto& w : j["warnings"]) r.warnings.push_back(w.get<std::string>());
  r.wall_time_s = j.value("wall_time_s", 0.0);
  r.interrupted = j.value("interrupted", false);
  r.method = j.value("method", "reference");
  if (j.contains("rules"))
    for (const auto& q : j["rules"])
      if (q.is_object()) r.rules.push_back(q.value("name", ""));
  r.jobs = j.value("jobs", 1);
  r.rounds = j.value("rounds", 0);
  r.runs_cancelled = j.value("runs_cancelled", 0);
  if (j.contains("error_mps") && j["error_mps"].is_number()) r.error_mps = j["error_mps"].get<double>();
  r.error_note = j.value("error_note", "");
  return r;
}

namespace {

// What a kept run must have been run with to stand for a run now: the resolved scene
// (velocity aside) and the ravel build.
std::string run_fingerprint(const std::string& scene_path, const std::vector<std::string>& overrides) {
  Scene base = load_scene(scene_path, overrides);
  base.projectile.velocity_mps = 0;
  return scene_to_toml(base) + "\nravel " + version() + " (source " + source_commit() + ")";
}

std::string kept_path(const std::string& cache_dir, double v) {
  char name[64];
  std::snprintf(name, sizeof name, "/runs/v%012.6f.json", v);
  return cache_dir + name;
}

}  // namespace

const std::vector<FastRuleInfo>& fast_rule_table() {
  static const std::vector<FastRuleInfo> t{
      {"ksection", &FastRules::ksection,
       "jobs runs in flight: a free bracket is cut into jobs + 1 parts, a slot that frees splits the part most "
       "likely to hold the limit"},
      {"cancel_moot", &FastRules::cancel_moot,
       "a run whose outcome can no longer move the bracket is stopped at once (listed as cancelled)"},
      {"residual_guess", &FastRules::residual_guess,
       "Lambert-Jonas p = 2 through the lowest perforating runs' residual velocities places the next points (75 % "
       "of a prior, 25 % uniform)"},
      {"two_sided_start", &FastRules::two_sided_start,
       "the first round tries start_mps and start_mps / growth at once"},
      {"reuse_fit_points", &FastRules::reuse_fit_points,
       "fit runs only where no perforating run is within fit_reuse_window of BL x factor"},
      {"probe_below", &FastRules::probe_below,
       "once converged, runs at hi x (1 - k probe_step), k = 1 .. probe_count: a perforation below the bracket "
       "moves it down (the limit is the lowest velocity that perforates)"},
      {"probe_gaps", &FastRules::probe_gaps,
       "with probe_below: the stopped runs below the bracket stand for probes, which fill only the gaps wider "
       "than probe_step x hi down to lo x (1 - probe_count probe_step), the fixed probes' spacing; they may start "
       "in slots the bracket has no use for once it is narrower than one probe step"},
      {"decisive_points", &FastRules::decisive_points,
       "a bracket point within half the tolerance beyond lo + tolerance (or hi - tolerance) is moved just "
       "inside it, so that its outcome alone ends the search"},
      {"decide_passing", &FastRules::decide_passing,
       "a run ends as perforated once the projectile is passing through (solver.decide_passing: some element "
       "broken, held only by yarns with no intact path to a clamp, and at its present drag it would travel further "
       "than the fabric's "
       "half-size before stopping); its residual velocity is the speed then"}};
  return t;
}

void add_rule_overrides(const FastRules& rules, std::vector<std::string>& overrides) {
  if (rules.decide_passing) overrides.push_back("solver.decide_passing=true");
}

bool leave_out_rule(FastRules& rules, const std::string& name) {
  for (const auto& info : fast_rule_table())
    if (name == info.name) {
      rules.*info.on = false;
      return true;
    }
  return false;
}

std::string fast_rule_names() {
  std::string out;
  for (const auto& r : fast_rule_table()) out += (out.empty() ? "" : ", ") + std::string(r.name);
  return out;
}

double run_velocity(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.6f", v);
  return std::strtod(b, nullptr);
}

RunFn scene_runner(const std::string& scene_path, const std::vector<std::string>& overrides,
                   std::function<void(const Simulation&)> on_run, const std::string& cache_dir) {
  const std::string fingerprint = cache_dir.empty() ? std::string() : run_fingerprint(scene_path, overrides);
  return [=](double v, const std::string&, const std::atomic<bool>* stop) {
    v = run_velocity(v);
    auto ov = overrides;
    char b[64];
    std::snprintf(b, sizeof b, "projectile.velocity_mps=%.6f", v);
    ov.push_back(b);
    ov.push_back("output.progress=false");
    std::string kept;
    if (!cache_dir.empty()) {
      kept = kept_path(cache_dir, v);
      std::error_code ec;
      if (std::filesystem::exists(kept, ec)) {
        const auto j = nlohmann::json::parse(read_text_file(kept), nullptr, false);
        if (!j.is_discarded() && j.value("fingerprint", std::string()) == fingerprint && j.contains("shot")) {
          Shot shot = shot_from_json(j["shot"]);
          shot.resumed = true;
          return shot;
        }
      }
    }
    Scene scene = load_scene(scene_path, ov);
    Simulation sim(scene);
    sim.run(stop);
    // A run that reached its end time undecided never counts as stopped (SPEC §8): it goes
    // on to solver.max_end_time_us.
    if (sim.extend_to(scene.solver.max_end_time_s)) sim.run(stop);
    const Summary s = sim.summary();
    Shot shot;
    shot.velocity_mps = v;
    if (s.status == RunStatus::interrupted) {  // stopped: no outcome, nothing kept
      shot.cancelled = true;
      shot.decided = false;
      shot.end_reason = "cancelled";
      shot.wall_time_s = s.wall_time_s;
      return shot;
    }
    if (s.status == RunStatus::diverged) {
      shot.failed = true;
      shot.error = "diverged: " + s.diagnosis;
    } else if (on_run) {
      on_run(sim);
    }
    shot.perforated = s.perforated;
    shot.residual_velocity_mps = s.residual_velocity_mps;
    shot.energy_absorbed_J = s.energy_absorbed_J;
    shot.perforation_time_s = s.perforation_time_s;
    shot.end_reason = to_string(s.end_reason);
    shot.decided = s.end_reason != EndReason::end_time;
    shot.decided_passing = s.decided_passing;
    shot.wall_time_s = s.wall_time_s;
    shot.broken_warp_yarns = s.broken_warp_yarns;
    shot.broken_weft_yarns = s.broken_weft_yarns;
    shot.broken_warp_lines = s.broken_warp_lines;
    shot.broken_weft_lines = s.broken_weft_lines;
    shot.friction_work_J = s.friction_work_J;
    shot.friction_work_to_first_break_J = s.friction_work_to_first_break_J;
    shot.first_break_distance_mm = s.first_break_time_s >= 0 ? s.first_break_distance_m * 1e3 : -1;
    if (!kept.empty()) {  // kept for a rerun after an interruption
      prepare_output_dir(cache_dir + "/runs");
      nlohmann::ordered_json j;
      j["fingerprint"] = fingerprint;
      j["shot"] = shot_to_json(shot);
      write_file_atomic(kept, j.dump(2) + "\n");
    }
    return shot;
  };
}

ShootFn scene_shooter(const std::string& scene_path, const std::vector<std::string>& overrides,
                      const std::atomic<bool>* interrupt, std::function<void(const Simulation&)> on_run,
                      const std::string& cache_dir) {
  RunFn run = scene_runner(scene_path, overrides, std::move(on_run), cache_dir);
  return [run, interrupt](double v, const std::string& why) {
    Shot s = run(v, why, interrupt);
    if (s.cancelled) throw std::runtime_error("interrupted");
    return s;
  };
}

std::vector<Shot> kept_runs(const std::string& scene_path, const std::vector<std::string>& overrides,
                            const std::string& cache_dir) {
  std::vector<Shot> out;
  std::error_code ec;
  if (cache_dir.empty() || !std::filesystem::is_directory(cache_dir + "/runs", ec)) return out;
  const std::string fingerprint = run_fingerprint(scene_path, overrides);
  for (const auto& e : std::filesystem::directory_iterator(cache_dir + "/runs", ec)) {
    if (e.path().extension() != ".json") continue;
    const auto j = nlohmann::json::parse(read_text_file(e.path().string()), nullptr, false);
    if (j.is_discarded() || j.value("fingerprint", std::string()) != fingerprint || !j.contains("shot")) continue;
    Shot shot = shot_from_json(j["shot"]);
    shot.resumed = true;
    out.push_back(shot);
  }
  std::sort(out.begin(), out.end(), [](const Shot& a, const Shot& b) { return a.velocity_mps < b.velocity_mps; });
  return out;
}

OutcomeBand outcome_band(const LimitResult& r) {
  OutcomeBand b;
  for (const auto& s : r.runs) {
    if (s.failed || s.cancelled || !s.decided) continue;
    if (s.perforated && (b.lowest_perforation < 0 || s.velocity_mps < b.lowest_perforation))
      b.lowest_perforation = s.velocity_mps;
    if (!s.perforated && s.velocity_mps > b.highest_stop) b.highest_stop = s.velocity_mps;
  }
  b.threshold = b.lowest_perforation < 0 || b.highest_stop < b.lowest_perforation;
  if (!b.threshold)
    for (const auto& s : r.runs) b.against += against_bracket(s, r.lo_mps, r.hi_mps);
  // V50: the kV50Pairs highest stops and lowest perforations (fewer when either side has fewer).
  std::vector<double> stops, perfs;
  for (const auto& s : r.runs) {
    if (s.failed || s.cancelled || !s.decided) continue;
    (s.perforated ? perfs : stops).push_back(s.velocity_mps);
  }
  std::sort(stops.begin(), stops.end(), std::greater<>());
  std::sort(perfs.begin(), perfs.end());
  const int k = std::min({kV50Pairs, int(stops.size()), int(perfs.size())});
  if (k > 0) {
    double sum = 0, lo = perfs[0], hi = stops[0];
    for (int i = 0; i < k; ++i) {
      sum += stops[size_t(i)] + perfs[size_t(i)];
      lo = std::min({lo, stops[size_t(i)], perfs[size_t(i)]});
      hi = std::max({hi, stops[size_t(i)], perfs[size_t(i)]});
    }
    b.v50 = sum / (2 * k);
    b.v50_pairs = k;
    b.v50_spread = hi - lo;
  }
  return b;
}

std::string lumped_mesh_warning(const Scene& scene) {
  const auto& f = scene.fabric;
  if (f.yarns_per_element > 1)
    return "the mesh is lumped (fabric.yarns_per_element = " + std::to_string(f.yarns_per_element) +
           "): on the default scene yarns_per_element = 2 answered 63.6 m/s against the full mesh's 79.5-80.5 "
           "(docs/tradeoff.md); run on the full mesh for the model's limit";
  if (f.far_yarns_per_element > 1 && f.weave == Weave::plain)
    return "the mesh is graded (fabric.far_yarns_per_element = " + std::to_string(f.far_yarns_per_element) +
           "): on the default scene graded meshes answered 70.5-83.8 m/s against the full mesh's 79.5-80.5, with "
           "perforating islands below the threshold (docs/tradeoff.md); run on the full mesh for the model's limit";
  return "";
}

std::string limit_json(const LimitResult& r, const LimitOptions& opt, const std::string& scene_path,
                       const std::vector<std::string>& overrides) {
  nlohmann::ordered_json j;
  j["ballistic_limit_mps"] =
      r.bracketed ? nlohmann::ordered_json(r.ballistic_limit_mps) : nlohmann::ordered_json(nullptr);
  auto end = [](double v) { return v >= 0 ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr); };
  j["bracket_mps"] = {end(r.lo_mps), end(r.hi_mps)};
  j["bracket_note"] = "lo: highest velocity that did not perforate; hi: lowest that perforated";
  j["tolerance_mps"] = opt.tolerance_mps;
  j["bracketed"] = r.bracketed;
  j["converged"] = r.converged;
  nlohmann::ordered_json f;
  f["law"] = "Vr = a (V^p - Vbl^p)^(1/p)";
  f["ok"] = r.fit.ok;
  f["a"] = r.fit.a;
  f["p"] = r.fit.p;
  f["vbl_mps"] = r.fit.vbl_mps;
  f["rms_mps"] = r.fit.rms_mps;
  f["points"] = r.fit.points;
  f["note"] = r.fit.note;
  j["lambert_jonas"] = f;
  j["runs"] = nlohmann::ordered_json::array();
  for (const auto& s : r.runs) {
    auto q = shot_to_json(s);
    if (s.resumed) q["resumed"] = true;
    j["runs"].push_back(q);
  }
  j["warnings"] = r.warnings;
  j["interrupted"] = r.interrupted;
  j["scene"] = scene_path;
  j["overrides"] = overrides;
  j["start_mps"] = opt.start_mps;
  j["growth"] = opt.growth;
  j["growth_accel"] = opt.growth_accel;
  if (r.method == "fast") {
    j["probe_step"] = opt.probe_step;
    j["probe_count"] = opt.probe_count;
  }
  j["method"] = r.method;
  j["method_note"] =
      r.method == "fast"
          ? "ravel limit (fast search): runs in flight at once, each run stopped once moot; the bracket's "
            "ends are full runs, or perforating runs decided once the projectile was passing through "
            "(docs/studies.md)"
          : "ravel limit --reference: bracketing from start_mps by growth, then plain bisection, one run "
            "at a time, every run to its end (docs/studies.md)";
  {
    // Each rule: what it does and the error it may add to the answer.
    nlohmann::ordered_json rules = nlohmann::ordered_json::array();
    for (const auto& name : r.rules) {
      nlohmann::ordered_json q;
      q["name"] = name;
      for (const auto& info : fast_rule_table())
        if (name == info.name) q["what"] = info.what;
      // None moves a bracket end: both are full runs, or (decide_passing) runs whose outcome
      // running on did not reverse in any case measured (docs/studies.md).
      q["error_mps"] = 0.0;
      rules.push_back(q);
    }
    j["rules"] = rules;
  }
  j["jobs"] = r.jobs;
  j["rounds"] = r.rounds;
  int finished = 0;
  for (const auto& s : r.runs) finished += !s.cancelled;
  j["runs_finished"] = finished;
  j["runs_cancelled"] = r.runs_cancelled;
  int decided = 0;
  for (const auto& s : r.runs) decided += s.decided_passing && !s.cancelled;
  j["runs_decided_passing"] = decided;
  j["skipped_full_runs"] = r.runs_cancelled > 0 || decided > 0;
  std::string skipped;
  if (r.runs_cancelled > 0)
    skipped = "this search stopped " + std::to_string(r.runs_cancelled) +
              " runs before their end once their outcome was moot (each listed with cancelled: true; none is a "
              "bracket end)";
  if (decided > 0)
    skipped += std::string(skipped.empty() ? "this search ended " : "; it ended ") + std::to_string(decided) +
               " perforating runs once the projectile was passing through (decided_passing: true; their residual "
               "velocity is the speed then, about 1 m/s above a full run's)";
  if (!skipped.empty()) j["skipped_note"] = skipped + "; the reference runs every run to its end";
  {
    // Whether the outcomes of this search's runs form a threshold in velocity (issue 36,
    // MODEL.md section 9): where they do not, the band from the lowest perforation to the
    // highest stop is where outcomes alternate, and two searches may bracket different places
    // in it (the limit, SPEC section 8, is the lowest perforation).
    const OutcomeBand b = outcome_band(r);
    j["lowest_perforation_mps"] =
        b.lowest_perforation >= 0 ? nlohmann::ordered_json(b.lowest_perforation) : nlohmann::ordered_json(nullptr);
    j["highest_stop_mps"] =
        b.highest_stop >= 0 ? nlohmann::ordered_json(b.highest_stop) : nlohmann::ordered_json(nullptr);
    j["threshold"] = b.threshold;
    j["runs_against_threshold"] = b.against;
    char note[320];
    if (b.threshold)
      std::snprintf(note, sizeof note,
                    "every decided run below the lowest perforation stopped and every one above the highest stop "
                    "perforated: over these runs the outcome is a threshold in velocity");
    else
      std::snprintf(note, sizeof note,
                    "outcomes alternate between %.2f and %.2f m/s (%d runs contradict a threshold): a bracket of two "
                    "runs sees one place of this band; the limit, the lowest velocity that perforates, is at most the "
                    "lowest perforation",
                    b.lowest_perforation, b.highest_stop, b.against);
    j["threshold_note"] = note;
    j["v50_mps"] = b.v50 >= 0 ? nlohmann::ordered_json(b.v50) : nlohmann::ordered_json(nullptr);
    j["v50_pairs"] = b.v50_pairs;
    j["v50_spread_mps"] = b.v50_spread >= 0 ? nlohmann::ordered_json(b.v50_spread) : nlohmann::ordered_json(nullptr);
    std::snprintf(note, sizeof note,
                  "V50 of ballistic testing (MIL-STD-662F): the mean of the %d highest stops and the %d lowest "
                  "perforations among the decided runs (not failed or cancelled), spread %.2f m/s%s; the search "
                  "places no run for it, so it is as good as the runs near the bracket",
                  b.v50_pairs, b.v50_pairs, std::max(0.0, b.v50_spread),
                  b.v50_pairs < kV50Pairs ? ", fewer pairs than the usual 3" : "");
    j["v50_note"] = b.v50 >= 0 ? std::string(note) : std::string("no V50: no decided run stopped, or none perforated");
  }
  j["error_mps"] = r.error_mps >= 0 ? nlohmann::ordered_json(r.error_mps) : nlohmann::ordered_json(nullptr);
  j["error_note"] = r.error_note;
  j["wall_time_s"] = r.wall_time_s;
  j["runs_per_hour"] = r.wall_time_s > 0 ? double(r.runs.size()) / (r.wall_time_s / 3600) : 0.0;
  return j.dump(2) + "\n";
}

}  // namespace ravel::studies
