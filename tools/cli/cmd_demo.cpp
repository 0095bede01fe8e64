// kuavo demo: the main job. Until the simulator and the dance pipeline land it
// runs the most complete thing that exists: the model summary of both variants.
#include <cstdio>
#include <initializer_list>

#include "tools/cli/commands.h"

namespace kuavo::cli {

int run_demo(int, char**) {
  std::printf("kuavo demo: the dance pipeline is not built yet; model summaries follow.\n");
  char arg0[] = "model";
  char variant_flag[] = "--variant";
  char json_flag[] = "--json";
  for (const char* v : {"s45", "s42"}) {
    char variant[4] = {v[0], v[1], v[2], '\0'};
    char* argv[] = {arg0, variant_flag, variant, json_flag};
    if (const int rc = run_model(4, argv); rc != 0) return rc;
  }
  return 0;
}

}  // namespace kuavo::cli
