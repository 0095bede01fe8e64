// urdf2model: writes controllers/model/generated/biped_sXX_tables.h from shared/robot.
//   urdf2model [--robot-dir DIR] [--variant s45|s42|all] [--out-dir DIR]
#include <cstdio>
#include <exception>
#include <fstream>
#include <string>

#include "rtos_shim/args.h"
#include "tools/urdf2model/urdf_model.h"

namespace {

constexpr const char* kUsage = "usage: urdf2model [--robot-dir DIR] [--variant s45|s42|all] [--out-dir DIR]\n";

int run(int argc, char** argv) {
  std::string robot_dir = std::string(KUAVO_DEFAULT_SHARED_DIR) + "/robot";
  std::string variant = "all";
  std::string out_dir = "controllers/model/generated";
  kuavo::args::Parser p("urdf2model");
  p.text("--robot-dir", "DIR", &robot_dir);
  p.choice("--variant", {"s45", "s42", "all"}, &variant);  // an unknown one generated nothing, exit 0
  p.text("--out-dir", "DIR", &out_dir);
  switch (p.parse(argc, argv)) {
    case kuavo::args::Parser::Result::kHelp:
      std::fputs(kUsage, stdout);
      return 0;
    case kuavo::args::Parser::Result::kError:
      std::fprintf(stderr, "%s\n%s", p.error().c_str(), kUsage);
      return 2;
    case kuavo::args::Parser::Result::kOk:
      break;
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

}  // namespace

// No exception leaves the program: one line and exit 1.
int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "urdf2model: internal error: %s\n", e.what());
  }
  return 1;
}
