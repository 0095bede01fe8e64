#include "drivers/ruiwo/ruiwo_bus.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace kuavo::drivers::ruiwo {

DriverError build_bus(const std::vector<MotorConfig>& motors, Bus& out, std::string& message) {
  out = Bus{};
  out.index_of_id.fill(-1);
  if (motors.size() > static_cast<std::size_t>(kMaxMotorsPerBus)) {
    message = "Ruiwo bus: " + std::to_string(motors.size()) + " motors, at most " +
              std::to_string(kMaxMotorsPerBus);
    return DriverError::kBadConfig;
  }
  for (std::size_t i = 0; i < motors.size(); ++i) {
    const MotorConfig& m = motors[i];
    const std::string who = "Ruiwo motor 0x" + [&] {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "%02X", m.motor_id);
      return std::string(buf);
    }();
    if (m.motor_id == 0 || m.motor_id > 0x7F) {
      message = who + ": ID outside 0x01..0x7F";
      return DriverError::kBadConfig;
    }
    if (out.index_of_id[m.motor_id] >= 0) {
      message = who + ": ID used twice on one bus";
      return DriverError::kDuplicateId;
    }
    if (m.joint < 0 || m.joint >= model::kNumJoints) {
      message = who + ": joint " + std::to_string(m.joint) + " outside 0.." +
                std::to_string(model::kNumJoints - 1);
      return DriverError::kBadConfig;
    }
    if (m.sign != 1 && m.sign != -1) {
      message = who + ": sign must be +1 or -1";
      return DriverError::kBadConfig;
    }
    const double values[] = {m.zero_offset_rad, m.position_min_rad, m.position_max_rad,
                             m.velocity_max_rad_s, m.torque_max_Nm};
    if (!std::all_of(std::begin(values), std::end(values), [](double v) { return std::isfinite(v); })) {
      message = who + ": non-finite offset or limit";
      return DriverError::kBadConfig;
    }
    if (!(m.position_min_rad < m.position_max_rad) || !(m.velocity_max_rad_s > 0.0) ||
        !(m.torque_max_Nm > 0.0)) {
      message = who + ": empty position range or non-positive velocity/torque limit";
      return DriverError::kBadConfig;
    }
    // A limit above what the wire carries (ruiwo_codec.h) is no limit: the codec would clamp
    // there anyway, so 1e308 N·m or 1e9 rad/s is a typing error, not a setting.
    if (m.velocity_max_rad_s > kVelocityMax_rad_s || m.torque_max_Nm > kTorqueMax_Nm) {
      char buf[160];
      std::snprintf(buf, sizeof buf, ": velocity limit %g rad/s and torque limit %g N·m must be in (0, %g] rad/s and (0, %g] N·m",
                    m.velocity_max_rad_s, m.torque_max_Nm, kVelocityMax_rad_s, kTorqueMax_Nm);
      message = who + buf;
      return DriverError::kBadConfig;
    }
    // The joint range mapped to the motor must fit the wire's position range.
    const double a = motor_position_rad(m, m.position_min_rad);
    const double b = motor_position_rad(m, m.position_max_rad);
    if (std::min(a, b) < kPositionMin_rad || std::max(a, b) > kPositionMax_rad) {
      message = who + ": joint range with offset exceeds the +-12.5 rad wire range";
      return DriverError::kBadConfig;
    }
    out.motors[i] = m;
    out.index_of_id[m.motor_id] = static_cast<std::int8_t>(i);
  }
  out.count = static_cast<int>(motors.size());
  message.clear();
  return DriverError::kOk;
}

std::vector<MotorConfig> default_motors(const model::Model& model) {
  // Leju negtive_address lists (shared/robot/leju_params/ruiwo_arm_can/*.yaml).
  static constexpr std::uint8_t kNegativeS45[] = {0x0D, 0x04, 0x08, 0x0A, 0x0B, 0x09, 0x05, 0x0C, 0x02};
  static constexpr std::uint8_t kNegativeS42[] = {0x0D, 0x02, 0x04, 0x08, 0x0A, 0x0B, 0x09};
  auto negative = [&](std::uint8_t id) {
    if (model.variant == model::Variant::kS45) {
      return std::find(std::begin(kNegativeS45), std::end(kNegativeS45), id) != std::end(kNegativeS45);
    }
    return std::find(std::begin(kNegativeS42), std::end(kNegativeS42), id) != std::end(kNegativeS42);
  };
  std::vector<MotorConfig> out;
  auto add = [&](std::uint8_t id, int joint) {
    MotorConfig m;
    m.motor_id = id;
    m.joint = joint;
    m.sign = negative(id) ? -1 : 1;
    m.position_min_rad = model.limits.position_min_rad[joint];
    m.position_max_rad = model.limits.position_max_rad[joint];
    m.velocity_max_rad_s = std::min(model.limits.velocity_rad_s[joint], kVelocityMax_rad_s);
    m.torque_max_Nm = std::min(model.limits.peak_torque_Nm[joint], kTorqueMax_Nm);
    out.push_back(m);
  };
  for (int k = 0; k < 6; ++k) add(static_cast<std::uint8_t>(0x01 + k), model::kLeftArmFirst + 1 + k);
  for (int k = 0; k < 6; ++k) add(static_cast<std::uint8_t>(0x07 + k), model::kRightArmFirst + 1 + k);
  add(0x0D, model::kHeadFirst);
  add(0x0E, model::kHeadFirst + 1);
  return out;
}

namespace {

std::uint8_t clamp_to(double& x, double lo, double hi, std::uint8_t flag) {
  if (!std::isfinite(x)) return 0;  // the wire clamp replaces and flags it
  if (x < lo) { x = lo; return flag; }
  if (x > hi) { x = hi; return flag; }
  return 0;
}

}  // namespace

std::uint8_t encode_command_rt(Bus& bus, int index, const hal::JointCommand& cmd, can_frame& out) {
  const MotorConfig& m = bus.motors[index];
  double q = cmd.position_ref_rad, v = cmd.velocity_ref_rad_s, tau = cmd.torque_ff_Nm;
  double kp = cmd.kp_Nm_per_rad, kd = cmd.kd_Nm_s_per_rad;
  switch (cmd.mode) {
    case hal::JointMode::kDisabled:
      q = v = tau = kp = kd = 0.0;
      break;
    case hal::JointMode::kDamping:
      q = v = tau = kp = 0.0;
      break;
    case hal::JointMode::kPdTorque:
      break;
  }
  std::uint8_t flags = 0;
  if (cmd.mode == hal::JointMode::kPdTorque) {
    flags |= clamp_to(q, m.position_min_rad, m.position_max_rad, kClampPosition);
  }
  flags |= clamp_to(v, -m.velocity_max_rad_s, m.velocity_max_rad_s, kClampVelocity);
  flags |= clamp_to(tau, -m.torque_max_Nm, m.torque_max_Nm, kClampTorque);
  PtmCommand c;
  // With kp = 0 the position field is irrelevant; send the offset (joint 0) in range.
  c.position_rad = cmd.mode == hal::JointMode::kPdTorque ? motor_position_rad(m, q) : m.zero_offset_rad;
  c.velocity_rad_s = m.sign * v;
  c.torque_Nm = m.sign * tau;
  c.kp_Nm_per_rad = kp;
  c.kd_Nm_s_per_rad = kd;
  flags |= encode_ptm_rt(m.motor_id, c, out);
  MotorState& s = bus.state[index];
  s.last_clamp_flags = flags;
  if (flags != 0) ++s.clamp_events;
  return flags;
}

void note_sent_rt(Bus& bus, int index, hal::TimeNs now_ns) {
  MotorState& s = bus.state[index];
  if (!s.awaiting_reply) s.sent_ns = now_ns;  // keep the oldest unanswered request
  s.awaiting_reply = true;
}

DriverError handle_reply_rt(Bus& bus, const can_frame& frame, hal::TimeNs stamp_ns,
                            hal::SensorFrame& sensors) {
  Status st;
  const DriverError e = decode_status_rt(frame, st);
  if (e != DriverError::kOk) {
    ++bus.bad_replies;
    return e;
  }
  const int index = bus.index_of_id[st.motor_id];
  if (index < 0) {
    ++bus.unknown_replies;
    return DriverError::kUnknownMotor;
  }
  const MotorConfig& m = bus.motors[index];
  MotorState& s = bus.state[index];
  s.last = st;
  s.reply_ns = stamp_ns;
  s.awaiting_reply = false;
  s.consecutive_misses = 0;
  s.silent = false;
  hal::JointSample& j = sensors.joints[m.joint];
  j.position_rad = joint_position_rad(m, st.position_rad);
  j.velocity_rad_s = m.sign * st.velocity_rad_s;
  j.torque_Nm = m.sign * st.torque_Nm;
  j.stamp_ns = stamp_ns;
  j.valid = true;
  return st.fault_code != 0 ? DriverError::kMotorFault : DriverError::kOk;
}

int check_timeouts_rt(Bus& bus, hal::TimeNs now_ns, hal::SensorFrame& sensors) {
  int silent = 0;
  for (int i = 0; i < bus.count; ++i) {
    MotorState& s = bus.state[i];
    if (s.awaiting_reply && now_ns - s.sent_ns > kReplyTimeout_ns) {
      ++s.consecutive_misses;
      ++s.total_misses;
      s.awaiting_reply = false;
      if (s.consecutive_misses >= kMaxConsecutiveMisses) s.silent = true;
    }
    if (s.silent) {
      sensors.joints[bus.motors[i].joint].valid = false;
      ++silent;
    }
  }
  return silent;
}

}  // namespace kuavo::drivers::ruiwo
