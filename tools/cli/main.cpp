// kuavo: the project's command-line entry point.
// Exit codes of every command: 0 ok, 1 runtime failure (including an exception or memory
// exhaustion, reported in one line), 2 bad input or usage.
// Help: `kuavo --help`, `kuavo help CMD` and `kuavo CMD --help` print to stdout and exit 0; an
// unknown command prints the overview to stderr and exits 2 (unknown options: each command).
#include <cstdio>
#include <cstring>
#include <exception>
#include <new>

#include "tools/cli/commands.h"
#include "tools/cli/usage.h"

namespace {

struct Command {
  const char* name;
  int (*run)(int, char**);
};

constexpr Command kCommands[] = {
    {"model", kuavo::cli::run_model},       {"simulate", kuavo::cli::run_simulate},
    {"demo", kuavo::cli::run_demo},         {"paper", kuavo::cli::run_paper},
    {"replay", kuavo::cli::run_replay},     {"retarget", kuavo::cli::run_retarget},
    {"retarget-sweep", kuavo::cli::run_retarget_sweep}, {"campaign", kuavo::cli::run_campaign},
};

bool is_help(const char* a) { return !std::strcmp(a, "--help") || !std::strcmp(a, "-h"); }

}  // namespace

int main(int argc, char** argv) {
  using kuavo::cli::print_overview;
  using kuavo::cli::print_usage;
  if (argc < 2) {
    print_overview(stderr);
    return 2;
  }
  if (is_help(argv[1])) {
    print_overview(stdout);
    return 0;
  }
  if (!std::strcmp(argv[1], "help")) {
    if (argc == 2) {
      print_overview(stdout);
      return 0;
    }
    if (kuavo::cli::command_help(argv[2]) == nullptr || argc > 3) {
      std::fprintf(stderr, "kuavo help: unknown command '%s'\n", argv[2]);
      print_overview(stderr);
      return 2;
    }
    print_usage(stdout, argv[2]);
    return 0;
  }
  for (const Command& c : kCommands) {
    if (std::strcmp(argv[1], c.name) != 0) continue;
    // `--help` anywhere among the command's arguments (also after other options).
    for (int i = 2; i < argc; ++i) {
      if (is_help(argv[i])) {
        print_usage(stdout, c.name);
        return 0;
      }
    }
    // No exception leaves a command: it becomes one line and exit 1, never an abort.
    try {
      return c.run(argc - 1, argv + 1);
    } catch (const std::bad_alloc&) {
      std::fprintf(stderr, "kuavo %s: out of memory\n", c.name);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "kuavo %s: internal error: %s\n", c.name, e.what());
    }
    return 1;
  }
  std::fprintf(stderr, "kuavo: unknown command '%s'\n", argv[1]);
  print_overview(stderr);
  return 2;
}
