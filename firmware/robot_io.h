// The drivers binding: every bus of the robot's DriversConfig, read and written
// once per control cycle in the order drivers/README.md prescribes, turning
// replies into a hal::SensorFrame and a hal::CommandFrame into frames. The
// robot passes CAN sockets, the firmware-in-the-loop tests socketpairs to the
// bus emulators; the code is the same.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "controllers/hal/types.h"
#include "drivers/can/can_port.h"
#include "drivers/canopen/cia402_drive.h"
#include "drivers/config/drivers_config.h"
#include "drivers/imu/mti_parser.h"
#include "drivers/ruiwo/ruiwo_bus.h"
#include "drivers/transmission/leg_transmission.h"
#include "firmware/watchdogs.h"

namespace kuavo::firmware {

struct CanopenBusIo {
  std::vector<drivers::canopen::DriveConfig> cfg;
  std::vector<drivers::canopen::DriveState> st;
  std::vector<drivers::canopen::DriveCommand> cmd;
  std::vector<int> slot;  // actuator slot per drive
  // CSP leg drives held at their last reported position (zero torque offset)
  // because their leg's state was invalid: the drive-side PD needs a target.
  std::uint64_t csp_holds = 0;
};

struct RobotIo {
  std::vector<drivers::CanPort> ports;  // one per plan bus
  std::vector<bool> is_ruiwo;           // per bus
  std::vector<drivers::ruiwo::Bus> ruiwo;   // per bus (unused on CANopen buses)
  std::vector<CanopenBusIo> canopen;        // per bus (empty on Ruiwo buses)
  std::array<drivers::LegTransmission, 2> legs{};
  int imu_fd = -1;  // -1: the caller fills sensors.imu (simulation)
  drivers::mti::Parser imu_parser{};
  int ruiwo_divider = 2;  // Ruiwo buses are served every n-th cycle
  hal::SensorFrame sensors{};
  BusStatus status{};    // this cycle's, reset by robot_receive_rt
};

// Start-up: builds the per-bus driver state from a validated configuration
// (ports are attached by the caller: open_buses or socketpairs).
bool build_robot_io(const drivers::DriversConfig& config, int ruiwo_divider, RobotIo& io, std::string& message);

// Start-up: sends the NMT reset that starts every drive's boot sequence and
// the enable frame to every Ruiwo motor (drivers/README.md, start-up 3-4).
void start_devices(RobotIo& io, hal::TimeNs now_ns);

// Receive half of cycle `cycle`: replies -> io.sensors, health -> io.status.
void robot_receive_rt(RobotIo& io, std::uint64_t cycle, hal::TimeNs now_ns,
                      hal::TimeNs realtime_to_monotonic_ns) noexcept;

// Send half: joint commands -> Ruiwo PTM frames and (through the leg
// transmissions) CiA 402 targets, then SYNC. CST leg drives get the joint law's
// torque at last tick's sample. CSP leg drives (drive loop tau = kp_d (target -
// q) - kd_d v + offset, fixed gains) get the position reference through the
// transmission as target (the sampled position for damping joints), and:
// - hip roll/yaw/pitch, knee (1:1 motors): the offset that makes the drive's law
//   equal the firmware's at the sample,
//     offset = tau_law(sample) - kp_d (target - q_sample) + kd_d v_sample,
//   exactly tau_ff + kd v_ref when the commanded gains equal the drive's (the
//   dance); any gain difference (standing, ramps, fades, damping) is applied from
//   the 500 Hz sample, as the CST binding applies all of it;
// - the ankle pair: the motor-space PD of two drives with one gain each cannot
//   realize the joint-space law (k J^T J ~ diag(2.0, 0.41) k), and correcting the
//   difference from the 500 Hz sample is the delayed ankle loop that made CST
//   unstable in swing. So the drives' gains ARE the ankle feedback law and the
//   offset is the feed-forward only: J^-T tau_ff + kd_d J v_ref. Commanded ankle
//   kp/kd (standing 150/3, dance 30/1.5, ramps, damping kd) are not applied.
// An invalid leg state holds each drive at its last reported position with zero
// offset (counted in csp_holds).

void robot_send_rt(RobotIo& io, std::uint64_t cycle, const hal::CommandFrame& command, hal::TimeNs now_ns) noexcept;

}  // namespace kuavo::firmware
