// SVG plots of a closed-loop motion run (sim::MotionTrace) for the demo report: joint
// tracking, CoM against the plan, and the ZMP against the support polygon.
#pragma once

#include <string>

#include "controllers/model/model.h"
#include "sim/motion_loop.h"

namespace kuavo::cli {

// Writes <stem>_tracking.svg, <stem>_com.svg, <stem>_zmp.svg. false with a message on I/O failure.
bool write_motion_plots(const model::Model& robot, const sim::MotionTrace& trace, const std::string& stem,
                        const std::string& title, std::string& error);

// The MPC horizon experiment (the paper's Fig. 7): <stem>_knee.svg, the left knee of both runs
// against the plan, and <stem>_feet.svg, the sole centres at each touchdown (a foot's load
// rising through 100 N after it had been below 5 N), top view. false with a message.
bool write_horizon_plots(const sim::MotionTrace& long_horizon, const sim::MotionTrace& short_horizon,
                         const std::string& stem, std::string& error);

}  // namespace kuavo::cli
