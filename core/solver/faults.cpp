// Divergence (SPEC §4, docs/robustness.md): every check that stops a run because the method
// broke, and the one place that records it (Solver::fault, also called by Simulation for the
// faults it finds: the nearest-pair search lost at many crossings). The message has one form:
// "diverged at step N (t = T us): why".
#include <cstdio>

#include "solver/stage.h"

namespace ravel {

namespace {
std::string fmt_g(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}
}  // namespace

void Solver::fault(const std::string& cause, const std::string& why) {
  detail::record_fault(run_, cause, why);
}

namespace detail {

void record_fault(RunState& run, const std::string& cause, const std::string& why) {
  if (!run.divergence.empty()) return;  // the first fault is the one that stopped the run
  run.divergence = "diverged at step " + std::to_string(run.steps) + " (t = " + fmt_g(run.time * 1e6) + " us): " + why;
  run.divergence_cause = cause;
  run.divergence_step = run.steps;
  run.divergence_time = run.time;
}

// The energy ledger against the impact energy, once per step (close_ledger_row).
template <class Real>
void check_balance(const Model& model, State<Real>& s, RunState& run, double max_balance_error, double total) {
  const double e0 = 0.5 * model.projectile_mass * model.impact_velocity * model.impact_velocity;
  if (!std::isfinite(total)) {
    record_fault(run, "non_finite", "the energy ledger became NaN/infinite (a node or element went non-finite)");
  } else if (e0 > 0) {
    // Every ledger term is computed from its own mechanism, so a ledger that no longer
    // adds up to the initial energy means the integration has gone wrong. Two ways:
    // unstable modes feeding energy in (fast: within a few hundred steps; tension-only
    // yarns then shed it by breaking, so it never blows up), or the slow drift of a long
    // run with hundreds of breaks at a coarse step (it vanishes as dt is lowered). The
    // first stops the run; the second is a warning until it reaches 4x the limit.
    const double err = std::abs(total - e0) / e0;
    constexpr long kBalanceWindow = 64;  // steps per window of the drift / instability test
    if (run.steps % kBalanceWindow == 0) {
      s.balance_window[(run.steps / kBalanceWindow) % 8] = err;
    }
    const double earlier = s.balance_window[(run.steps / kBalanceWindow + 1) % 8];  // ~8 windows ago
    const double recent = s.balance_window[(run.steps / kBalanceWindow) % 8];       // this window's start
    // Half the limit gained within one window (64 steps) is an instability even below the
    // limit itself: a mode growing that fast breaks the yarns it runs in before the ledger
    // reaches the limit (a pin-jointed patch at dt_factor 2 tore apart in 32 steps with 4.4 %
    // created).
    const bool jumped = err - recent > 0.5 * max_balance_error;
    const bool fast = jumped || err - earlier > 0.5 * max_balance_error || err > 4 * max_balance_error;
    if (err > max_balance_error || jumped) {
      if (fast) {
        record_fault(run, "energy_balance",
                     "the energy ledger is off by " + fmt_g(100 * (total - e0) / e0) +
                         " % of the impact energy (energy " + (total > e0 ? "created" : "lost") +
                         " without a mechanism): the explicit integration is unstable");
      } else if (!run.diag.balance_drift) {
        run.diag.balance_drift = true;
        run.diag.balance_drift_time = run.time;
      }
    }
  }
}

// Yarn nodes after the free update (integrate): non-finite, or far outside the fabric.
void check_positions(RunState& run, double escape_radius2, double max_r2) {
  if (!std::isfinite(max_r2))
    record_fault(run, "non_finite", "a yarn node position became NaN/infinite");
  else if (!(max_r2 < escape_radius2))
    record_fault(run, "node_escaped", "a yarn node escaped the domain (more than 10 fabric sizes from the centre)");
}

// The projectile, every kProjectileCheckEvery steps (step): non-finite, or gone from the domain
// without perforating (a broken contact) or without touching the fabric (it crossed the fabric
// within one time step).
template <class Real>
void check_projectile(const Model& model, const State<Real>& s, RunState& run) {
  const double r = double(s.xp.norm());
  if (!std::isfinite(r)) {
    record_fault(run, "non_finite", "the projectile's position became NaN/infinite");
  } else if (r > 10 * (model.half_width + model.half_length) + 1) {
    record_fault(
        run, "projectile_left_domain",
        std::string("the projectile left the domain (more than 10 fabric sizes from the centre) without ") +
            (run.had_contact ? "perforating" : "touching the fabric: it crossed the fabric within one time step"));
  }
}

// The two precisions (solver.h: Precision).
template void check_balance(const Model&, State<float>&, RunState&, double, double);
template void check_balance(const Model&, State<double>&, RunState&, double, double);
template void check_projectile(const Model&, const State<float>&, RunState&);
template void check_projectile(const Model&, const State<double>&, RunState&);

}  // namespace detail
}  // namespace ravel
