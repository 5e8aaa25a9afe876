// Benchmark: the default scene at 260 m/s, to perforation or end_time. Prints CSV.
//   bench_impact [--set k=v ...] [--repeat N]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "../app/cli/omp_env.h"
#include "scene.h"
#include "solver/simd/contact_lanes.h"
#include "simulation.h"
#include "solver.h"

int main(int argc, char** argv) {
  ravel::app::choose_omp_wait_policy(argv);  // as the ravel executable does
  std::vector<std::string> ov{"projectile.velocity_mps=260", "output.progress=false"};
  int repeat = 1;
  std::vector<std::vector<std::string>> cases;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--set") && i + 1 < argc)
      ov.push_back(argv[++i]);
    else if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc)
      repeat = std::atoi(argv[++i]);
  }
  std::printf(
      "model,contact,precision,threads,nodes,steps,sim_time_us,wall_s,node_steps_per_s,ns_per_node_step,perforated,"
      "residual_velocity_mps,omp_spincount,simd\n");
  for (int r = 0; r < repeat; ++r) {
    ravel::Scene scene = ravel::load_scene(ravel::default_scene_path(), ov);
    ravel::Simulation sim(scene);
    const auto t0 = std::chrono::steady_clock::now();
    sim.run();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const auto s = sim.summary();
    const double ns = double(s.modelled_node_count) * double(s.step_count);
    const char* spin = std::getenv("GOMP_SPINCOUNT");
    std::printf("%s,%s,%s,%d,%d,%ld,%.2f,%.4f,%.4g,%.2f,%d,%.2f,%s,%s\n", s.model.c_str(), s.contact_model.c_str(),
                scene.solver.precision == ravel::Precision::double_precision ? "double" : "float", scene.solver.threads,
                s.modelled_node_count, s.step_count, s.end_time_s * 1e6, wall, ns / wall, wall / ns * 1e9,
                int(s.perforated), s.residual_velocity_mps, spin ? spin : "default",
                sim.solver().simd_active() ? ravel::lanes::isa_name(ravel::lanes::isa()) : "off");
  }
  return 0;
}
