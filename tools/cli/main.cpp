// kuavo: the project's command-line entry point.
// Exit codes of every command: 0 ok, 1 runtime failure (including an exception or memory
// exhaustion, reported in one line), 2 bad input or usage.
#include <cstdio>
#include <cstring>
#include <exception>
#include <new>

#include "tools/cli/commands.h"

namespace {

struct Command {
  const char* name;
  int (*run)(int, char**);
  const char* usage;
};

constexpr Command kCommands[] = {
    {"model", kuavo::cli::run_model, "model [--variant s45|s42] [--mass KG] --json   robot model summary"},
    {"simulate", kuavo::cli::run_simulate,
     "simulate --stand SECONDS [--ground floor|carpet] [--push T:FX,FY,FZ:DURATION] [--seed N] --log CSV --summary JSON"},
    {"demo", kuavo::cli::run_demo, "demo [--out DIR]                                 the main job"},
    {"retarget", kuavo::cli::run_retarget, "retarget [IN.bvh] -o OUT.motion [--variant s45|s42] [--contacts auto|FILE] --report R.json"},
    {"retarget-sweep", kuavo::cli::run_retarget_sweep,
     "retarget-sweep [IN.bvh] --out DIR [--horizons 0.2,0.4,...,1.4]   dynamic stage per TO horizon (Fig. 6)"},
    {"campaign", kuavo::cli::run_campaign,
     "campaign SPEC.json [--out DIR] [--seeds N] [--jobs N] [--sshloginfile FILE] | --example   runs over seeds"},
};

int usage() {
  std::fprintf(stderr, "usage: kuavo <command> [options]\n");
  for (const Command& c : kCommands) std::fprintf(stderr, "  kuavo %s\n", c.usage);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage();
  for (const Command& c : kCommands) {
    if (std::strcmp(argv[1], c.name) != 0) continue;
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
  return usage();
}
