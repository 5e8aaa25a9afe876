// SweepRunner: a sweep on a background thread, for the app's progress bar and live chart.
//
// The UI thread calls start(), then each frame snapshot() (a copy taken under a short
// lock) and draws only that copy; cancel() sets the interrupt (the running cases stop
// between steps and leave nothing half-written; a later start() resumes).
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "chart.h"
#include "sweep.h"

namespace ravel::studies {

class SweepRunner {
 public:
  struct Snapshot {
    bool running = false, finished = false;
    SweepProgress progress;
    SweepReport report;  // valid when finished
    std::string error;   // bad input or output error (not started / stopped)
    Csv results;         // one row per case done so far: case, varied keys, summary keys
    std::vector<std::string> varied_keys;
    // Repeats (apply_repeats): each velocity run `repeats` times; base_of maps each run's
    // velocity to the one it repeats (perforation_table groups by it).
    int repeats = 1;
    std::map<std::string, std::string> base_of;
    // Charts of `results` (energy absorbed, residual velocity vs the first varied key).
    std::vector<std::pair<std::string, Chart>> charts() const { return sweep_charts(results, varied_keys); }
  };

  SweepRunner() = default;
  ~SweepRunner();  // cancels and joins
  SweepRunner(const SweepRunner&) = delete;
  SweepRunner& operator=(const SweepRunner&) = delete;

  // `vary` as on the command line ("key=start:stop:step" or "key=v1,v2"), `repeats` as
  // `ravel sweep --repeats`. Validates on the calling thread (returns false and sets *error,
  // nothing started), then runs; once finished, writes perforation.csv and its chart as the
  // command does (write_perforation_outputs).
  bool start(const SweepOptions& options, const std::vector<std::string>& vary, std::string* error, int repeats = 1);
  void cancel();
  bool running() const;
  Snapshot snapshot() const;

 private:
  mutable std::mutex mu_;
  Snapshot state_;
  std::atomic<bool> interrupt_{false};
  std::thread thread_;
};

}  // namespace ravel::studies
