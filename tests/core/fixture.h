// Small helpers that keep the physics tests short (after Jolt's PhysicsTestContext and
// MuJoCo's test fixture): build a scene from overrides, run it, read numbers back.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "model.h"
#include "scene.h"
#include "simulation.h"
#include "solver.h"

namespace ravel::test {

// The default scene (the paper's test) with overrides applied.
inline Scene scene_with(std::vector<std::string> overrides) {
  overrides.push_back("output.progress=false");
  return load_scene(default_scene_path(), overrides);
}

// A small, quick plain-weave patch: 24 x 24 mm, 4 mm 1 g sphere.
inline std::vector<std::string> small_patch() {
  return {"fabric.width_mm=24", "fabric.length_mm=24", "projectile.diameter_mm=4", "projectile.mass_g=1",
          "solver.end_time_us=60"};
}

inline std::vector<std::string> operator+(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// Run to the end and return the summary.
inline Summary simulate(const Scene& scene) {
  Simulation sim(scene);
  sim.run();
  return sim.summary();
}

// Run until simulated time t (or the end of the run).
inline void run_until(Simulation& sim, double t_s) {
  while (!sim.finished() && sim.time_s() < t_s) sim.step();
}

}  // namespace ravel::test
