// The ravel command line: one executable, one function per sub-command.
// Each takes the arguments after the sub-command name and returns the exit code.
#pragma once

#include <string>
#include <vector>

namespace ravel::app {

using Args = std::vector<std::string>;

int cmd_run(const Args& args);        // app/cli/cmd_run.cpp
int cmd_snapshot(const Args& args);   // app/cli/cmd_snapshot.cpp
int cmd_gui(const Args& args);        // app/gui/cmd_gui.cpp
int cmd_keys(const Args& args);       // app/cli/cmd_run.cpp: list scene keys
int cmd_sweep(const Args& args);      // app/cli/cmd_studies.cpp
int cmd_limit(const Args& args);      // app/cli/cmd_studies.cpp
int cmd_paper(const Args& args);      // app/cli/cmd_studies.cpp
int cmd_demo(const Args& args);       // app/cli/cmd_demo.cpp: guided demos, headless PNGs
int cmd_tradeoff(const Args& args);   // app/cli/cmd_tradeoff.cpp: speed against accuracy
int cmd_stability(const Args& args);  // app/cli/cmd_tradeoff.cpp: where the methods fail

}  // namespace ravel::app
