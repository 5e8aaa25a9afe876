#include "sim_worker.h"

#include <algorithm>
#include <cstdio>

#include "solver.h"

namespace ravel::app {

namespace {
using Clock = std::chrono::steady_clock;
// The UI draws at most ~60 times a second; publishing more often only costs copies.
constexpr auto kPublishEvery = std::chrono::milliseconds(15);
// When paced and idle, wake up at least this often to check the clock.
constexpr auto kPaceSleepMax = std::chrono::milliseconds(5);
// If the solver falls this far behind a slow-motion rate, re-anchor instead of racing.
constexpr double kMaxLag_s = 0.25;

double seconds(Clock::duration d) {
  return std::chrono::duration<double>(d).count();
}

std::string run_label(long run_id, const Scene& s) {
  char b[160];
  std::snprintf(b, sizeof b, "run %ld: mu %.2f, %.0f m/s", run_id, s.yarn.friction, s.projectile.velocity_mps);
  return b;
}
}  // namespace

const char* to_string(WorkerState s) {
  switch (s) {
    case WorkerState::running:
      return "running";
    case WorkerState::paused:
      return "paused";
    case WorkerState::finished:
      return "finished";
    case WorkerState::diverged:
      return "diverged";
  }
  return "?";
}

SimWorker::SimWorker(const Scene& scene, bool start_paused, ClockFn clock)
    : sim_(std::make_unique<Simulation>(scene)), scene_(scene) {
  clock_ = clock ? std::move(clock) : ClockFn([] { return Clock::now(); });
  paused_.store(start_paused);
  pacing_live_ = pacing_;
  publish(true);
  thread_ = std::thread([this] { loop(); });
}

SimWorker::~SimWorker() {
  request_exit();
  if (thread_.joinable()) thread_.join();
}

// ---- Commands --------------------------------------------------------------------------

void SimWorker::notify() {
  commands_issued_.fetch_add(1);
  // Taking the mutex orders the notification after the worker's predicate check, so a
  // command issued while the worker is about to sleep is never lost.
  { std::lock_guard<std::mutex> lk(mutex_); }
  wake_.notify_all();
}

void SimWorker::play() {
  paused_.store(false);
  steps_requested_.store(0);
  notify();
}

void SimWorker::pause() {
  paused_.store(true);
  pause_serial_.fetch_add(1);
  notify();
}

void SimWorker::toggle_pause() {
  if (paused_.load())
    play();
  else
    pause();
}

void SimWorker::step_once(int steps) {
  paused_.store(true);
  pause_serial_.fetch_add(1);
  steps_requested_.fetch_add(std::max(1, steps));
  notify();
}

void SimWorker::reset() {
  reset_.store(true);
  notify();
}

void SimWorker::restart(const Scene& scene) {
  {
    std::lock_guard<std::mutex> lk(mutex_);
    pending_.scene = scene;
    pending_.restart_pause_serial = pause_serial_.load();
    has_pending_.store(true);
  }
  notify();
}

void SimWorker::set_pacing(const Pacing& pacing) {
  {
    std::lock_guard<std::mutex> lk(mutex_);
    pending_.pacing = pacing;
    pacing_ = pacing;
    has_pending_.store(true);
  }
  notify();
}

Pacing SimWorker::pacing() const {
  std::lock_guard<std::mutex> lk(mutex_);
  return pacing_;
}

void SimWorker::set_threads(int threads) {
  {
    std::lock_guard<std::mutex> lk(mutex_);
    pending_.threads = threads;
    has_pending_.store(true);
  }
  notify();
}

void SimWorker::pause_at(double t_s, bool hold) {
  {
    std::lock_guard<std::mutex> lk(mutex_);
    pending_.pause_at_s = t_s;
    pending_.pause_hold = hold;
    has_pending_.store(true);
  }
  notify();
}

void SimWorker::clear_past_runs() {
  {
    std::lock_guard<std::mutex> lk(mutex_);
    pending_.clear_past = true;
    has_pending_.store(true);
  }
  notify();
}

void SimWorker::set_max_past_runs(int n) {
  {
    std::lock_guard<std::mutex> lk(mutex_);
    pending_.max_past_runs = std::max(0, n);
    has_pending_.store(true);
  }
  notify();
}

void SimWorker::request_exit() {
  exit_.store(true);
  notify();
}

// ---- UI side ---------------------------------------------------------------------------

bool SimWorker::sync(WorkerView& view) {
  std::lock_guard<std::mutex> lk(mutex_);
  const Shared& s = shared_;
  if (view.run_id != s.run_id) {
    view.run_id = s.run_id;
    view.scene = s.scene;
    view.history.clear();
  }
  bool changed = false;
  if (view.frame_serial != s.frame_serial) {
    // Swap, not copy: O(1) under the lock. The worker replaces shared_.frame wholesale
    // before it publishes again, so what the UI leaves behind is never shown.
    std::swap(view.frame, shared_.frame);
    view.frame_serial = s.frame_serial;
    changed = true;
  }
  view.new_frames.clear();
  std::swap(view.new_frames, shared_.queued);  // O(1): the worker starts a fresh queue
  if (view.history.size() > s.history.size()) view.history.clear();
  view.history.insert(view.history.end(), s.history.begin() + long(view.history.size()), s.history.end());
  view.step_count = s.step_count;
  view.summary = s.summary;
  view.state = s.state;
  view.message = s.message;
  view.steps_per_s = s.steps_per_s;
  view.sim_us_per_wall_s = s.sim_us_per_wall_s;
  if (view.past_serial != s.past_serial) {
    view.past_runs = s.past_runs;
    view.past_serial = s.past_serial;
  }
  return changed;
}

bool SimWorker::wait_for_steps(long steps, std::chrono::milliseconds timeout) {
  const long issued = commands_issued_.load();  // commands given before this call count
  std::unique_lock<std::mutex> lk(mutex_);
  return published_.wait_for(lk, timeout, [&] {
    return shared_.commands_applied >= issued && (shared_.step_count >= steps || shared_.state != WorkerState::running);
  });
}

bool SimWorker::wait_idle(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lk(mutex_);
  return published_.wait_for(lk, timeout, [&] {
    return shared_.commands_applied >= commands_issued_.load() && steps_requested_.load() == 0 &&
           shared_.state != WorkerState::running;
  });
}

void SimWorker::queue_frames(bool on) {
  queue_frames_.store(on);
}

bool SimWorker::busy() const {
  std::lock_guard<std::mutex> lk(mutex_);
  return !(shared_.commands_applied >= commands_issued_.load() && steps_requested_.load() == 0 &&
           shared_.state != WorkerState::running);
}

// ---- Worker thread ---------------------------------------------------------------------

WorkerState SimWorker::current_state() const {
  if (diverged_) return WorkerState::diverged;
  if (sim_->finished()) return WorkerState::finished;
  if (paused_.load() && steps_requested_.load() == 0) return WorkerState::paused;
  return WorkerState::running;
}

void SimWorker::retire_current_run() {
  if (sim_->history().size() < 2) return;  // nothing worth overlaying
  PastRun run;
  run.run_id = run_id_;
  run.label = run_label(run_id_, scene_);
  run.history = sim_->history();
  std::lock_guard<std::mutex> lk(mutex_);
  shared_.past_runs.push_back(std::move(run));
  while (int(shared_.past_runs.size()) > max_past_runs_) shared_.past_runs.erase(shared_.past_runs.begin());
  ++shared_.past_serial;
}

bool SimWorker::rebuild(const Scene& edited) {
  std::unique_ptr<Simulation> fresh;
  Scene scene = edited;
  try {
    scene.warnings.clear();
    validate_scene(scene);  // the Simulation trusts its scene; edits from the UI are checked here
    fresh = std::make_unique<Simulation>(scene);
  } catch (const std::exception& e) {
    message_ = std::string("could not build the scene: ") + e.what();
    return false;
  }
  retire_current_run();
  sim_ = std::move(fresh);
  scene_ = scene;
  ++run_id_;
  diverged_ = false;
  pause_at_fired_ = false;
  message_.clear();
  published_rows_ = 0;
  anchor_wall_ = clock_();
  anchor_sim_s_ = 0;
  rate_wall_ = anchor_wall_;
  rate_steps_ = 0;
  rate_sim_s_ = 0;
  return true;
}

bool SimWorker::apply_commands() {
  bool changed = false;
  if (has_pending_.exchange(false)) {
    Pending p;
    {
      std::lock_guard<std::mutex> lk(mutex_);
      std::swap(p, pending_);
    }
    if (p.pacing) {
      pacing_live_ = *p.pacing;
      anchor_wall_ = clock_();
      anchor_sim_s_ = sim_->time_s();
    }
    if (p.threads) {
      scene_.solver.threads = *p.threads;
      sim_->solver().set_threads(*p.threads);
    }
    if (p.pause_at_s) {
      pause_at_s_ = *p.pause_at_s;
      pause_at_fired_ = !p.pause_hold && pause_at_s_ >= 0 && sim_->time_s() + 0.5 * sim_->dt_s() >= pause_at_s_;
    }
    if (p.max_past_runs) max_past_runs_ = *p.max_past_runs;
    if (p.clear_past) {
      std::lock_guard<std::mutex> lk(mutex_);
      shared_.past_runs.clear();
      ++shared_.past_serial;
    }
    if (p.scene) {
      reset_.store(false);  // a restart is a reset with new values
      // A restart is to watch the new values play out (unless paused since); a refused one
      // keeps the current run as it was, paused or not.
      if (rebuild(*p.scene) && pause_serial_.load() == p.restart_pause_serial) {
        steps_requested_.store(0);
        paused_.store(false);
      }
    }
    changed = true;
  }
  if (reset_.exchange(false)) {
    rebuild(scene_);
    changed = true;
  }
  return changed;
}

void SimWorker::publish(bool force) {
  const auto now = Clock::now();
  if (!force && now - last_publish_ < kPublishEvery) return;
  last_publish_ = now;
  Frame frame = sim_->frame();  // outside the lock: only this thread reads the Simulation
  Summary summary = sim_->summary();
  const auto& rows = sim_->history();
  const WorkerState state = current_state();
  const bool queue = queue_frames_.load();
  Frame copy;
  if (queue) copy = frame;
  {
    std::lock_guard<std::mutex> lk(mutex_);
    Shared& s = shared_;
    if (s.run_id != run_id_) {
      s.run_id = run_id_;
      s.scene = scene_;
      s.history.clear();
      s.queued.clear();
    }
    if (queue) {
      constexpr std::size_t kMaxQueued = 64;
      if (s.queued.size() >= kMaxQueued) {  // nobody synced for a while: keep every other
        std::vector<std::pair<Frame, long>> half;
        for (std::size_t i = 1; i < s.queued.size(); i += 2) half.push_back(std::move(s.queued[i]));
        s.queued = std::move(half);
      }
      s.queued.emplace_back(std::move(copy), sim_->step_count());
    }
    std::swap(s.frame, frame);
    ++s.frame_serial;
    s.step_count = sim_->step_count();
    s.history.insert(s.history.end(), rows.begin() + long(published_rows_), rows.end());
    s.summary = std::move(summary);
    s.state = state;
    s.message = message_;
    s.steps_per_s = steps_per_s_;
    s.sim_us_per_wall_s = sim_rate_;
    s.commands_applied = applied_commands_;
  }
  published_rows_ = rows.size();
  published_.notify_all();
}

void SimWorker::loop() {
  bool was_stepping = false;
  long seen_commands = -1;
  while (!exit_.load()) {
    const long issued = commands_issued_.load();
    const bool changed = apply_commands();
    if (exit_.load()) break;

    const bool may_step = !diverged_ && !sim_->finished() && (!paused_.load() || steps_requested_.load() > 0);
    if (!may_step) {
      // Single steps asked of a run that has ended cannot be honoured: drop them, or they
      // would stay pending (wait_idle never returns) and leak into the next run.
      if (diverged_ || sim_->finished()) steps_requested_.store(0);
      steps_per_s_ = sim_rate_ = 0;
      if (changed || was_stepping || issued != seen_commands) {
        applied_commands_ = issued;
        publish(true);
      }
      published_.notify_all();
      seen_commands = issued;
      was_stepping = false;
      std::unique_lock<std::mutex> lk(mutex_);
      wake_.wait_for(lk, std::chrono::milliseconds(100),
                     [&] { return exit_.load() || commands_issued_.load() != issued; });
      continue;
    }

    const auto now = clock_();
    if (!was_stepping) {
      // (Re)start the pacing clock and the rate meter from here.
      anchor_wall_ = now;
      anchor_sim_s_ = sim_->time_s();
      rate_wall_ = now;
      rate_steps_ = sim_->step_count();
      rate_sim_s_ = sim_->time_s();
      was_stepping = true;
    }
    if (changed || issued != seen_commands) {
      // Say "applied" only together with the state those commands produced.
      applied_commands_ = issued;
      publish(true);
    }
    seen_commands = issued;

    // Pacing: a slow-motion run may not get ahead of wall time (single steps are exempt).
    const bool single = paused_.load();
    if (!single && !pacing_live_.max_speed) {
      const double rate_s_per_s = pacing_live_.sim_us_per_wall_s * 1e-6;
      double allowed = anchor_sim_s_ + rate_s_per_s * seconds(now - anchor_wall_);
      if (allowed - sim_->time_s() > rate_s_per_s * kMaxLag_s) {
        anchor_wall_ = now;  // the solver cannot keep up: do not try to catch up in a burst
        anchor_sim_s_ = sim_->time_s();
        allowed = anchor_sim_s_;
      }
      const double next_s = sim_->time_s() + sim_->dt_s();
      if (next_s > allowed) {
        const auto wait = std::chrono::duration_cast<Clock::duration>(
            std::chrono::duration<double>((next_s - allowed) / std::max(rate_s_per_s, 1e-12)));
        publish(false);
        std::unique_lock<std::mutex> lk(mutex_);
        wake_.wait_for(lk, std::min<Clock::duration>(kPaceSleepMax, wait),
                       [&] { return exit_.load() || commands_issued_.load() != issued; });
        continue;
      }
    }

    // One step: the only place the Simulation advances.
    bool alive = true;
    try {
      alive = sim_->step();
    } catch (const std::exception& e) {
      sim_->interrupt(std::string("solver error: ") + e.what());
      message_ = std::string("solver error: ") + e.what();
      diverged_ = true;
      alive = false;
    }
    if (single && steps_requested_.load() > 0) steps_requested_.fetch_sub(1);
    bool force = single;
    if (!alive) {
      const Summary s = sim_->summary();
      if (s.status == RunStatus::diverged) {
        diverged_ = true;
        paused_.store(true);
        char b[96];
        std::snprintf(b, sizeof b, "the run diverged at t = %.2f us and was paused: ", sim_->time_s() * 1e6);
        message_ = b + s.diagnosis;
      }
      force = true;
    }
    if (pause_at_s_ >= 0 && !pause_at_fired_ && sim_->time_s() + 0.5 * sim_->dt_s() >= pause_at_s_) {
      paused_.store(true);
      pause_at_fired_ = true;  // Play goes on past it; the next run stops there again
      force = true;
    }

    // Rate meter, over half-second windows.
    const auto after = clock_();
    if (after - rate_wall_ > std::chrono::milliseconds(500)) {
      const double dt = seconds(after - rate_wall_);
      steps_per_s_ = double(sim_->step_count() - rate_steps_) / dt;
      sim_rate_ = (sim_->time_s() - rate_sim_s_) * 1e6 / dt;
      rate_wall_ = after;
      rate_steps_ = sim_->step_count();
      rate_sim_s_ = sim_->time_s();
    }
    publish(force);
  }
  publish(true);
  published_.notify_all();
}

}  // namespace ravel::app
