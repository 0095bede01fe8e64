#include "drivers/emulator/plant_binding.h"

namespace kuavo::drivers::emulator {

void write_ruiwo_motors(const ruiwo::Bus& wiring, const PlantJoints& plant, RuiwoEmulator& emu) {
  for (int i = 0; i < wiring.count; ++i) {
    const ruiwo::MotorConfig& m = wiring.motors[i];
    const int e = emu.index_of_id[m.motor_id];
    if (e < 0) continue;
    emu.motors[e].position_rad = ruiwo::motor_position_rad(m, plant.position_rad[m.joint]) + emu.motors[e].zero_rad;
    emu.motors[e].velocity_rad_s = m.sign * plant.velocity_rad_s[m.joint];
  }
}

void add_ruiwo_torques(const ruiwo::Bus& wiring, const RuiwoEmulator& emu,
                       std::array<double, model::kNumJoints>& joint_torque_Nm) {
  for (int i = 0; i < wiring.count; ++i) {
    const ruiwo::MotorConfig& m = wiring.motors[i];
    const int e = emu.index_of_id[m.motor_id];
    if (e >= 0) joint_torque_Nm[m.joint] += m.sign * motor_torque_Nm(emu.motors[e]);
  }
}

namespace {

EmulatedDrive* find_drive(Cia402Emulator& emu, std::uint8_t node) {
  for (int i = 0; i < emu.count; ++i)
    if (emu.drives[i].config.node_id == node) return &emu.drives[i];
  return nullptr;
}

}  // namespace

DriverError write_leg_drives(const LegWiring& leg, const PlantJoints& plant, Cia402Emulator& emu) {
  std::array<EmulatedDrive*, kLegActuators> d{};
  for (int k = 0; k < kLegActuators; ++k) d[k] = find_drive(emu, leg.node_ids[k]);
  if ((d[4] == nullptr) != (d[5] == nullptr)) return DriverError::kBadConfig;
  const LegTransmission& t = leg.transmission;
  const int j0 = leg.first_joint;
  for (int k = 0; k < 4; ++k) {
    if (d[k] == nullptr) continue;
    d[k]->position_rad = motor_position_rad(t.serial[k], plant.position_rad[j0 + k]);
    d[k]->velocity_rad_s = motor_velocity_rad_s(t.serial[k], plant.velocity_rad_s[j0 + k]);
  }
  if (d[4] == nullptr) return DriverError::kOk;
  const Vec2 q(plant.position_rad[j0 + 4], plant.position_rad[j0 + 5]);
  Vec2 crank;
  if (!ankle_motor_from_joint_rt(t.ankle, q, crank)) return DriverError::kTransmissionUnsolved;
  const Vec2 rate = ankle_motor_velocity_rt(ankle_jacobian_rt(t.ankle, q, crank),
                                            Vec2(plant.velocity_rad_s[j0 + 4], plant.velocity_rad_s[j0 + 5]));
  for (int k = 0; k < 2; ++k) {
    d[4 + k]->position_rad = motor_position_rad(t.ankle_motor[k], crank[k]);
    d[4 + k]->velocity_rad_s = motor_velocity_rad_s(t.ankle_motor[k], rate[k]);
  }
  return DriverError::kOk;
}

DriverError add_leg_torques(const LegWiring& leg, const PlantJoints& plant, const Cia402Emulator& emu,
                            std::array<double, model::kNumJoints>& joint_torque_Nm, std::uint32_t* saturations) {
  std::array<const EmulatedDrive*, kLegActuators> d{};
  for (int k = 0; k < kLegActuators; ++k) {
    for (int i = 0; i < emu.count; ++i) {
      if (emu.drives[i].config.node_id == leg.node_ids[k]) d[k] = &emu.drives[i];
    }
  }
  if ((d[4] == nullptr) != (d[5] == nullptr)) return DriverError::kBadConfig;
  const LegTransmission& t = leg.transmission;
  const int j0 = leg.first_joint;
  // Each drive's torque at the motor state this plant state gives (the drive's
  // own encoder, not the last TPDO): CST ignores it, CSP closes its loop on it.
  auto torque = [&](const EmulatedDrive& drive, double pos, double vel) {
    bool sat = false;
    const double tau = drive_torque_at_Nm(drive, pos, vel, &sat);
    if (sat && saturations != nullptr) ++*saturations;
    return tau;
  };
  for (int k = 0; k < 4; ++k) {
    if (d[k] == nullptr) continue;
    const double tau = torque(*d[k], motor_position_rad(t.serial[k], plant.position_rad[j0 + k]),
                              motor_velocity_rad_s(t.serial[k], plant.velocity_rad_s[j0 + k]));
    joint_torque_Nm[j0 + k] += drivers::joint_torque_Nm(t.serial[k], tau);
  }
  if (d[4] == nullptr) return DriverError::kOk;
  const Vec2 q(plant.position_rad[j0 + 4], plant.position_rad[j0 + 5]);
  Vec2 crank;
  if (!ankle_motor_from_joint_rt(t.ankle, q, crank)) return DriverError::kTransmissionUnsolved;
  const Mat2 J = ankle_jacobian_rt(t.ankle, q, crank);
  const Vec2 rate = ankle_motor_velocity_rt(J, Vec2(plant.velocity_rad_s[j0 + 4], plant.velocity_rad_s[j0 + 5]));
  Vec2 crank_tau;
  for (int k = 0; k < 2; ++k) {
    const LinearTransmission& m = t.ankle_motor[k];
    crank_tau[k] = drivers::joint_torque_Nm(
        m, torque(*d[4 + k], motor_position_rad(m, crank[k]), motor_velocity_rad_s(m, rate[k])));
  }
  const Vec2 tau = ankle_joint_torque_rt(J, crank_tau);
  joint_torque_Nm[j0 + 4] += tau[0];
  joint_torque_Nm[j0 + 5] += tau[1];
  return DriverError::kOk;
}

}  // namespace kuavo::drivers::emulator
