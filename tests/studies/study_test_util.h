// Shared bits of the studies tests: a scratch folder per test and the cheap scene.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

namespace ravel::studies::testing {

// A fresh, empty folder for the running test.
inline std::string scratch_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string dir = std::string(RAVEL_STUDIES_TEST_DIR) + "/" + info->test_suite_name() + "." + info->name();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// A 20 x 20 mm patch struck by a 4 mm, 0.5 g sphere: ~300 nodes in the quarter model, a
// run to perforation takes a few hundredths of a second. dt_factor 0.3 keeps it well
// inside the stable range for these small elements. Near its ballistic limit (~60 m/s)
// the projectile needs ~800 us to push through: end time 1500 us decides every run.
inline std::vector<std::string> cheap_scene() {
  return {"fabric.width_mm=20",    "fabric.length_mm=20",  "projectile.diameter_mm=4",
          "projectile.mass_g=0.5", "solver.dt_factor=0.3", "solver.end_time_us=1500"};
}

}  // namespace ravel::studies::testing
