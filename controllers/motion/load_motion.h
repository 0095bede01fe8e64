// The one path from a motion file to the MotionPlan the online stack follows: read, validate
// (variant, layout, checksums, every frame finite and within the robot's limits), starts
// standing in double support, optionally balance-filtered. `kuavo_fw --dance`, `kuavo_fw_sim`
// and `kuavo simulate` all call load_motion, so the simulator cannot accept a motion the robot
// refuses. Start-up only, before anything is sent: it allocates (the file's bytes, 288 B a frame
// plus the header, and the balance filter's workspace) and may take seconds.
//
// A folder apart from planner/: this is the file format, file I/O and its checks, done once at
// start-up; planner/ holds the plan and its real-time sampling and knows no file format.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "controllers/motion/motion_reader.h"
#include "controllers/planner/balance_filter.h"
#include "controllers/planner/motion_plan.h"

namespace kuavo::motion {

// Largest valid motion file: the header and kMotionMaxFrames records.
inline constexpr std::uint64_t kMotionMaxFileBytes =
    kMotionHeaderBytes + std::uint64_t{kMotionMaxFrames} * kMotionRecordBytes;

// The bytes of a motion file. A directory, device or pipe is refused before reading (a
// directory makes a stream throw; /dev/zero never ends), and so is a file larger than
// kMotionMaxFileBytes. false with a message naming the file.
bool read_motion_bytes(const std::string& path, std::vector<std::uint8_t>& bytes, std::string& error);

// read_motion_header with a message prefixed by `what` that says what differs (the file's
// variant, the byte count the header promises).
bool check_motion_header(const std::vector<std::uint8_t>& bytes, const model::Model& robot, const std::string& what,
                         MotionHeader& header, std::string& error);

// Frame i of checked bytes, read and checked (check_motion_frame), with a message naming the
// frame, the joint and its limits, or the base pose.
bool read_checked_motion_frame(const std::vector<std::uint8_t>& bytes, const model::Model& robot, std::uint32_t i,
                               const std::string& what, dynamics::ConfigVector& q, ContactLabel& label,
                               std::string& error);

// The firmware starts every dance from standing: frame 0 must have every sole corner within
// kStartSoleHeight_m of the ground (forward kinematics of the frame), and is then labelled
// double support whatever the file says (the contact detector labels the built-in dance's
// frame 0 "flight": it has no speed history there). nullptr, or what is wrong. data is scratch.
inline constexpr double kStartSoleHeight_m = 0.01;  // 1 cm: a sole resting on the floor, not a lift
const char* motion_start_standing(const model::Model& robot, dynamics::Data& data, planner::MotionPlan& plan);

struct MotionOptions {
  // The cart-table ZMP preview filter (planner/balance_filter.h). Off by default: the dynamic
  // stage of `kuavo retarget` makes the motion feasible, and the filter's base correction
  // takes its stretched legs out of reach; on for geometric-stage motions.
  bool balance_filter = false;
};

// A plan already filled with frames and contacts → one the stack may follow:
// motion_plan_finish (checks, velocities), motion_start_standing, then the balance filter if
// asked. false with a message prefixed by `what`.
bool prepare_motion(const model::Model& robot, const MotionOptions& options, const std::string& what,
                    planner::MotionPlan& plan, planner::BalanceFilterReport& report, std::string& error);

// File → prepared plan (read_motion_bytes, check_motion_header, every frame checked, then
// prepare_motion). false with a message naming the file and the problem.
bool load_motion(const std::string& path, const model::Model& robot, const MotionOptions& options,
                 planner::MotionPlan& plan, planner::BalanceFilterReport& report, std::string& error);

// The same from a motion file's bytes already in memory (`what` names them in messages):
// `kuavo retarget` checks its own output in the closed-loop simulation this way.
bool load_motion_bytes(const std::vector<std::uint8_t>& bytes, const std::string& what, const model::Model& robot,
                       const MotionOptions& options, planner::MotionPlan& plan, planner::BalanceFilterReport& report,
                       std::string& error);

}  // namespace kuavo::motion
