// The offline stage after the geometric retargeting, as `kuavo retarget` runs it by default:
// feasibility repair (tools/mocap/feasibility_repair.h), dynamic retargeting
// (tools/mocap/dynamic_retarget.h), the independent dynamics check of the geometric and the
// dynamic result (tools/mocap/dynamics_check.h), expressiveness metrics, the report's
// "dynamic" object, the trajectory CSV and the paper's Fig. 4 / 5 plots.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tools/mocap/dynamic_retarget.h"
#include "tools/mocap/feasibility_repair.h"
#include "tools/mocap/human_targets.h"
#include "tools/mocap/retarget.h"

namespace kuavo::cli {

struct DynamicStageOptions {
  mocap::RepairConfig repair;
  std::vector<mocap::RepairOverride> overrides;
  mocap::DynamicRetargetConfig dynamic;
  // The oracle's second pass (mocap::attenuate_gestures): up to this many more rounds of
  // repair + TO, each scaling the gestures by attenuation_gain where the result asks a stance
  // leg joint for more than attenuation_torque_ratio × its limit. Off by default (kuavo
  // retarget --attenuate N): two rounds carried cmu_05_20 from a fall at 6.7 s to 10.2 s and
  // cmu_05_07 from 8.0 to 9.1 s (neither to the end), but scaled 18 s of the built-in dance,
  // which dances without it (hand keypoint error 4.6 → 8.4 cm), at 3× the solve time.
  int attenuation_rounds = 0;
  double attenuation_torque_ratio = 1.5;
  double attenuation_gain = 0.5;
  std::string csv_path;   // the dynamic trajectory, "" = none
  std::string plots_dir;  // Fig. 4 / 5 SVGs (retarget_figures.h), "" = none; the directory must exist
};

struct DynamicStageResult {
  std::vector<dynamics::ConfigVector> q;
  std::vector<mocap::ContactLabel> contacts;
  mocap::RepairedMotion repaired;
  mocap::DynamicResult dynamic;
};

// 0 done, 1 the optimization failed, 2 the motion is bad input (the message says why).
int run_dynamic_stage(const model::Model& robot, const mocap::HumanTargets& targets,
                      const mocap::RetargetResult& geometric, const DynamicStageOptions& options,
                      DynamicStageResult& result, nlohmann::ordered_json& report, std::string& error);

}  // namespace kuavo::cli
