// OpenMP wait policy for ravel's executables, chosen from the machine's load at start-up.
//
// A step of the solver has about seven parallel regions, so its threads meet at a barrier
// every ~0.1 ms. How they wait there decides the speed-up (default scene, 2 threads vs 1,
// measured on this project's 2-core machine, 2026-11-22):
//   idle machine:           sleep at barriers (passive) 1.22x; spin up to 20,000 rounds
//                           (GOMP_SPINCOUNT=20000) 1.87x; spin for ever (active) 1.93x;
//   1 busy process besides: passive 0.94x, spin 20,000 0.63x;
//   3 busy processes:       passive 1.01x, spin 20,000 0.53x;
//   6 busy processes:       passive 0.74x, spin 20,000 0.52x, spin 100,000 0.20x.
// Spinning pays while there is a core for every thread; on an oversubscribed machine a
// spinning thread burns the time slice the thread it waits for needs. So, unless the user
// has chosen (OMP_WAIT_POLICY or GOMP_SPINCOUNT set), the executable counts the runnable
// processes (/proc/stat procs_running, itself included, least of a few samples): with a core free for each
// solver thread it spins up to 20,000 rounds, otherwise it sleeps at once. libgomp reads
// both variables when the program loads, so the executable sets them and re-executes
// itself once. The GUI always sleeps: its render thread needs a core of its own.
#pragma once

#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <string>

namespace ravel::app {

// Runnable processes (threads) on the machine right now, this one included; -1 if unknown.
inline int runnable_now() {
  std::ifstream in("/proc/stat");
  std::string key;
  long value = 0;
  while (in >> key) {
    if (key == "procs_running" && in >> value) return int(value);
    in.ignore(1 << 20, '\n');
  }
  return -1;
}
// The sustained part of it: the least of a few samples 4 ms apart (a shell, a `ps`, the
// process that started us show up in one sample and are gone in the next; a busy process
// is in all of them).
inline int runnable_sustained() {
  int least = runnable_now();
  for (int k = 0; k < 5 && least > 1; ++k) {
    usleep(4000);
    const int r = runnable_now();
    if (r >= 0 && r < least) least = r;
  }
  return least;
}

// The wait policy for `threads` solver threads (<= 0: one per core) given `runnable`
// processes including this one and `cores` cores: true = spin briefly, false = sleep.
inline bool spin_at_barriers(int threads, int runnable, int cores) {
  if (threads <= 0) threads = cores;
  if (threads < 2 || runnable < 0 || cores < 2) return false;
  const int others = runnable - 1;
  return others + threads <= cores;
}

// Call first thing in main(). `interactive`: the GUI (always sleeps).
inline void choose_omp_wait_policy(char** argv, bool interactive = false) {
  if (std::getenv("OMP_WAIT_POLICY") || std::getenv("GOMP_SPINCOUNT")) return;
  const int cores = int(sysconf(_SC_NPROCESSORS_ONLN));
  const bool spin = !interactive && spin_at_barriers(cores, runnable_sustained(), cores);
  setenv("OMP_WAIT_POLICY", "passive", 1);
  setenv("GOMP_SPINCOUNT", spin ? "20000" : "0", 1);
  execv("/proc/self/exe", argv);  // returns only on failure: then run on as we are
}

}  // namespace ravel::app
