// Small shared argument handling for the sub-commands: `[SCENE] [--set k=v ...]
// [--out DIR] [--threads N]` plus each command's own flags.
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "scene.h"

namespace ravel::app {

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct CommonArgs {
  std::string scene_path;              // "" = default scene
  std::vector<std::string> overrides;  // --set k=v, in order
  std::string out_dir;
  int threads = -1;                                       // -1: as the scene says
  std::map<std::string, std::string> flags;               // --name value / --name=value (the last of repeatable ones)
  std::map<std::string, std::vector<std::string>> multi;  // every value given, in order
  std::vector<std::string> switches;                      // --name without value
};

// The options of `command` as app/cli/commands_table.cpp lists them; anything else, or a
// single-valued option given twice, throws UsageError.
CommonArgs parse_args(const std::vector<std::string>& args, const std::string& command);

// The scene file the arguments name: the default scene when none, a bare name finds the
// shipped scene of that name.
std::string scene_path_from(const CommonArgs& a);

// The --set overrides, with --threads N appended as solver.threads=N when given.
std::vector<std::string> overrides_from(const CommonArgs& a);

// Load the scene the arguments name (scene_path_from), with overrides_from.
Scene load_scene_from(const CommonArgs& a);

// --jobs N (1..1024; default: one per core). Throws UsageError.
int jobs_from(const CommonArgs& a);

bool has_switch(const CommonArgs& a, const std::string& name);

// Print an error in the one-line house style and return the exit code for it.
int report_error(const std::exception& e);

enum ExitCode { exit_ok = 0, exit_failure = 1, exit_usage = 2, exit_diverged = 3, exit_interrupted = 130 };

}  // namespace ravel::app
