// The dance the firmware plays: a robot motion file (tools/mocap/motion_reader.h format,
// as `kuavo retarget` writes it) read, validated against this robot's variant and layout,
// turned into a planner::MotionPlan and, with balance_filter, balance-filtered -- the same
// pipeline as `kuavo simulate MOTION` (tools/mocap/motion_plan_io.h). The filter is off by
// default since the dynamic stage of `kuavo retarget` is: its motions are dynamically
// feasible and the filter's base correction takes their stretched legs out of reach; it
// stays for geometric-stage motions (`kuavo retarget --stage geometric`). Start-up only, before anything is
// sent: it allocates (the file's bytes, the filter's workspace) and may take seconds.
#pragma once

#include <string>

#include "controllers/model/model.h"
#include "controllers/planner/balance_filter.h"
#include "controllers/planner/motion_plan.h"

namespace kuavo::firmware {

// false with a message naming the file and the problem (unreadable, not a motion file,
// checksum, recorded for the other arm variant, too long, not starting from standing,
// not balanceable).
bool load_dance_motion(const std::string& path, const model::Model& robot, bool balance_filter,
                       planner::MotionPlan& plan, planner::BalanceFilterReport& report, std::string& error);

// The firmware starts every dance from standing: frame 0 must have every sole corner
// within kStartSoleHeight_m of the ground (forward kinematics of the frame), and is then
// labelled double support whatever the file says (the contact detector labels the
// built-in dance's frame 0 "flight": it has no speed history there). nullptr, or what is
// wrong. Start-up; data is scratch. Before the balance filter (motion_plan_finish does not
// read the contact labels).
inline constexpr double kStartSoleHeight_m = 0.01;
const char* dance_motion_start_standing(const model::Model& robot, dynamics::Data& data, planner::MotionPlan& plan);

}  // namespace kuavo::firmware
