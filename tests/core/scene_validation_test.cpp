// Scene validation beyond the single key (issue 8): where each message points, values
// that look like another unit, the projectile against the fabric, the node mass
// tolerance, run lengths no machine finishes, and text that must survive scene.toml.
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "scene.h"

namespace ravel {
namespace {

std::string error_of(const std::string& toml, const std::vector<std::string>& ov = {}) {
  try {
    parse_scene(toml, "test.toml", ov);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

std::vector<std::string> warnings_of(const std::string& toml, const std::vector<std::string>& ov = {}) {
  return parse_scene(toml, "test.toml", ov).warnings;
}

bool any_has(const std::vector<std::string>& v, const std::string& needle) {
  for (const auto& s : v)
    if (s.find(needle) != std::string::npos) return true;
  return false;
}

#define EXPECT_HAS(haystack, needle) EXPECT_NE(std::string(haystack).find(needle), std::string::npos) << haystack

// The two-stage compression law's keys: the packed distance must lie below the rest distance
// (0.20 mm at the default 0.40 mm thickness), forces must be positive, and a value typed in
// micrometres is caught as a unit slip.
TEST(SceneValidation, TwoStageCompressionKeys) {
  EXPECT_HAS(error_of("[fabric]\npacked_gap_mm = 0.25\n"),
             "test.toml:2: fabric.packed_gap_mm: the packed centre distance (0.25 mm) must be below the rest distance");
  EXPECT_HAS(error_of("[fabric]\nflattening_force_n = -5\n"), "fabric.flattening_force_n");
  EXPECT_HAS(error_of("[fabric]\npacked_gap_mm = 130\n"), "fabric.packed_gap_mm");
  EXPECT_EQ(error_of("[fabric]\npacked_gap_mm = 0.13\nflattening_force_n = 50\n"), "");
}

TEST(SceneValidation, ChecksAfterParsingNameTheLineOfTheKey) {
  // The geometry check runs after parsing; it still points at the line the value is on.
  EXPECT_HAS(error_of("name = \"x\"\n[fabric]\nweave = \"plain\"\nwidth_mm = 1.0\n"),
             "test.toml:4: fabric.width_mm: the fabric must span at least two yarn spacings");
  EXPECT_HAS(error_of("[fabric]\ncrossing_gap_mm = 2.0\n"), "test.toml:2: fabric.crossing_gap_mm: L1 larger");
  EXPECT_HAS(error_of("[fabric]\nnode_mass_g = 1.0\n"), "test.toml:2: fabric.node_mass_g:");
  // A value from --set says so; a key left at its default names the file.
  EXPECT_HAS(error_of("", {"fabric.crossing_gap_mm=2"}), "--set: fabric.crossing_gap_mm:");
  EXPECT_HAS(error_of("[fabric]\nspacing_mm = 0.15\n"), "test.toml: fabric.crossing_gap_mm: L1 larger");
}

TEST(SceneValidation, ProjectileLargerThanTheFabricHasItsOwnMessage) {
  EXPECT_HAS(error_of("[projectile]\ndiameter_mm = 150.0\n"),
             "test.toml:2: projectile.diameter_mm: the projectile (150 mm) is larger than the fabric (120 x 120 mm)");
  EXPECT_HAS(error_of("", {"fabric.length_mm=10"}), "the projectile (12 mm) is larger than the fabric (120 x 10 mm)");
  // Fits as a whole but not where it strikes: the offset is named.
  EXPECT_HAS(error_of("[projectile]\noffset_x_mm = 55.0\n"),
             "test.toml:2: projectile.offset_x_mm: the projectile does not fit inside the fabric at the strike point");
  // Nearly as large: allowed, with a warning.
  EXPECT_TRUE(any_has(warnings_of("", {"projectile.diameter_mm=110"}), "nearly as large as the fabric"));
}

TEST(SceneValidation, ValuesThatLookLikeAnotherUnit) {
  // Refused values say which unit they look like.
  EXPECT_HAS(
      error_of("", {"fabric.spacing_mm=0.000844"}),
      "fabric.spacing_mm: more than 4000 yarns per direction (142180, from fabric.width_mm = 120, fabric.length_mm = 120 at fabric.spacing_mm = 0.000844); this would not fit in memory; it looks like a "
      "value in m (0.000844 m = 0.844 mm; the key is in mm)");
  EXPECT_HAS(error_of("", {"yarn.failure_strain=5.2"}),
             "must be <= 1, got 5.2; it looks like a value in % (5.2 % = 0.052");
  EXPECT_HAS(error_of("", {"solver.end_time_us=3e5"}), "must be <= 100000, got 300000 us; it looks like a value in ns");
  // The mass check blames the value that looks wrong, not the node mass.
  EXPECT_HAS(
      error_of("[yarn]\ndensity_kg_m3 = 1.44\n"),
      "test.toml:2: yarn.density_kg_m3: node mass 9.4e-05 g is inconsistent with density x area x element length = "
      "9.54e-08 g (more than 3x apart); it looks like a value in g/cm^3");
  EXPECT_HAS(error_of("", {"fabric.node_mass_g=9.4e-8"}), "fabric.node_mass_g: node mass 9.4e-08 g is inconsistent");
  EXPECT_HAS(error_of("", {"fabric.node_mass_g=9.4e-8"}), "it looks like a value in kg (the key is in g)");
  // Allowed values that look like another unit warn.
  auto w = warnings_of("", {"projectile.mass_g=0.007"});
  ASSERT_EQ(w.size(), 1u);
  EXPECT_HAS(w[0],
             "projectile.mass_g = 0.007 g is far outside the usual 0.05 .. 100000 g; it looks like a value in kg "
             "(0.007 kg = 7 g");
  EXPECT_TRUE(any_has(warnings_of("", {"projectile.velocity_mps=0.26"}), "looks like a value in km/s"));
  EXPECT_TRUE(any_has(warnings_of("", {"yarn.area_m2=0.0764", "fabric.node_mass_g=94"}), "yarn.area_m2"));
  // Ordinary values do not.
  EXPECT_TRUE(warnings_of("").empty());
}

TEST(SceneValidation, NodeMassToleranceIs25PercentWarningAndFactor3Error) {
  // rho A sqrt(L0^2 + L1^2) = 1440 x 7.64e-8 x 0.867e-3 = 9.54e-8 kg for the default scene.
  EXPECT_TRUE(warnings_of("", {"fabric.node_mass_g=1.15e-4"}).empty());  // +21 %
  auto w = warnings_of("", {"fabric.node_mass_g=1.25e-4"});              // +31 %
  ASSERT_EQ(w.size(), 1u);
  EXPECT_HAS(w[0], "fabric.node_mass_g differs from density x area x element length by 31 % (tolerance 25 %)");
  EXPECT_EQ(error_of("", {"fabric.node_mass_g=2.8e-4"}), "");  // 2.9x: warned, allowed
  EXPECT_HAS(error_of("", {"fabric.node_mass_g=2.9e-4"}), "more than 3x apart");
  EXPECT_HAS(error_of("", {"fabric.node_mass_g=3.0e-5"}), "more than 3x apart");
}

TEST(SceneValidation, FailureStrainBeyondTheMaterialModel) {
  // The Zener fit covers Gu's data up to 5.7 %: beyond 0.2 warns, beyond 1 is refused.
  auto w = warnings_of("", {"yarn.failure_strain=0.3"});
  ASSERT_EQ(w.size(), 1u);
  EXPECT_HAS(w[0], "yarn.failure_strain = 0.3 is beyond the small-strain range the Zener fit");
  EXPECT_TRUE(warnings_of("", {"yarn.failure_strain=0.3", "yarn.material=elastic"}).empty());
  EXPECT_HAS(error_of("", {"yarn.failure_strain=1.5"}), "yarn.failure_strain: must be <= 1, got 1.5");
}

TEST(SceneValidation, RunsNoMachineFinishesAreRefused) {
  // k1 given in GPa: the wave speed is 0.2 m/s, one step is longer than the run.
  EXPECT_HAS(
      error_of("[yarn]\nk1_pa = 72.8\n[solver]\nend_time_us = 150\n"),
      "test.toml:2: yarn.k1_pa: one time step (dt = alpha L0 / c = 1.88e+03 us, wave speed c = 0.225 m/s) is longer "
      "than the run (solver.end_time_us = 150)");
  EXPECT_HAS(error_of("[yarn]\nk1_pa = 72.8\n[solver]\nend_time_us = 150\n"), "it looks like a value in GPa");
  // With the auto end, the run's length is its cap, which must hold at least 100 steps.
  EXPECT_HAS(error_of("[yarn]\nk1_pa = 72.8\n"), "is longer than the run (solver.max_end_time_us = 5e+03)");
  // A modulus far too large: billions of steps.
  EXPECT_HAS(error_of("", {"yarn.material=elastic", "yarn.modulus_pa=1e30", "solver.end_time_us=1000"}),
             "yarn.modulus_pa: this scene would need about");
  EXPECT_TRUE(any_has(warnings_of("", {"solver.end_time_us=1e5", "solver.dt_factor=0.01"}),
                      "time steps; expect it to take long"));
}

TEST(SceneValidation, SingleYarnNodeCountIsBounded) {
  EXPECT_HAS(error_of("", {"fabric.weave=single_yarn", "fabric.length_mm=1e6", "fabric.spacing_mm=0.01",
                           "fabric.crossing_gap_mm=0", "fabric.node_mass_g=1.1e-6"}),
             "fabric.spacing_mm: more than a million nodes along the yarn");
}

TEST(SceneValidation, AnyTextValueSurvivesTheWrittenSceneToml) {
  // Quotes, backslashes, tabs and non-ASCII in a name are written escaped and read back.
  const Scene a = parse_scene("name = \"a\\\"b\\\\c\\td\\u00e9\"\n", "test.toml");
  const Scene b = parse_scene(scene_to_toml(a), "round.toml");
  EXPECT_EQ(b.name, a.name);
  EXPECT_EQ(a.name, "a\"b\\c\td\xc3\xa9");
  // Text that no TOML file can hold is refused where it enters (a --set).
  EXPECT_HAS(error_of("", {"name=\xff\xfe"}), "--set: name: is not valid UTF-8 text");
  EXPECT_HAS(error_of("", {"name=\xed\xa0\x80"}), "not valid UTF-8");  // a surrogate
}

TEST(SceneValidation, WrittenNumbersReadBackBitForBit) {
  // scene.toml reproduces a run exactly: every SI value reads back to the same double.
  const Scene a = parse_scene("", "t.toml",
                              {"fabric.spacing_mm=0.8440000000000001", "projectile.velocity_mps=263.14159265358979",
                               "yarn.area_m2=7.6400000000000001e-8", "solver.end_time_us=33.333333333333336"});
  const Scene b = parse_scene(scene_to_toml(a), "round.toml");
  EXPECT_EQ(b.fabric.spacing_m, a.fabric.spacing_m);
  EXPECT_EQ(b.projectile.velocity_mps, a.projectile.velocity_mps);
  EXPECT_EQ(b.yarn.area_m2, a.yarn.area_m2);
  EXPECT_EQ(b.solver.end_time_s, a.solver.end_time_s);
  // The default scene still writes its plain values.
  EXPECT_NE(scene_to_toml(a).find("velocity_mps = 263.1415926535898 "), std::string::npos);
  EXPECT_NE(scene_to_toml(parse_scene("", "d.toml")).find("spacing_mm = 0.844 "), std::string::npos);
}

}  // namespace
}  // namespace ravel
