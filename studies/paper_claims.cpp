// The claims of run_paper (paper_internal.h): each statement of the paper beside ravel's
// numbers, with a verdict computed from stated thresholds (listed under the report's table).
#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "paper_internal.h"

namespace ravel::studies::paper_detail {

namespace {

// The first yarn break of a history (time in us, and a column's value then): what splits a
// run's friction work into the part before any yarn broke and the part after.
struct FirstBreak {
  double t_us = NAN, friction_J = NAN;
};

FirstBreak first_break(const std::map<double, Csv>& histories, double mu) {
  FirstBreak fb;
  const auto it = histories.find(mu);
  if (it == histories.end()) return fb;
  const Csv& h = it->second;
  const int tc = h.column("t_s"), bw = h.column("broken_warp"), bf = h.column("broken_weft"),
            fc = h.column("friction_work_J");
  if (tc < 0 || bw < 0 || bf < 0 || fc < 0) return fb;
  for (const auto& r : h.rows)
    if (to_d(r[size_t(bw)]) + to_d(r[size_t(bf)]) > 0) {
      fb.t_us = to_d(r[size_t(tc)]) * 1e6;
      fb.friction_J = to_d(r[size_t(fc)]);
      break;
    }
  return fb;
}

}  // namespace

std::string broken_yarns_text(const Shot& s) {
  std::string t =
      std::to_string(s.broken_weft_yarns) + " weft and " + std::to_string(s.broken_warp_yarns) + " warp yarns broken";
  // Only the yarns through the strike point (grid line 0, in the symmetry planes): they
  // cannot slip aside in a symmetric model, whatever the friction (docs/MODEL.md §9).
  bool pole_only =
      s.broken_weft_yarns + s.broken_warp_yarns > 0 &&
      int(s.broken_weft_lines.size() + s.broken_warp_lines.size()) == s.broken_weft_yarns + s.broken_warp_yarns;
  for (const auto* lines : {&s.broken_weft_lines, &s.broken_warp_lines})
    for (int l : *lines) pole_only = pole_only && l == 0;
  if (pole_only) t += " (only the yarns through the strike point, which a symmetric model holds on the projectile)";
  return t;
}

std::string limit_friction_text(const Shot& s) {
  if (s.first_break_distance_mm < 0) return "";
  return "; at the limit (its lowest perforating run, " + num(s.velocity_mps, "%.1f") +
         " m/s): " + num(s.friction_work_to_first_break_J, "%.2f") + " J before the first break (" +
         num(s.first_break_distance_mm, "%.1f") + " mm from the strike point), " + num(s.friction_work_J, "%.2f") +
         " J in all";
}

EnergyPeak find_energy_peak(const Series& s, double min_fall, double window_mps) {
  EnergyPeak p;
  const int n = int(std::min(s.x.size(), s.y.size()));
  for (int i = 0; i < n && p.peak < 0; ++i) {
    if (!std::isfinite(s.y[size_t(i)]) || s.y[size_t(i)] <= 0) continue;
    if (i > 0 && s.y[size_t(i - 1)] > s.y[size_t(i)]) continue;  // not a local maximum (rising side)
    int low = -1;
    for (int j = i + 1; j < n && s.x[size_t(j)] <= s.x[size_t(i)] + window_mps; ++j)
      if (std::isfinite(s.y[size_t(j)]) && (low < 0 || s.y[size_t(j)] < s.y[size_t(low)])) low = j;
    if (low < 0 || s.y[size_t(i + 1)] > s.y[size_t(i)]) continue;  // falls right after it
    const double fall = (s.y[size_t(i)] - s.y[size_t(low)]) / s.y[size_t(i)];
    if (fall < min_fall) continue;
    p.peak = i, p.trough = low, p.fall = fall;
  }
  if (p.peak < 0) return p;
  for (int j = p.trough + 1; j < n; ++j)
    if (std::isfinite(s.y[size_t(j)]) && s.y[size_t(j)] >= s.y[size_t(p.peak)]) {
      p.regain = j;
      break;
    }
  return p;
}

void make_claims(PaperState& ps) {
  const PaperPlan& plan = ps.plan;
  PaperResult& result = ps.result;
  const std::vector<LimitEntry>& limits = ps.limits;
  std::vector<Claim>& claims = ps.claims;
  auto bl_of = [&](double mu) -> const LimitEntry* {
    for (const auto& e : limits)
      if (!std::isnan(e.mu) && same(e.mu, mu) && e.have && e.result.bracketed) return &e;
    return nullptr;
  };
  // A search's lowest perforating run: the upper end of its bracket (nullptr if not in its runs).
  auto lowest_perforation = [](const LimitEntry& e) -> const Shot* {
    for (const auto& s : e.result.runs)
      if (s.perforated && same(s.velocity_mps, e.result.hi_mps)) return &s;
    return nullptr;
  };
  const LimitEntry* pin_entry = nullptr;
  for (const auto& e : limits)
    if (std::isnan(e.mu) && e.have && e.result.bracketed) pin_entry = &e;
  {  // 1. a peak near 250 m/s, then a fall with further velocity
    Claim c{"11, 13",
            "Energy absorbed rises with impact velocity until about 250 m/s, then drops suddenly and decreases "
            "with further increase.",
            "", "not measured"};
    // What one series shows, in words, and whether its peak is near 250 m/s and stays the top.
    auto describe = [](const Series& s, bool& found, bool& near, bool& kept) {
      const EnergyPeak p = find_energy_peak(s);
      found = p.peak >= 0;
      near = kept = false;
      if (!found)
        return "no peak followed by a fall of 15 % within 60 m/s over " + num(s.x.front()) + "-" + num(s.x.back()) +
               " m/s";
      const size_t i = size_t(p.peak), j = size_t(p.trough);
      near = s.x[i] >= 220 && s.x[i] <= 280;
      kept = p.regain < 0;
      std::string t = "rises to " + num(s.y[i], "%.1f") + " J at " + num(s.x[i]) + " m/s, falls " +
                      num(100 * p.fall, "%.0f") + " % to " + num(s.y[j], "%.1f") + " J by " + num(s.x[j]) + " m/s";
      if (kept)
        t += " and stays below that peak up to " + num(s.x.back()) + " m/s";
      else
        t += ", then rises again to " + num(s.y[size_t(p.regain)], "%.1f") + " J at " + num(s.x[size_t(p.regain)]) +
             " m/s";
      return t;
    };
    const Series s = ps.energy_series(kReferenceFriction, kDefaultFailure, "");
    if (s.y.size() >= 3) {
      bool found = false, near = false, kept = false;
      c.ravel = "mu = 0.2: " + describe(s, found, near, kept);
      c.verdict = !found ? "differs" : near && kept ? "agrees" : "partly";
      c.ravel += found && !near ? " (not near 250 m/s)" : "";
      // The paper's Fig. 11 also has the upper failure strain.
      for (double f : ps.plan.failure_strains) {
        if (same(f, kDefaultFailure)) continue;
        const Series u = ps.energy_series(kReferenceFriction, f, "");
        if (u.y.size() < 3) continue;
        bool uf = false, un = false, uk = false;
        c.ravel += "; failure strain " + num(100 * f) + " %: " + describe(u, uf, un, uk);
      }
    }
    claims.push_back(c);
  }
  {  // 2. mu = 0.2 absorbs most; steep rise below 0.06; slow fall above 0.2
    Claim c{"13", "mu = 0.2 absorbs the most energy over the whole velocity range.", "", "not measured"};
    int best = 0, n = 0;
    std::string others;
    for (double v : plan.velocities_mps) {
      double emax = -INFINITY, mu_max = NAN;
      for (double mu : plan.frictions)
        if (const VelocityRow* r = ps.find_row(mu, kDefaultFailure, v))
          if (r->energy_J > emax) emax = r->energy_J, mu_max = mu;
      if (std::isnan(mu_max)) continue;
      ++n;
      if (same(mu_max, kReferenceFriction))
        ++best;
      else
        others += (others.empty() ? "" : ", ") + num(v) + " m/s: mu = " + num(mu_max);
    }
    if (n > 0) {
      c.ravel = "mu = 0.2 is highest at " + std::to_string(best) + " of " + std::to_string(n) + " velocities" +
                (others.empty() ? "" : " (highest elsewhere: " + others + ")");
      c.verdict = best == n ? "agrees" : 2 * best >= n ? "partly" : "differs";
    }
    claims.push_back(c);
    Claim d{"13", "For mu < 0.06 absorption rises steeply with mu; above 0.2 it falls slowly.", "", "not measured"};
    auto mean_e = [&](double mu) {
      double s = 0;
      int k = 0;
      for (double v : plan.velocities_mps)
        if (const VelocityRow* r = ps.find_row(mu, kDefaultFailure, v)) s += r->energy_J, ++k;
      return k ? s / k : NAN;
    };
    const double e0 = mean_e(0), e6 = mean_e(0.06), e2 = mean_e(0.2), e10 = mean_e(1.0);
    if (std::isfinite(e0) && std::isfinite(e6) && std::isfinite(e2) && std::isfinite(e10)) {
      const double rise = (e6 - e0) / 0.06, fall = (e2 - e10) / 0.8;
      d.ravel = "mean over velocities: " + num(e0, "%.1f") + " J (mu 0), " + num(e6, "%.1f") + " J (0.06), " +
                num(e2, "%.1f") + " J (0.2), " + num(e10, "%.1f") + " J (1.0); slope " + num(rise, "%.0f") +
                " J per unit mu below 0.06, " + num(-fall, "%.0f") + " above 0.2";
      d.verdict = rise > 0 && fall > 0 && rise > 3 * fall ? "agrees"
                  : rise > 0 && rise > 3 * std::abs(fall) ? "partly"
                                                          : "differs";
    }
    claims.push_back(d);
  }
  {  // 3. perforation times at 260
    const double vh = plan.history_velocity_mps;
    Claim c{"14", "At 260 m/s mu = 1.0 perforates at about 73 us, earlier than mu = 0.2.", "", "not measured"};
    const VelocityRow* r1 = ps.find_row(1.0, kDefaultFailure, vh);
    const VelocityRow* r2 = ps.find_row(0.2, kDefaultFailure, vh);
    if (r1 && r2) {
      auto t = [](const VelocityRow* r) {
        return r->perforated ? num(r->perforation_time_s * 1e6, "%.1f") + " us" : std::string("no perforation");
      };
      c.ravel = "mu = 1.0: " + t(r1) + "; mu = 0.2: " + t(r2);
      // What sets the time: the first yarn breaks (a strain build-up nearly independent of mu).
      const FirstBreak b1 = first_break(ps.histories, 1.0), b2 = first_break(ps.histories, 0.2);
      if (std::isfinite(b1.t_us) && std::isfinite(b2.t_us))
        c.ravel += " (first yarn breaks at " + num(b1.t_us, "%.1f") + " and " + num(b2.t_us, "%.1f") + " us)";
      if (r1->perforated && r2->perforated) {
        const bool earlier = r1->perforation_time_s < r2->perforation_time_s;
        const bool near73 = std::abs(r1->perforation_time_s * 1e6 - 73) <= 15;
        c.verdict = earlier && near73 ? "agrees" : earlier || near73 ? "partly" : "differs";
      } else {
        c.verdict = "differs";
      }
    }
    claims.push_back(c);
    Claim d{"14", "mu <= 0.08 decelerates the projectile very gently (yarns slip off).", "", "not measured"};
    if (r2 && r2->perforated) {
      const double loss_ref = vh - r2->residual;
      std::string txt;
      bool all_gentle = true, any = false;
      for (double mu : plan.frictions) {
        if (mu > 0.08) continue;
        const VelocityRow* r = ps.find_row(mu, kDefaultFailure, vh);
        if (!r) continue;
        any = true;
        const double loss = r->perforated ? vh - r->residual : vh;
        txt += (txt.empty() ? "" : ", ") + std::string("mu ") + num(mu) + ": " + num(loss, "%.0f") + " m/s";
        all_gentle = all_gentle && r->perforated && loss < 0.5 * loss_ref;
      }
      if (any) {
        d.ravel = "velocity lost by perforation: " + txt + " vs " + num(loss_ref, "%.0f") + " m/s at mu 0.2";
        d.verdict = all_gentle ? "agrees" : "differs";
      }
    }
    claims.push_back(d);
  }
  {  // 4. friction losses
    Claim c{"15", "Friction losses are small: about 1 J for mu = 0.2 at 260 m/s.", "", "not measured"};
    if (const VelocityRow* r = ps.find_row(0.2, kDefaultFailure, plan.history_velocity_mps)) {
      c.ravel = "yarn-yarn friction work " + num(r->friction_work_J, "%.2f") + " J of " + num(r->energy_J, "%.1f") +
                " J absorbed";
      // Isolated: what friction took before any yarn broke, and after (broken yarns retracting
      // through the weave, unclamped yarns dragged through it by the projectile).
      const FirstBreak b = first_break(ps.histories, 0.2);
      if (std::isfinite(b.t_us))
        c.ravel += "; " + num(b.friction_J, "%.2f") + " J of it before the first yarn broke (" + num(b.t_us, "%.1f") +
                   " us), the rest after";
      // The same split at the ballistic limit (docs/MODEL.md §10, "At the ballistic limit").
      if (const LimitEntry* e = bl_of(0.2))
        if (const Shot* s = lowest_perforation(*e)) c.ravel += limit_friction_text(*s);
      c.verdict = r->friction_work_J >= 1.0 / 3 && r->friction_work_J <= 3 ? "agrees"
                  : r->friction_work_J < 0.1 * r->energy_J                 ? "partly"
                                                                           : "differs";
    }
    claims.push_back(c);
  }
  {  // 5. ballistic limits
    auto bl = [&](double mu) {
      const LimitEntry* e = bl_of(mu);
      return e ? e->result.ballistic_limit_mps : NAN;
    };
    const double tol = plan.limit_tolerance_mps;
    const double p1 = paper_limit(0.1), p2 = paper_limit(0.2);
    Claim a{"16", "BL is about " + num(p2) + " m/s for mu = 0.2 and " + num(p1) + " m/s for mu = 0.1.", "",
            "not measured"};
    if (std::isfinite(bl(0.2)) && std::isfinite(bl(0.1))) {
      a.ravel = "BL " + num(bl(0.2), "%.1f") + " m/s (mu 0.2), " + num(bl(0.1), "%.1f") + " m/s (mu 0.1), +- " +
                num(tol / 2) + " m/s";
      const bool ok2 = std::abs(bl(0.2) - p2) <= kPaperLimitTolerance * p2,
                 ok1 = std::abs(bl(0.1) - p1) <= kPaperLimitTolerance * p1;
      a.verdict = ok2 && ok1 ? "agrees" : ok2 || ok1 ? "partly" : "differs";
    }
    claims.push_back(a);
    Claim b{"16", "BL(mu = 0) is about half of BL(mu = 0.1).", "", "not measured"};
    if (std::isfinite(bl(0)) && std::isfinite(bl(0.1))) {
      const double r = bl(0) / bl(0.1);
      b.ravel =
          "BL(0) / BL(0.1) = " + num(r, "%.2f") + " (" + num(bl(0), "%.1f") + " / " + num(bl(0.1), "%.1f") + " m/s)";
      b.verdict = r >= 0.4 && r <= 0.6 ? "agrees" : r < 0.8 ? "partly" : "differs";
    }
    claims.push_back(b);
    Claim c{"16", "BL is nearly flat for mu = 0.2-0.6 and lower at mu = 0.8-1.0.", "", "not measured"};
    double hi_mu = NAN;
    for (double m : {0.6, 0.4})
      if (std::isfinite(bl(m)) && std::isnan(hi_mu)) hi_mu = m;
    if (std::isfinite(bl(0.2)) && std::isfinite(hi_mu) && std::isfinite(bl(1.0))) {
      const double flat = std::abs(bl(hi_mu) - bl(0.2)) / bl(0.2);
      const bool lower = bl(1.0) < std::min(bl(0.2), bl(hi_mu)) - tol;
      c.ravel = "BL " + num(bl(0.2), "%.1f") + " (mu 0.2), " + num(bl(hi_mu), "%.1f") + " (mu " + num(hi_mu) + "), " +
                num(bl(1.0), "%.1f") + " m/s (mu 1.0)";
      c.verdict = flat <= 0.1 && lower ? "agrees" : flat <= 0.1 || lower ? "partly" : "differs";
    }
    claims.push_back(c);
    Claim d{"16", "The pin-jointed model's BL is also below that of mu = 0.2.", "", "not measured"};
    for (const auto& e : limits)
      if (std::isnan(e.mu) && !pin_entry)
        d.ravel = "no ballistic limit found for the pin-jointed model: " + (!e.error.empty() ? e.error
                                                                            : !e.result.warnings.empty()
                                                                                ? e.result.warnings.front()
                                                                                : "no bracket");
    if (pin_entry && std::isfinite(bl(0.2))) {
      d.ravel = "pin-jointed " + num(pin_entry->result.ballistic_limit_mps, "%.1f") + " m/s (bracket " +
                num(pin_entry->result.lo_mps, "%.1f") + "-" + num(pin_entry->result.hi_mps, "%.1f") +
                (pin_entry->result.converged ? "" : ", not converged") + ") vs " + num(bl(0.2), "%.1f") +
                " m/s (mu 0.2)";
      d.verdict = pin_entry->result.ballistic_limit_mps < bl(0.2) - tol ? "agrees"
                  : pin_entry->result.ballistic_limit_mps < bl(0.2)     ? "partly"
                                                                        : "differs";
    }
    claims.push_back(d);
  }
  {  // 6. perforation shapes
    Claim a{"8, 12",
            "At 200 m/s perforation is slit-like: clamped (weft) yarns break, unclamped (warp) yarns slide off.", "",
            "not measured"};
    if (const VelocityRow* r = ps.find_row(0.2, kDefaultFailure, 200)) {
      a.ravel = "broken yarns: " + std::to_string(r->broken_weft_yarns) + " weft (clamped), " +
                std::to_string(r->broken_warp_yarns) + " warp (free)";
      a.verdict = r->broken_weft_yarns > 0 && r->broken_warp_yarns * 3 <= r->broken_weft_yarns ? "agrees"
                  : r->broken_warp_yarns < r->broken_weft_yarns                                ? "partly"
                                                                                               : "differs";
    }
    claims.push_back(a);
    Claim b{"12", "At 360-400 m/s perforation is square (equal counts of broken warp and weft yarns).", "",
            "not measured"};
    if (const VelocityRow* r = ps.find_row(0.2, kDefaultFailure, 360)) {
      b.ravel = "broken yarns: " + std::to_string(r->broken_weft_yarns) + " weft, " +
                std::to_string(r->broken_warp_yarns) + " warp";
      const double ratio = r->broken_weft_yarns > 0 ? double(r->broken_warp_yarns) / r->broken_weft_yarns : 0;
      b.verdict = ratio >= 0.7 && ratio <= 1.4 ? "agrees" : ratio >= 0.4 && ratio <= 2.5 ? "partly" : "differs";
    }
    claims.push_back(b);
    Claim c{"17", "At mu = 0.02 no yarn breaks at the BL (the free edges ravel).", "", "not measured"};
    if (const LimitEntry* e = bl_of(0.02))
      if (const Shot* s = lowest_perforation(*e)) {
        c.ravel = "lowest perforating run (" + num(s->velocity_mps, "%.1f") + " m/s): " + broken_yarns_text(*s);
        c.verdict = s->broken_weft_yarns + s->broken_warp_yarns == 0 ? "agrees" : "differs";
      }
    claims.push_back(c);
  }
  for (const auto& c : claims) {
    if (c.verdict == "agrees")
      ++result.claims_agree;
    else if (c.verdict == "partly")
      ++result.claims_partly;
    else if (c.verdict == "differs")
      ++result.claims_differ;
    else
      ++result.claims_unknown;
  }
}

}  // namespace ravel::studies::paper_detail
