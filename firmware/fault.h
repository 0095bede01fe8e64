// Faults of the firmware: one enum, stable numbers. The numbers appear in logs
// and fault records, so a value is never renumbered or reused; a new fault takes
// a fresh number in its block. Any fault latches and sends the robot to damping
// (mode_machine.h); only an operator clear in damping, with the cause gone,
// releases it.
#pragma once

#include <cstdint>

namespace kuavo::firmware {

enum class Fault : std::uint16_t {
  kNone = 0,

  // Operator (1..9)
  kEstop = 1,  // e-stop input asserted (latched until released and cleared)

  // Watchdogs (10..29)
  kSensorStale = 10,         // a joint sample older than sensor_max_age_ns (hal stamp)
  kImuStale = 11,            // IMU sample older than imu_max_age_ns or never valid
  kMotorSilent = 12,         // drivers report a motor/drive not answering (reply/TPDO timeout)
  kBusOff = 13,              // a CAN controller went bus-off
  kDriveFault = 14,          // a CiA 402 drive failed (fault state, heartbeat lost, ...)
  kMotorFault = 15,          // a Ruiwo status frame carried a fault byte
  kPlanStale = 16,           // MPC result older than plan_max_age_ns
  kEstimatorDiverged = 17,   // the estimator flagged divergence
  kTiltExceeded = 18,        // torso tilt beyond max_tilt_rad (IMU)
  kSelfCheckTimeout = 19,    // self-check did not pass within self_check_timeout_ns
  kBusIo = 20,               // send/receive failed on a bus (I/O error, peer closed)
  kSensorImplausible = 21,   // a joint reading non-finite or beyond its stops (broken sample)

  // Commands refused by the safety filter (30..49)
  kCommandNonFinite = 30,      // NaN/Inf in any field
  kCommandPositionLimit = 31,  // q_ref outside the joint's position limits
  kCommandTorqueLimit = 32,    // |tau_ff| above the joint's peak torque
  kCommandGainRange = 33,      // kp or kd negative or above the configured maximum
  kCommandMode = 34,           // a JointMode value the firmware does not know
};

const char* to_string(Fault f) noexcept;

}  // namespace kuavo::firmware
