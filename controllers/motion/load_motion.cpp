#include "controllers/motion/load_motion.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include "controllers/dynamics/rigid_body.h"

namespace kuavo::motion {

bool read_motion_bytes(const std::string& path, std::vector<std::uint8_t>& bytes, std::string& error) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) {
    error = path + ": cannot open";
    return false;
  }
  if (!std::filesystem::is_regular_file(status)) {
    error = path + ": not a regular file";
    return false;
  }
  const std::uintmax_t file_bytes = std::filesystem::file_size(path, ec);
  if (ec) {
    error = path + ": cannot open";
    return false;
  }
  if (file_bytes > kMotionMaxFileBytes) {
    error = path + ": " + std::to_string(file_bytes) + " bytes, more than the largest motion (" +
            std::to_string(kMotionMaxFileBytes) + " bytes, " + std::to_string(kMotionMaxFrames) + " frames)";
    return false;
  }
  std::ifstream in(path, std::ios::binary);
  bytes.assign(static_cast<std::size_t>(file_bytes), 0);
  if (in) in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!in || in.gcount() != static_cast<std::streamsize>(bytes.size())) {
    error = path + ": cannot read";
    return false;
  }
  return true;
}

bool check_motion_header(const std::vector<std::uint8_t>& bytes, const model::Model& robot, const std::string& what,
                         MotionHeader& header, std::string& error) {
  const MotionError e = read_motion_header(bytes.data(), bytes.size(), robot, header);
  if (e == MotionError::kOk) return true;
  if (e == MotionError::kWrongVariant) {
    const bool known = bytes[16] == static_cast<std::uint8_t>(model::Variant::kS45) ||
                       bytes[16] == static_cast<std::uint8_t>(model::Variant::kS42);
    const auto file_variant = static_cast<model::Variant>(bytes[16]);
    error = what + ": " +
            (known ? to_string(e) + std::string(" (file: ") + model::to_string(file_variant) + ", expected: " +
                         model::to_string(robot.variant) + ")"
                   : "unknown robot variant byte " + std::to_string(bytes[16]) + " at offset 16 (expected " +
                         std::to_string(static_cast<int>(robot.variant)) + " = " + model::to_string(robot.variant) + ")");
  } else if (e == MotionError::kTrailingBytes) {
    const std::uint32_t frames = motion_get_u32(bytes.data() + 32);
    error = what + ": " + to_string(e) + ": " + std::to_string(bytes.size()) + " bytes, the header and its " +
            std::to_string(frames) + " frames make " +
            std::to_string(kMotionHeaderBytes + std::size_t{frames} * kMotionRecordBytes);
  } else if (e == MotionError::kTooManyFrames) {
    error = what + ": " + to_string(e) + ": the header says " + std::to_string(motion_get_u32(bytes.data() + 32)) +
            " frames, the capacity is " + std::to_string(kMotionMaxFrames);
  } else {
    error = what + ": " + to_string(e);
  }
  return false;
}

bool read_checked_motion_frame(const std::vector<std::uint8_t>& bytes, const model::Model& robot, std::uint32_t i,
                               const std::string& what, dynamics::ConfigVector& q, ContactLabel& label,
                               std::string& error) {
  MotionError e = read_motion_frame(bytes.data(), bytes.size(), i, q, label);
  int joint = -1;
  if (e == MotionError::kOk) e = check_motion_frame(robot, q, joint);
  if (e == MotionError::kOk) return true;
  error = what + ": frame " + std::to_string(i) + ": " + to_string(e);
  char buf[160];
  if (e == MotionError::kJointOutOfLimits) {
    std::snprintf(buf, sizeof buf, ": %s = %.9g rad, limits [%.4f, %.4f] rad", model::joint_name(robot, joint),
                  q[7 + joint], robot.limits.position_min_rad[joint], robot.limits.position_max_rad[joint]);
    error += buf;
  } else if (e == MotionError::kBaseImplausible) {
    std::snprintf(buf, sizeof buf,
                  ": position (%.9g, %.9g, %.9g) m (|x|, |y| <= %.0f m, height %.1f..%.1f m), quaternion norm %.9g",
                  q[0], q[1], q[2], kMotionBaseHorizontalMax_m, kMotionBaseHeightMin_m, kMotionBaseHeightMax_m,
                  q.segment<4>(3).norm());
    error += buf;
  }
  return false;
}

const char* motion_start_standing(const model::Model& robot, dynamics::Data& data, planner::MotionPlan& plan) {
  if (plan.frame_count < 1) return "the motion has no frames";
  dynamics::forward_kinematics(robot, data, plan.q[0]);
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    if (std::abs(dynamics::frame_position(robot, data, c).z()) > kStartSoleHeight_m) {
      return "the first frame does not stand (a sole corner more than 1 cm off the ground); the robot dances from "
             "standing";
    }
  }
  plan.foot_contact[0] = {true, true};
  return nullptr;
}

bool prepare_motion(const model::Model& robot, const MotionOptions& options, const std::string& what,
                    planner::MotionPlan& plan, planner::BalanceFilterReport& report, std::string& error) {
  report = planner::BalanceFilterReport{};
  if (const char* why = planner::motion_plan_finish(plan)) {
    error = what + ": " + why;
    return false;
  }
  auto data = std::make_unique<dynamics::Data>();
  if (const char* why = motion_start_standing(robot, *data, plan)) {
    error = what + ": " + why;
    return false;
  }
  if (!options.balance_filter) return true;
  auto ws = std::make_unique<planner::BalanceFilterWorkspace>();
  if (const char* why = planner::balance_filter(robot, planner::BalanceFilterConfig{}, plan, *ws, report)) {
    error = what + ": " + why;  // the filter's messages name it
    return false;
  }
  return true;
}

bool load_motion(const std::string& path, const model::Model& robot, const MotionOptions& options,
                 planner::MotionPlan& plan, planner::BalanceFilterReport& report, std::string& error) {
  std::vector<std::uint8_t> bytes;
  if (!read_motion_bytes(path, bytes, error)) return false;
  return load_motion_bytes(bytes, path, robot, options, plan, report, error);
}

bool load_motion_bytes(const std::vector<std::uint8_t>& bytes, const std::string& path, const model::Model& robot,
                       const MotionOptions& options, planner::MotionPlan& plan, planner::BalanceFilterReport& report,
                       std::string& error) {
  MotionHeader header;
  if (!check_motion_header(bytes, robot, path, header, error)) return false;
  // The header bounds frame_count by kMotionMaxFrames = the plan's capacity.
  plan.rate_hz = header.rate_hz;
  plan.frame_count = static_cast<int>(header.frame_count);
  plan.start_ns = 0;
  for (std::uint32_t i = 0; i < header.frame_count; ++i) {
    ContactLabel label;
    if (!read_checked_motion_frame(bytes, robot, i, path, plan.q[i], label, error)) return false;
    plan.foot_contact[i] = {left_in_contact(label), right_in_contact(label)};
  }
  return prepare_motion(robot, options, path, plan, report, error);
}

}  // namespace kuavo::motion
