#include "firmware/sitl/firmware_loop.h"

#include <Eigen/Core>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/standing/standing_controller.h"
#include "drivers/emulator/fault_injection.h"
#include "rtos_shim/clock.h"

namespace kuavo::firmware::sitl {

namespace d = drivers;
namespace emu = drivers::emulator;

bool parse_leg_binding(const char* text, LegBinding& out) {
  if (!std::strcmp(text, "cst")) return out = LegBinding::kCst, true;
  if (!std::strcmp(text, "csp")) return out = LegBinding::kCsp, true;
  return false;
}
const char* to_string(LegBinding b) { return b == LegBinding::kCsp ? "csp" : "cst"; }

void LegDriveLoop::add_joint_torques(const std::array<double, model::kNumJoints>& q,
                                     const std::array<double, model::kNumJoints>& v,
                                     std::array<double, model::kNumJoints>& tau) const noexcept {
  emu::PlantJoints pj;
  pj.position_rad = q;
  pj.velocity_rad_s = v;
  for (const auto& e : drives_) {
    if (!e) continue;
    for (const auto& leg : legs_) {
      if (emu::add_leg_torques(leg, pj, *e, tau, &saturations) != d::DriverError::kOk) ++failures;
    }
  }
  // The shoulder pitch drives in CSP (1:1): their loop at this state too.
  for (int s = 0; s < shoulder_count_; ++s) {
    const ShoulderDrive& sd = shoulders_[s];
    bool sat = false;
    tau[sd.slot] += emu::drive_torque_at_Nm(drives_[sd.bus]->drives[sd.index], q[sd.slot], v[sd.slot], &sat);
    if (sat) ++saturations;
  }
}

Firmware& FirmwareLoop::fw() {
  static Firmware f;  // the controller workspace: static, as on the robot
  return f;
}
DanceControl& FirmwareLoop::dance() {
  static DanceControl dc;
  return dc;
}
DancePlanner& FirmwareLoop::planner() {
  static DancePlanner p;
  return p;
}
DanceChannels& FirmwareLoop::channels() {
  static DanceChannels c;
  return c;
}

FirmwareLoop::FirmwareLoop(const model::Model& m, const LoopConfig& lc) : model_(m), imu_(lc.seed) {
  config_ = lc.drivers != nullptr ? *lc.drivers : d::default_drivers_config(m);
  d::BusLoadReport report;
  std::string msg;
  ok_ = true;
  if (lc.legs == LegBinding::kCsp) {
    // The drives hold the WBC's output gains, the law the dance commands.
    csp_legs_ = dance_use_csp_drives(config_, msg);
    if (!csp_legs_) ok_ = false, error_ = "CSP legs: " + msg;
  }
  if (lc.ankle_motor_limit_Nm > 0.0) {
    for (d::DriveEntry& e : config_.drives) {
      if (e.slot < 2 * model::kLegJoints && e.slot % model::kLegJoints >= 4) e.config.torque_limit_Nm = lc.ankle_motor_limit_Nm;
    }
  }
  if (ok_ && d::validate_drivers_config(config_, report, msg) != d::DriverError::kOk) ok_ = false, error_ = msg;
  io_ = std::make_unique<RobotIo>();
  if (ok_ && !build_robot_io(config_, lc.firmware.ruiwo_divider, *io_, msg)) ok_ = false, error_ = msg;
  if (ok_ && !buses_.init(config_, *io_, lc.seed, msg)) ok_ = false, error_ = msg;
  // The emulators' drives in the robot I/O's order (as advance_plant reads them).
  for (std::size_t b = 0; ok_ && csp_legs_ && b < buses(); ++b) {
    for (int i = 0; buses_.drives(b) != nullptr && i < buses_.drives(b)->count; ++i) {
      const int slot = io_->canopen[b].slot[static_cast<std::size_t>(i)];
      if (slot == model::kLeftArmFirst || slot == model::kRightArmFirst) leg_loop_.add_shoulder(b, i, slot);
    }
  }
  log_ = std::make_unique<LogSink>();
  firmware_init(fw(), m, lc.firmware, log_.get());
  control_ = ControlTask{};
  control_.firmware = &fw();
  control_.io = io_.get();
  controller_.inner.fw = &fw();
  controller_.inner.dance = nullptr;
  sim::PlantConfig pc;
  pc.integrator = sim::Integrator::kCvodeBdf;  // error-controlled reference integrator
  pc.ground = lc.ground;
  plant_ = std::make_unique<sim::Plant>(m, pc);
  dynamics::ConfigVector q0 = dynamics::neutral_configuration(m);
  q0.tail<model::kNumJoints>() = fw().standing.pose_rad;
  control::place_on_ground(m, fw().standing.data, q0);
  plant_->reset(q0, dynamics::VelocityVector::Zero());
  plant_->set_push(lc.push);
  if (ok_) start_devices(*io_, now_);
  cycle_us_.reserve(1 << 16);  // before the counted ticks; pushes happen outside them
  plan_ms_.reserve(1 << 12);
}

FirmwareLoop::~FirmwareLoop() = default;

bool FirmwareLoop::enable_dance(const planner::MotionPlan& motion, const stack::StackConfig& config,
                                hal::TimeNs plan_latency_ns) {
  const char* why = nullptr;
  if (!dance_init(dance(), planner(), channels(), model_, config, fw().config, motion, why)) {
    error_ = why;
    return false;
  }
  dance_set_ankle_motors(dance(), config_);
  dance_set_serial_leg_drives(dance(), config_);
  dance_standing_pose(fw(), motion);
  controller_.inner.dance = &dance();
  control_.dance = &dance();
  plan_latency_ns_ = plan_latency_ns;
  dynamics::ConfigVector q0 = motion.q[0];
  control::place_on_ground(model_, fw().standing.data, q0);
  plant_->reset(q0, dynamics::VelocityVector::Zero());
  return true;
}

void FirmwareLoop::tick(CycleInputs in) {
  const sim::PlantTruth& truth = plant_->truth();
  emu::PlantJoints pj;
  for (int j = 0; j < model::kNumJoints; ++j) {
    pj.position_rad[j] = truth.q[7 + j];
    pj.velocity_rad_s[j] = truth.v[6 + j];
  }
  // Devices sample the plant; drives answer last tick's SYNC. A fallen robot's ankle may
  // leave the linkage's reach: counted, the drives then report their last position (the
  // firmware is in damping by then).
  binding_failures_ += buses_.drives_answer_rt(pj, now_);
  for (std::size_t b = 0; b < buses(); ++b) {
    if (buses_.drives(b) != nullptr) inspect_drives(b, buses_.frames_received(b));
  }
  imu_.sample(truth, now_, imu_frame_);
  // The planning task's result lands its latency after the state it used.
  if (publish_at_ns_ >= 0 && now_ >= publish_at_ns_) {
    if (corrupt_ > 0) {
      PlanMessage& msg = channels().plan.back_rt();
      msg.plan.knots[msg.plan.count / 2].joint_position_rad[3] = std::numeric_limits<double>::quiet_NaN();
      if (corrupt_ == 1) corrupt_ = 0;
    }
    channels().plan.publish_rt();
    publish_at_ns_ = -1;
  }
  // The control task -- the real-time part: allocations counted, Eigen's heap use trapped.
  const rtos::TimeNs wall0_ns = rtos::now_ns();
  {
    const std::size_t before = count_allocations_ != nullptr ? count_allocations_() : 0;
    const bool eigen_allowed = Eigen::internal::is_malloc_allowed();
    Eigen::internal::set_is_malloc_allowed(false);
    control_task_step_rt(control_, cycle_, now_, in, imu_stopped_ ? nullptr : &imu_frame_.imu, controller_);
    Eigen::internal::set_is_malloc_allowed(eigen_allowed);
    if (count_allocations_ != nullptr) allocations_ += count_allocations_() - before;
  }
  const rtos::TimeNs wall1_ns = rtos::now_ns();
  if (fw().mode.mode == Mode::kDance) cycle_us_.push_back(1e-3 * static_cast<double>(wall1_ns - wall0_ns));
  // The planning task, released on its period with the latest request.
  if (control_.dance != nullptr && !planner_stopped_ && now_ % fw().config.planner_period_ns == 0) {
    const std::size_t before = count_allocations_ != nullptr ? count_allocations_() : 0;
    const bool eigen_allowed = Eigen::internal::is_malloc_allowed();
    Eigen::internal::set_is_malloc_allowed(false);
    const bool planned = planning_task_step_rt(planner(), channels());
    Eigen::internal::set_is_malloc_allowed(eigen_allowed);
    if (count_allocations_ != nullptr) planner_allocations_ += count_allocations_() - before;
    if (planned) {
      publish_at_ns_ = now_ + plan_latency_ns_;
      plan_ms_.push_back(1e-6 * static_cast<double>(rtos::now_ns() - wall1_ns));
    }
  }
  // Ruiwo boards answer this tick's commands (read next Ruiwo cycle).
  buses_.ruiwo_answer_rt();
  for (std::size_t b = 0; b < buses(); ++b) {
    if (buses_.ruiwo(b) != nullptr) inspect_ruiwo(b, buses_.frames_received(b));
  }
  // Motor torques -> plant.
  if (!gantry_) advance_plant(pj);
  now_ += kTick_ns;
  ++cycle_;
}

bool FirmwareLoop::reach(Mode m, int max_ticks) {
  for (int i = 0; i < max_ticks && fw().mode.mode != m; ++i) {
    CycleInputs in;
    const Mode cur = fw().mode.mode;
    if (cur == Mode::kDamping) in.request = Request::kStandUp;
    if (cur == Mode::kReady && m != Mode::kReady) in.request = m == Mode::kFinish ? Request::kFinish : Request::kDance;
    tick(in);
  }
  return fw().mode.mode == m;
}

bool FirmwareLoop::bring_up(hal::TimeNs settle_ns) {
  if (!reach(Mode::kReady)) return false;
  release_gantry();
  for (hal::TimeNs t = 0; t < settle_ns; t += kTick_ns) tick();
  return fw().mode.mode == Mode::kReady;
}

hal::TimeNs FirmwareLoop::ticks_to_damping(hal::TimeNs max_ns, CycleInputs in) {
  const hal::TimeNs start = now_;
  for (hal::TimeNs t = 0; t <= max_ns; t += kTick_ns) {
    tick(in);
    bool damping = true;
    for (const hal::JointCommand& j : control_.command.joints) damping = damping && j.mode == hal::JointMode::kDamping;
    if (damping) return now_ - kTick_ns - start;
  }
  return -1;
}

void FirmwareLoop::hang_on_gantry() {
  gantry_ = true;
  const dynamics::ConfigVector q = plant_->truth().q;
  plant_->reset(q, dynamics::VelocityVector::Zero(), plant_->time_s());
}

double FirmwareLoop::tilt_deg() const {
  const auto& q = plant_->truth().q;
  hal::ImuSample s;
  s.orientation_xyzw = {q[3], q[4], q[5], q[6]};
  return tilt_rad(s) * 180.0 / M_PI;
}

std::uint64_t FirmwareLoop::csp_holds() const {
  std::uint64_t n = 0;
  for (const auto& c : io_->canopen) n += c.csp_holds;
  return n;
}

void FirmwareLoop::advance_plant(const emu::PlantJoints& pj) {
  std::array<double, model::kNumJoints> tau{};
  hal::CommandFrame applied;  // what the motors do, in joint space
  for (std::size_t b = 0; b < buses(); ++b) {
    if (buses_.ruiwo(b) != nullptr) {
      // A Ruiwo board closes its MIT law at its own (kHz) rate: hand the law
      // the board decoded from the wire to the plant's continuous drive model
      // rather than a torque sampled every 2 ms (which would chatter on the
      // light wrist links).
      const d::ruiwo::Bus& wiring = io_->ruiwo[b];
      for (int i = 0; i < buses_.ruiwo(b)->count; ++i) {
        const emu::EmulatedRuiwoMotor& mo = buses_.ruiwo(b)->motors[i];
        const d::ruiwo::MotorConfig& mc = wiring.motors[i];
        hal::JointCommand& c = applied.joints[mc.joint];
        if (!mo.enabled) continue;  // disabled: no torque
        c.mode = hal::JointMode::kPdTorque;
        c.position_ref_rad = d::ruiwo::joint_position_rad(mc, mo.command.position_rad);
        c.velocity_ref_rad_s = mc.sign * mo.command.velocity_rad_s;
        c.torque_ff_Nm = mc.sign * mo.command.torque_Nm;
        c.kp_Nm_per_rad = mo.command.kp_Nm_per_rad;
        c.kd_Nm_s_per_rad = mo.command.kd_Nm_s_per_rad;
      }
      continue;
    }
    // CSP legs: the plant runs the drives' loop itself (leg_loop_), nothing held here.
    if (!csp_legs_) {
      for (const auto& leg : buses_.legs()) binding_failures_ += emu::add_leg_torques(leg, pj, *buses_.drives(b), tau) != d::DriverError::kOk;
    }
    for (int i = 0; i < buses_.drives(b)->count; ++i) {
      const int slot = io_->canopen[b].slot[i];
      // CSP shoulders: the plant runs their loop (leg_loop_); CST: the torque held for the tick.
      if (!csp_legs_ && (slot == model::kLeftArmFirst || slot == model::kRightArmFirst)) {
        tau[slot] += emu::drive_torque_Nm(buses_.drives(b)->drives[i]);
      }
    }
  }
  // CiA 402 drives in CST: the torque the firmware computed, held for the tick.
  for (std::size_t b = 0; b < buses(); ++b) {
    if (buses_.drives(b) == nullptr) continue;
    for (int i = 0; i < buses_.drives(b)->count; ++i) {
      // The ankle pair's slots are the two ankle joints, which the linkage couples.
      const int j = io_->canopen[b].slot[i];
      applied.joints[j] = hal::JointCommand{};  // kDisabled: CSP drives' torques come from leg_loop_
      if (csp_legs_) continue;
      applied.joints[j].mode = hal::JointMode::kPdTorque;
      applied.joints[j].torque_ff_Nm = tau[j];
    }
  }
  if (leg_pd_in_drive_) {
    // The leg drives as impedance drives: the firmware's joint PD law, run continuously by
    // the drive (as the sim's drive model does), instead of the CST torque the firmware
    // evaluated from last tick's sample. Bypasses the wire: the CSP binding is the real one.
    for (int j = 0; j < 2 * model::kLegJoints; ++j) applied.joints[j] = control_.command.joints[j];
  }
  plant_->set_command(applied);
  plant_->set_torque_source(csp_legs_ ? &leg_loop_ : nullptr);
  if (plant_->advance(1e-9 * static_cast<double>(kTick_ns)) != sim::PlantError::kOk) plant_failed_ = true;
}

void FirmwareLoop::bad(const std::string& what) {
  ++check_.bad_values;
  if (check_.first_bad.empty()) check_.first_bad = what + " at t=" + std::to_string(now_);
}

void FirmwareLoop::inspect_ruiwo(std::size_t b, std::uint32_t frames) {
  check_.frames_inspected += frames;
  const model::Model& m = model_;
  const d::ruiwo::Bus& bus = io_->ruiwo[b];
  // One wire quantum of each field (ruiwo_codec.h ranges and bit widths).
  const double q_quantum = 25.0 / 65535.0, tau_quantum = 100.0 / 4095.0, gain_quantum = 250.0 / 4095.0;
  for (int i = 0; i < buses_.ruiwo(b)->count; ++i) {
    const d::ruiwo::PtmCommand& c = buses_.ruiwo(b)->motors[i].command;
    const d::ruiwo::MotorConfig& mc = bus.motors[i];
    const int j = mc.joint;
    if (!std::isfinite(c.position_rad) || !std::isfinite(c.torque_Nm) || !std::isfinite(c.kp_Nm_per_rad) ||
        !std::isfinite(c.kd_Nm_s_per_rad) || !std::isfinite(c.velocity_rad_s)) {
      bad("non-finite Ruiwo field, joint " + std::to_string(j));
    }
    const double q = d::ruiwo::joint_position_rad(mc, c.position_rad);
    if (c.kp_Nm_per_rad > 0.0 && (q < m.limits.position_min_rad[j] - q_quantum || q > m.limits.position_max_rad[j] + q_quantum)) {
      bad("Ruiwo position outside limits, joint " + std::to_string(j));
    }
    if (std::abs(c.torque_Nm) > m.limits.peak_torque_Nm[j] + tau_quantum) bad("Ruiwo torque above peak, joint " + std::to_string(j));
    if (c.kp_Nm_per_rad > fw().config.kp_max_Nm_per_rad + gain_quantum || c.kp_Nm_per_rad < 0.0 ||
        c.kd_Nm_s_per_rad > fw().config.kd_max_Nm_s_per_rad + gain_quantum || c.kd_Nm_s_per_rad < 0.0) {
      bad("Ruiwo gain out of range, joint " + std::to_string(j));
    }
    if (bus.state[i].last_clamp_flags & d::ruiwo::kNonFinite) ++check_.nonfinite_clamps;
  }
}

void FirmwareLoop::inspect_drives(std::size_t b, std::uint32_t frames) {
  check_.frames_inspected += frames;
  const emu::Cia402Emulator& e = *buses_.drives(b);
  for (int i = 0; i < e.count; ++i) {
    const emu::EmulatedDrive& dr = e.drives[i];
    const d::canopen::DriveConfig& c = dr.config;
    const double tau = dr.target_torque_permille * c.rated_torque_Nm / 1000.0;
    if (dr.mode == d::canopen::kModeCyclicSyncPosition) {
      // CSP: the field is the offset, and the drive clips kp (target − q) − kd q̇ + offset.
      // The firmware wrote it against one of the drive's last two reports: the drive's torque
      // at that sample must be within the limit (plus the field's and the target's quanta).
      const double kp = d::canopen::register_to_gain(dr.kp_register), kd = d::canopen::register_to_gain(dr.kd_register);
      const double target = d::canopen::counts_to_rad(c, dr.target_position_counts);
      const double quanta = c.rated_torque_Nm / 1000.0 + kp * 2.0 * std::numbers::pi / c.counts_per_rev;
      double at_sample = std::numeric_limits<double>::infinity();
      for (int k = 0; k < 2; ++k) {
        at_sample = std::min(at_sample, std::abs(tau + kp * (target - dr.reported_position_rad[k]) -
                                                 kd * dr.reported_velocity_rad_s[k]));
      }
      if (at_sample > c.torque_limit_Nm + quanta) bad("CSP drive torque at the sample above limit, node " + std::to_string(c.node_id));
      continue;
    }
    if (std::abs(tau) > c.torque_limit_Nm + c.rated_torque_Nm / 1000.0) bad("drive torque above limit, node " + std::to_string(c.node_id));
  }
}

}  // namespace kuavo::firmware::sitl
