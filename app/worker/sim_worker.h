// SimWorker: the app's simulation thread (STYLE.md "Threads", after MuJoCo `simulate`).
//
// The worker owns the Simulation and steps it on a std::thread; the UI thread never
// touches the Simulation. They meet in two places only:
//
//   commands  UI -> worker. Pause / play / single step / reset / exit are atomics the
//             worker reads between steps. Everything else (a new scene, pacing, solver
//             threads, clearing the overlays) goes into a `Pending` struct under the
//             mutex and is applied by the worker at the next step boundary.
//   Shared    worker -> UI. After some steps the worker builds a Frame (outside the lock:
//             only the worker reads the Simulation), then takes the mutex for a moment
//             to swap it in with the new history rows, the summary and the status, all
//             from the same step. The UI's sync() takes the mutex for a moment, swaps
//             the frame out and copies the new rows, and draws only its own copy.
//
// Simulated time is paced against wall time: as fast as possible, or a slow-motion
// rate in simulated microseconds per wall second. A diverged run pauses with the
// solver's diagnosis as the message. A finished run keeps its last frame on show; its
// history joins the "past runs" (faint overlays in the charts) when the run is reset or
// restarted.
//
// No GL, no ImGui, no GLFW here: the worker is unit-tested and run under ThreadSanitizer
// without a window (tests/app/sim_worker_test.cpp).
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "simulation.h"

namespace ravel::app {

// How simulated time relates to wall time.
struct Pacing {
  bool max_speed = true;           // step as fast as the solver can
  double sim_us_per_wall_s = 2.0;  // slow motion when !max_speed (simulated us per wall second)
};

enum class WorkerState {
  running,   // stepping (or waiting for wall time to catch up when paced)
  paused,    // by the user, or after a divergence (see message)
  finished,  // the run ended (perforated, rebounded, end time)
  diverged,  // the run diverged; paused with the diagnosis in `message`
};
const char* to_string(WorkerState s);

// A finished or abandoned run, kept for the charts' overlays.
struct PastRun {
  long run_id = 0;
  std::string label;  // e.g. "run 2: mu 0.10, 260 m/s"
  std::vector<HistoryRow> history;
};

// What the UI reads. Filled by SimWorker::sync(); everything in it comes from one step.
struct WorkerView {
  long run_id = 0;  // changes on reset / restart
  Scene scene;      // the scene of the current run (as built)
  Frame frame;
  std::uint64_t frame_serial = 0;   // changes with every published frame
  long step_count = 0;              // steps of the current run when the frame was taken
  std::vector<HistoryRow> history;  // of the current run, from t = 0
  Summary summary;
  WorkerState state = WorkerState::paused;
  std::string message;             // divergence diagnosis, scene error, ... ("" = none)
  double steps_per_s = 0;          // measured over the last half second of stepping
  double sim_us_per_wall_s = 0;    // measured simulated rate
  std::vector<PastRun> past_runs;  // oldest first
  std::uint64_t past_serial = 0;
  // With SimWorker::queue_frames: every frame published since the last sync (oldest first,
  // with the run's step count when it was taken), not only the newest one. The app's
  // timeline keeps them all.
  std::vector<std::pair<Frame, long>> new_frames;
};

class SimWorker {
 public:
  // Builds the first Simulation on the calling thread (throws SceneError / whatever the
  // Simulation constructor throws), then starts the thread.
  // The clock that paces slow motion and times the rate meter (steady_clock::now when
  // empty); a test injects one it advances by hand.
  using ClockFn = std::function<std::chrono::steady_clock::time_point()>;
  explicit SimWorker(const Scene& scene, bool start_paused = false, ClockFn clock = {});
  ~SimWorker();  // requests exit and joins
  SimWorker(const SimWorker&) = delete;
  SimWorker& operator=(const SimWorker&) = delete;

  // ---- Commands: any thread, cheap, never block on the solver. ---------------------
  void play();
  void pause();
  void toggle_pause();
  void step_once(int steps = 1);     // while paused: advance this many steps
  void reset();                      // rebuild the current scene, t = 0 (stays paused if paused)
  void restart(const Scene& scene);  // rebuild with new values, t = 0, and play (a refused scene changes nothing)
  void set_pacing(const Pacing& pacing);
  void set_threads(int threads);  // solver threads, applied live
  // Pause every run when its simulated time reaches t_s (< 0: never). Play continues
  // past it; a reset or restart stops there again. With `hold` (the side-by-side runs of a
  // comparison, which ask again each frame from a view that may lag the run) a run already
  // at or past t_s pauses after its next step instead of playing on past it.
  void pause_at(double t_s, bool hold = false);
  void clear_past_runs();
  void set_max_past_runs(int n);  // default 6
  // Queue every published frame for the UI (WorkerView::new_frames), at most 64 between two
  // syncs (beyond that every other is dropped). Off by default: it costs a Frame copy per
  // publish.
  void queue_frames(bool on);
  void request_exit();

  bool paused() const { return paused_.load(); }
  Pacing pacing() const;

  // ---- UI side. ---------------------------------------------------------------------
  // Bring `view` up to date under a short lock: swap in the newest frame if there is
  // one, append the history rows `view` does not have yet, copy summary and status.
  // Returns true when the frame changed.
  bool sync(WorkerView& view);

  // Block until the worker has applied the commands given so far and published a frame
  // with step_count >= steps of the current run, or the run is paused/finished/diverged,
  // or the timeout passes (tests).
  bool wait_for_steps(long steps, std::chrono::milliseconds timeout);
  // Block until no command is left unapplied and the worker is idle (paused, finished
  // or diverged) or the timeout passes (tests).
  bool wait_idle(std::chrono::milliseconds timeout);
  // Not idle: a command is not applied yet, steps are pending, or the run is going (the
  // non-blocking form of wait_idle, for the UI's scripted `wait`).
  bool busy() const;

 private:
  struct Pending {
    std::optional<Scene> scene;     // restart with this scene
    long restart_pause_serial = 0;  // pause_serial_ when the restart was asked for
    std::optional<Pacing> pacing;
    std::optional<int> threads;
    std::optional<double> pause_at_s;
    bool pause_hold = false;
    std::optional<int> max_past_runs;
    bool clear_past = false;
  };
  struct Shared {
    long run_id = 0;
    Scene scene;
    Frame frame;
    std::uint64_t frame_serial = 0;
    long step_count = 0;
    std::vector<HistoryRow> history;
    Summary summary;
    WorkerState state = WorkerState::paused;
    std::string message;
    double steps_per_s = 0, sim_us_per_wall_s = 0;
    std::vector<PastRun> past_runs;
    std::uint64_t past_serial = 0;
    long commands_applied = 0;
    std::vector<std::pair<Frame, long>> queued;  // frames since the last sync (queue_frames)
  };

  void loop();
  bool apply_commands();             // at a step boundary; true if anything changed
  bool rebuild(const Scene& scene);  // worker thread only; false (message_ says why) keeps the old run
  void publish(bool force);          // worker thread only
  void retire_current_run();         // current history -> past runs
  WorkerState current_state() const;
  void notify();

  // Worker-thread-only state.
  std::unique_ptr<Simulation> sim_;
  Scene scene_;
  long run_id_ = 1;
  int next_label_ = 1;
  Pacing pacing_live_;
  double pause_at_s_ = -1;
  bool pause_at_fired_ = false;
  int max_past_runs_ = 6;
  std::string message_;
  bool diverged_ = false;
  size_t published_rows_ = 0;
  long applied_commands_ = 0;  // commands_issued_ as of the last apply_commands()
  std::chrono::steady_clock::time_point last_publish_{};
  // Pacing anchor: at wall time anchor_wall_ the simulation was at anchor_sim_s_.
  ClockFn clock_;  // pacing and rate meter
  std::chrono::steady_clock::time_point anchor_wall_{};
  double anchor_sim_s_ = 0;
  // Rate measurement.
  std::chrono::steady_clock::time_point rate_wall_{};
  long rate_steps_ = 0;
  double rate_sim_s_ = 0;
  double steps_per_s_ = 0, sim_rate_ = 0;

  // Commands.
  std::atomic<bool> paused_{false};
  // Counts pause and single-step commands: a restart plays its new run only if no pause
  // was asked for after it, and a refused restart leaves the current run as it was.
  std::atomic<long> pause_serial_{0};
  std::atomic<bool> exit_{false};
  std::atomic<bool> reset_{false};
  std::atomic<int> steps_requested_{0};
  std::atomic<bool> has_pending_{false};
  std::atomic<long> commands_issued_{0};
  std::atomic<bool> queue_frames_{false};

  mutable std::mutex mutex_;           // guards pending_ and shared_
  std::condition_variable wake_;       // worker waits here when idle
  std::condition_variable published_;  // tests wait here
  Pending pending_;
  Shared shared_;
  Pacing pacing_;  // last requested pacing (for pacing())

  std::thread thread_;
};

}  // namespace ravel::app
