// The Ruiwo motors of one CAN bus: per-motor configuration (ID, joint, sign,
// zero offset, joint-side limits), joint<->motor mapping, reply matching and
// reply-timeout tracking. Request/response protocol: every command frame is
// answered by exactly one status frame whose byte 0 is the motor ID.
//
// Per control cycle the firmware calls drivers/cycle/ruiwo_io.h, which does:
//   receive: handle_reply_rt for every frame, then check_timeouts_rt
//   send:    encode_command_rt -> send_rt -> note_sent_rt for every motor
#pragma once

#include <array>
#include <cstdint>
#include <linux/can.h>
#include <string>
#include <vector>

#include "controllers/hal/types.h"
#include "controllers/model/model.h"
#include "drivers/driver_error.h"
#include "drivers/ruiwo/ruiwo_codec.h"

namespace kuavo::drivers::ruiwo {

inline constexpr int kMaxMotorsPerBus = 16;  // IDs 0x01..0x10 incl. the claws (FACTS.md §5.2)

// A reply normally arrives within ~0.3 ms; with 14 motors sent back to back the
// last reply is ~2 ms late (14 x 2 frames x 135 bit at 1 Mbit/s). 3 ms keeps
// the check inside the 4 ms (250 Hz) cycle.
inline constexpr hal::TimeNs kReplyTimeout_ns = 3'000'000;
// 4 consecutive misses (16 ms at 250 Hz) make a motor silent: inside the 20 ms
// budget to reach damping. An exchange is lost with its request or its reply, ~2 %
// at 1 % random frame loss: 3 in a row (8e-6) over 16 motors at 250 Hz tripped about
// once a minute, i.e. several times in a 4-minute show; 4 in a row (1.6e-7), once in
// ~26 minutes.
inline constexpr std::uint32_t kMaxConsecutiveMisses = 4;

struct MotorConfig {
  std::uint8_t motor_id = 0;  // CAN arbitration ID, 0x01..0x7F
  int joint = -1;             // controller joint index (model order)
  int sign = 1;               // +1 or -1 (Leju "negtive_address")
  double zero_offset_rad = 0.0;  // motor position at joint zero, motor side
  // Joint-side limits; commands are clamped to these before the wire clamp.
  double position_min_rad = 0.0, position_max_rad = 0.0;
  double velocity_max_rad_s = kVelocityMax_rad_s;
  double torque_max_Nm = kTorqueMax_Nm;
};

struct MotorState {
  Status last{};
  hal::TimeNs sent_ns = 0;
  hal::TimeNs reply_ns = 0;
  bool awaiting_reply = false;
  bool silent = false;                 // consecutive misses reached the limit
  std::uint32_t consecutive_misses = 0;
  std::uint32_t total_misses = 0;
  std::uint32_t clamp_events = 0;      // commands that needed any clamp
  std::uint8_t last_clamp_flags = 0;
};

struct Bus {
  std::array<MotorConfig, kMaxMotorsPerBus> motors{};
  std::array<MotorState, kMaxMotorsPerBus> state{};
  int count = 0;
  std::array<std::int8_t, 256> index_of_id{};  // -1 for IDs not on this bus
  std::uint32_t unknown_replies = 0;
  std::uint32_t bad_replies = 0;
};

// Validates and installs the configuration (start-up). Refuses duplicate IDs,
// IDs outside 1..0x7F, signs other than +-1, bad joints, non-finite values,
// empty or inverted limits.
DriverError build_bus(const std::vector<MotorConfig>& motors, Bus& out, std::string& message);

// Factory layout for the 4Pro: L-arm joints 2-7 = 0x01-0x06, R-arm = 0x07-0x0C,
// head yaw 0x0D, head pitch 0x0E; signs from Leju's config (s45 uses
// long_arm_config.yaml, s42 config.yaml); zero offsets 0; limits from the model.
std::vector<MotorConfig> default_motors(const model::Model& model);

// Joint command -> PTM frame for motor `index`. Joint-side clamps (limits)
// then the wire clamps; returns the union of ClampFlag bits and records them.
//   kDisabled: zero gains and torque (no torque, the motor still replies)
//   kDamping:  tau = -kd v (kp = 0, v_ref = 0, tau_ff = 0)
//   kPdTorque: full PTM
std::uint8_t encode_command_rt(Bus& bus, int index, const hal::JointCommand& cmd, can_frame& out);

void note_sent_rt(Bus& bus, int index, hal::TimeNs now_ns);

// Matches a status frame to its motor and fills the joint sample (joint side).
// kUnknownMotor for IDs not on this bus; decode errors as decode_status_rt.
DriverError handle_reply_rt(Bus& bus, const can_frame& frame, hal::TimeNs stamp_ns,
                            hal::SensorFrame& sensors);

// Counts the motors whose awaited reply is older than kReplyTimeout_ns; marks
// samples invalid and motors silent after kMaxConsecutiveMisses. Returns the
// number of silent motors.
int check_timeouts_rt(Bus& bus, hal::TimeNs now_ns, hal::SensorFrame& sensors);

// Motor<->joint maps (exposed for tests and the emulator).
inline double motor_position_rad(const MotorConfig& m, double joint_rad) {
  return m.sign * joint_rad + m.zero_offset_rad;
}
inline double joint_position_rad(const MotorConfig& m, double motor_rad) {
  return m.sign * (motor_rad - m.zero_offset_rad);
}

}  // namespace kuavo::drivers::ruiwo
