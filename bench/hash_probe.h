// The hash probe's cases (bench/hash_probe.cpp, tests/core/hash_probe_test.cpp): scenes that
// between them take every path of a step (one and two threads, float, the full fabric, a
// ravelling low-friction patch, the pin-jointed model), each run for a fixed number of steps.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "scene.h"
#include "simulation.h"

namespace ravel {

struct ProbeCase {
  std::string name;
  std::vector<std::string> overrides;  // on top of the default scene
  long steps;
};

inline const std::vector<ProbeCase>& probe_cases() {
  static const std::vector<ProbeCase> cases = {
      {"default_1thread", {"solver.threads=1"}, 600},
      {"default_2threads", {"solver.threads=2"}, 600},
      {"float", {"solver.precision=float", "solver.threads=1"}, 400},
      {"full_patch",
       {"solver.symmetry=full", "fabric.width_mm=24", "fabric.length_mm=24", "projectile.diameter_mm=6",
        "solver.threads=2"},
       800},
      {"ravel_patch",
       {"fabric.width_mm=30", "fabric.length_mm=30", "projectile.diameter_mm=6", "yarn.friction=0.02",
        "projectile.velocity_mps=400", "solver.threads=1"},
       1500},
      {"pin_jointed", {"solver.model=pin_jointed", "solver.threads=1"}, 600},
  };
  return cases;
}

struct ProbeResult {
  long steps = 0;
  std::uint64_t hash = 0;
};

inline ProbeResult run_probe(const ProbeCase& c, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> ov = c.overrides;
  ov.push_back("output.progress=false");
  ov.insert(ov.end(), extra.begin(), extra.end());
  Simulation sim(load_scene(default_scene_path(), ov));
  while (sim.step_count() < c.steps && sim.step()) {
  }
  return {sim.step_count(), sim.state_hash()};
}

}  // namespace ravel
