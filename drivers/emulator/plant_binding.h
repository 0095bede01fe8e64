// Binds the emulated devices to a rigid-body plant (the simulator): plant
// joint state -> motor state the emulated boards/drives report, and the
// torques the emulated motors produce -> joint torques the plant applies.
// The wiring (signs, offsets, transmissions) is the robot's physical truth;
// the simulator passes the same configuration the firmware loads, so a sign
// error in that configuration shows up as a control failure, not a mismatch.
// Real-time safe.
#pragma once

#include <array>
#include <cstdint>

#include "controllers/model/model_tables.h"
#include "drivers/driver_error.h"
#include "drivers/emulator/cia402_emulator.h"
#include "drivers/emulator/ruiwo_emulator.h"
#include "drivers/ruiwo/ruiwo_bus.h"
#include "drivers/transmission/leg_transmission.h"

namespace kuavo::drivers::emulator {

struct PlantJoints {
  std::array<double, model::kNumJoints> position_rad{};
  std::array<double, model::kNumJoints> velocity_rad_s{};
};

// Ruiwo motors: q_motor = sign q + offset (as the real wiring), v and tau by sign.
void write_ruiwo_motors(const ruiwo::Bus& wiring, const PlantJoints& plant, RuiwoEmulator& emu);
// Adds each emulated motor's torque, in joint space, to joint_torque_Nm.
void add_ruiwo_torques(const ruiwo::Bus& wiring, const RuiwoEmulator& emu,
                       std::array<double, model::kNumJoints>& joint_torque_Nm);

// One leg: slots first_joint .. first_joint + 5 driven by the drives with
// these node IDs (slot order; ankle slots = motors A, B).
struct LegWiring {
  LegTransmission transmission{};
  int first_joint = 0;
  std::array<std::uint8_t, kLegActuators> node_ids{};
};

// A leg may span buses (one emulator each): every call handles the drives of
// the leg that `emu` holds and skips the others. Ankle motors A and B must sit
// on the same emulator (kBadConfig otherwise); kTransmissionUnsolved if the
// plant's ankle pose has no linkage solution.
DriverError write_leg_drives(const LegWiring& leg, const PlantJoints& plant, Cia402Emulator& emu);
// Adds the leg drives' torques, each evaluated at the motor state `plant` gives
// (CST: the target torque; CSP: the drive's PD on that state, so a simulator
// calling this at every force evaluation runs the drive loop continuously).
// `saturations` (optional) counts drives at their torque limit.
DriverError add_leg_torques(const LegWiring& leg, const PlantJoints& plant, const Cia402Emulator& emu,
                            std::array<double, model::kNumJoints>& joint_torque_Nm,
                            std::uint32_t* saturations = nullptr);

}  // namespace kuavo::drivers::emulator
