// Fault drills on the firmware-in-the-loop rig (kuavo_fw_sim --inject, tests/firmware/
// fault_dance_test.cpp): one fault of the robot's hardware or of the planning task, armed
// at a chosen moment of the dance. Each goes through a hook that exists below the firmware
// -- the bus emulators' own injection (armed-only, drivers/emulator/fault_injection.h) or
// the rig's (FirmwareLoop::stop_imu, stop_planner) -- so the firmware has to find the fault
// itself, as on the robot. Arming runs in the harness between ticks, never in a task body.
#pragma once

#include <cstdint>
#include <string>

#include "firmware/sitl/firmware_loop.h"

namespace kuavo::firmware::sitl {

enum class FaultDrill : std::uint8_t {
  kSilentLegDrive,  // the left knee's CiA 402 drive stops answering (no TPDO, no heartbeat)
  kSilentArmMotor,  // the left elbow's Ruiwo motor stops answering
  kBusOff,          // the left knee's bus (can1 in the default plan) reports bus-off
  kFrameLoss1Pct,   // from now on 1 % of the reply frames on every bus are lost
  kImuDropout,      // the IMU stream ends (cable, device)
  kStarvedPlanner,  // the planning task gets no CPU: no release runs from now on
};
inline constexpr int kFaultDrillCount = 6;

const char* to_string(FaultDrill d);                  // "silent-leg-drive", ...
bool parse_fault_drill(const char* text, FaultDrill& out);

// The longest dance kuavo_fw_sim loads is 5 min (controllers/planner/motion_plan.h).
inline constexpr double kMaxInjectAt_s = 600.0;

// kuavo_fw_sim --inject KIND@SECONDS: SECONDS of virtual time after the cycle that entered
// dance mode (motion time 0), a finite number in [0, kMaxInjectAt_s].
struct Injection {
  FaultDrill kind = FaultDrill::kBusOff;
  double at_s = 0.0;
};
inline constexpr const char* kInjectValueName =
    "KIND@SECONDS (KIND: silent-leg-drive, silent-arm-motor, bus-off, frame-loss-1pct, imu-dropout, "
    "starved-planner; SECONDS after the dance began, 0..600)";
bool parse_injection(const char* text, Injection& out);  // false: out untouched

// Arms `d` on the rig now. false (message says why) if there is no such device or an
// emulator refused (its injection disarmed). `target` names what was hit.
bool arm_fault_drill(FirmwareLoop& loop, FaultDrill d, std::string& target, std::string& message);

}  // namespace kuavo::firmware::sitl
