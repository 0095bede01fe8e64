#include "tools/cli/commands.h"
#include <cstdio>
namespace kuavo::cli {
int run_paper(int, char**) { std::fprintf(stderr, "kuavo paper: not yet\n"); return 1; }
}  // namespace kuavo::cli
