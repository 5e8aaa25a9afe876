// The fast ballistic-limit search (limit.h, find_ballistic_limit_fast; docs/studies.md,
// "The fast search"): the reference's guarantee -- the answer is the middle of a bracket
// whose ends are full runs that stopped and perforated, at most the tolerance apart -- with
// several runs in flight, runs stopped once moot, and the next velocities placed from the
// residual velocities already measured.
//
// One engine, two clocks: a thread per run (the real search) or a virtual clock on which
// each run lasts its Shot::wall_time_s (tests and what-if estimates: deterministic).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <exception>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "limit.h"
#include "limit_internal.h"

namespace ravel::studies {

namespace {

struct Ended {
  int id = -1;
  Shot shot;
};

class Executor {
 public:
  virtual ~Executor() = default;
  virtual void start(int id, double v, const std::string& purpose) = 0;
  virtual void cancel(int id) = 0;
  // Blocks until a run ends. With heed_interrupt, returns false (nothing ended) once the
  // interrupt is set.
  virtual bool wait(Ended* e, bool heed_interrupt) = 0;
  virtual double now() const = 0;
};

// Each run on its own thread with its own stop flag.
class ThreadExecutor final : public Executor {
 public:
  ThreadExecutor(const RunFn& run, const std::atomic<bool>* interrupt)
      : run_(run), interrupt_(interrupt), t0_(std::chrono::steady_clock::now()) {}
  ~ThreadExecutor() override {
    for (auto& [id, flag] : stops_) flag->store(true);
    for (auto& t : threads_)
      if (t.joinable()) t.join();
  }
  void start(int id, double v, const std::string& purpose) override {
    auto& flag = stops_[id];
    flag = std::make_unique<std::atomic<bool>>(false);
    std::atomic<bool>* stop = flag.get();
    threads_.emplace_back([this, id, v, purpose, stop] {
      Ended e;
      e.id = id;
      try {
        e.shot = run_(v, purpose, stop);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mu_);
        if (!error_) error_ = std::current_exception();
        e.shot = Shot{};
        e.shot.failed = true;
        e.shot.error = "the run threw";
      }
      {
        std::lock_guard<std::mutex> lock(mu_);
        ended_.push_back(std::move(e));
      }
      cv_.notify_all();
    });
  }
  void cancel(int id) override {
    auto it = stops_.find(id);
    if (it != stops_.end()) it->second->store(true);
  }
  bool wait(Ended* e, bool heed_interrupt) override {
    std::unique_lock<std::mutex> lock(mu_);
    for (;;) {
      if (!ended_.empty()) {
        *e = std::move(ended_.front());
        ended_.pop_front();
        return true;
      }
      if (heed_interrupt && interrupt_ && interrupt_->load()) return false;
      cv_.wait_for(lock, std::chrono::milliseconds(50));
    }
  }
  double now() const override { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count(); }
  void rethrow() {
    std::lock_guard<std::mutex> lock(mu_);
    if (error_) std::rethrow_exception(error_);
  }

 private:
  const RunFn& run_;
  const std::atomic<bool>* interrupt_;
  std::chrono::steady_clock::time_point t0_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<Ended> ended_;
  std::map<int, std::unique_ptr<std::atomic<bool>>> stops_;
  std::vector<std::thread> threads_;
  std::exception_ptr error_;
};

// A virtual clock: a run of `target` lasts its Shot::wall_time_s (<= 0: 1 s).
class VirtualExecutor final : public Executor {
 public:
  explicit VirtualExecutor(const ShootFn& target) : target_(target) {}
  void start(int id, double v, const std::string& purpose) override {
    Pending p;
    p.shot = target_(v, purpose);
    p.start = now_;
    p.end = now_ + (p.shot.wall_time_s > 0 ? p.shot.wall_time_s : 1.0);
    pending_[id] = p;
  }
  void cancel(int id) override {
    auto it = pending_.find(id);
    if (it == pending_.end() || it->second.cancelled) return;
    it->second.cancelled = true;
    it->second.end = now_;
  }
  bool wait(Ended* e, bool) override {
    if (pending_.empty()) throw std::logic_error("virtual executor: nothing in flight");
    auto best = pending_.begin();
    for (auto it = pending_.begin(); it != pending_.end(); ++it)
      if (it->second.end < best->second.end) best = it;  // ties: the lower id (map order)
    now_ = std::max(now_, best->second.end);
    e->id = best->first;
    if (best->second.cancelled) {
      e->shot = Shot{};
      e->shot.cancelled = true;
      e->shot.decided = false;
      e->shot.end_reason = "cancelled";
    } else {
      e->shot = best->second.shot;
    }
    e->shot.wall_time_s = best->second.end - best->second.start;
    pending_.erase(best);
    return true;
  }
  double now() const override { return now_; }

 private:
  struct Pending {
    Shot shot;
    double start = 0, end = 0;
    bool cancelled = false;
  };
  const ShootFn& target_;
  std::map<int, Pending> pending_;
  double now_ = 0;
};

double normal_cdf(double x) {
  return 0.5 * std::erfc(-x / std::sqrt(2.0));
}

// Where the limit probably is inside (lo, hi): 25 % uniform, 75 % a normal around the
// residual-velocity guess (truncated to the bracket); uniform alone without a guess.
struct Prior {
  double lo = 0, hi = 1, guess = -1, sigma = 1;
  double z = 0;  // the normal's mass inside (lo, hi)
  void setup() { z = guess > 0 ? normal_cdf((hi - guess) / sigma) - normal_cdf((lo - guess) / sigma) : 0; }
  double cdf(double v) const {
    const double u = std::clamp((v - lo) / (hi - lo), 0.0, 1.0);
    if (z < 1e-9) return u;
    const double n = (normal_cdf((std::clamp(v, lo, hi) - guess) / sigma) - normal_cdf((lo - guess) / sigma)) / z;
    return 0.25 * u + 0.75 * n;
  }
  double quantile(double q) const {
    double a = lo, b = hi;
    for (int i = 0; i < 80; ++i) {
      const double m = 0.5 * (a + b);
      (cdf(m) < q ? a : b) = m;
    }
    return 0.5 * (a + b);
  }
};

struct Flight {
  int id;
  double v;
  std::string purpose;
  double started;
  int round;
  int fit_index;  // the fit factor it stands for (-1: none)
};

class Engine {
 public:
  Engine(Executor& ex, const LimitOptions& opt, bool with_fit, const LimitHooks& hooks)
      : ex_(ex), opt_(opt), with_fit_(with_fit), hooks_(hooks), jobs_(std::max(1, opt.jobs)) {
    const FastRules& r = opt.rules;
    if (r.ksection && jobs_ > 1) res_.rules.push_back("ksection");
    if (r.cancel_moot) res_.rules.push_back("cancel_moot");
    if (r.residual_guess) res_.rules.push_back("residual_guess");
    if (r.two_sided_start && jobs_ > 1) res_.rules.push_back("two_sided_start");
    if (r.reuse_fit_points && with_fit) res_.rules.push_back("reuse_fit_points");
    if (r.probe_below && opt.probe_count > 0) res_.rules.push_back("probe_below");
    if (r.probe_below && opt.probe_count > 0 && r.probe_gaps) res_.rules.push_back("probe_gaps");
    if (r.decisive_points) res_.rules.push_back("decisive_points");
    if (r.decide_passing) res_.rules.push_back("decide_passing");  // (the runner's scene: add_rule_overrides)
    res_.method = "fast";
    res_.jobs = jobs_;
    fit_done_.assign(opt.fit_factors.size(), false);
  }

  // Runs already made count as finished (round 0).
  void add_prior(const std::vector<Shot>& prior) {
    for (Shot s : prior) {
      if (s.cancelled) continue;
      if (s.purpose.empty()) s.purpose = "bracket";
      s.resumed = true;
      s.round = 0;
      record(s);
      if (s.failed) failed_ = true;
    }
    update_bracket();
  }

  LimitResult run(bool* interrupted) {
    for (;;) {
      if (!failed_) launch();
      if (flying_.empty()) break;
      Ended e;
      if (!ex_.wait(&e, true)) {
        *interrupted = true;
        for (const auto& f : flying_) cancel(f, "interrupted");
        while (!flying_.empty()) {
          ex_.wait(&e, false);
          land(e);
        }
        break;
      }
      land(e);
    }
    finish();
    return res_;
  }

 private:
  // ---- the bracket and the guess from the runs so far
  static bool usable(const Shot& s) { return !s.failed && !s.cancelled; }
  static bool stopped(const Shot& s) { return usable(s) && !s.perforated && s.decided; }
  static bool perforated(const Shot& s) { return usable(s) && s.perforated; }

  void update_bracket() {
    hi_ = -1;
    for (const auto& s : res_.runs)
      if (perforated(s)) hi_ = hi_ < 0 ? s.velocity_mps : std::min(hi_, s.velocity_mps);
    lo_ = -1;
    for (const auto& s : res_.runs)
      if (stopped(s) && (hi_ < 0 || s.velocity_mps < hi_)) lo_ = std::max(lo_, s.velocity_mps);
    undecided_.clear();
    for (const auto& s : res_.runs)
      if (usable(s) && !s.perforated && !s.decided) undecided_.push_back(s.velocity_mps);
    guess_ = -1;
    if (!opt_.rules.residual_guess) return;
    // Lambert-Jonas with p = 2: Vr^2 = a^2 (V^2 - Vbl^2), a line in V^2 through the two
    // perforating runs closest to the limit; one run: a = 1 (an upper bound of Vbl for a <= 1).
    std::vector<std::pair<double, double>> p;
    for (const auto& s : res_.runs)
      if (perforated(s) && s.residual_velocity_mps > 0 && s.residual_velocity_mps < s.velocity_mps)
        p.emplace_back(s.velocity_mps, s.residual_velocity_mps);
    std::sort(p.begin(), p.end());
    if (p.empty()) return;
    const double v1 = p[0].first, r1 = p[0].second;
    double g = std::sqrt(v1 * v1 - r1 * r1);
    guess_points_ = 1;
    if (p.size() >= 2) {
      const double v2 = p[1].first, r2 = p[1].second;
      const double a2 = (r2 * r2 - r1 * r1) / (v2 * v2 - v1 * v1);
      if (a2 > 0.05 && a2 < 4) {
        const double b2 = v1 * v1 - r1 * r1 / a2;
        if (b2 > 0) g = std::sqrt(b2), guess_points_ = 2;
      }
    }
    if (!(std::isfinite(g) && g > 0)) return;
    // The guess's spread: 8 % from one run (a = 1 is a bound, not a value), 3 % from the first
    // secant, then what the last new run moved the secant by (one that has settled is
    // trusted more), at least half the tolerance.
    if (guess_points_ < 2) {
      sigma_ = 0.08 * g;
    } else if (std::abs(g - last_secant_) > 1e-9 * g) {
      sigma_ = last_secant_ > 0 ? std::max(0.5 * opt_.tolerance_mps, 1.5 * std::abs(g - last_secant_)) : 0.015 * g;
      last_secant_ = g;
    }
    guess_ = g;
  }

  bool bracketed() const { return lo_ > 0 && hi_ > 0; }
  bool converged() const { return bracketed() && hi_ - lo_ <= opt_.tolerance_mps; }
  double estimate() const { return bracketed() ? 0.5 * (lo_ + hi_) : guess_; }

  // ---- the fit's runs
  bool fit_wanted() const { return with_fit_ && bracketed(); }
  // The fit factor a run at `v` would stand for (-1: none still missing).
  int fit_slot(double v) const {
    const double bl = estimate();
    if (!with_fit_ || bl <= 0 || !opt_.rules.reuse_fit_points) return -1;
    for (size_t i = 0; i < opt_.fit_factors.size(); ++i) {
      if (fit_done_[i] || fit_flying(int(i))) continue;
      const double t = bl * opt_.fit_factors[i];
      if (std::abs(v / t - 1) <= opt_.fit_reuse_window) return int(i);
    }
    return -1;
  }
  bool fit_flying(int i) const {
    for (const auto& f : flying_)
      if (f.fit_index == i) return true;
    return false;
  }
  // Mark the factors the finished perforating runs already stand for.
  void cover_fit_points() {
    if (!with_fit_ || !bracketed()) return;
    const double bl = estimate();
    for (size_t i = 0; i < opt_.fit_factors.size(); ++i) {
      if (fit_done_[i]) continue;
      const double t = bl * opt_.fit_factors[i];
      if (t > opt_.max_mps) fit_done_[i] = true;  // as the reference: beyond the bound, no run
      if (!opt_.rules.reuse_fit_points) continue;
      for (const auto& s : res_.runs)
        if (perforated(s) && s.residual_velocity_mps > 0 && s.velocity_mps >= hi_ &&
            std::abs(s.velocity_mps / t - 1) <= opt_.fit_reuse_window)
          fit_done_[i] = true;
    }
  }

  // ---- planning: the next velocity to start, or none
  bool in_use(double v, double near) const {
    for (const auto& f : flying_)
      if (std::abs(f.v - v) <= near) return true;
    for (const auto& s : res_.runs)
      if (usable(s) && std::abs(s.velocity_mps - v) <= near) return true;
    return false;
  }
  int budget() const {
    int n = int(flying_.size());
    for (const auto& s : res_.runs) n += !s.cancelled;
    return opt_.max_runs - n;
  }

  // FastRules::decisive_points: v moved just inside lo + tolerance (or hi - tolerance) when it
  // lies at most half the tolerance beyond, the smaller move if both; kept in (a, b).
  double decisive(double v, double a, double b) const {
    if (!opt_.rules.decisive_points) return v;
    const double tol = opt_.tolerance_mps, reach = 0.5 * tol, inside = 0.999 * tol;
    const double down = v - (lo_ + inside);  // > 0: a perforation at v leaves hi - lo > tolerance
    const double up = (hi_ - inside) - v;    // > 0: a stop at v leaves it too
    double moved = v, by = reach;
    if (down > 0 && down <= by) moved = v - down, by = down;
    if (up > 0 && up < by) moved = v + up;
    // (not into the outer twentieth of the gap, where the planner never puts a point)
    return moved >= a + 0.05 * (b - a) && moved <= b - 0.05 * (b - a) ? moved : v;
  }

  struct Plan {
    double v = -1;
    std::string purpose;
    int fit_index = -1;
  };

  std::vector<Plan> plan(int free) {
    std::vector<Plan> out;
    const double g = opt_.growth;
    if (!bracketed()) {
      bool any = false;
      for (const auto& s : res_.runs) any |= usable(s);
      if (!any) {
        // The start, and (both sides at once) one growth step below it.
        std::vector<double> c{opt_.start_mps};
        if (opt_.rules.two_sided_start && jobs_ > 1) c.push_back(opt_.start_mps / g);
        for (double v : c) {
          v = std::clamp(v, opt_.min_mps, opt_.max_mps);
          if (int(out.size()) < free && !in_use(v, 1e-9) && !planned(out, v)) out.push_back({v, "bracket"});
        }
        return out;
      }
      if (hi_ > 0) {  // perforated, nothing stopped yet: down
        double low = hi_;
        for (const auto& f : flying_)
          if (f.purpose != "fit") low = std::min(low, f.v);
        while (int(out.size()) < free) {
          double v = -1;
          const double below = guess_ - 2 * std::max(sigma_, 0.5 * opt_.tolerance_mps);
          if (guess_ > 0 && below < hi_ && !in_use(below, 0.5 * sigma_) && !planned(out, below))
            v = below;  // two spreads below the guess: the stop the bracket lacks
          else
            v = low / (guess_ > 0 ? 1.15 : g);
          v = std::max(v, opt_.min_mps);
          if (v >= hi_ || in_use(v, 1e-9) || planned(out, v)) break;
          out.push_back({v, "bracket"});
          low = std::min(low, v);
        }
        return out;
      }
      if (lo_ > 0) {  // stopped, nothing perforated yet: up
        double high = lo_;
        for (const auto& f : flying_)
          if (f.purpose != "fit") high = std::max(high, f.v);
        while (int(out.size()) < free) {
          const double v = std::min(high * g, opt_.max_mps);
          if (v <= high || in_use(v, 1e-9)) break;
          out.push_back({v, "bracket"});
          high = v;
        }
        return out;
      }
      // Only undecided runs: up from the highest, as the reference walks up from one.
      double high = 0;
      for (const auto& s : res_.runs)
        if (usable(s)) high = std::max(high, s.velocity_mps);
      for (const auto& f : flying_) high = std::max(high, f.v);
      const double v = std::min(high * g, opt_.max_mps);
      if (v > high && free > 0) out.push_back({v, "bracket"});
      return out;
    }
    if (!converged()) {
      Prior prior;
      prior.lo = lo_;
      prior.hi = hi_;
      // A guess outside the bracket has been proved wrong on that side: the points split the
      // bracket evenly until a new perforating run corrects it.
      prior.guess = guess_ > lo_ && guess_ < hi_ ? guess_ : -1;
      prior.sigma = std::max(0.5 * opt_.tolerance_mps, sigma_);
      prior.setup();
      std::vector<double> pts{lo_, hi_};
      int inside = 0;
      for (const auto& f : flying_)
        if (f.purpose != "fit" && f.v > lo_ && f.v < hi_) pts.push_back(f.v), ++inside;
      for (double u : undecided_)
        if (u > lo_ && u < hi_) pts.push_back(u);
      std::sort(pts.begin(), pts.end());
      const int k = opt_.rules.ksection ? free : std::min(free, inside == 0 ? 1 : 0);
      if (inside == 0 && pts.size() == 2 && k >= 2) {
        // Every slot free: the bracket cut into k + 1 parts of equal prior mass.
        for (int i = 1; i <= k; ++i) {
          double v = prior.quantile(double(i) / (k + 1));
          v = std::clamp(v, lo_ + 0.05 * (hi_ - lo_), hi_ - 0.05 * (hi_ - lo_));
          // Moved only where no other point of the round lies (two points near lo + tolerance
          // would both move there, and the second would leave its slot idle).
          if (const double d = decisive(v, lo_, hi_);
              !in_use(d, 0.25 * opt_.tolerance_mps) && !planned(out, d, 0.25 * opt_.tolerance_mps))
            v = d;
          if (!in_use(v, 0.25 * opt_.tolerance_mps) && !planned(out, v, 0.25 * opt_.tolerance_mps))
            out.push_back({v, "bisect"});
        }
        if (!out.empty()) return out;
      }
      for (int n = 0; n < k; ++n) {
        // The gap most likely to hold the limit, wider than the tolerance, split at its median.
        std::vector<double> all = pts;
        for (const auto& p : out) all.push_back(p.v);
        std::sort(all.begin(), all.end());
        double best_mass = -1, best_v = -1;
        for (size_t i = 0; i + 1 < all.size(); ++i) {
          const double a = all[i], b = all[i + 1];
          // Beside an undecided run the reference splits down to half the tolerance.
          const bool by_undecided = std::find(undecided_.begin(), undecided_.end(), a) != undecided_.end() ||
                                    std::find(undecided_.begin(), undecided_.end(), b) != undecided_.end();
          if (b - a <= (by_undecided ? 0.5 : 1.0) * opt_.tolerance_mps) continue;
          const double m = prior.cdf(b) - prior.cdf(a) + 1e-12 * (b - a);
          if (m > best_mass) {
            best_mass = m;
            double v = prior.quantile(0.5 * (prior.cdf(a) + prior.cdf(b)));
            best_v = decisive(std::clamp(v, a + 0.05 * (b - a), b - 0.05 * (b - a)), a, b);
          }
        }
        if (best_v < 0) break;
        out.push_back({best_v, "bisect"});
      }
      if (int(out.size()) >= free) return out;
    }
    // Once converged (with probe_gaps, once the bracket has no use for a slot and is narrower
    // than a probe step): the probes below the bracket (FastRules::probe_below), long runs first.
    for (const double v : missing_probes()) {
      if (int(out.size()) >= free) return out;
      if (!planned(out, v, probe_near(v))) out.push_back({v, "probe"});
    }
    // Slots the bracket has no use for: the fit's runs.
    if (fit_wanted() && (converged() || opt_.rules.reuse_fit_points)) {
      cover_fit_points();
      const double bl = estimate();
      for (size_t i = 0; i < opt_.fit_factors.size() && int(out.size()) < free; ++i) {
        if (fit_done_[i] || fit_flying(int(i))) continue;
        if (!converged() && hi_ - lo_ > 0.05 * bl) break;  // early only once the limit is known within 2.5 %
        const double v = bl * opt_.fit_factors[i];
        if (v > opt_.max_mps) continue;
        bool dup = false;
        for (const auto& p : out) dup |= p.fit_index == int(i);
        if (!dup) out.push_back({v, "fit", int(i)});
      }
    }
    return out;
  }
  // The probes below the bracket still to make, highest first. Fixed (probe_gaps off): at
  // hi x (1 - k probe_step) once converged, none in flight or made within probe_near of each
  // (a run there, of any purpose, stands for it). By gaps: see probe_gaps_left.
  static double probe_near(double v) { return 0.01 * v; }
  std::vector<double> missing_probes() const {
    std::vector<double> out;
    if (!opt_.rules.probe_below || !bracketed() || failed_) return out;
    if (opt_.rules.probe_gaps) return probe_gaps_left();
    if (!converged()) return out;
    for (int k = 1; k <= opt_.probe_count; ++k) {
      const double v = hi_ * (1 - k * opt_.probe_step);
      if (v < opt_.min_mps || v >= lo_) continue;
      if (!in_use(v, probe_near(v))) out.push_back(v);
    }
    return out;
  }
  // FastRules::probe_gaps: walking down from lo, every run below it that did not perforate
  // (finished, or a probe in flight) is a sample; where no sample lies within probe_step x hi
  // (plus twice probe_near: the fixed probes' stand-ins may lie 1 % off each, so they leave
  // gaps up to that wide) below the last, a probe goes
  // one step down, not below lo x (1 - probe_count probe_step), until a sample lies within
  // probe_near of that bottom. So no stretch below the bracket down there is left wider than
  // the fixed probes leave it, and a bisection run already there saves a probe. Before
  // convergence only once the bracket is narrower than one step: hi then falls by less than
  // a step, which moves the step by under 0.25 % of hi, inside the slack, and the bottom, set
  // from lo, only up. `now` false: the probes the present samples would leave, even before
  // they may start (the ETA's estimate).
  std::vector<double> probe_gaps_left(bool now = true) const {
    std::vector<double> out;
    const double step = opt_.probe_step * hi_;
    if (step <= 0 || opt_.probe_count <= 0) return out;
    if (now && !converged() && hi_ - lo_ > step) return out;
    const double bottom = std::max(lo_ * (1 - opt_.probe_count * opt_.probe_step), opt_.min_mps);
    if (bottom >= lo_) return out;
    std::vector<double> samples;
    for (const auto& s : res_.runs)
      if (usable(s) && !s.perforated && s.velocity_mps < lo_) samples.push_back(s.velocity_mps);
    for (const auto& f : flying_)
      if (f.purpose == "probe" && f.v < lo_) samples.push_back(f.v);
    std::sort(samples.begin(), samples.end(), std::greater<double>());
    double cur = lo_;
    size_t i = 0;
    while (cur > bottom + probe_near(bottom)) {
      double next = -1;
      for (; i < samples.size() && samples[i] >= cur - step - 2 * probe_near(cur); ++i)
        if (samples[i] < cur) next = samples[i];  // the lowest sample close enough below cur
      if (next > 0) {
        cur = next;
        continue;
      }
      // One step down, or the bottom itself where that is close enough (saves a probe).
      cur = cur - bottom <= step + 2 * probe_near(cur) ? bottom : std::max(cur - step, bottom);
      out.push_back(cur);
    }
    return out;
  }
  static bool planned(const std::vector<Plan>& out, double v, double near = 1e-9) {
    for (const auto& p : out)
      if (std::abs(p.v - v) <= near) return true;
    return false;
  }

  void launch() {
    const int free = jobs_ - int(flying_.size());
    if (free <= 0 || budget() <= 0) return;
    auto plans = plan(std::min(free, budget()));
    for (const auto& p : plans) {
      Flight f{next_id_++, run_velocity(p.v), p.purpose, ex_.now(), depth_ + 1, p.fit_index};
      flying_.push_back(f);
      ex_.start(f.id, f.v, f.purpose);
      if (hooks_.on_start) {
        Shot s;
        s.velocity_mps = f.v;
        s.purpose = f.purpose;
        s.started_s = f.started;
        s.round = f.round;
        hooks_.on_start(s);
      }
    }
  }

  void cancel(const Flight& f, const std::string& why) {
    if (cancel_reason_.count(f.id)) return;
    cancel_reason_[f.id] = why;
    ex_.cancel(f.id);
  }

  void record(const Shot& s) {
    char b[400];
    if (s.failed) {
      std::snprintf(b, sizeof b, "the run at %.2f m/s failed (%s)", s.velocity_mps, s.error.c_str());
      res_.warnings.push_back(b);
    } else if (!s.cancelled && !s.decided && !s.perforated) {
      std::snprintf(b, sizeof b,
                    "the run at %.2f m/s reached its end time (%s) undecided, neither perforated nor stopped: left "
                    "out of the bracket; raise solver.max_end_time_us",
                    s.velocity_mps, s.end_reason.c_str());
      res_.warnings.push_back(b);
    }
    res_.runs.push_back(s);
  }

  void land(const Ended& e) {
    auto it = std::find_if(flying_.begin(), flying_.end(), [&](const Flight& f) { return f.id == e.id; });
    if (it == flying_.end()) return;
    const Flight f = *it;
    flying_.erase(it);
    Shot s = e.shot;
    s.velocity_mps = f.v;
    s.purpose = f.purpose;
    s.started_s = f.started;
    s.ended_s = ex_.now();
    s.round = f.round;
    if (s.cancelled) {  // stopped by the search: no outcome
      s.perforated = false;
      s.decided = false;
      s.end_reason = "cancelled";
      s.cancel_reason = cancel_reason_.count(f.id) ? cancel_reason_[f.id] : "stopped";
      ++res_.runs_cancelled;
    } else {  // a full run (one asked to stop that had just ended is one too)
      if (!s.resumed) run_time_ += s.wall_time_s, ++timed_;
      depth_ = std::max(depth_, f.round);
      if (f.fit_index >= 0) fit_done_[size_t(f.fit_index)] = true;  // whatever its outcome: never twice
    }
    record(s);
    if (s.failed) {
      if (f.purpose != "fit") {  // as the reference: nothing after a failed run is trusted
        failed_ = true;
        for (const auto& o : flying_) cancel(o, "a run failed");
      }
    } else if (!s.cancelled) {
      update_bracket();
      if (opt_.rules.cancel_moot) cancel_moot(s);
    }
    if (hooks_.on_finish) hooks_.on_finish(res_.runs.back(), progress());
  }

  // A bracket run that can no longer move the bracket, stopped (or, when the fit wants a
  // run there, kept as the fit's).
  void cancel_moot(const Shot& because) {
    for (auto& f : flying_) {
      if (f.purpose == "fit") continue;
      // A probe is below the bracket by design: moot only once a perforation below it is known.
      const bool probe = f.purpose == "probe";
      const bool above = hi_ > 0 && f.v >= hi_, below = !probe && lo_ > 0 && f.v <= lo_;
      if (!above && !below && (probe || !converged())) continue;
      if (above && with_fit_) {
        const int slot = fit_slot(f.v);
        if (slot >= 0) {
          f.purpose = "fit";
          f.fit_index = slot;
          continue;
        }
      }
      char b[160];
      if (converged())
        std::snprintf(b, sizeof b, "moot: the bracket reached the tolerance (%.2f m/s %s)", because.velocity_mps,
                      because.perforated ? "perforated" : "stopped");
      else
        std::snprintf(b, sizeof b, "moot: %.2f m/s %s", because.velocity_mps,
                      because.perforated ? "perforated below it" : "stopped above it");
      cancel(f, b);
    }
  }

  LimitProgress progress() const {
    LimitProgress p;
    p.lo_mps = lo_;
    p.hi_mps = hi_;
    p.guess_mps = guess_;
    p.jobs = jobs_;
    p.elapsed_s = ex_.now();
    for (const auto& s : res_.runs) (s.cancelled ? p.cancelled : p.finished)++;
    for (const auto& f : flying_) {
      Shot s;
      s.velocity_mps = f.v;
      s.purpose = f.purpose;
      s.started_s = f.started;
      p.in_flight.push_back(s);
    }
    if (bracketed() && timed_ > 0) {
      const double mean = run_time_ / timed_;
      // k-section: each round cuts the bracket into jobs + 1 parts; then the fit's runs.
      const double w = hi_ - lo_;
      int rounds =
          w > opt_.tolerance_mps ? int(std::ceil(std::log(w / opt_.tolerance_mps) / std::log(jobs_ + 1.0))) : 0;
      int fits = 0;
      if (with_fit_)
        for (size_t i = 0; i < fit_done_.size(); ++i) fits += !fit_done_[i];
      int fit_flights = 0;
      for (const auto& f : flying_) fit_flights += f.purpose == "fit";
      fits = std::max(0, fits - fit_flights);
      int probes = 0;
      if (opt_.rules.probe_below && opt_.rules.probe_gaps) {
        // The gaps the samples leave now (before the bracket is narrower than a step none may
        // start yet, but they will be needed unless bisection runs land in them).
        probes = failed_ ? 0 : int(probe_gaps_left(false).size());
      } else if (opt_.rules.probe_below) {
        probes = opt_.probe_count;
        for (const auto& f : flying_) probes -= f.purpose == "probe";
        for (const auto& s : res_.runs) probes -= s.purpose == "probe" && !s.cancelled;
        probes = std::max(0, probes);
      }
      rounds += (fits + probes + jobs_ - 1) / jobs_;
      double eta = rounds * mean;
      double oldest = 0;
      for (const auto& f : flying_) oldest = std::max(oldest, ex_.now() - f.started);
      if (!flying_.empty()) eta += std::max(0.0, mean - oldest);
      p.eta_s = eta;
    }
    return p;
  }

  void finish() {
    res_.lo_mps = lo_;
    res_.hi_mps = hi_;
    res_.bracketed = bracketed();
    res_.converged = converged();
    res_.rounds = depth_;
    if (!res_.bracketed) {
      if (!failed_)
        res_.warnings.push_back(lo_ < 0 ? "no velocity down to the minimum failed to perforate"
                                        : "no velocity up to the maximum perforated");
    } else {
      res_.ballistic_limit_mps = 0.5 * (lo_ + hi_);
      if (!res_.converged)
        res_.warnings.push_back(failed_ ? "search stopped by a failed run before the bracket reached the tolerance"
                                : budget() > 0 ? "undecided runs inside the bracket left nothing to bisect"
                                               : "run budget exhausted before the bracket reached the tolerance");
      if (with_fit_ && !failed_) {
        std::vector<double> vs, vrs;
        for (const auto& s : res_.runs)
          if (perforated(s) && s.velocity_mps >= hi_) {
            vs.push_back(s.velocity_mps);
            vrs.push_back(s.residual_velocity_mps);
          }
        res_.fit = fit_lambert_jonas(vs, vrs, res_.ballistic_limit_mps);
      }
    }
    warn_non_monotone(res_);
    describe_error(res_);
    res_.wall_time_s = ex_.now();
  }

  Executor& ex_;
  const LimitOptions& opt_;
  const bool with_fit_;
  const LimitHooks& hooks_;
  const int jobs_;
  LimitResult res_;
  std::vector<Flight> flying_;
  std::map<int, std::string> cancel_reason_;
  std::vector<double> undecided_;
  std::vector<bool> fit_done_;
  double lo_ = -1, hi_ = -1, guess_ = -1, last_secant_ = -1, sigma_ = 1;
  int guess_points_ = 0;
  bool failed_ = false;
  int next_id_ = 0, depth_ = 0;
  double run_time_ = 0;
  int timed_ = 0;
};

}  // namespace

std::string LimitProgress::line() const {
  char b[300];
  int n = std::snprintf(b, sizeof b, "%d runs", finished);
  if (cancelled) n += std::snprintf(b + n, sizeof b - size_t(n), " (%d cancelled)", cancelled);
  if (lo_mps > 0 && hi_mps > 0)
    n += std::snprintf(b + n, sizeof b - size_t(n), ", bracket %.2f - %.2f m/s", lo_mps, hi_mps);
  else
    n += std::snprintf(b + n, sizeof b - size_t(n), ", bracketing (%s)",
                       hi_mps > 0   ? "perforated, going down"
                       : lo_mps > 0 ? "stopped, going up"
                                    : "no outcome yet");
  if (guess_mps > 0) n += std::snprintf(b + n, sizeof b - size_t(n), ", guess %.1f m/s", guess_mps);
  if (!in_flight.empty()) n += std::snprintf(b + n, sizeof b - size_t(n), ", %zu in flight", in_flight.size());
  if (eta_s >= 0) {
    if (eta_s < 120)
      std::snprintf(b + n, sizeof b - size_t(n), ", ~%.0f s left", eta_s);
    else
      std::snprintf(b + n, sizeof b - size_t(n), ", ~%.1f min left", eta_s / 60);
  }
  return b;
}

LimitResult find_ballistic_limit_fast(const RunFn& run, const LimitOptions& opt, bool with_fit,
                                      const std::atomic<bool>* interrupt, const LimitHooks& hooks,
                                      const std::vector<Shot>& prior) {
  ThreadExecutor ex(run, interrupt);
  Engine engine(ex, opt, with_fit, hooks);
  engine.add_prior(prior);
  bool interrupted = false;
  LimitResult r = engine.run(&interrupted);
  ex.rethrow();
  r.interrupted = interrupted;
  if (interrupted)
    r.warnings.push_back("interrupted after " + std::to_string(r.runs.size() - size_t(r.runs_cancelled)) +
                         " finished runs; rerun the same command to resume");
  return r;
}

LimitResult simulate_fast_search(const ShootFn& target, const LimitOptions& opt, bool with_fit) {
  VirtualExecutor ex(target);
  LimitHooks none;
  Engine engine(ex, opt, with_fit, none);
  bool interrupted = false;
  return engine.run(&interrupted);
}

}  // namespace ravel::studies
