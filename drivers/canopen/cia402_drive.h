// Supervisor of one CiA 402 drive on CANopen: boot (NMT reset communication,
// wait for boot-up), configuration (the SDO sequence of pdo_layout.h, one write
// in flight), NMT start, then cyclic operation (RPDO1 each cycle, TPDOs after
// each SYNC) with the 402 power state machine and heartbeat supervision.
// Works in motor units (rad, rad/s, Nm at the drive output); the transmissions
// map joints to motors.
//
// Per control cycle the firmware calls drivers/cycle/canopen_io.h, which does
// (after start_drive() once per drive):
//   receive: handle_frame_rt(cfg, st, frame, stamp) for every frame and drive
//   (motor_sample(cfg, st) -> transmissions -> controller -> DriveCommand)
//   send:    step_rt(cfg, st, now, cmd, frame) -> send_rt for every drive,
//            then SYNC (latches the RPDOs, triggers the TPDOs read next cycle)
#pragma once

#include <cstdint>
#include <linux/can.h>

#include "controllers/hal/types.h"
#include "drivers/canopen/canopen_frames.h"
#include "drivers/canopen/cia402_state.h"
#include "drivers/canopen/pdo_layout.h"
#include "drivers/driver_error.h"

namespace kuavo::drivers::canopen {

// Timeouts of the start-up phases: generous, they are not in the control budget.
inline constexpr hal::TimeNs kBootTimeout_ns = 2'000'000'000;
inline constexpr hal::TimeNs kSdoTimeout_ns = 100'000'000;   // CiA 301 typical 100 ms
inline constexpr int kSdoRetries = 2;
inline constexpr hal::TimeNs kStartTimeout_ns = 500'000'000;
inline constexpr hal::TimeNs kEnableTimeout_ns = 1'000'000'000;

struct DriveConfig {
  std::uint8_t node_id = 0;  // 1..127
  double counts_per_rev = 131072.0 * 10.0;  // encoder counts per output turn (FACTS.md §5.1)
  double rated_torque_Nm = 1.0;   // 0x6076: torque per 1000 per-mille
  double torque_limit_Nm = 0.0;   // motor side: CST's target torque, CSP's torque at the sample (cia402_drive.cpp)
  std::uint16_t heartbeat_period_ms = 20;  // producer time written to 0x1017
  // Consumer timeout: 3 periods, so one lost heartbeat is tolerated.
  hal::TimeNs heartbeat_timeout_ns = 60'000'000;
  std::uint32_t cycle_period_us = 2000;   // written to 0x1006
  // TPDOs answer every SYNC; 4 missing cycles (8 ms at 500 Hz) make the drive
  // silent, inside the 20 ms budget to reach damping. With 3 (1e-6 at 1 % frame
  // loss, 12 drives at 500 Hz) a whole dance under 1 % loss tripped once in 33 s
  // (kuavo_fw_sim --inject frame-loss-1pct, seed 1); 4 in a row is 1e-8.
  hal::TimeNs tpdo_timeout_ns = 8'000'000;
  // Cyclic mode: kModeCyclicSyncTorque (CST, the master sends the torque) or
  // kModeCyclicSyncPosition (CSP: the drive closes
  //   tau = csp_kp (target - position) - csp_kd velocity + torque offset
  // in its own fast loop; the gains are written once at start-up, motor side).
  std::int8_t mode = kModeCyclicSyncTorque;
  double csp_kp_Nm_per_rad = 0.0;
  double csp_kd_Nm_s_per_rad = 0.0;
};

enum class DrivePhase : std::uint8_t {
  kIdle = 0,         // start_drive not called
  kWaitBoot = 1,
  kConfiguring = 2,
  kStarting = 3,
  kOperational = 4,
  kFailed = 5,       // `error` says why; restart with start_drive. A drive that had
                     // reached operational keeps getting a safe RPDO1 (disable
                     // voltage, zero torque): in CST the last target would persist.
};

struct DriveCommand {
  bool enable = false;      // false: walk to switch-on disabled, zero torque
  double torque_Nm = 0.0;   // motor side: CST target torque; CSP torque offset
  double position_rad = 0.0;  // motor side, sent as 0x607A (the CSP target)
};

struct MotorSample {
  double position_rad = 0.0;
  double velocity_rad_s = 0.0;
  double torque_Nm = 0.0;
  hal::TimeNs stamp_ns = 0;
  bool valid = false;
};

struct DriveState {
  DrivePhase phase = DrivePhase::kIdle;
  DriverError error = DriverError::kOk;  // latched reason for kFailed / last fault
  NmtState nmt = NmtState::kUnknown;
  Cia402State power = Cia402State::kNotReadyToSwitchOn;
  Cia402Control control{};
  ConfigSequence config{};
  int config_step = 0;
  int sdo_attempts = 0;
  bool sdo_pending = false;
  std::uint32_t last_abort_code = 0;
  hal::TimeNs phase_since_ns = 0;
  hal::TimeNs sdo_sent_ns = 0;
  hal::TimeNs heartbeat_ns = 0;
  hal::TimeNs enable_since_ns = -1;  // when enable was first requested, -1 = not requested
  TxPdo1 tpdo1{};
  TxPdo2 tpdo2{};
  hal::TimeNs tpdo1_ns = 0;
  bool have_tpdo1 = false, have_tpdo2 = false;
  bool stale = false;  // no TPDO1 within tpdo_timeout_ns (sample invalid)
  bool was_operational = false;  // PDO mapping is ours: safe RPDO1 allowed after a failure
  Emergency last_emergency{};
  std::uint32_t emergencies = 0;
  std::uint32_t torque_clamps = 0;
  std::uint32_t refused_commands = 0;  // CSP targets refused (kCommandRefused), drive held instead
};

// Begins (or restarts) the boot sequence; fills `out` with the NMT reset.
void start_drive(const DriveConfig& cfg, DriveState& st, hal::TimeNs now_ns, can_frame& out);

// Feeds one received frame. kWrongCanId when the frame is not this node's.
DriverError handle_frame_rt(const DriveConfig& cfg, DriveState& st, const can_frame& f,
                            hal::TimeNs stamp_ns);

// Advances the supervisor; returns true with `out` filled when a frame is owed.
// In kOperational it always emits RPDO1 (disabled drives get zero torque); in
// kFailed after operational, RPDO1 with controlword 0 and zero torque. In CSP
// the target is the drive's last reported position with zero offset whenever
// torque is not on (so enabling never jumps) and when the command is refused.
bool step_rt(const DriveConfig& cfg, DriveState& st, hal::TimeNs now_ns, const DriveCommand& cmd,
             can_frame& out);

MotorSample motor_sample(const DriveConfig& cfg, const DriveState& st);

// Unit conversions (exposed for tests and the emulator).
double counts_to_rad(const DriveConfig& cfg, double counts);
std::int32_t rad_to_counts(const DriveConfig& cfg, double rad);
// Clamps to +-torque_limit_Nm (NaN -> 0) and converts; `clamped` set if changed.
std::int16_t torque_to_permille(const DriveConfig& cfg, double torque_Nm, bool& clamped);
// Checked position for a CSP target: kCommandRefused (counts untouched) if not
// finite or beyond the i32 range; never clamps.
DriverError position_to_counts_rt(const DriveConfig& cfg, double rad, std::int32_t& counts);
// The loop configuration start_drive writes (mode, gain registers); gains that
// gain_to_register refuses give false (validate_drivers_config checks this).
bool drive_loop(const DriveConfig& cfg, DriveLoop& out);

}  // namespace kuavo::drivers::canopen
