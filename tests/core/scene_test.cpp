// Scene reading: every bad-input class gets one message naming the key, where it came
// from (file:line or --set) and the problem.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "scene.h"

namespace ravel {
namespace {

// The message of the SceneError a TOML text (plus overrides) raises, or "" if none.
std::string error_of(const std::string& toml, const std::vector<std::string>& ov = {}) {
  try {
    parse_scene(toml, "test.toml", ov);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

#define EXPECT_HAS(haystack, needle) EXPECT_NE(std::string(haystack).find(needle), std::string::npos) << haystack

TEST(Scene, DefaultSceneIsThePapersTest) {
  const Scene s = load_scene(default_scene_path());
  EXPECT_DOUBLE_EQ(s.fabric.width_m, 0.120);
  EXPECT_DOUBLE_EQ(s.fabric.spacing_m, 0.844e-3);
  EXPECT_DOUBLE_EQ(s.fabric.crossing_gap_m, 0.2e-3);
  EXPECT_DOUBLE_EQ(s.fabric.node_mass_kg, 9.4e-8);
  EXPECT_DOUBLE_EQ(s.yarn.k1_pa, 7.28e10);
  EXPECT_DOUBLE_EQ(s.yarn.k2_pa, 4.17e11);
  EXPECT_DOUBLE_EQ(s.yarn.damping_pa_s, 6.26e8);
  EXPECT_DOUBLE_EQ(s.yarn.friction, 0.2);
  EXPECT_DOUBLE_EQ(s.projectile.mass_kg, 7e-3);
  EXPECT_DOUBLE_EQ(s.projectile.diameter_m, 12e-3);
  EXPECT_DOUBLE_EQ(s.projectile.friction, 0.27);
  EXPECT_EQ(s.solver.model, ContactModel::sliding);
  EXPECT_TRUE(s.fabric.clamped.left && s.fabric.clamped.right);
  EXPECT_FALSE(s.fabric.clamped.bottom || s.fabric.clamped.top);
  EXPECT_TRUE(s.warnings.empty());
}

TEST(Scene, OverridesUseTheFilesUnits) {
  const Scene s = load_scene(default_scene_path(), {"projectile.velocity_mps=300", "fabric.width_mm=60",
                                                    "solver.end_time_us=40", "fabric.clamped=all"});
  EXPECT_DOUBLE_EQ(s.projectile.velocity_mps, 300);
  EXPECT_DOUBLE_EQ(s.fabric.width_m, 0.060);
  EXPECT_DOUBLE_EQ(s.solver.end_time_s, 40e-6);
  EXPECT_TRUE(s.fabric.clamped.top && s.fabric.clamped.bottom);
}

TEST(Scene, RoundTripsThroughToml) {
  Scene a = load_scene(default_scene_path(), {"yarn.friction=0.37", "fabric.clamped=left,top",
                                              "solver.model=pin_jointed", "projectile.shape=cylinder"});
  Scene b = parse_scene(scene_to_toml(a), "round.toml");
  EXPECT_EQ(scene_to_toml(a), scene_to_toml(b));
  EXPECT_DOUBLE_EQ(b.yarn.friction, 0.37);
  EXPECT_EQ(b.solver.model, ContactModel::pin_jointed);
  EXPECT_TRUE(b.fabric.clamped.left && b.fabric.clamped.top && !b.fabric.clamped.right);
}

TEST(Scene, UnknownKeyNamesItWithLineAndSuggestion) {
  const std::string m = error_of("[projectile]\nvelocity_mps = 200\nvelocty_mps = 300\n");
  EXPECT_HAS(m, "test.toml:3");
  EXPECT_HAS(m, "projectile.velocty_mps");
  EXPECT_HAS(m, "unknown key");
  EXPECT_HAS(m, "did you mean 'projectile.velocity_mps'");
  EXPECT_HAS(error_of("[yarns]\nfriction = 0.1\n"), "unknown section");
  EXPECT_HAS(error_of("", {"yarn.frcition=0.3"}), "did you mean 'yarn.friction'");
}

TEST(Scene, WrongType) {
  const std::string m = error_of("[projectile]\nmass_g = \"heavy\"\n");
  EXPECT_HAS(m, "test.toml:2");
  EXPECT_HAS(m, "projectile.mass_g");
  EXPECT_HAS(m, "wrong type: expected a number");
  EXPECT_HAS(error_of("", {"solver.contact_iterations=2.5"}), "whole number");
  EXPECT_HAS(error_of("", {"yarn.breakable=maybe"}), "true or false");
  EXPECT_HAS(error_of("[solver]\nmodel = \"springy\"\n"), "choose one of: sliding, pin_jointed");
}

TEST(Scene, NegativeZeroNanInfinite) {
  EXPECT_HAS(error_of("[projectile]\nmass_g = -7.0\n"), "projectile.mass_g: must be positive, got -7 g");
  EXPECT_HAS(error_of("", {"fabric.spacing_mm=0"}), "must be positive");
  EXPECT_HAS(error_of("", {"yarn.friction=nan"}), "yarn.friction: is NaN");
  EXPECT_HAS(error_of("[yarn]\nfriction = nan\n"), "is NaN");
  EXPECT_HAS(error_of("", {"projectile.velocity_mps=inf"}), "infinite");
  EXPECT_HAS(error_of("", {"yarn.friction=-0.1"}), "must not be negative");
  EXPECT_HAS(error_of("", {"yarn.failure_strain=2"}), "yarn.failure_strain");
}

TEST(Scene, ImpossibleGeometry) {
  EXPECT_HAS(error_of("", {"projectile.diameter_mm=200"}), "larger than the fabric");
  EXPECT_HAS(error_of("", {"projectile.offset_x_mm=57"}), "does not fit inside the fabric at the strike point");
  EXPECT_HAS(error_of("", {"fabric.crossing_gap_mm=2"}), "fabric.crossing_gap_mm");
  EXPECT_HAS(error_of("", {"fabric.width_mm=1"}), "at least two yarn spacings");
  EXPECT_HAS(error_of("", {"fabric.node_mass_g=1"}), "inconsistent with density x area");
}

TEST(Scene, MissingFileAndSyntaxError) {
  try {
    load_scene("/nonexistent/scene.toml");
    FAIL() << "no error";
  } catch (const SceneError& e) {
    EXPECT_HAS(e.what(), "/nonexistent/scene.toml");
    EXPECT_HAS(e.what(), "cannot open");
  }
  const std::string m = error_of("[fabric]\nwidth_mm = = 3\n");
  EXPECT_HAS(m, "test.toml:2");
  EXPECT_HAS(m, "TOML syntax error");
  EXPECT_HAS(error_of("", {"just-a-word"}), "not of the form section.key=value");
}

TEST(Scene, QuestionableButAllowedSettingsWarn) {
  const Scene s = load_scene(default_scene_path(), {"solver.dt_factor=1.3"});
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_HAS(s.warnings[0], "solver.dt_factor");
}

// The fuzz corpus's seeds with the outcome each is there for: the replay only checks
// invariants (no crash, a message), so a seed that should be refused is checked here.
TEST(SceneCorpus, SeedsHaveTheirExpectedOutcome) {
  const std::string dir = RAVEL_FUZZ_CORPUS;
  const std::pair<const char*, const char*> refused[] = {
      {"typo_key.toml", "did you mean 'projectile.velocity_mps'"},
      {"syntax_error.toml", "TOML syntax error"},
      {"unknown_section.toml", "unknown section"},
      {"spacing_in_metres.toml", "looks like a value in m"},
      {"nan_inf.toml", "is infinite"},
      {"array_of_tables.toml", "fabric: unknown key"}};
  for (const auto& [file, why] : refused) {
    try {
      load_scene(dir + "/" + file);
      ADD_FAILURE() << file << " was accepted";
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << file << ": " << e.what();
    }
  }
  for (const char* file : {"default_scene.toml", "small_patch.toml", "single_yarn.toml", "oblique_cone.toml",
                           "inline_tables.toml", "name_escapes.toml", "clamped_list.toml"})
    EXPECT_NO_THROW(load_scene(dir + "/" + file)) << file;
}

// Not a scene: a folder, an empty file, only comments, /dev/null are refused (they would
// otherwise run the built-in defaults).
TEST(SceneCorpus, NonScenesAreRefused) {
  const std::string tmp = ::testing::TempDir();
  std::ofstream(tmp + "/ravel_empty.toml").close();
  std::ofstream(tmp + "/ravel_comments.toml") << "# nothing\n\n   # here\n";
  for (const std::string& path : {tmp, tmp + "/ravel_empty.toml", tmp + "/ravel_comments.toml", std::string("/dev/null")}) {
    try {
      load_scene(path);
      ADD_FAILURE() << path << " was accepted";
    } catch (const SceneError& e) {
      const std::string m = e.what();
      EXPECT_TRUE(m.find("holds no scene keys") != std::string::npos || m.find("is a folder") != std::string::npos)
          << path << ": " << m;
    }
  }
}

}  // namespace
}  // namespace ravel
