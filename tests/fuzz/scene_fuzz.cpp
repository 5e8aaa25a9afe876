// libFuzzer target for the scene reader: parse_scene (TOML + `--set` overrides) and
// validate_scene, with the scene_to_toml round trip as an invariant.
//
// Input: TOML text, then optionally `--set` overrides, each after a NUL byte:
//   "[yarn]\nfriction = 0.3\n" "\0" "projectile.velocity_mps=300" "\0" "name=x"
//
// What must hold for every input:
//   - parse_scene either returns a scene or throws SceneError with a non-empty message
//     that names its key (any other exception, crash, hang or sanitizer report is a bug);
//   - a scene that parsed writes a scene.toml that parses again, to the same text
//     (fixed point), with the same warnings: `ravel run DIR/scene.toml` reproduces a run.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "scene.h"

namespace {

[[noreturn]] void broken(const char* what, const std::string& detail) {
  std::fprintf(stderr, "scene_fuzz: invariant broken: %s\n%s\n", what, detail.c_str());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 64 * 1024) return 0;  // scenes are small; long inputs only slow the search
  const std::string input(reinterpret_cast<const char*>(data), size);
  std::string toml;
  std::vector<std::string> overrides;
  std::size_t start = 0, nul = input.find('\0');
  toml = input.substr(0, nul);
  while (nul != std::string::npos) {
    start = nul + 1;
    nul = input.find('\0', start);
    overrides.push_back(input.substr(start, nul == std::string::npos ? std::string::npos : nul - start));
  }

  ravel::Scene scene;
  try {
    scene = ravel::parse_scene(toml, "fuzz.toml", overrides);
  } catch (const ravel::SceneError& e) {
    const std::string m = e.what();
    if (m.empty() || e.problem().empty()) broken("empty SceneError message", m);
    if (!e.key().empty() && m.find(e.key()) == std::string::npos) broken("SceneError does not name its key", m);
    return 0;
  }

  const std::string text = ravel::scene_to_toml(scene);
  ravel::Scene again;
  try {
    again = ravel::parse_scene(text, "round.toml");
  } catch (const ravel::SceneError& e) {
    broken("scene_to_toml wrote a scene that does not read back", std::string(e.what()) + "\n--- written:\n" + text);
  }
  const std::string text2 = ravel::scene_to_toml(again);
  if (text2 != text) broken("scene_to_toml is not a fixed point", "--- first:\n" + text + "--- second:\n" + text2);
  if (again.warnings != scene.warnings) {
    std::string w;
    for (const auto& s : scene.warnings) w += "first: " + s + "\n";
    for (const auto& s : again.warnings) w += "second: " + s + "\n";
    broken("the written scene warns differently", w);
  }
  return 0;
}
