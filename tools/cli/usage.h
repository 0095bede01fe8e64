// The `kuavo` commands' usage texts, one place for `kuavo --help`, `kuavo help CMD`,
// `kuavo CMD --help` and the commands' own usage errors.
#pragma once

#include <cstdio>

#include "rtos_shim/args.h"

namespace kuavo::cli {

struct CommandHelp {
  const char* name;
  const char* summary;  // one line for `kuavo --help`
  const char* usage;    // the full text for `kuavo help CMD`
};

// nullptr for an unknown command.
const CommandHelp* command_help(const char* name);
// Every command, in `kuavo --help` order.
const CommandHelp* commands_help(int& count);

// `kuavo --help` text to out.
void print_overview(std::FILE* out);
// One command's usage to out (the overview for an unknown name).
void print_usage(std::FILE* out, const char* name);
// A usage error: the command's usage on stderr; returns 2, the exit code.
int usage_error(const char* name);
// Parses a command's line: -1 to go on; else the exit code (0 after --help, the usage on
// stdout; 2 after a refusal, its message and the usage on stderr).
int parse_command_line(args::Parser& parser, int argc, char** argv, const char* name);

}  // namespace kuavo::cli
