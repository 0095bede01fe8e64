// URDF (+ Leju limit files) -> constexpr C++ model tables (controllers/model/model_tables.h).
// Offline tool code: allocates freely, reports every problem as a clear message.
#pragma once

#include <string>

namespace kuavo::tools {

struct GeneratorInput {
  std::string variant;          // "s45" or "s42"
  std::string urdf_path;
  std::string kuavo_json_path;  // velocity and peak limits
  std::string task_info_path;   // WBC torque limits (torqueLimitsTask)
};

struct GeneratorResult {
  bool ok = false;
  std::string error;   // set when !ok: names the file, the element and the problem
  std::string source;  // the generated header when ok
};

// Paths of the published files for a variant below shared/robot.
GeneratorInput default_generator_input(const std::string& robot_dir, const std::string& variant);

GeneratorResult generate_model_tables(const GeneratorInput& input);

}  // namespace kuavo::tools
