// The command line's one table: every sub-command with its synopsis and options. The
// parser (parse_args) accepts exactly the options listed here, and `ravel help COMMAND` /
// `ravel COMMAND --help` print them, so the help cannot drift from what is accepted.
#include "commands_table.h"

#include <cstdio>

#include "limit.h"
#include "version.h"

namespace ravel::app {

namespace {

// Options most commands share.
const CommandOption kSet{"set", "KEY=VALUE", true,
                         "override a scene key (repeatable; see ravel keys), e.g. --set yarn.friction=0.1"};
const CommandOption kOut{"out", "DIR", false, "the output folder (created; outputs are written atomically)"};
const CommandOption kThreads{"threads", "N", false,
                             "solver threads per run (default: the scene's solver.threads, 0 = one per core)"};
const CommandOption kQuiet{"quiet", nullptr, false, "no progress lines"};
const CommandOption kJobs{"jobs", "N", false, "runs at a time (default: one per core)"};

// The --without help names the rules from the table the parser reads (studies::fast_rule_table).
const std::string& without_help() {
  static const std::string h = "the fast search without these of its rules (" + studies::fast_rule_names() +
                               "; docs/studies.md), to measure what each saves";
  return h;
}

std::vector<Command> make_table() {
  std::vector<Command> t;
  t.push_back(
      {"gui",
       "ravel [gui] [SCENE] [options]",
       "the interactive app (the default command when a display exists)",
       {kSet,
        kThreads,
        {"size", "WxH", false, "window size (default: 1600x1000, or 90 % of a smaller screen; at least 640x480)"},
        {"view", "NAME", false, "initial camera: oblique (default), top, back or section"},
        {"field", "NAME", false, "initial colour field: strain (default), velocity, sliding or friction"},
        {"paused", nullptr, false, "open paused at t = 0"},
        {"pause-at-us", "T", false, "pause when the simulated time reaches T us"},
        {"frames", "N", false, "quit after N UI frames (for scripts and tests)"},
        {"screenshot", "FILE", false, "PNG of the whole window at the last frame"},
        {"do", "FRAME:ACTION", true,
         "at UI frame FRAME do ACTION (repeatable): play, pause, step, reset, restart, clear, fast, "
         "slow:US_PER_S, set:KEY=VALUE, view:NAME, field:NAME, colormap:NAME, range:LO:HI (or range:auto), "
         "scrub:T_US, live, pick:ELEMENT_ID, pick-crossing:ID, open:PATH, screenshot:FILE, export-results, "
         "export-scene, export-vtk:DIR, record:DIR, sweep:KEY=LIST[;KEY=LIST], sweep-charts[:X_KEY], limit, demo:NAME, "
         "continue, "
         "compare-exit"},
        {"budget-mb", "MB", false, "memory for the kept frames of a run (time slider; default 256)"},
        {"export-dir", "DIR", false, "the Export panel's folder (default: ./ravel_export)"}}});
  t.push_back({"run",
               "ravel run [SCENE] [--set KEY=VALUE ...] --out DIR [options]",
               "one headless run: DIR/summary.json, DIR/history.csv, DIR/scene.toml",
               {kSet,
                kOut,
                kThreads,
                {"frames", "every=N|final|none", false,
                 "PNG frames into DIR/frames/ every N steps, the last one only, or none (default)"},
                {"vtk", nullptr, false, "a VTU series DIR/vtk/frame.pvd at the --frames times (default every=100)"},
                {"view", "NAME", false, "camera of the PNG frames: oblique (default), top, back or section"},
                {"field", "NAME", false, "colour of the PNG frames: strain (default), velocity, sliding or friction"},
                {"resume", nullptr, false,
                 "continue from DIR/checkpoint.bin (a killed or interrupted run of the same scene and build) "
                 "instead of t = 0"},
                {"checkpoint-every", "S", false,
                 "write DIR/checkpoint.bin every S seconds of wall time and on Ctrl-C (default 60; 0 = never); "
                 "removed when the run ends"},
                kQuiet}});
  t.push_back({"snapshot",
               "ravel snapshot [SCENE] [--set ...] --at T_US[,T_US...] --out DIR [options]",
               "PNG images of the fabric at given times",
               {kSet,
                kOut,
                kThreads,
                {"at", "T_US[,T_US...]", false, "simulated times in us (required)"},
                {"view", "NAME", false, "oblique (default), top, back or section"},
                {"field", "NAME", false, "strain (default), velocity, sliding or friction"},
                {"range", "LO:HI", false, "a fixed colour range (default: the field's own)"},
                {"size", "WxH", false, "image size (default 1600x1200)"},
                kQuiet}});
  t.push_back({"keys", "ravel keys", "every scene key with its unit, built-in default, allowed range and meaning", {}});
  t.push_back(
      {"sweep",
       "ravel sweep [SCENE] --vary KEY=START:STOP:STEP|V1,V2,... [--vary ...] --out DIR [options]",
       "a parameter sweep: one run per case, DIR/results.csv and charts; rerun to resume",
       {kSet,
        kOut,
        kThreads,
        kJobs,
        {"vary", "KEY=START:STOP:STEP|V1,V2,...", true, "a key and its values (repeatable: the cases are the product)"},
        {"shard", "i/n", false, "only the cases k with k mod n = i - 1 (to split a sweep over machines)"},
        {"chart-x", "KEY", false,
         "the --vary key the charts put on the x axis (default: the first; the others make the series)"},
        {"chart-y", "COLUMN,...", false,
         "more results.csv columns to chart beside energy absorbed and residual velocity (e.g. "
         "first_break_distance_mm,clamp_friction_J; rerun a finished sweep with it to chart it)"},
        {"repeats", "N", false,
         "run each --vary projectile.velocity_mps value N times, raised by 0, 1e-6, 2e-6 ... m/s: near the ballistic "
         "limit an outcome is a random variable (docs/studies.md, the zone of mixed results); writes "
         "DIR/perforation.csv and the perforation probability chart"},
        {"no-extend", nullptr, false,
         "a run that reaches its end time undecided is not extended to solver.max_end_time_us"},
        {"restart", nullptr, false, "start over in a folder that holds another sweep's cases (they are removed)"},
        kQuiet}});
  t.push_back({"limit",
               "ravel limit [SCENE] [--set ...] --out DIR [options]",
               "the ballistic limit by bracketing and bisection, with a Lambert-Jonas fit; rerun to resume",
               {kSet,
                kOut,
                kThreads,
                {"jobs", "N", false,
                 "runs in flight at once, each on one solver thread unless --threads (default: one per core)"},
                {"tolerance", "MPS", false, "stop when the bracket is this narrow (default 1 m/s)"},
                {"start", "MPS", false, "the first velocity tried (default 100 m/s)"},
                {"max-runs", "N", false, "give up after N runs (default 60)"},
                {"no-fit", nullptr, false, "no extra runs for the Lambert-Jonas fit"},
                {"reference", nullptr, false,
                 "the reference search: bisection, one run at a time, every run to its end (docs/studies.md); "
                 "default: the fast search, the same bracket guarantee"},
                {"without", "RULE,...", false, without_help().c_str()},
                kQuiet}});
  t.push_back({"paper",
               "ravel paper --out DIR [options]",
               "the paper's studies reproduced on the full mesh: DIR/report.md with verdicts; rerun to resume",
               {kSet,
                kOut,
                kThreads,
                kJobs,
                {"quick", nullptr, false, "a small mesh and few cases (minutes, for a check)"},
                {"reference-limits", nullptr, false,
                 "ballistic limits by the bisection of ravel limit --reference (default: the fast search, one run "
                 "in flight per search, with its probes below the bracket)"},
                kQuiet}});
  t.push_back({"demo",
               "ravel demo --list | NAME|all --out DIR [options]",
               "guided demos as captioned PNGs and charts",
               {kSet,
                kOut,
                kThreads,
                {"list", nullptr, false, "list the demos"},
                {"quick", nullptr, false, "smaller, faster versions"},
                {"size", "WxH", false, "image size (default 1600x1000, at least 320x240)"},
                kQuiet}});
  t.push_back({"tradeoff",
               "ravel tradeoff [SCENE] [--set ...] --out DIR [options]",
               "error against cost of every speed/accuracy knob (docs/tradeoff.md)",
               {kSet,
                kOut,
                kThreads,
                kJobs,
                {"quick", nullptr, false, "fewer values per knob"},
                {"knob", "KEY=V1,V2,...", true, "replace one knob's values (repeatable)"},
                {"only", "KEY[,KEY...]", false, "only these knobs ('searches' alone: none, with --searches)"},
                {"reference", "KEY=VALUE", true, "the reference's value of a knob (default: its finest)"},
                {"around", "scene|reference", false, "vary each knob around the scene (default) or the reference"},
                {"cost", "wall|cpu", false, "cost measure (default wall)"},
                {"limit", nullptr, false, "also the ballistic limit of every setting"},
                {"tolerance", "MPS", false, "ballistic-limit tolerance with --limit or --searches (default 1 m/s)"},
                {"searches", "all|none|RULE,...", false,
                 "also the ballistic-limit searches on the scene's settings, one after another: the reference, "
                 "the fast search, and the fast search without each rule named (searches.csv; --only searches: "
                 "no knob rows)"},
                {"note", "TEXT", false, "a note recorded with the results"},
                {"date", "YYYY-MM-DD", false, "the date recorded (default today)"},
                kQuiet}});
  t.push_back({"stability",
               "ravel stability [SCENE] [--set ...] --out DIR [options]",
               "maps of where the methods fail (stable / warned / diverged)",
               {kSet,
                kOut,
                kThreads,
                kJobs,
                {"quick", nullptr, false, "coarser maps"},
                {"map", "NAME", true, "only this map: dt_factor, friction, friction_penalty or velocity (repeatable)"},
                kQuiet}});
  t.push_back({"help", "ravel help [COMMAND]", "this text, or one command's options", {}});
  return t;
}

}  // namespace

const std::vector<Command>& command_table() {
  static const std::vector<Command> t = make_table();
  return t;
}

const Command* find_command(const std::string& name) {
  for (const auto& c : command_table())
    if (name == c.name) return &c;
  return nullptr;
}

void print_usage() {
  std::printf(
      "ravel %s: yarn-level simulation of a projectile striking woven fabric armour\n\n"
      "usage: ravel [COMMAND] [SCENE] [--set section.key=value ...] [options]\n\ncommands:\n",
      version());
  for (const auto& c : command_table()) std::printf("  %-10s %s\n", c.name, c.summary);
  std::printf(
      "\nravel help COMMAND (or ravel COMMAND --help) lists a command's options; ravel --version.\n"
      "SCENE is a TOML file, a run's output folder (its scene.toml) or the name of a shipped scene\n"
      "(default: twaron_ct716).\n"
      "Exit codes: 0 done, 1 output error, 2 bad input, 3 run diverged, 130 interrupted.\n");
}

void print_command_help(const Command& c) {
  std::printf("%s\n  %s\n", c.synopsis, c.summary);
  if (!c.options.empty()) std::printf("\noptions:\n");
  for (const auto& o : c.options) {
    std::string left = std::string("--") + o.name + (o.value ? std::string(" ") + o.value : "");
    if (left.size() <= 26)
      std::printf("  %-26s %s\n", left.c_str(), o.help);
    else
      std::printf("  %s\n  %-26s %s\n", left.c_str(), "", o.help);
  }
  std::printf("  %-26s %s\n", "--help, -h", "this text");
}

void print_version() {
  std::printf("ravel %s (source %s)\n", version(), source_commit());
}

}  // namespace ravel::app
