// The VTU / PVD writer (core/vtk.h) on a synthetic frame: structure and sizes. The
// optional ctest `render_vtu_meshio` reads the same files with python3-meshio.
#include "core/vtk.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/render/synthetic_frame.h"

namespace ravel::testing {
namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(Vtk, SeriesWritesVtuPerFrameAndAPvdIndex) {
  const std::string dir = std::string(RAVEL_RENDER_OUTPUT_DIR) + "/vtk_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  SyntheticFabric s;
  s.yarns = 6;
  s.hole_radius_m = 1e-3f;
  VtkSeries series(dir, "frame");
  for (int i = 0; i < 3; ++i) {
    s.time_s = i * 1e-6;
    std::string error;
    ASSERT_TRUE(series.add(make_synthetic_frame(s), &error)) << error;
  }
  EXPECT_EQ(series.count(), 3);
  const std::string pvd = slurp(series.pvd_path());
  EXPECT_NE(pvd.find("timestep=\"2e-06\""), std::string::npos) << pvd;
  EXPECT_NE(pvd.find("file=\"frame_00002.vtu\""), std::string::npos) << pvd;

  const Frame f = make_synthetic_frame(s);
  const std::string vtu = slurp(dir + "/frame_00002.vtu");
  // Quarter model mirrored to the full fabric: 4 copies of points and cells.
  EXPECT_NE(vtu.find("NumberOfPoints=\"" + std::to_string(4 * f.node_pos.size()) + "\""), std::string::npos);
  EXPECT_NE(vtu.find("NumberOfCells=\"" + std::to_string(4 * f.elem_a.size()) + "\""), std::string::npos);
  for (const char* name : {"strain", "stress", "velocity", "broken", "yarn_id"})
    EXPECT_NE(vtu.find(std::string("Name=\"") + name + "\""), std::string::npos) << name;
  // Appended raw data: each array = 8-byte length + payload. Points: 4 * nodes * 3 floats.
  const std::size_t np = 4 * f.node_pos.size(), nc = 4 * f.elem_a.size();
  const std::size_t payload = (np * 3 * 4 + 8) * 2 + (np * 4 + 8)            // points, velocity, slip
                              + 3 * (nc * 4 + 8)                             // strain, ratio, stress
                              + 3 * (nc + 8) + (nc * 4 + 8)                  // broken, family, copy, yarn
                              + (2 * nc * 8 + 8) + (nc * 8 + 8) + (nc + 8);  // cells
  const std::size_t start = vtu.find('_', vtu.find("<AppendedData")) + 1;
  const std::size_t end = vtu.rfind("\n  </AppendedData>");
  ASSERT_NE(end, std::string::npos);
  EXPECT_EQ(end - start, payload);
  // No temporary files left behind.
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(entry.path().string().find(".tmp."), std::string::npos) << entry.path();
}

}  // namespace
}  // namespace ravel::testing
