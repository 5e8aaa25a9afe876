// ravel: one executable for the desktop app and the headless command line.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "commands.h"
#include "commands_table.h"
#include "omp_env.h"

int main(int argc, char** argv) {
  using namespace ravel::app;
  // How solver threads wait at the step's barriers: spin briefly on an idle machine, sleep
  // on a loaded one or in the GUI (see app/cli/omp_env.h).
  std::string cmd = argc > 1 ? argv[1] : "";
  const bool opens_gui = cmd.empty() || cmd == "gui" || (cmd.size() > 5 && cmd.substr(cmd.size() - 5) == ".toml");
  choose_omp_wait_policy(argv, opens_gui);
  Args rest;
  for (int i = 2; i < argc; ++i) rest.push_back(argv[i]);
  if (cmd == "help" || cmd == "--help" || cmd == "-h") {
    if (rest.empty()) {
      print_usage();
      return 0;
    }
    const Command* c = find_command(rest[0]);
    if (!c) {
      std::fprintf(stderr, "ravel: no command '%s' (see 'ravel help')\n", rest[0].c_str());
      return 2;
    }
    print_command_help(*c);
    return 0;
  }
  if (cmd == "--version" || cmd == "version") {
    print_version();
    return 0;
  }
  // `ravel COMMAND --help` (or -h) anywhere among its arguments.
  if (const Command* c = find_command(cmd)) {
    for (const auto& r : rest)
      if (r == "--help" || r == "-h") {
        print_command_help(*c);
        return 0;
      }
  }
  if (cmd == "run") return cmd_run(rest);
  if (cmd == "keys") return cmd_keys(rest);
  if (cmd == "sweep") return cmd_sweep(rest);
  if (cmd == "limit") return cmd_limit(rest);
  if (cmd == "paper") return cmd_paper(rest);
  if (cmd == "tradeoff") return cmd_tradeoff(rest);
  if (cmd == "stability") return cmd_stability(rest);
#ifdef RAVEL_HAVE_SNAPSHOT
  if (cmd == "snapshot") return cmd_snapshot(rest);
#endif
#ifdef RAVEL_HAVE_DEMO
  if (cmd == "demo") return cmd_demo(rest);
#endif
#ifdef RAVEL_HAVE_GUI
  if (cmd.empty() || cmd == "gui") return cmd_gui(rest);
  // `ravel scene.toml` opens the app on that scene.
  if (cmd.size() > 5 && cmd.substr(cmd.size() - 5) == ".toml") {
    Args all{cmd};
    all.insert(all.end(), rest.begin(), rest.end());
    return cmd_gui(all);
  }
#else
  if (cmd.empty() || cmd == "gui") {
    std::fprintf(stderr, "ravel: this build has no GUI; use 'ravel run --out DIR'\n");
    return 2;
  }
#endif
  std::fprintf(stderr, "ravel: unknown command '%s' (see 'ravel help')\n", cmd.c_str());
  return 2;
}
