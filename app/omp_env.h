// OpenMP wait policy for ravel's executables.
//
// libgomp reads OMP_WAIT_POLICY once, when the program loads, so setting it in main() is
// too late. Its default spins at every barrier; on a loaded machine (more runnable threads
// than cores) a spinning solver thread starves the one doing the work: measured 2 threads
// 5-20x slower than 1 at load 6-10 on 2 cores. So, when the user has not chosen a policy,
// the executable sets "passive" (threads sleep at barriers) and re-executes itself once.
// Set OMP_WAIT_POLICY=active to keep spinning (slightly faster on an idle machine).
#pragma once

#include <unistd.h>

#include <cstdlib>

namespace ravel::app {

inline void ensure_passive_omp_wait(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY")) return;
  setenv("OMP_WAIT_POLICY", "passive", 1);
  execv("/proc/self/exe", argv);  // returns only on failure: then run on as we are
}

}  // namespace ravel::app
