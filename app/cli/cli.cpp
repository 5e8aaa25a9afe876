#include "cli.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <new>
#include <string>
#include <thread>

#include "commands_table.h"
#include "results.h"
#include "sweep.h"

namespace ravel::app {

CommonArgs parse_args(const std::vector<std::string>& args, const std::string& command) {
  const Command* cmd = find_command(command);
  if (!cmd) throw UsageError("unknown command '" + command + "'");
  auto option = [&](const std::string& n) -> const CommandOption* {
    for (const auto& o : cmd->options)
      if (n == o.name) return &o;
    return nullptr;
  };
  CommonArgs a;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& s = args[i];
    if (s.rfind("--", 0) == 0 && s.size() > 2) {
      std::string name = s.substr(2), value;
      bool has_value = false;
      if (auto eq = name.find('='); eq != std::string::npos) {
        value = name.substr(eq + 1);
        name = name.substr(0, eq);
        has_value = true;
      }
      const CommandOption* o = option(name);
      if (!o)
        throw UsageError("unknown option --" + name + " for ravel " + command + " (see 'ravel help " + command + "')");
      if (!o->value) {
        if (has_value) throw UsageError("--" + name + " takes no value");
        a.switches.push_back(name);
        continue;
      }
      if (!has_value) {
        if (i + 1 >= args.size()) throw UsageError("--" + name + " needs a value (" + o->value + ")");
        value = args[++i];
      }
      if (!o->repeatable && a.multi.count(name))
        throw UsageError("--" + name + " given twice ('" + a.multi[name].front() + "' and '" + value + "')");
      a.multi[name].push_back(value);
      if (name == "set") {
        a.overrides.push_back(value);
      } else if (name == "out") {
        if (value.empty()) throw UsageError("--out needs a folder name");
        a.out_dir = value;
      } else if (name == "threads") {
        char* end = nullptr;
        long t = std::strtol(value.c_str(), &end, 10);
        if (value.empty() || *end || t < 0 || t > 256)
          throw UsageError("--threads: expected a whole number 0..256, got '" + value + "'");
        a.threads = int(t);
      } else {
        a.flags[name] = value;
      }
    } else {
      if (!a.scene_path.empty())
        throw UsageError("more than one scene file given ('" + a.scene_path + "' and '" + s + "')");
      a.scene_path = s;
    }
  }
  return a;
}

std::string scene_path_from(const CommonArgs& a) {
  std::string path = a.scene_path;
  if (path.empty()) path = default_scene_path();
  // A run's (or a sweep case's) output folder stands for the scene it ran: its scene.toml.
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    const std::string inside = (std::filesystem::path(path) / "scene.toml").string();
    if (!std::filesystem::is_regular_file(inside, ec))
      throw SceneError("", path, "is a folder without a scene.toml; give a scene file or a run's output folder");
    static bool said = false;  // once per command, however often the path is resolved
    if (!said)
      std::fprintf(stderr, "ravel: %s is a folder: using the scene it holds, %s\n", path.c_str(), inside.c_str());
    said = true;
    return inside;
  }
  // A bare name finds the shipped scene: `ravel run twaron_ct716`.
  if (!std::filesystem::exists(path)) {
    std::string shipped =
        assets_dir() + "/scenes/" + path + (path.size() > 5 && path.substr(path.size() - 5) == ".toml" ? "" : ".toml");
    if (std::filesystem::exists(shipped)) path = shipped;
  }
  return path;
}

std::vector<std::string> overrides_from(const CommonArgs& a) {
  std::vector<std::string> ov = a.overrides;
  if (a.threads >= 0) ov.push_back("solver.threads=" + std::to_string(a.threads));
  return ov;
}

Scene load_scene_from(const CommonArgs& a) {
  return load_scene(scene_path_from(a), overrides_from(a));
}

int jobs_from(const CommonArgs& a) {
  auto it = a.flags.find("jobs");
  if (it == a.flags.end()) return std::max(1u, std::thread::hardware_concurrency());
  char* end = nullptr;
  const long j = std::strtol(it->second.c_str(), &end, 10);
  if (it->second.empty() || *end || j < 1 || j > 1024)
    throw UsageError("--jobs: expected a whole number 1..1024, got '" + it->second + "'");
  return int(j);
}

bool has_switch(const CommonArgs& a, const std::string& name) {
  return std::find(a.switches.begin(), a.switches.end(), name) != a.switches.end();
}

int report_error(const std::exception& e) {
  if (dynamic_cast<const SceneError*>(&e)) {
    std::fprintf(stderr, "ravel: scene error: %s\n", e.what());
    return exit_usage;
  }
  if (dynamic_cast<const studies::StudyError*>(&e)) {  // a bad study flag: names flag and value
    std::fprintf(stderr, "ravel: %s\n", e.what());
    return exit_usage;
  }
  if (dynamic_cast<const UsageError*>(&e)) {
    const std::string m = e.what();
    std::fprintf(stderr, "ravel: %s%s\n", m.c_str(),
                 m.find("'ravel help") == std::string::npos ? " (see 'ravel help')" : "");
    return exit_usage;
  }
  if (dynamic_cast<const OutputError*>(&e)) {
    std::fprintf(stderr, "ravel: output error: %s\n", e.what());
    return exit_failure;
  }
  if (dynamic_cast<const std::bad_alloc*>(&e)) {
    std::fprintf(stderr,
                 "ravel: out of memory: the scene needs more memory than this machine could give (scene checks "
                 "estimate it before a run; other programs may have taken it since); make the fabric smaller or "
                 "coarser, or use fewer --jobs\n");
    return exit_failure;
  }
  std::fprintf(stderr, "ravel: error: %s\n", e.what());
  return exit_failure;
}

}  // namespace ravel::app
