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
