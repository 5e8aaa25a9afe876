// Simulation driver: model choice, stepping, history sampling, end-of-run tests.
#include "simulation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include "model.h"
#include "solver.h"
#include "version.h"

namespace ravel {

const char* to_string(RunStatus s) {
  switch (s) {
    case RunStatus::running:
      return "running";
    case RunStatus::completed:
      return "completed";
    case RunStatus::diverged:
      return "diverged";
    case RunStatus::interrupted:
      return "interrupted";
  }
  return "?";
}

const char* to_string(EndReason r) {
  switch (r) {
    case EndReason::none:
      return "none";
    case EndReason::perforated:
      return "perforated";
    case EndReason::rebounded:
      return "rebounded";
    case EndReason::caught:
      return "caught";
    case EndReason::end_time:
      return "end_time";
    case EndReason::diverged:
      return "diverged";
    case EndReason::interrupted:
      return "interrupted";
  }
  return "?";
}

namespace {
// A perforation is confirmed when the projectile has been free of every node for this long
// while still moving forward, and no node lies ahead of it within its silhouette.
constexpr double kPerforationConfirm_s = 3e-6;
// A node this close to the projectile's surface (or inside it) touches it: the contact puts
// touching nodes on the surface to rounding.
constexpr double kTouching_m = 1e-6;
// Caught: after contact, not perforated, the projectile's forward speed has stayed below this
// share of the impact speed (its kinetic energy below 1e-4 of the impact's) for kCaught_s.
// Near the ballistic limit a projectile held by friction in a deflected fabric creeps on
// for milliseconds without turning back (0.25 m/s after 5 ms at 75 m/s, mu = 0.2): with
// nothing left to perforate with, it is stopped.
constexpr double kCaughtSpeed = 0.01;
constexpr double kCaught_s = 100e-6;
// Passing (solver.decide_passing, docs/MODEL.md §8): the projectile, above this share of the
// impact speed, would at its present drag (the loss of its kinetic energy over the last
// kPassWindow_s) travel further than the fabric's largest half-size from the strike point
// before stopping, has done so for kPassHold_s, and no node on it is held to a clamp by
// unbroken elements: only yarns held by friction drag it, and the longest of them is pulled
// out of the weave within that distance. The share is the caught rule's, so that no speed is
// left to neither rule's speed test: with 2 % (until 2026-12-06) a projectile coasting at 1-2 % of its
// impact speed with no drag at all ran to solver.max_end_time_us undecided (mu = 0.02 at
// 50 m/s on the default scene: 0.72 m/s from 1.2 to 5 ms, carrying the ravelled pole warp).
constexpr double kPassSpeed = kCaughtSpeed;
constexpr double kPassWindow_s = 50e-6;
constexpr double kPassHold_s = 100e-6;
// solver.max_search_lost never trips on fewer crossings than this in one step (a small
// patch has a few hundred crossings; one lost pair is a warning, not a divergence).
constexpr double kMinSearchLost = 4;
// Yarn-yarn friction work below -kNegativeFrictionShare of the initial energy is reported: at
// mu = 1.0 with fabric.flattened_gap_mm = 0.16 the soft stick springs fed 0.65 J (0.27 %) into
// the yarns by 64 us; excursions of a few hundredths of a J (0.01-0.02 %) were seen at other
// settings.
constexpr double kNegativeFrictionShare = 5e-4;
// "Near a clamp" for the failure-site counts of the summary (issue 37's acceptance: at most a
// quarter of the elements broken before perforation within 2 mm of a clamp).
constexpr double kNearClamp_m = 2e-3;

std::string fmt(const char* f, double v) {
  char b[96];
  std::snprintf(b, sizeof b, f, v);
  return b;
}
}  // namespace

struct Simulation::Impl {
  Scene scene;
  std::unique_ptr<Solver> solver;
  std::vector<HistoryRow> history;
  RunStatus status = RunStatus::running;
  EndReason reason = EndReason::none;
  std::string diagnosis;
  long sample_every = 1;
  double worst_balance = 0;
  double perforation_time = -1;
  double last_attached_touch = -1;  // last check that found a node attached to the clamps on the projectile
  // Friction-work windows (docs/MODEL.md §8): the ledger's yarn-yarn friction work (modelled
  // part) at the first broken element, at the last step the projectile touched any node, and at
  // the last check that found an attached node on it; perforation_time is one of those two.
  double first_break_time = -1;
  double friction_at_first_break = 0;
  double friction_at_last_contact = 0;
  double friction_at_attached_touch = 0;
  double friction_at_perforation = 0;
  // Where the fabric failed (docs/MODEL.md §8): the in-plane distance from the impact point of
  // the first broken element (nearest, if several broke in that step), and the elements broken
  // before perforation (or by the end) and those of them within kNearClamp_m of a clamp.
  double first_break_distance = -1;
  double broken_before_perforation = -1, broken_near_clamp = -1;
  int extensions = 0;   // times extend_to reopened the run
  double end_time = 0;  // the model's, or later when a study extends an undecided run (extend_to)
  double wall_s = 0;
  std::vector<std::string> warnings;
  long search_lost_before = 0;  // diagnostics().skipped_nodes after the previous step
  double slow_since = -1;       // time from which the projectile has been below kCaughtSpeed V0 (-1: not)
  // Passing (solver.decide_passing): the projectile's forward kinetic energy per unit mass at
  // the checks of the last kPassWindow_s, and since when the stopping distance has been long.
  std::vector<std::pair<double, double>> pass_track;
  double passing_since = -1;
  bool decided_passing = false;

  const Model& model() const { return solver->model(); }

  // How many whole-fabric items each modelled one stands for: symmetry_factor, halved for
  // each symmetry plane the item lies on (a warp yarn at x = 0, a weft yarn at y = 0, a
  // node on the plane). Counts in the results are for the whole fabric; energies need no
  // such weights (the masses and areas on a plane are already halved).
  std::vector<double> elem_weight, crossing_weight;
  double fabric_nodes = 0;
  void compute_weights() {
    const Model& m = model();
    auto on_plane = [&](int yarn) {
      const bool is_warp = m.yarn_family[yarn] == warp;
      return m.yarn_grid[yarn] == 0 && (is_warp ? m.mirror_x : m.mirror_y);
    };
    elem_weight.assign(m.element_count, m.symmetry_factor);
    for (int e = 0; e < m.element_count; ++e)
      if (on_plane(m.elem_yarn[e])) elem_weight[e] *= 0.5;
    crossing_weight.assign(m.crossings.size(), m.symmetry_factor);
    for (size_t c = 0; c < m.crossings.size(); ++c) {
      if (on_plane(m.crossings[c].warp_yarn)) crossing_weight[c] *= 0.5;
      if (on_plane(m.crossings[c].weft_yarn)) crossing_weight[c] *= 0.5;
    }
    constexpr double on = 1e-9;  // m: nodes are placed on the plane exactly
    fabric_nodes = 0;
    for (int i = 0; i < m.node_count; ++i) {
      double w = m.symmetry_factor;
      if (m.mirror_x && std::abs(m.x0[i].x()) < on) w *= 0.5;
      if (m.mirror_y && std::abs(m.x0[i].y()) < on) w *= 0.5;
      fabric_nodes += w;
    }
  }
  // Broken elements of a family, weighted for the symmetry (every history row asks: the sweep
  // over the elements is redone only when the solver's count has changed; elements break for
  // good, so the same solver at a later step with the same count has the same ones).
  int broken_elements(int family) const {
    const int count = solver->broken_count(family);
    if (count == 0) return 0;
    BrokenCache& c = broken_cache[family];
    if (c.who == solver.get() && c.count == count && solver->steps() >= c.steps) return c.weighted;
    const Model& m = model();
    double n = 0;
    for (int e = 0; e < m.element_count; ++e)
      if (m.yarn_family[m.elem_yarn[e]] == family && solver->broken(e)) n += elem_weight[e];
    c = {solver.get(), count, solver->steps(), int(std::lround(n))};
    return c.weighted;
  }
  struct BrokenCache {
    const Solver* who = nullptr;
    int count = -1;
    long steps = 0;
    int weighted = 0;
  };
  mutable BrokenCache broken_cache[2];
  // An element's midpoint in the initial configuration, measured in the fabric's plane from
  // the projectile's aim point (or from the nearest clamped edge).
  Vec3d element_mid0(int e) const {
    const Model& m = model();
    return 0.5 * (m.x0[m.elem_a[e]] + m.x0[m.elem_b[e]]);
  }
  double nearest_break_to_impact() const {
    const Model& m = model();
    double best = -1;
    for (int e = 0; e < m.element_count; ++e) {
      if (!solver->broken(e)) continue;
      const Vec3d d = element_mid0(e) - m.projectile_x0;
      const double r = std::hypot(d.x(), d.y());
      if (best < 0 || r < best) best = r;
    }
    return best;
  }
  double clamp_distance(const Vec3d& x) const {
    const Model& m = model();
    double d = std::numeric_limits<double>::infinity();
    if (m.clamped.left) d = std::min(d, x.x() + m.half_width);
    if (m.clamped.right) d = std::min(d, m.half_width - x.x());
    if (m.clamped.bottom) d = std::min(d, x.y() + m.half_length);
    if (m.clamped.top) d = std::min(d, m.half_length - x.y());
    return d;
  }
  void count_breaks(double* broken, double* near_clamp) const {
    const Model& m = model();
    double n = 0, nc = 0;
    for (int e = 0; e < m.element_count; ++e) {
      if (!solver->broken(e)) continue;
      n += elem_weight[e];
      if (clamp_distance(element_mid0(e)) <= kNearClamp_m) nc += elem_weight[e];
    }
    *broken = n;
    *near_clamp = nc;
  }
  // Loaded crossings (normal force > 0), sliding and stuck, whole fabric.
  void loaded_crossings(int* sliding, int* stuck) const {
    double sl = 0, st = 0;
    for (size_t c = 0; c < crossing_weight.size(); ++c) {
      if (!solver->crossing_active(int(c)) || !(solver->crossing_normal_force(int(c)) > 0)) continue;
      (solver->crossing_sliding(int(c)) ? sl : st) += crossing_weight[c];
    }
    *sliding = int(std::lround(sl));
    *stuck = int(std::lround(st));
  }

  double forward_velocity() const { return solver->projectile_velocity().dot(model().flight_dir); }

  HistoryRow sample() const {
    const Model& m = model();
    const double f = m.symmetry_factor;
    HistoryRow r;
    r.t_s = std::max(0.0, solver->ledger_time());
    r.projectile_z_m = solver->projectile_position().z();
    r.projectile_velocity_mps = forward_velocity();
    r.ledger = solver->ledger().scaled(f);
    const double e0 = m.initial_energy();
    r.balance_error = e0 > 0 ? (r.ledger.total() - e0) / e0 : 0;
    r.broken_warp = broken_elements(warp);
    r.broken_weft = broken_elements(weft);
    r.max_strain = solver->max_strain();
    r.projectile_contact_force_N = solver->projectile_contact_force() * f;
    r.yarn_contact_force_N = solver->yarn_contact_force() * f;
    r.nodes_on_projectile = solver->nodes_on_projectile();
    loaded_crossings(&r.sliding_crossings, &r.stuck_crossings);
    return r;
  }

  // Perforated (docs/MODEL.md §8): the projectile has been free of every node attached to the
  // clamps for kPerforationConfirm_s, still moves forward, and no attached node lies ahead of
  // it inside its silhouette: it has passed through the fabric. Loose pieces (broken-off
  // yarn, or a yarn that ravelled out of the weave and rides on the projectile) neither hold
  // it nor stand in its way. An attached node ahead counts whatever its speed: fabric that
  // runs ahead of a slowed projectile has caught it, not let it through.
  bool perforation_confirmed() {
    if (!solver->had_contact() || forward_velocity() <= 0) return false;
    const Model& m = model();
    const Vec3d xp = solver->projectile_position();
    std::vector<char> attached;
    double last_touch = solver->last_contact_time();
    if (solver->nodes_on_projectile() > 0) {
      attached = attached_nodes();
      for (int i = 0; i < m.node_count; ++i) {
        if (!attached[i]) continue;
        Vec3d nrm;
        if (m.shape.sdf(Vec3d(solver->position(i) - xp), nrm) <= kTouching_m) {
          last_attached_touch = solver->time();
          friction_at_attached_touch = solver->ledger().friction_work_J;
          return false;
        }
      }
      last_touch = last_attached_touch >= 0 ? last_attached_touch : solver->time();
      if (last_attached_touch < 0) {
        last_attached_touch = solver->time();
        friction_at_attached_touch = solver->ledger().friction_work_J;
      }
    }
    if (solver->time() - last_touch < kPerforationConfirm_s) return false;
    if (attached.empty()) attached = attached_nodes();
    const double R = m.shape.radius;
    for (int i = 0; i < m.node_count; ++i) {
      if (!attached[i]) continue;
      const Vec3d rel = solver->position(i) - xp;
      const double ahead = rel.dot(m.flight_dir);
      if (ahead <= 0) continue;
      if ((rel - ahead * m.flight_dir).squaredNorm() < R * R) return false;
    }
    perforation_time = last_touch;  // the last contact with the attached fabric
    count_breaks(&broken_before_perforation, &broken_near_clamp);
    friction_at_perforation = last_touch == last_attached_touch ? friction_at_attached_touch : friction_at_last_contact;
    return true;
  }

  // Nodes connected to a clamped node (or, for a fabric without clamps, to the node
  // farthest from the impact) through unbroken elements and touching crossings (with
  // through_crossings false: through unbroken elements only, the yarns that hold by tension).
  std::vector<char> attached_nodes(bool through_crossings = true) const {
    const Model& m = model();
    const int n = m.node_count;
    std::vector<int> parent(n);
    for (int i = 0; i < n; ++i) parent[i] = i;
    auto find = [&](int a) {
      while (parent[a] != a) a = parent[a] = parent[parent[a]];
      return a;
    };
    auto join = [&](int a, int b) { parent[find(a)] = find(b); };
    // (A yarn a slipping clamp has fed out to its depth has left the clamp: it holds by nothing.)
    auto left_clamp = [&](int e) {
      return !m.grip_of_elem.empty() && m.grip_of_elem[e] >= 0 &&
             solver->grip_payout(m.grip_of_elem[e]) >= m.clamp_depth;
    };
    for (int e = 0; e < m.element_count; ++e)
      if (!solver->broken(e) && !left_clamp(e)) join(m.elem_a[e], m.elem_b[e]);
    for (int c = 0; c < int(m.crossings.size()) && through_crossings; ++c) {
      if (!solver->crossing_active(c) || solver->crossing_gap(c) > m.crossings[c].contact_distance) continue;
      const auto& cr = m.crossings[c];
      join(m.yarn_node(cr.warp_yarn, solver->crossing_warp_node(c)),
           m.yarn_node(cr.weft_yarn, solver->crossing_weft_node(c)));
    }
    std::vector<char> root_anchor(n, 0);
    bool any = false;
    for (int i = 0; i < n; ++i)
      if (m.fixed[i] == fix_all) root_anchor[find(i)] = 1, any = true;
    if (!any) {
      int far = 0;
      double best = -1;
      for (int i = 0; i < n; ++i)
        if (m.x0[i].squaredNorm() > best) best = m.x0[i].squaredNorm(), far = i;
      root_anchor[find(far)] = 1;
    }
    std::vector<char> out(n);
    for (int i = 0; i < n; ++i) out[i] = root_anchor[find(i)];
    return out;
  }

  // Passing (solver.decide_passing; the constants above). Called with the perforation check.
  bool passing() {
    const Model& m = model();
    const double v = forward_velocity(), t = solver->time();
    // Not before the first element breaks: an intact fabric is clamped through every yarn,
    // and the projectile passes it only once yarns break or slip aside, the latter seen by
    // the perforation test. Its drag grows from zero as the fabric deflects, so early in
    // contact the drag test alone would pass any slow strike; and a free yarn it touches,
    // pressed onto clamped yarns, is held by their normal force, not by friction.
    if (!solver->had_contact() || v < kPassSpeed * m.impact_velocity || first_break_time < 0) {
      pass_track.clear();
      passing_since = -1;
      return false;
    }
    pass_track.emplace_back(t, 0.5 * v * v);
    size_t old = 0;  // the latest check at least kPassWindow_s back
    while (old + 1 < pass_track.size() && t - pass_track[old + 1].first >= kPassWindow_s) ++old;
    pass_track.erase(pass_track.begin(), pass_track.begin() + long(old));
    const auto [t0, ke0] = pass_track.front();
    if (t - t0 < kPassWindow_s) return false;
    const double ke = pass_track.back().second, power = (ke0 - ke) / (t - t0);
    const double reach = std::max(0.5 * scene.fabric.width_m + std::abs(scene.projectile.offset_x_m),
                                  0.5 * scene.fabric.length_m + std::abs(scene.projectile.offset_y_m));
    // Stopping distance at constant drag: ke / (power / v).
    if (!(power <= 0 || ke * v > power * reach)) {
      passing_since = -1;
      return false;
    }
    if (passing_since < 0) passing_since = t;
    if (t - passing_since < kPassHold_s) return false;
    const std::vector<char> held = attached_nodes(false);
    const Vec3d xp = solver->projectile_position();
    for (int i = 0; i < m.node_count; ++i) {
      Vec3d nrm;
      if (held[i] && m.shape.sdf(Vec3d(solver->position(i) - xp), nrm) <= kTouching_m) return false;
    }
    return true;
  }

  void finish(RunStatus s, EndReason r, const std::string& why) {
    if (status != RunStatus::running) return;
    status = s;
    reason = r;
    diagnosis = why;
    if (history.empty() || history.back().t_s < solver->ledger_time()) history.push_back(sample());
  }

  bool step() {
    if (status != RunStatus::running) return false;
    solver->step();
    const long n = solver->steps();
    // The friction windows: cheap per step (the solver keeps the counts and the ledger).
    if (solver->last_contact_time() == solver->time()) friction_at_last_contact = solver->ledger().friction_work_J;
    if (first_break_time < 0 && solver->broken_count(warp) + solver->broken_count(weft) > 0) {
      first_break_time = solver->time();
      friction_at_first_break = solver->ledger().friction_work_J;
      first_break_distance = nearest_break_to_impact();
    }
    if (n % sample_every == 0) {
      history.push_back(sample());
      worst_balance = std::max(worst_balance, std::abs(history.back().balance_error));
    }
    if (solver->diverged()) {
      stop_diverged();
      return false;
    }
    // Nearest-pair search lost (SPEC §4): the 3 x 3 search of Fig. 2 assumes yarns slide at
    // most one node per step. A few crossings past that is a warning in the summary; at
    // many crossings in one step the contact state is no longer the model's.
    const long lost_total = solver->diagnostics().skipped_nodes;
    const long lost_now = lost_total - search_lost_before;
    search_lost_before = lost_total;
    if (lost_now > 0 && scene.solver.max_search_lost < 1) {
      const double limit = std::max(kMinSearchLost, scene.solver.max_search_lost * double(model().crossings.size()));
      if (double(lost_now) > limit) {
        diverge("search_lost", "the nearest-pair search lost track at " + std::to_string(lost_now) + " of " +
                                   std::to_string(model().crossings.size()) +
                                   " crossings in one step (yarns slid more than one node; solver.max_search_lost = " +
                                   fmt("%.3g", scene.solver.max_search_lost) + ")");
        return false;
      }
    }
    if (n % 16 == 0 || solver->time() >= end_time) {
      if (perforation_confirmed()) {
        finish(RunStatus::completed, EndReason::perforated, "the projectile passed through the fabric");
        return false;
      }
      if (scene.solver.decide_passing && passing()) {
        decided_passing = true;
        perforation_time = solver->time();
        count_breaks(&broken_before_perforation, &broken_near_clamp);
        friction_at_perforation = solver->ledger().friction_work_J;
        finish(RunStatus::completed, EndReason::perforated,
               "the projectile is passing through the fabric: a yarn element has broken, it is held only by yarns "
               "with no intact path to a clamp, and at its present drag it would travel further than the fabric's "
               "half-size before stopping (solver.decide_passing)");
        return false;
      }
      if (solver->had_contact() && forward_velocity() < 0) {
        finish(RunStatus::completed, EndReason::rebounded, "the fabric stopped the projectile and turned it back");
        return false;
      }
      if (solver->had_contact() && std::abs(forward_velocity()) < kCaughtSpeed * model().impact_velocity) {
        if (slow_since < 0) slow_since = solver->time();
        if (solver->time() - slow_since >= kCaught_s) {
          finish(RunStatus::completed, EndReason::caught,
                 "the fabric stopped the projectile: below 1 % of the impact speed for 100 us, not perforated");
          return false;
        }
      } else {
        slow_since = -1;
      }
    }
    if (solver->time() >= end_time - 0.5 * model().dt) {
      finish(RunStatus::completed, EndReason::end_time,
             std::string("reached ") + (scene.solver.end_time_auto ? "solver.max_end_time_us" : "solver.end_time_us") +
                 " before perforation or rebound");
      return false;
    }
    return true;
  }

  // A fault judged here against the scene (solver.max_search_lost): recorded by the solver's
  // Solver::fault like its own, so the message has one form.
  void diverge(const std::string& cause, const std::string& why) {
    solver->fault(cause, why);
    stop_diverged();
  }
  void stop_diverged() { finish(RunStatus::diverged, EndReason::diverged, solver->divergence() + ". " + advice()); }

  std::string advice() const {
    const Model& m = model();
    const double alpha = scene.solver.dt_factor;
    if (alpha > 0.9 * m.held_dt_factor) {
      const std::string held = m.held_dt_factor < m.critical_dt_factor
                                   ? ", about " + fmt("%.2f", m.held_dt_factor) +
                                         " once nodes ride on the projectile in a long run (docs/MODEL.md §3)"
                                   : "";
      return "solver.dt_factor = " + fmt("%.3g", alpha) +
             " is at or beyond the central-difference stability limit (about " + fmt("%.2f", m.critical_dt_factor) +
             " for this mesh" + held + "): lower solver.dt_factor (default 0.5)";
    }
    return "lower solver.dt_factor (default 0.5) or raise solver.contact_iterations; check the scene's units";
  }
};

Simulation::Simulation(const Scene& scene) : impl_(std::make_unique<Impl>()) {
  impl_->scene = scene;
  Model m = build_model(scene);
  impl_->solver = make_solver(m, scene.solver.precision, scene.solver.threads);
  impl_->solver->set_simd(scene.solver.simd);
  impl_->solver->set_max_balance_error(scene.solver.max_balance_error);
  impl_->compute_weights();
  impl_->sample_every = std::max<long>(1, std::lround(scene.output.history_interval_s / m.dt));
  impl_->end_time = m.end_time;
  impl_->warnings = scene.warnings;
  impl_->history.push_back(impl_->sample());
}

Simulation::~Simulation() = default;

bool Simulation::step() {
  // Stepped one at a time (the app's worker): the wall time is the steps' own.
  const auto t0 = std::chrono::steady_clock::now();
  const bool alive = impl_->step();
  impl_->wall_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return alive;
}

void Simulation::run(const std::atomic<bool>* interrupt, const std::function<void(const Simulation&)>& on_sample) {
  const auto t0 = std::chrono::steady_clock::now();
  size_t seen = impl_->history.size();
  while (impl_->status == RunStatus::running) {
    if (interrupt && interrupt->load(std::memory_order_relaxed)) {
      this->interrupt("interrupted by signal");
      break;
    }
    impl_->step();
    if (on_sample && impl_->history.size() != seen) {
      seen = impl_->history.size();
      on_sample(*this);
    }
  }
  impl_->wall_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

bool Simulation::extend_to(double end_time_s) {
  Impl& I = *impl_;
  if (I.status != RunStatus::completed || I.reason != EndReason::end_time || end_time_s <= I.end_time) return false;
  I.end_time = end_time_s;
  I.status = RunStatus::running;
  I.reason = EndReason::none;
  I.diagnosis.clear();
  ++I.extensions;
  return true;
}

double Simulation::end_time_s() const {
  return impl_->end_time;
}

void Simulation::interrupt(const std::string& why) {
  impl_->finish(RunStatus::interrupted, EndReason::interrupted, why);
}

bool Simulation::finished() const {
  return impl_->status != RunStatus::running;
}
double Simulation::time_s() const {
  return impl_->solver->time();
}
long Simulation::step_count() const {
  return impl_->solver->steps();
}
double Simulation::dt_s() const {
  return impl_->model().dt;
}
const Scene& Simulation::scene() const {
  return impl_->scene;
}
const std::vector<HistoryRow>& Simulation::history() const {
  return impl_->history;
}
const Solver& Simulation::solver() const {
  return *impl_->solver;
}
Solver& Simulation::solver() {
  return *impl_->solver;
}
std::uint64_t Simulation::state_hash() const {
  return impl_->solver->state_hash();
}

namespace {
constexpr char kCheckpointMagic[9] = "RAVELCK1";

template <class Ar, class I>
void impl_io(Ar& ar, I& s) {
  ar.mark(0x52564931);  // "RVI1"
  ar.vec(s.history);
  ar.pod(s.status);
  ar.pod(s.reason);
  ar.str(s.diagnosis);
  ar.pod(s.sample_every);
  ar.pod(s.worst_balance);
  ar.pod(s.perforation_time);
  ar.pod(s.last_attached_touch);
  ar.pod(s.first_break_time);
  ar.pod(s.friction_at_first_break);
  ar.pod(s.friction_at_last_contact);
  ar.pod(s.friction_at_attached_touch);
  ar.pod(s.friction_at_perforation);
  ar.pod(s.first_break_distance);
  ar.pod(s.broken_before_perforation);
  ar.pod(s.broken_near_clamp);
  ar.pod(s.extensions);
  ar.pod(s.end_time);
  ar.pod(s.wall_s);
  ar.strings(s.warnings);
  ar.pod(s.search_lost_before);
  ar.pod(s.slow_since);
  ar.vec(s.pass_track);
  ar.pod(s.passing_since);
  ar.pod(s.decided_passing);
}
}  // namespace

std::string Simulation::checkpoint_fingerprint() const {
  Scene s = impl_->scene;
  s.solver.threads = 0;  // a run may resume with another thread count
  s.source.clear();
  s.warnings.clear();
  return scene_to_toml(s) + "\nravel " + version() + " (source " + source_commit() + ")";
}

// FNV-1a over the checkpoint's bytes, appended to it: a damaged checkpoint is refused before
// anything in it is believed (array sizes, node and element indices).
static std::uint64_t checkpoint_sum(const char* p, std::size_t n) {
  std::uint64_t h = kFnvBasis;
  fnv1a(h, p, n);
  return h;
}

std::string Simulation::checkpoint() const {
  StateWriter w;
  for (char c : std::string(kCheckpointMagic)) w.pod(c);
  w.str(checkpoint_fingerprint());
  impl_io(w, const_cast<Impl&>(*impl_));
  impl_->solver->save_state(w);
  std::string bytes = w.data();
  const std::uint64_t sum = checkpoint_sum(bytes.data(), bytes.size());
  bytes.append(reinterpret_cast<const char*>(&sum), sizeof sum);
  return bytes;
}

void Simulation::restore(const std::string& whole) {
  std::uint64_t sum = 0;
  if (whole.size() < sizeof sum) throw std::runtime_error("checkpoint: truncated");
  std::memcpy(&sum, whole.data() + whole.size() - sizeof sum, sizeof sum);
  const std::string bytes = whole.substr(0, whole.size() - sizeof sum);
  if (checkpoint_sum(bytes.data(), bytes.size()) != sum)
    throw std::runtime_error("checkpoint: damaged (its checksum does not match)");
  StateReader r(bytes);
  std::string magic(8, ' ');
  for (char& c : magic) r.pod(c);
  if (magic != kCheckpointMagic) throw std::runtime_error("checkpoint: not a ravel checkpoint");
  std::string fingerprint;
  r.str(fingerprint);
  if (fingerprint != checkpoint_fingerprint())
    throw std::runtime_error(
        "checkpoint: written for another scene or ravel build (the scene's keys, or the build that wrote it, "
        "differ); run without --resume to start over");
  // Read everything into scratch first (the fields into a spare Impl, the solver's state into a
  // fresh solver of the same model), so damaged bytes change nothing; then read the fields
  // again, into this run, from bytes now known to be whole.
  const std::size_t fields_at = r.position();
  Impl scratch;
  impl_io(r, scratch);
  const Solver& old = *impl_->solver;
  std::unique_ptr<Solver> fresh = make_solver(old.model(), impl_->scene.solver.precision, impl_->scene.solver.threads);
  fresh->set_simd(impl_->scene.solver.simd);
  fresh->set_max_balance_error(impl_->scene.solver.max_balance_error);
  fresh->load_state(r);
  if (!r.at_end()) throw std::runtime_error("checkpoint: trailing bytes");
  impl_->solver = std::move(fresh);
  impl_->broken_cache[0] = impl_->broken_cache[1] = {};  // (another solver, maybe at the old one's address)
  r.seek(fields_at);
  impl_->history.clear();  // a list: read whole
  impl_io(r, *impl_);
}

Summary Simulation::summary() const {
  const Impl& I = *impl_;
  const Model& m = I.model();
  Summary s;
  s.scene_name = I.scene.name;
  s.status = I.status;
  s.end_reason = I.reason;
  s.diagnosis = I.diagnosis;
  s.divergence_cause = I.solver->divergence_cause();
  s.divergence_step = I.solver->divergence_step();
  s.divergence_time_s = I.solver->divergence_time();
  s.perforated = I.reason == EndReason::perforated;
  s.decided_passing = I.decided_passing;
  s.impact_velocity_mps = m.impact_velocity;
  const double vf = I.forward_velocity();
  // Residual velocity: the exit speed after perforation; 0 when the fabric stopped the
  // projectile; the current forward speed when the run ended undecided.
  s.residual_velocity_mps =
      s.perforated ? vf : (I.reason == EndReason::rebounded || I.reason == EndReason::caught ? 0.0 : std::max(0.0, vf));
  s.energy_absorbed_J = 0.5 * m.projectile_mass_full *
                        (m.impact_velocity * m.impact_velocity - s.residual_velocity_mps * s.residual_velocity_mps);
  s.perforation_time_s = I.perforation_time;
  s.energy_balance_error = I.worst_balance;
  s.friction_work_J = I.solver->ledger().friction_work_J * m.symmetry_factor;
  s.clamp_friction_J = I.solver->ledger().clamp_friction_J * m.symmetry_factor;
  for (size_t g = 0; g < m.grips.size(); ++g) {
    const double fed = I.solver->grip_payout(int(g));
    s.clamp_slip_max_m = std::max(s.clamp_slip_max_m, std::min(fed, m.clamp_depth));
    // real yarns: a clamp's grip is the scene's per yarn times the yarns it holds (k when
    // lumped, half a yarn on a symmetry plane)
    if (fed >= m.clamp_depth) s.clamp_pulled_out += m.symmetry_factor * m.grips[g].force / I.scene.fabric.clamp_grip_n;
  }
  s.first_break_time_s = I.first_break_time;
  s.friction_work_to_first_break_J =
      I.first_break_time >= 0 ? I.friction_at_first_break * m.symmetry_factor : s.friction_work_J;
  s.friction_work_to_perforation_J = s.perforated ? I.friction_at_perforation * m.symmetry_factor : s.friction_work_J;
  s.first_break_distance_m = I.first_break_distance;
  double nb = I.broken_before_perforation, nc = I.broken_near_clamp;
  if (nb < 0) I.count_breaks(&nb, &nc);  // not perforated: every break so far
  s.broken_before_perforation = int(std::lround(nb));
  s.broken_near_clamp = int(std::lround(nc));
  s.model = m.symmetry_label;
  s.model_reason = m.symmetry_reason;
  s.contact_model = to_string(m.contact);
  s.modelled_node_count = m.node_count;
  s.modelled_element_count = m.element_count;
  s.modelled_crossing_count = int(m.crossings.size());
  s.node_count = int(std::lround(I.fabric_nodes));
  double ew = 0, cw = 0;
  for (double w : I.elem_weight) ew += w;
  for (double w : I.crossing_weight) cw += w;
  s.element_count = int(std::lround(ew));
  s.crossing_count = int(std::lround(cw));
  s.step_count = I.solver->steps();
  s.dt_s = m.dt;
  s.end_time_s = I.solver->time();
  s.wall_time_s = I.wall_s;
  s.node_steps_per_s = I.wall_s > 0 ? double(m.node_count) * double(s.step_count) / I.wall_s : 0;
  s.broken_warp = I.broken_elements(warp);
  s.broken_weft = I.broken_elements(weft);
  // Broken yarns (whole fabric): a yarn on a symmetry plane stands for one yarn, others for two.
  for (int y = 0; y < m.yarn_count(); ++y) {
    bool any = false;
    for (int e = m.yarn_elem_offset[y]; e < m.yarn_elem_offset[y + 1] && !any; ++e) any = I.solver->broken(e);
    if (!any) continue;
    const bool is_warp = m.yarn_family[y] == warp;
    const bool mirrored = is_warp ? m.mirror_x : m.mirror_y;
    const int count = mirrored && m.yarn_grid[y] != 0 ? 2 : 1;
    (is_warp ? s.broken_warp_yarns : s.broken_weft_yarns) += count;
    auto& lines = is_warp ? s.broken_warp_lines : s.broken_weft_lines;
    lines.push_back(m.yarn_grid[y]);
    if (count == 2) lines.push_back(-m.yarn_grid[y]);
  }
  std::sort(s.broken_warp_lines.begin(), s.broken_warp_lines.end());
  std::sort(s.broken_weft_lines.begin(), s.broken_weft_lines.end());
  double ms = 0;
  for (const auto& r : I.history) ms = std::max(ms, r.max_strain);
  s.max_strain = ms;
  s.warnings = I.warnings;
  const auto& d = I.solver->diagnostics();
  auto at = [](double t, int i, int j) {
    return " (first at t = " + fmt("%.3g", t * 1e6) + " us, crossing I=" + std::to_string(i) +
           ", J=" + std::to_string(j) + ")";
  };
  if (d.skipped_nodes)
    s.warnings.push_back("nearest-pair search: yarns slid more than one node in one step " +
                         std::to_string(d.skipped_nodes) + " times" +
                         at(d.first_skip_time, d.first_skip_i, d.first_skip_j) +
                         "; the 3 x 3 search assumes at most one; lower solver.dt_factor");
  if (d.repaired)
    s.warnings.push_back("nearest-pair search: the tracked node pair of a crossing moved more than one node " +
                         std::to_string(d.repaired) +
                         " times while its yarns moved less than half a node against "
                         "each other" +
                         at(d.first_repair_time, d.first_repair_i, d.first_repair_j) +
                         ": the yarns' shape changed (folded, bunched or apart near the projectile), they did not "
                         "outrun the search; a smaller time step does not change it");
  if (d.ravelled)
    s.warnings.push_back(
        std::to_string(d.ravelled) +
        " crossings ravelled out (a yarn slipped off its partner's free or broken end) and were released" +
        at(d.first_ravel_time, d.first_ravel_i, d.first_ravel_j));
  if (d.passed_through)
    s.warnings.push_back(
        std::to_string(d.passed_through) +
        " crossings found with yarns passed through each other by more than a yarn diameter; released" +
        at(d.first_pass_time, d.first_pass_i, d.first_pass_j));
  if (d.shift_broken)
    s.warnings.push_back(
        std::to_string(d.shift_broken) +
        " yarn elements of the modelled part were stretched to failure by contact position shifts (penetration "
        "left from earlier steps, removed by moving nodes) rather than by their own tension (first at t = " +
        fmt("%.4g", d.first_shift_break_time * 1e6) +
        " us): those breaks are the contact method's; lower solver.dt_factor (docs/MODEL.md §4)");
  if (d.balance_drift)
    s.warnings.push_back(
        "the energy balance drifted past solver.max_balance_error = " + fmt("%.3g", I.scene.solver.max_balance_error) +
        " (from t = " + fmt("%.4g", d.balance_drift_time * 1e6) + " us; worst " + fmt("%.2g", 100 * I.worst_balance) +
        " %) slowly, not by an instability: the discretisation error of a long run with many breaks "
        "at this time step; lower solver.dt_factor to reduce it");
  // Yarn-yarn friction must dissipate; its book going below zero means the stick penalty springs
  // fed energy into the yarns (docs/MODEL.md §4, "Friction's energy"). Rounding and the
  // springs' own timing stay below 0.05 % of the initial energy in the runs measured.
  if (!I.history.empty()) {
    const double e0 = I.history.front().ledger.total();
    const HistoryRow* worst = nullptr;
    for (const auto& r : I.history)
      if (!worst || r.ledger.friction_work_J < worst->ledger.friction_work_J) worst = &r;
    if (e0 > 0 && worst->ledger.friction_work_J < -kNegativeFrictionShare * e0)
      s.warnings.push_back("yarn-yarn friction work went below zero (" + fmt("%.3g", worst->ledger.friction_work_J) +
                           " J at t = " + fmt("%.4g", worst->t_s * 1e6) + " us, " +
                           fmt("%.2g", -100 * worst->ledger.friction_work_J / e0) +
                           " % of the initial energy): the soft stick penalty springs fed energy into the yarns; "
                           "solver.friction_penalty = 0.75-1 kept it dissipative where measured, but is less stable "
                           "at very high friction (docs/MODEL.md §4)");
  }
  if (I.reason == EndReason::end_time) {
    if (I.scene.solver.end_time_auto || I.extensions > 0)
      s.warnings.push_back(
          "the run reached its end time cap, solver.max_end_time_us = " + fmt("%.4g", I.end_time * 1e6) +
          " us, undecided (neither perforated nor stopped); raise solver.max_end_time_us");
    else
      s.warnings.push_back("the run reached solver.end_time_us = " + fmt("%.4g", I.end_time * 1e6) +
                           " us undecided (neither perforated nor stopped); set solver.end_time_us = \"auto\" to run "
                           "until it decides, or raise it");
  }
  return s;
}

Frame Simulation::frame() const {
  const Impl& I = *impl_;
  const Model& m = I.model();
  const Solver& S = *I.solver;
  Frame f;
  f.scene_name = I.scene.name;
  f.model_label = m.symmetry_label + ", " + to_string(m.contact);
  f.time_s = S.time();
  f.friction = I.scene.yarn.friction;
  f.impact_velocity_mps = m.impact_velocity;
  f.perforated = I.reason == EndReason::perforated;
  f.node_pos.resize(m.node_count);
  f.node_vel.resize(m.node_count);
  f.node_slip_rate.assign(m.node_count, 0.f);
  f.node_friction_j_per_g.assign(m.node_count, 0.f);
  for (int i = 0; i < m.node_count; ++i) {
    const Vec3d x = S.position(i), v = S.velocity(i);
    f.node_pos[i] = {float(x.x()), float(x.y()), float(x.z())};
    f.node_vel[i] = {float(v.x()), float(v.y()), float(v.z())};
  }
  const size_t nc = m.crossings.size();
  f.crossing_warp_node.resize(nc);
  f.crossing_weft_node.resize(nc);
  f.crossing_i.resize(nc);
  f.crossing_j.resize(nc);
  f.crossing_normal_force_n.resize(nc);
  f.crossing_slip_rate.resize(nc);
  f.crossing_active.resize(nc);
  for (size_t c = 0; c < nc; ++c) {
    const int ci = int(c);
    const float r = float(S.crossing_slip_rate(ci));
    const auto& cr = m.crossings[c];
    const int a = m.yarn_node(cr.warp_yarn, S.crossing_warp_node(ci));
    const int b = m.yarn_node(cr.weft_yarn, S.crossing_weft_node(ci));
    f.crossing_warp_node[c] = std::uint32_t(a);
    f.crossing_weft_node[c] = std::uint32_t(b);
    f.crossing_i[c] = cr.grid_i;
    f.crossing_j[c] = cr.grid_j;
    f.crossing_normal_force_n[c] = float(S.crossing_normal_force(ci));
    f.crossing_slip_rate[c] = r;
    f.crossing_active[c] = S.crossing_active(ci) ? 1 : 0;
    // The crossing's friction heat, half to each yarn's node where the contact is now, per
    // gram of the two nodes (on a symmetry plane heat and mass are both halved).
    if (const double q = S.crossing_friction_heat(ci); q > 0) {
      const double g = (m.mass[a] + m.mass[b]) * 1e3;
      f.node_friction_j_per_g[a] += float(q / g);
      f.node_friction_j_per_g[b] += float(q / g);
    }
    if (r <= 0) continue;
    f.node_slip_rate[a] = std::max(f.node_slip_rate[a], r);
    f.node_slip_rate[b] = std::max(f.node_slip_rate[b], r);
  }
  const int ne = m.element_count;
  f.elem_a.resize(ne);
  f.elem_b.resize(ne);
  f.elem_family.resize(ne);
  f.elem_broken.resize(ne);
  f.elem_yarn.resize(ne);
  f.elem_strain.resize(ne);
  f.elem_stress_pa.resize(ne);
  for (int e = 0; e < ne; ++e) {
    f.elem_a[e] = std::uint32_t(m.elem_a[e]);
    f.elem_b[e] = std::uint32_t(m.elem_b[e]);
    f.elem_yarn[e] = std::uint32_t(m.elem_yarn[e]);
    f.elem_family[e] = m.yarn_family[m.elem_yarn[e]];
    f.elem_broken[e] = S.broken(e) ? 1 : 0;
    f.elem_strain[e] = float(S.strain(e));
    f.elem_stress_pa[e] = float(S.stress(e));
  }
  f.yarn_grid.assign(m.yarn_grid.begin(), m.yarn_grid.end());
  f.yarn_family.assign(m.yarn_family.begin(), m.yarn_family.end());
  f.failure_strain = float(m.failure_strain);
  f.yarn_diameter_m = float(0.5 * m.thickness);
  f.mirror_x = m.mirror_x;
  f.mirror_y = m.mirror_y;
  f.half_width_m = float(m.half_width);
  f.half_length_m = float(m.half_length);
  f.clamped_left = m.clamped.left;
  f.clamped_right = m.clamped.right;
  f.clamped_bottom = m.clamped.bottom;
  f.clamped_top = m.clamped.top;
  f.projectile_shape = int(m.shape.kind);
  const Vec3d xp = S.projectile_position();
  f.projectile_pos = {float(xp.x()), float(xp.y()), float(xp.z())};
  f.projectile_axis = {float(m.flight_dir.x()), float(m.flight_dir.y()), float(m.flight_dir.z())};
  f.projectile_radius_m = float(m.shape.radius);
  f.projectile_length_m = float(m.shape.length);
  return f;
}

}  // namespace ravel
