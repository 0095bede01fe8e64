#include "firmware/robot_io.h"

#include "drivers/cycle/canopen_io.h"
#include "drivers/cycle/imu_io.h"
#include "drivers/cycle/ruiwo_io.h"

namespace kuavo::firmware {

namespace d = drivers;

namespace {

constexpr int kLegFirst[2] = {model::kLeftLegFirst, model::kRightLegFirst};

bool is_shoulder(int slot) { return slot == model::kLeftArmFirst || slot == model::kRightArmFirst; }

// The torque offset that makes a CSP drive's law, kp (target − q_s) − kd v_s + offset, equal
// `law_Nm` at the sample m it closes on.
double csp_offset_Nm(const d::canopen::DriveConfig& cfg, double target_rad, const d::canopen::MotorSample& m,
                     double law_Nm) {
  return law_Nm - cfg.csp_kp_Nm_per_rad * (target_rad - m.position_rad) + cfg.csp_kd_Nm_s_per_rad * m.velocity_rad_s;
}

bool ruiwo_cycle(const RobotIo& io, std::uint64_t cycle) {
  return cycle % static_cast<std::uint64_t>(io.ruiwo_divider) == 0;
}

}  // namespace

bool build_robot_io(const d::DriversConfig& config, int ruiwo_divider, RobotIo& io, std::string& message) {
  const std::size_t n = config.plan.buses.size();
  io.ports.assign(n, d::CanPort{});
  io.is_ruiwo.assign(n, false);
  io.ruiwo.assign(n, d::ruiwo::Bus{});
  io.canopen.assign(n, CanopenBusIo{});
  io.legs = config.legs;
  io.ruiwo_divider = ruiwo_divider;
  for (std::size_t b = 0; b < n; ++b) {
    const std::vector<d::ruiwo::MotorConfig> motors = d::ruiwo_motors_on_bus(config, static_cast<int>(b));
    if (!motors.empty()) {
      io.is_ruiwo[b] = true;
      if (d::ruiwo::build_bus(motors, io.ruiwo[b], message) != d::DriverError::kOk) return false;
    }
  }
  for (const d::DriveEntry& e : config.drives) {
    CanopenBusIo& c = io.canopen[static_cast<std::size_t>(e.bus)];
    c.cfg.push_back(e.config);
    c.st.emplace_back();
    c.cmd.emplace_back();
    c.slot.push_back(e.slot);
  }
  return true;
}

void start_devices(RobotIo& io, hal::TimeNs now_ns) {
  for (std::size_t b = 0; b < io.ports.size(); ++b) {
    if (io.is_ruiwo[b]) {
      const d::ruiwo::Bus& bus = io.ruiwo[b];
      for (int i = 0; i < bus.count; ++i) {
        can_frame f{};
        d::ruiwo::encode_special_rt(bus.motors[i].motor_id, d::ruiwo::SpecialCommand::kEnable, f);
        (void)d::send_rt(io.ports[b], f);  // a lost enable shows as a silent motor
      }
      continue;
    }
    CanopenBusIo& c = io.canopen[b];
    for (std::size_t i = 0; i < c.cfg.size(); ++i) {
      can_frame f{};
      d::canopen::start_drive(c.cfg[i], c.st[i], now_ns, f);
      (void)d::send_rt(io.ports[b], f);  // a lost reset shows as kBootTimeout
    }
  }
}

void robot_receive_rt(RobotIo& io, std::uint64_t cycle, hal::TimeNs now_ns, hal::TimeNs rt_to_mono_ns) noexcept {
  io.status = BusStatus{};
  std::array<std::array<d::canopen::MotorSample, d::kLegActuators>, 2> leg_motors{};
  for (std::size_t b = 0; b < io.ports.size(); ++b) {
    d::CanPort& port = io.ports[b];
    if (io.is_ruiwo[b]) {
      if (ruiwo_cycle(io, cycle)) {
        const d::RuiwoReceiveReport r = d::ruiwo_receive_rt(port, io.ruiwo[b], now_ns, rt_to_mono_ns, io.sensors);
        io.status.silent_motors += r.silent;
        io.status.motor_faults += r.faulted;
        io.status.io_failures += r.peer_closed ? 1 : 0;
      }
    } else {
      CanopenBusIo& c = io.canopen[b];
      const d::CanopenReceiveReport r = d::canopen_receive_rt(port, c.cfg, c.st, now_ns, rt_to_mono_ns);
      io.status.io_failures += r.peer_closed ? 1 : 0;
      for (std::size_t i = 0; i < c.cfg.size(); ++i) {
        const d::canopen::DriveState& st = c.st[i];
        if (st.phase == d::canopen::DrivePhase::kFailed) ++io.status.drive_failures;
        if (st.phase == d::canopen::DrivePhase::kOperational && st.stale) ++io.status.silent_motors;
        const d::canopen::MotorSample m = d::canopen::motor_sample(c.cfg[i], st);
        const int slot = c.slot[i];
        if (is_shoulder(slot)) {  // 1:1, no transmission
          hal::JointSample& j = io.sensors.joints[slot];
          if (m.valid) j = hal::JointSample{m.position_rad, m.velocity_rad_s, m.torque_Nm, m.stamp_ns, true};
          else j.valid = false;  // keep the old stamp: the watchdog measures its age
          continue;
        }
        for (int side = 0; side < 2; ++side) {
          const int k = slot - kLegFirst[side];
          if (k >= 0 && k < d::kLegActuators) leg_motors[side][k] = m;
        }
      }
    }
    if (port.health.bus_off) ++io.status.bus_off;
  }
  for (int side = 0; side < 2; ++side) {
    std::array<hal::JointSample, d::kLegActuators> joints{};
    for (int k = 0; k < d::kLegActuators; ++k) joints[k] = io.sensors.joints[kLegFirst[side] + k];
    (void)d::leg_joints_from_motors_rt(io.legs[side], leg_motors[side], joints);  // unsolved: samples invalid
    for (int k = 0; k < d::kLegActuators; ++k) {
      hal::JointSample& out = io.sensors.joints[kLegFirst[side] + k];
      if (joints[k].valid) out = joints[k];
      else out.valid = false;  // keep the last good stamp for the staleness watchdog
    }
  }
  if (io.imu_fd >= 0) {
    const d::ImuReceiveReport r = d::imu_receive_rt(io.imu_fd, io.imu_parser, now_ns, io.sensors.imu);
    io.status.io_failures += r.device_lost ? 1 : 0;
  }
}

void robot_send_rt(RobotIo& io, std::uint64_t cycle, const hal::CommandFrame& command, hal::TimeNs now_ns) noexcept {
  // Leg joint torques -> motor torques (the ankle through its Jacobian).
  std::array<std::array<double, d::kLegActuators>, 2> motor_tau{};
  std::array<bool, 2> leg_ok{};
  // CSP targets: the position references in motor space (PD joints only).
  std::array<std::array<double, d::kLegActuators>, 2> motor_ref{};
  std::array<std::array<bool, d::kLegActuators>, 2> has_ref{};
  for (int side = 0; side < 2; ++side) {
    const d::LegTransmission& t = io.legs[side];
    const int j0 = kLegFirst[side];
    const auto pd = [&](int k) { return command.joints[j0 + k].mode == hal::JointMode::kPdTorque; };
    for (int k = 0; k < 4; ++k) {
      has_ref[side][k] = pd(k);
      if (pd(k)) motor_ref[side][k] = d::motor_position_rad(t.serial[k], command.joints[j0 + k].position_ref_rad);
    }
    d::Vec2 crank = d::Vec2::Zero();
    if (pd(4) && pd(5) &&
        d::ankle_motor_from_joint_rt(t.ankle,
                                     d::Vec2(command.joints[j0 + 4].position_ref_rad, command.joints[j0 + 5].position_ref_rad),
                                     crank)) {
      for (int i = 0; i < 2; ++i) {
        has_ref[side][4 + i] = true;
        motor_ref[side][4 + i] = d::motor_position_rad(t.ankle_motor[i], crank[i]);
      }
    }
  }
  // CSP ankle pair: the feed-forward only (tau_ff, v_ref) in motor space; the feedback is
  // the drives' own (see robot_io.h).
  std::array<std::array<double, 2>, 2> ankle_ff_Nm{}, ankle_vref_rad_s{};
  for (int side = 0; side < 2; ++side) {
    std::array<hal::JointSample, d::kLegActuators> joints{};
    std::array<double, d::kLegActuators> joint_tau{}, ff_tau{}, ff_motor{};
    bool valid = true;
    for (int k = 0; k < d::kLegActuators; ++k) {
      const int j = kLegFirst[side] + k;
      joints[k] = io.sensors.joints[j];
      valid = valid && joints[k].valid;
      joint_tau[k] = d::joint_torque_command_Nm(command.joints[j], joints[k]);
    }
    // Without a valid leg state the PD cannot be evaluated: zero torque.
    leg_ok[side] = valid && d::leg_motor_torques_rt(io.legs[side], joints, joint_tau, motor_tau[side]) ==
                                d::DriverError::kOk;
    const int j0 = kLegFirst[side];
    if (!leg_ok[side] || !has_ref[side][4]) continue;  // ankle not in PD: no feed-forward
    const d::LegTransmission& t = io.legs[side];
    ff_tau[4] = command.joints[j0 + 4].torque_ff_Nm;
    ff_tau[5] = command.joints[j0 + 5].torque_ff_Nm;
    const d::Vec2 q(joints[4].position_rad, joints[5].position_rad);
    d::Vec2 crank;
    if (d::leg_motor_torques_rt(t, joints, ff_tau, ff_motor) != d::DriverError::kOk ||
        !d::ankle_motor_from_joint_rt(t.ankle, q, crank)) {
      continue;  // cannot happen after the solve above; zero feed-forward then
    }
    const d::Vec2 rate = d::ankle_motor_velocity_rt(
        d::ankle_jacobian_rt(t.ankle, q, crank),
        d::Vec2(command.joints[j0 + 4].velocity_ref_rad_s, command.joints[j0 + 5].velocity_ref_rad_s));
    for (int i = 0; i < 2; ++i) {
      ankle_ff_Nm[side][i] = ff_motor[4 + i];
      ankle_vref_rad_s[side][i] = d::motor_velocity_rad_s(t.ankle_motor[i], rate[i]);
    }
  }
  for (std::size_t b = 0; b < io.ports.size(); ++b) {
    d::CanPort& port = io.ports[b];
    if (io.is_ruiwo[b]) {
      if (!ruiwo_cycle(io, cycle)) continue;
      const d::RuiwoSendReport r = d::ruiwo_send_rt(port, io.ruiwo[b], command, now_ns);
      io.status.io_failures += r.failed > 0 && !port.health.bus_off ? 1 : 0;
      continue;
    }
    CanopenBusIo& c = io.canopen[b];
    for (std::size_t i = 0; i < c.cfg.size(); ++i) {
      const int slot = c.slot[i];
      d::canopen::DriveCommand& dc = c.cmd[i];
      dc = d::canopen::DriveCommand{};
      dc.enable = command.joints[slot].mode != hal::JointMode::kDisabled;
      if (is_shoulder(slot)) {
        const hal::JointSample& js = io.sensors.joints[slot];
        const d::canopen::DriveConfig& cfg = c.cfg[i];
        if (cfg.mode != d::canopen::kModeCyclicSyncPosition) {
          dc.torque_Nm = js.valid ? d::joint_torque_command_Nm(command.joints[slot], js) : 0.0;
          continue;
        }
        // CSP (1:1): as the hips and knees, the offset makes the drive's law equal the
        // command's law at the sample; a damping or disabled joint targets the sample.
        const d::canopen::MotorSample m = d::canopen::motor_sample(cfg, c.st[i]);
        dc.position_rad = m.position_rad;  // hold: the last reported position
        if (!js.valid || !m.valid) {
          if (dc.enable) ++c.csp_holds;
          continue;
        }
        if (command.joints[slot].mode == hal::JointMode::kPdTorque) dc.position_rad = command.joints[slot].position_ref_rad;
        dc.torque_Nm = csp_offset_Nm(cfg, dc.position_rad, m, d::joint_torque_command_Nm(command.joints[slot], js));
        continue;
      }
      for (int side = 0; side < 2; ++side) {
        const int k = slot - kLegFirst[side];
        if (k < 0 || k >= d::kLegActuators) continue;
        const d::canopen::DriveConfig& cfg = c.cfg[i];
        if (cfg.mode != d::canopen::kModeCyclicSyncPosition) {
          dc.torque_Nm = leg_ok[side] ? motor_tau[side][k] : 0.0;
          continue;
        }
        const d::canopen::MotorSample m = d::canopen::motor_sample(cfg, c.st[i]);
        dc.position_rad = m.position_rad;  // hold: the last reported position
        if (!leg_ok[side] || !m.valid) {
          if (dc.enable) ++c.csp_holds;
          continue;
        }
        if (has_ref[side][k]) dc.position_rad = motor_ref[side][k];
        if (k >= 4) {  // the ankle pair: the drives' gains are the feedback law
          dc.torque_Nm = ankle_ff_Nm[side][k - 4] + cfg.csp_kd_Nm_s_per_rad * ankle_vref_rad_s[side][k - 4];
          continue;
        }
        dc.torque_Nm = csp_offset_Nm(cfg, dc.position_rad, m, motor_tau[side][k]);
      }
    }
    const d::CanopenSendReport r = d::canopen_send_rt(port, c.cfg, c.st, c.cmd, now_ns);
    io.status.io_failures += r.failed > 0 && !port.health.bus_off ? 1 : 0;
  }
}

}  // namespace kuavo::firmware
