#include "cli.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include "results.h"
#include "sweep.h"

namespace ravel::app {

CommonArgs parse_args(const std::vector<std::string>& args, const std::vector<std::string>& value_flags,
                      const std::vector<std::string>& switch_flags, const std::vector<std::string>& repeatable) {
  CommonArgs a;
  auto takes_value = [&](const std::string& n) {
    return n == "set" || n == "out" || n == "threads" ||
           std::find(value_flags.begin(), value_flags.end(), n) != value_flags.end();
  };
  auto is_switch = [&](const std::string& n) {
    return std::find(switch_flags.begin(), switch_flags.end(), n) != switch_flags.end();
  };
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
      if (is_switch(name)) {
        if (has_value) throw UsageError("--" + name + " takes no value");
        a.switches.push_back(name);
        continue;
      }
      if (!takes_value(name)) throw UsageError("unknown option --" + name);
      if (!has_value) {
        if (i + 1 >= args.size()) throw UsageError("--" + name + " needs a value");
        value = args[++i];
      }
      if (name == "set") {
        a.overrides.push_back(value);
      } else if (name == "out") {
        a.out_dir = value;
      } else if (name == "threads") {
        char* end = nullptr;
        long t = std::strtol(value.c_str(), &end, 10);
        if (value.empty() || *end || t < 0 || t > 256)
          throw UsageError("--threads: expected a whole number 0..256, got '" + value + "'");
        a.threads = int(t);
      } else {
        if (a.flags.count(name) && std::find(repeatable.begin(), repeatable.end(), name) == repeatable.end())
          throw UsageError("--" + name + " given twice");
        a.flags[name] = value;
        a.multi[name].push_back(value);
      }
    } else if (s == "-h") {
      throw UsageError("help");
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
    std::fprintf(stderr, "ravel: %s (see 'ravel help')\n", e.what());
    return exit_usage;
  }
  if (dynamic_cast<const OutputError*>(&e)) {
    std::fprintf(stderr, "ravel: output error: %s\n", e.what());
    return exit_failure;
  }
  std::fprintf(stderr, "ravel: error: %s\n", e.what());
  return exit_failure;
}

}  // namespace ravel::app
