// The VTU / PVD writer (core/vtk.h) on a synthetic frame: structure, sizes and values read
// back from the raw arrays; PNGs decoded. The ctest `render_vtu_meshio` reads the same files with python3-meshio.
#include "core/vtk.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "render/renderer.h"
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#include <stb/stb_image.h>
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
  for (const char* name : {"strain", "stress", "velocity", "friction_heat_J_per_g", "broken", "yarn_id"})
    EXPECT_NE(vtu.find(std::string("Name=\"") + name + "\""), std::string::npos) << name;
  // Appended raw data: each array = 8-byte length + payload. Points: 4 * nodes * 3 floats.
  const std::size_t np = 4 * f.node_pos.size(), nc = 4 * f.elem_a.size();
  const std::size_t payload = (np * 3 * 4 + 8) * 2 + 2 * (np * 4 + 8)        // points, velocity, slip, friction
                              + (np + 8)                                     // point duplicate
                              + 3 * (nc * 4 + 8)                             // strain, ratio, stress
                              + 4 * (nc + 8) + (nc * 4 + 8)                  // broken, family, copy, duplicate, yarn
                              + (2 * nc * 8 + 8) + (nc * 8 + 8) + (nc + 8);  // cells
  const std::size_t start = vtu.find('_', vtu.find("<AppendedData")) + 1;
  const std::size_t end = vtu.rfind("\n  </AppendedData>");
  ASSERT_NE(end, std::string::npos);
  EXPECT_EQ(end - start, payload);

  // Values read back from the raw arrays (at their offset: an 8-byte length, then the data).
  // The first copy of the points and cells is the modelled part itself, in frame order.
  auto array = [&](const std::string& name, std::size_t elem_size, std::size_t count) {
    const std::size_t at = vtu.find("Name=\"" + name + "\"");
    EXPECT_NE(at, std::string::npos) << name;
    const std::size_t off = std::stoull(vtu.substr(vtu.find("offset=\"", at) + 8));
    std::uint64_t bytes = 0;
    std::memcpy(&bytes, vtu.data() + start + off, 8);
    EXPECT_EQ(bytes, elem_size * count) << name;
    return vtu.data() + start + off + 8;
  };
  const char* pts = array("Points", 4, 3 * np);
  const char* strain = array("strain", 4, nc);
  const char* broken = array("broken", 1, nc);
  const char* yarn = array("yarn_id", 4, nc);
  int broken_seen = 0;
  for (std::size_t i = 0; i < f.node_pos.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      float v;
      std::memcpy(&v, pts + 4 * (3 * i + k), 4);
      ASSERT_EQ(v, f.node_pos[i][k]) << "point " << i;
    }
  for (std::size_t e = 0; e < f.elem_a.size(); ++e) {
    float v;
    std::memcpy(&v, strain + 4 * e, 4);
    ASSERT_EQ(v, f.elem_strain[e]) << "strain of cell " << e;
    ASSERT_EQ(std::uint8_t(broken[e]), f.elem_broken[e]) << "broken flag of cell " << e;
    broken_seen += broken[e] ? 1 : 0;
    std::int32_t id;
    std::memcpy(&id, yarn + 4 * e, 4);
    EXPECT_GE(id, 0);
  }
  EXPECT_GT(broken_seen, 0);  // the synthetic hole (hole_radius_m) is in the file
  // No temporary files left behind (write_file_atomic's are ".NAME.tmpPID_N").
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
}

// The VTU and PNG writers go through core's write_file_atomic: a folder that does not
// exist gives false and a message naming the file, and nothing is left behind.
TEST(Vtk, WritersReportTheFileTheyCouldNotWrite) {
  const std::string dir = std::string(RAVEL_RENDER_OUTPUT_DIR) + "/vtk_missing_test";
  std::filesystem::remove_all(dir);
  const std::string vtu = dir + "/no/such/folder/frame.vtu";
  std::string error;
  SyntheticFabric s;
  s.yarns = 4;
  EXPECT_FALSE(write_vtu(make_synthetic_frame(s), vtu, true, &error));
  EXPECT_NE(error.find(vtu), std::string::npos) << error;
  const std::string pvd = dir + "/no/such/folder/series.pvd";
  error.clear();
  EXPECT_FALSE(write_pvd(pvd, {}, &error));
  EXPECT_NE(error.find(pvd), std::string::npos) << error;
  const std::string png = dir + "/no/such/folder/image.png";
  error.clear();
  EXPECT_FALSE(render::write_png(png, 2, 1, std::vector<std::uint8_t>(6, 128), &error));
  EXPECT_NE(error.find(png), std::string::npos) << error;
  EXPECT_FALSE(std::filesystem::exists(dir));
}

// A PNG written through the atomic writer is a whole PNG and leaves no temporary file.
TEST(Vtk, PngIsWrittenWholeWithNoTemporaryLeft) {
  const std::string dir = std::string(RAVEL_RENDER_OUTPUT_DIR) + "/png_atomic_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::vector<std::uint8_t> rgb(16 * 8 * 3);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = std::uint8_t(i * 7);
  std::string error;
  ASSERT_TRUE(render::write_png(dir + "/a.png", 16, 8, rgb, &error)) << error;
  const std::string bytes = slurp(dir + "/a.png");
  ASSERT_GT(bytes.size(), 8u + 25u);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  // IHDR: width 16, height 8, big-endian, right after the signature and chunk header.
  EXPECT_EQ(std::uint8_t(bytes[19]), 16);
  EXPECT_EQ(std::uint8_t(bytes[23]), 8);
  EXPECT_EQ(bytes.substr(bytes.size() - 8, 4), "IEND");
  // Decoded, it holds exactly the pixels written.
  int w = 0, h = 0, ch = 0;
  unsigned char* px = stbi_load((dir + "/a.png").c_str(), &w, &h, &ch, 3);
  ASSERT_NE(px, nullptr) << stbi_failure_reason();
  EXPECT_EQ(w, 16);
  EXPECT_EQ(h, 8);
  int same = 0;
  for (std::size_t i = 0; i < rgb.size(); ++i) same += px[i] == rgb[i];
  stbi_image_free(px);
  EXPECT_EQ(same, int(rgb.size()));
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    ++files;
    EXPECT_EQ(entry.path().filename().string(), "a.png");
  }
  EXPECT_EQ(files, 1);
}

}  // namespace
}  // namespace ravel::testing
