// The `kuavo` commands' usage texts, one place for `kuavo --help`, `kuavo help CMD`,
// `kuavo CMD --help` and the commands' own usage errors.
#pragma once

#include <cstdio>

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

}  // namespace kuavo::cli
