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

}  // namespace kuavo::cli
