// urdf2model: writes controllers/model/generated/biped_sXX_tables.h from shared/robot.
//   urdf2model [--robot-dir DIR] [--variant s45|s42|all] [--out-dir DIR]
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>

#include "tools/urdf2model/urdf_model.h"

int main(int argc, char** argv) {
  std::string robot_dir = std::string(KUAVO_DEFAULT_SHARED_DIR) + "/robot";
  std::string variant = "all";
  std::string out_dir = "controllers/model/generated";
  for (int i = 1; i < argc; ++i) {
    auto next = [&](std::string& v) {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "urdf2model: %s needs a value\n", argv[i]);
        std::exit(2);
      }
      v = argv[++i];
    };
    if (!std::strcmp(argv[i], "--robot-dir")) next(robot_dir);
    else if (!std::strcmp(argv[i], "--variant")) next(variant);
    else if (!std::strcmp(argv[i], "--out-dir")) next(out_dir);
    else {
      std::fprintf(stderr, "usage: urdf2model [--robot-dir DIR] [--variant s45|s42|all] [--out-dir DIR]\n");
      return 2;
    }
  }
  for (const char* v : {"s45", "s42"}) {
    if (variant != "all" && variant != v) continue;
    const auto result = kuavo::tools::generate_model_tables(kuavo::tools::default_generator_input(robot_dir, v));
    if (!result.ok) {
      std::fprintf(stderr, "urdf2model: %s\n", result.error.c_str());
      return 1;
    }
    const std::string path = out_dir + "/biped_" + v + "_tables.h";
    std::ofstream out(path);
    out << result.source;
    if (!out) {
      std::fprintf(stderr, "urdf2model: cannot write %s\n", path.c_str());
      return 1;
    }
    std::printf("wrote %s\n", path.c_str());
  }
  return 0;
}
