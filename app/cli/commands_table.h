// The command line's one table of sub-commands and their options (app/cli/commands_table.cpp):
// what parse_args accepts and what `ravel help COMMAND` prints.
#pragma once

#include <string>
#include <vector>

namespace ravel::app {

struct CommandOption {
  const char* name;   // without the leading --
  const char* value;  // the value's placeholder; nullptr: a switch without value
  bool repeatable;    // may be given more than once (every value is kept)
  const char* help;
};

struct Command {
  const char* name;
  const char* synopsis;
  const char* summary;
  std::vector<CommandOption> options;
};

const std::vector<Command>& command_table();
const Command* find_command(const std::string& name);  // nullptr when there is none

void print_usage();                         // `ravel help`
void print_command_help(const Command& c);  // `ravel help COMMAND`, `ravel COMMAND --help`
void print_version();                       // `ravel --version`

}  // namespace ravel::app
