// ravel: one executable for the desktop app and the headless command line.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "commands.h"
#include "omp_env.h"

namespace {

void usage() {
  std::printf(
      "ravel: yarn-level simulation of a projectile striking woven fabric armour\n\n"
      "usage: ravel [COMMAND] [SCENE] [--set section.key=value ...] [options]\n\n"
      "commands:\n"
      "  gui [SCENE]              the interactive app (default when a display exists)\n"
      "  run [SCENE] --out DIR    one headless run: DIR/history.csv, DIR/summary.json\n"
      "  snapshot [SCENE] --at T_US[,T_US..] --out DIR   PNG images of the fabric\n"
      "  keys                     list every scene key with its unit\n"
      "  sweep [SCENE] --vary key=a:b:step|v1,v2 --out DIR [--jobs N] [--shard i/n]   parameter sweep\n"
      "  limit [SCENE] --out DIR [--tolerance MPS]   ballistic limit + Lambert-Jonas fit\n"
      "  paper --out DIR [--quick]  reproduce the paper's studies, DIR/report.md\n"
      "  demo NAME --out DIR      a guided demo's key frames as captioned PNGs (demo --list)\n"
      "  tradeoff [SCENE] --out DIR [--quick] [--limit]   error against cost of every speed/accuracy knob\n"
      "  stability [SCENE] --out DIR [--quick]   map where the methods fail (dt, iterations, velocity)\n"
      "  help                     this text\n\n"
      "SCENE is a TOML file or the name of a shipped scene (default: twaron_ct716).\n"
      "Exit codes: 0 done, 1 output error, 2 bad input, 3 run diverged, 130 interrupted.\n");
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ravel::app;
  // How solver threads wait at the step's barriers: spin briefly on an idle machine, sleep
  // on a loaded one or in the GUI (see app/omp_env.h).
  std::string cmd = argc > 1 ? argv[1] : "";
  const bool opens_gui = cmd.empty() || cmd == "gui" || (cmd.size() > 5 && cmd.substr(cmd.size() - 5) == ".toml");
  choose_omp_wait_policy(argv, opens_gui);
  Args rest;
  for (int i = 2; i < argc; ++i) rest.push_back(argv[i]);
  if (cmd == "help" || cmd == "--help" || cmd == "-h") {
    usage();
    return 0;
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
