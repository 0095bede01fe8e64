#include "drivers/config/drivers_config.h"

#include <algorithm>
#include <cmath>

#include "drivers/config/drive_defaults.h"
#include "drivers/imu/serial_port.h"

namespace kuavo::drivers {

DriversConfig default_drivers_config(const model::Model& model) {
  DriversConfig c;
  c.plan = default_bus_plan();
  c.ruiwo_motors = ruiwo::default_motors(model);
  c.legs = {default_leg_transmission(true), default_leg_transmission(false)};
  sync_drives_with_plan(c);
  return c;
}

void sync_drives_with_plan(DriversConfig& config) {
  std::vector<DriveEntry> old = std::move(config.drives);
  config.drives.clear();
  for (const DeviceConfig& d : config.plan.devices) {
    if (d.kind != DeviceKind::kCia402Drive || d.bus < 0 ||
        d.bus >= static_cast<int>(config.plan.buses.size())) {
      continue;
    }
    const BusConfig& bus = config.plan.buses[d.bus];
    DriveEntry e;
    e.slot = d.slot;
    e.bus = d.bus;
    e.config = default_drive_config(d.slot, d.id, bus.cycle_rate_hz, bus.heartbeat_rate_hz);
    for (const DriveEntry& o : old) {
      if (o.slot != d.slot) continue;
      // Keep the motor parameters; IDs and timing always follow the plan.
      e.config.counts_per_rev = o.config.counts_per_rev;
      e.config.rated_torque_Nm = o.config.rated_torque_Nm;
      e.config.torque_limit_Nm = o.config.torque_limit_Nm;
      e.config.mode = o.config.mode;
      e.config.csp_kp_Nm_per_rad = o.config.csp_kp_Nm_per_rad;
      e.config.csp_kd_Nm_s_per_rad = o.config.csp_kd_Nm_s_per_rad;
    }
    config.drives.push_back(e);
  }
}

namespace {


// Physical ranges of configuration numbers (values outside are typing errors or corruption):
// - a transmission ratio (motor rad per joint rad): the robot's gearboxes and linkages lie
//   between 1:1 and ~1:100 in magnitude; 0.01..1000 leaves two decades of margin each way;
constexpr double kMinRatioMagnitude = 0.01, kMaxRatioMagnitude = 1000.0;
// - a motor offset (motor position at joint zero) more than one joint turn of motor travel
//   (2π·|ratio| rad) away from the motor's zero is not an offset;
// - encoder counts per output turn: 1024 (10 bits) is the coarsest encoder a servo drive
//   takes; above 2^31 one turn overflows the i32 position object 0x607A;
constexpr double kMinCountsPerRev = 1024.0, kMaxCountsPerRev = 2147483648.0;
// - drive torques: 1000 N·m is 7× the model's largest peak joint torque (knee, 135 N·m).
constexpr double kMaxDriveTorque_Nm = 1000.0;

bool ratio_in_range(double r) {
  return std::isfinite(r) && std::abs(r) >= kMinRatioMagnitude && std::abs(r) <= kMaxRatioMagnitude;
}
bool offset_in_range(double offset_rad, double ratio) {
  return std::isfinite(offset_rad) && std::abs(offset_rad) <= 2.0 * M_PI * std::abs(ratio);
}

DriverError check_transmissions(const DriversConfig& c, std::string& message) {
  for (int side = 0; side < 2; ++side) {
    const LegTransmission& t = c.legs[side];
    const char* name = side == 0 ? "left leg" : "right leg";
    for (const LinearTransmission& s : t.serial) {
      if (!ratio_in_range(s.ratio_motor_per_joint) || !offset_in_range(s.motor_offset_rad, s.ratio_motor_per_joint)) {
        message = std::string(name) + ": transmission ratio must be 0.01..1000 in magnitude and the offset within "
                                      "one joint turn (2π·|ratio| rad)";
        return DriverError::kBadConfig;
      }
    }
    for (const LinearTransmission& s : t.ankle_motor) {
      if (!ratio_in_range(s.ratio_motor_per_joint) || !offset_in_range(s.motor_offset_rad, s.ratio_motor_per_joint)) {
        message = std::string(name) + ": ankle motor ratio must be 0.01..1000 in magnitude and the offset within "
                                      "one joint turn (2π·|ratio| rad)";
        return DriverError::kBadConfig;
      }
    }
    Vec2 m;
    if (!ankle_motor_from_joint_rt(t.ankle, Vec2::Zero(), m) || m.cwiseAbs().maxCoeff() > 1e-9) {
      message = std::string(name) + ": ankle linkage does not assemble at the zero pose";
      return DriverError::kBadConfig;
    }
  }
  return DriverError::kOk;
}

}  // namespace

DriverError validate_drivers_config(const DriversConfig& c, BusLoadReport& report, std::string& message) {
  if (const DriverError e = check_bus_plan(c.plan, report, message); e != DriverError::kOk) return e;
  for (std::size_t b = 0; b < c.plan.buses.size(); ++b) {
    ruiwo::Bus bus;
    const std::vector<ruiwo::MotorConfig> motors = ruiwo_motors_on_bus(c, static_cast<int>(b));
    if (const DriverError e = ruiwo::build_bus(motors, bus, message); e != DriverError::kOk) {
      message = c.plan.buses[b].interface + ": " + message;
      return e;
    }
  }
  for (const DeviceConfig& d : c.plan.devices) {
    const std::string where = c.plan.buses[d.bus].interface + " ID " + std::to_string(d.id);
    if (d.kind == DeviceKind::kRuiwoMotor) {
      int found = 0;
      for (const ruiwo::MotorConfig& m : c.ruiwo_motors) {
        if (m.motor_id != d.id) continue;
        ++found;
        if (m.joint != d.slot) {
          message = where + ": Ruiwo motor configured for joint " + std::to_string(m.joint) +
                    " but the bus plan puts it on slot " + std::to_string(d.slot);
          return DriverError::kBadConfig;
        }
      }
      if (found != 1) {
        message = where + ": " + std::to_string(found) + " Ruiwo motor configurations (need exactly 1)";
        return found == 0 ? DriverError::kBadConfig : DriverError::kDuplicateId;
      }
    } else {
      const DriveEntry* e = nullptr;
      for (const DriveEntry& x : c.drives)
        if (x.slot == d.slot) e = &x;
      if (e == nullptr || e->config.node_id != d.id || e->bus != d.bus) {
        message = where + ": drive entry missing or out of date (call sync_drives_with_plan)";
        return DriverError::kBadConfig;
      }
      const canopen::DriveConfig& k = e->config;
      if (!(k.counts_per_rev >= kMinCountsPerRev && k.counts_per_rev <= kMaxCountsPerRev) ||
          !(k.rated_torque_Nm > 0 && k.rated_torque_Nm <= kMaxDriveTorque_Nm) ||
          !(k.torque_limit_Nm > 0 && k.torque_limit_Nm <= kMaxDriveTorque_Nm) ||
          k.torque_limit_Nm / k.rated_torque_Nm * 1000.0 > 32767.0) {
        message = where + ": counts per turn must be 1024..2^31, torques in (0, 1000] N·m, and the torque "
                          "limit within the int16 per-mille range";
        return DriverError::kBadConfig;
      }
      canopen::DriveLoop loop;
      if (!canopen::drive_loop(k, loop)) {
        message = where + ": mode must be CST (10) or CSP (8), CSP gains finite, >= 0 and <= 4000";
        return DriverError::kBadConfig;
      }
    }
  }
  if (c.ruiwo_motors.size() != static_cast<std::size_t>(std::count_if(
                                   c.plan.devices.begin(), c.plan.devices.end(),
                                   [](const DeviceConfig& d) { return d.kind == DeviceKind::kRuiwoMotor; }))) {
    message = "Ruiwo motor configurations without a device in the bus plan";
    return DriverError::kBadConfig;
  }
  if (const DriverError e = check_transmissions(c, message); e != DriverError::kOk) return e;
  // A device path is an absolute path without NUL (the kernel would open only up to the NUL).
  if (c.imu_device.empty() || c.imu_device[0] != '/' || c.imu_device.find('\0') != std::string::npos) {
    message = "IMU device path must be an absolute path without NUL bytes";
    return DriverError::kBadConfig;
  }
  if (!serial_baud_supported(c.imu_baud)) {
    message = "IMU baud rate " + std::to_string(c.imu_baud) +
              " is not one the serial port sets (115200, 230400, 460800, 921600, 1000000, 2000000, 4000000 baud)";
    return DriverError::kBadConfig;
  }
  message.clear();
  return DriverError::kOk;
}

bool use_csp_leg_drives(DriversConfig& config, const std::array<double, kLegActuators>& joint_kp,
                        const std::array<double, kLegActuators>& joint_kd, std::string& message) {
  for (int side = 0; side < 2; ++side) {
    const LegTransmission& t = config.legs[side];
    const int first = side == 0 ? model::kLeftLegFirst : model::kRightLegFirst;
    // Ankle: crank-space gain k with k * trace(J^T J) = kp_pitch + kp_roll at the zero pose.
    Vec2 crank;
    if (!ankle_motor_from_joint_rt(t.ankle, Vec2::Zero(), crank)) {
      message = "ankle linkage has no solution at the zero pose";
      return false;
    }
    const Mat2 J = ankle_jacobian_rt(t.ankle, Vec2::Zero(), crank);
    const double tr = (J.transpose() * J).trace();
    for (DriveEntry& e : config.drives) {
      const int k = e.slot - first;
      if (k < 0 || k >= kLegActuators) continue;
      double kp = 0.0, kd = 0.0, r = 1.0;
      if (k < 4) {
        r = t.serial[k].ratio_motor_per_joint;
        kp = joint_kp[k];
        kd = joint_kd[k];
      } else {
        r = t.ankle_motor[k - 4].ratio_motor_per_joint;
        kp = (joint_kp[4] + joint_kp[5]) / tr;
        kd = (joint_kd[4] + joint_kd[5]) / tr;
      }
      e.config.mode = canopen::kModeCyclicSyncPosition;
      e.config.csp_kp_Nm_per_rad = kp / (r * r);  // motor side: tau_j = r tau_m, q_m = r q_j
      e.config.csp_kd_Nm_s_per_rad = kd / (r * r);
      canopen::DriveLoop loop;
      if (!canopen::drive_loop(e.config, loop)) {
        message = "CSP gains of slot " + std::to_string(e.slot) + " not representable";
        return false;
      }
    }
  }
  return true;
}

bool use_csp_shoulder_drives(DriversConfig& config, double joint_kp, double joint_kd, std::string& message) {
  for (DriveEntry& e : config.drives) {
    if (e.slot != model::kLeftArmFirst && e.slot != model::kRightArmFirst) continue;
    e.config.mode = canopen::kModeCyclicSyncPosition;
    e.config.csp_kp_Nm_per_rad = joint_kp;  // 1:1: the drive reports the joint
    e.config.csp_kd_Nm_s_per_rad = joint_kd;
    canopen::DriveLoop loop;
    if (!canopen::drive_loop(e.config, loop)) {
      message = "CSP gains of slot " + std::to_string(e.slot) + " not representable";
      return false;
    }
  }
  return true;
}

std::vector<ruiwo::MotorConfig> ruiwo_motors_on_bus(const DriversConfig& config, int bus) {
  std::vector<ruiwo::MotorConfig> out;
  for (const DeviceConfig& d : config.plan.devices) {
    if (d.bus != bus || d.kind != DeviceKind::kRuiwoMotor) continue;
    for (const ruiwo::MotorConfig& m : config.ruiwo_motors)
      if (m.motor_id == d.id) out.push_back(m);
  }
  return out;
}

}  // namespace kuavo::drivers
