// Writes a small synthetic VTU series into argv[1] for tests/render/check_vtu_meshio.py.
#include <cstdio>

#include "core/vtk.h"
#include "tests/render/synthetic_frame.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: write_test_vtu DIR\n");
    return 2;
  }
  ravel::testing::SyntheticFabric s;
  s.yarns = 8;
  s.peak_strain = 0.5f;
  s.dent_depth_m = 0.002f;
  s.hole_radius_m = 1.5e-3f;
  ravel::VtkSeries series(argv[1], "frame");
  for (int i = 0; i < 2; ++i) {
    s.time_s = (i + 1) * 5e-6;
    std::string error;
    if (!series.add(ravel::testing::make_synthetic_frame(s), &error)) {
      std::fprintf(stderr, "write_test_vtu: %s\n", error.c_str());
      return 1;
    }
  }
  const ravel::Frame f = ravel::testing::make_synthetic_frame(s);
  int broken = 0;
  for (auto b : f.elem_broken) broken += b;
  // What the checker should find (whole fabric: 4 mirrored copies).
  std::printf("%zu %zu %d %.9g\n", 4 * f.node_pos.size(), 4 * f.elem_a.size(), 4 * broken, f.failure_strain);
  return 0;
}
