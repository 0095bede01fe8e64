// kuavo model: the robot model summary (variant, DoF, mass, zero-pose CoM and contact points).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <nlohmann/json.hpp>

#include "controllers/dynamics/rigid_body.h"
#include "tools/cli/args.h"
#include "tools/cli/commands.h"

namespace kuavo::cli {

int run_model(int argc, char** argv) {
  model::Variant variant = model::Variant::kS45;
  double mass_kg = model::kDefaultTotalMass_kg;
  bool json = false;
  std::string variant_name = "s45";
  args::Parser p("kuavo model");
  p.choice("--variant", {"s45", "s42"}, &variant_name);
  // The 55 kg robot scaled: build_model refuses a mass its torso cannot carry; this bounds the token.
  p.number("--mass", "KG", 1.0, 1000.0, "kg", &mass_kg);
  p.flag("--json", &json);
  const args::Parser::Result parsed = p.parse(argc, argv);
  if (parsed != args::Parser::Result::kOk) {
    if (parsed == args::Parser::Result::kError) std::fprintf(stderr, "%s\n", p.error().c_str());
    std::fprintf(parsed == args::Parser::Result::kHelp ? stdout : stderr,
                 "usage: kuavo model [--variant s45|s42] [--mass KG] --json\n");
    return parsed == args::Parser::Result::kHelp ? 0 : 2;
  }
  model::parse_variant(variant_name.c_str(), variant);  // one of the two names
  auto robot = std::make_unique<model::Model>();
  if (const auto err = model::build_model(variant, mass_kg, *robot); err != model::ModelError::kOk) {
    std::fprintf(stderr, "kuavo model: %s (--mass %g)\n", model::to_string(err), mass_kg);
    return 2;
  }
  auto data = std::make_unique<dynamics::Data>();
  dynamics::ConfigVector q = dynamics::ConfigVector::Zero();
  q[6] = 1.0;  // base at the origin, identity orientation: world = base frame
  dynamics::forward_kinematics(*robot, *data, q);
  dynamics::crba(*robot, *data);

  nlohmann::ordered_json out;
  out["variant"] = model::to_string(variant);
  out["dof"] = model::kNumJoints;
  out["total_mass_kg"] = data->total_mass_kg;
  out["com_zero_m"] = {data->com_m.x(), data->com_m.y(), data->com_m.z()};
  auto points = nlohmann::json::array();
  for (int f = 0; f < model::kNumContactPoints; ++f) {
    const dynamics::Vec3 p = dynamics::frame_position(*robot, *data, f);
    points.push_back({p.x(), p.y(), p.z()});
  }
  out["contact_points_zero_m"] = points;
  auto names = nlohmann::json::array();
  for (int j = 0; j < model::kNumJoints; ++j) names.push_back(model::joint_name(*robot, j));
  out["joint_names"] = names;
  if (json) {
    std::printf("%s\n", out.dump(2).c_str());
  } else {
    std::printf("Kuavo 4Pro %s: %d joints, %.3f kg, zero-pose CoM (%.4f, %.4f, %.4f) m in the base frame\n",
                model::to_string(variant), model::kNumJoints, data->total_mass_kg, data->com_m.x(),
                data->com_m.y(), data->com_m.z());
  }
  return 0;
}

}  // namespace kuavo::cli
