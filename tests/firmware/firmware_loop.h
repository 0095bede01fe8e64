// Firmware-in-the-loop rig: the firmware cycle and its drivers binding
// (firmware/robot_io.h) talk over socketpairs to the drivers' bus emulators,
// which are bound to the Simbody plant; all in lockstep virtual time, 2 ms per
// tick. The plant is held (robot on its gantry) until the firmware reaches
// ready, then integrated. After every emulator pass the rig inspects what the
// emulated motors and drives decoded from the wire: every frame they received.
//
// With enable_dance() the firmware's dance mode runs the online stack; the planning
// task is called in the same virtual time: released every planner period (on the
// firmware clock), its plan published a fixed modelled latency later -- the lockstep
// scheduler's rule in sim/ -- so runs are deterministic.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <sys/socket.h>
#include <unistd.h>
#include <vector>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/wbc/wbc_config.h"
#include "drivers/emulator/bus_fault.h"
#include "drivers/emulator/plant_binding.h"
#include "firmware/control_cycle.h"
#include "firmware/dance.h"
#include "firmware/robot_io.h"
#include "rtos_shim/clock.h"
#include "sim/plant.h"
#include "sim/sensor_model.h"
#include "tests/firmware/firmware_test_support.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::firmware::test_support {

namespace d = drivers;
namespace emu = drivers::emulator;

inline constexpr hal::TimeNs kTick_ns = 2'000'000;
inline constexpr hal::TimeNs kDampingBudget_ns = 20'000'000;  // issue 7

struct Wire {
  int fd[2]{-1, -1};
  d::CanPort host, device;
  Wire() {
    EXPECT_EQ(socketpair(AF_UNIX, SOCK_SEQPACKET, 0, fd), 0);
    const int buf = 1 << 20;  // a whole cycle's frames in flight
    for (int f : fd) setsockopt(f, SOL_SOCKET, SO_SNDBUF, &buf, sizeof(buf));
    host = d::attach_can_port(fd[0], false);
    device = d::attach_can_port(fd[1], false);
  }
  ~Wire() {
    close(fd[0]);
    close(fd[1]);
  }
};

// The controller the firmware runs (standing, or the dance once enabled), with an
// optional corruption of one field of one joint from a given time on (a buggy controller).
struct InjectingController {
  CycleController inner;
  int joint = -1;
  double hal::JointCommand::*field = nullptr;
  double value = 0.0;
  void operator()(const hal::SensorFrame& s, hal::CommandFrame& out) const noexcept {
    inner(s, out);
    if (joint >= 0) out.joints[joint].*field = value;
  }
};

struct WireCheck {
  std::uint64_t frames_inspected = 0;  // frames the emulators received and decoded
  std::uint64_t bad_values = 0;        // out-of-limit or non-finite values seen on the wire
  std::uint64_t nonfinite_clamps = 0;  // commands the drivers had to repair (NaN/Inf)
  std::string first_bad;
};

// The leg drives' CSP loop, closed by the emulated drives on the plant's state at every
// force evaluation (continuous, as a drive's fast loop): the targets, offsets and gains are
// those the emulator decoded from the wire (RPDO1, SDO 0x2010).
class LegDriveLoop : public sim::JointTorqueSource {
 public:
  LegDriveLoop(const std::array<emu::LegWiring, 2>& legs, const std::vector<std::unique_ptr<emu::Cia402Emulator>>& drives)
      : legs_(legs), drives_(drives) {}
  void add_joint_torques(const std::array<double, model::kNumJoints>& q, const std::array<double, model::kNumJoints>& v,
                         std::array<double, model::kNumJoints>& tau) const noexcept override {
    emu::PlantJoints pj;
    pj.position_rad = q;
    pj.velocity_rad_s = v;
    for (const auto& e : drives_) {
      if (!e) continue;
      for (const auto& leg : legs_) {
        if (emu::add_leg_torques(leg, pj, *e, tau, &saturations) != d::DriverError::kOk) ++failures;
      }
    }
  }
  mutable std::uint64_t failures = 0;  // force evaluations at an unsolvable ankle
  mutable std::uint32_t saturations = 0;  // drive-evaluations at the drive's torque limit

 private:
  const std::array<emu::LegWiring, 2>& legs_;
  const std::vector<std::unique_ptr<emu::Cia402Emulator>>& drives_;
};

enum class LegBinding { kCst, kCsp };
inline constexpr double kAnkleMotorMax_Nm = 18.0 * 2.1;  // CK: max current x torque constant

class FirmwareLoop {
 public:
  explicit FirmwareLoop(const FirmwareConfig& fw_config = FirmwareConfig{}, LegBinding legs = LegBinding::kCst) {
    const model::Model& m = test_model();
    config_ = d::default_drivers_config(m);
    d::BusLoadReport report;
    std::string msg;
    if (legs == LegBinding::kCsp) {
      // The drives hold the WBC's output gains, the law the dance commands.
      const wbc::WbcConfig w;
      csp_legs_ = d::use_csp_leg_drives(config_, w.leg_kp, w.leg_kd, msg);
      EXPECT_TRUE(csp_legs_) << msg;
      // The ankle motors clamp at the CK motor's electrical maximum (18 A x 2.1 N m/A,
      // FACTS.md §5.1) instead of the default 27 N m (kuavo.json's ankle peak, applied per
      // motor): through the linkage roll = 0.46 (tau_A - tau_B), so two 27 N m motors give
      // less roll torque than the model's 27 N m per ankle joint the WBC plans with, and the
      // side steps fail (4.2 s) on that clamp. firmware/README.md, known limits.
      for (d::DriveEntry& e : config_.drives) {
        if (e.slot < 2 * model::kLegJoints && e.slot % model::kLegJoints >= 4) e.config.torque_limit_Nm = kAnkleMotorMax_Nm;
      }
    }
    ok_ = d::validate_drivers_config(config_, report, msg) == d::DriverError::kOk;
    EXPECT_TRUE(ok_) << msg;
    io_ = std::make_unique<RobotIo>();
    ok_ = ok_ && build_robot_io(config_, fw_config.ruiwo_divider, *io_, msg);
    EXPECT_TRUE(ok_) << msg;
    const std::size_t n = io_->ports.size();
    ruiwo_.resize(n);
    drives_.resize(n);
    for (std::size_t b = 0; b < n; ++b) {
      wires_.push_back(std::make_unique<Wire>());
      io_->ports[b] = wires_[b]->host;
      if (io_->is_ruiwo[b]) {
        ruiwo_[b] = std::make_unique<emu::RuiwoEmulator>();
        std::uint8_t ids[d::ruiwo::kMaxMotorsPerBus];
        for (int i = 0; i < io_->ruiwo[b].count; ++i) ids[i] = io_->ruiwo[b].motors[i].motor_id;
        emu::init_ruiwo_emulator(*ruiwo_[b], ids, io_->ruiwo[b].count);
        emu::arm_fault_injection(ruiwo_[b]->faults, static_cast<std::uint32_t>(100 + b));
      } else {
        drives_[b] = std::make_unique<emu::Cia402Emulator>();
        for (const auto& c : io_->canopen[b].cfg) emu::add_drive(*drives_[b], c);
        emu::arm_fault_injection(drives_[b]->faults, static_cast<std::uint32_t>(200 + b));
      }
    }
    for (int side = 0; side < 2; ++side) {
      legs_[side].transmission = config_.legs[side];
      legs_[side].first_joint = side == 0 ? model::kLeftLegFirst : model::kRightLegFirst;
      for (const d::DriveEntry& e : config_.drives) {
        const int k = e.slot - legs_[side].first_joint;
        if (k >= 0 && k < d::kLegActuators) legs_[side].node_ids[k] = e.config.node_id;
      }
    }
    log_ = std::make_unique<LogSink>();
    firmware_init(fw(), m, fw_config, log_.get());
    controller_.inner.fw = &fw();
    controller_.inner.dance = nullptr;
    sim::PlantConfig pc;
    pc.integrator = sim::Integrator::kCvodeBdf;  // error-controlled reference integrator
    plant_ = std::make_unique<sim::Plant>(m, pc);
    dynamics::ConfigVector q0 = dynamics::neutral_configuration(m);
    q0.tail<model::kNumJoints>() = fw().standing.pose_rad;
    control::place_on_ground(m, fw().standing.data, q0);
    plant_->reset(q0, dynamics::VelocityVector::Zero());
    start_devices(*io_, now_);
    cycle_us_.reserve(1 << 16);  // before the trapped ticks; pushes happen outside the trap
    plan_ms_.reserve(1 << 12);
  }

  static Firmware& fw() {
    static Firmware f;  // the controller workspace: static, as on the robot
    return f;
  }
  // The dance's state, static as on the robot (the planner's MPC workspace is ~15 MB).
  static DanceControl& dance() {
    static DanceControl d;
    return d;
  }
  static DancePlanner& planner() {
    static DancePlanner p;
    return p;
  }
  static DanceChannels& channels() {
    static DanceChannels c;
    return c;
  }

  // Loads the motion into the firmware's dance mode (before bring-up): the standing pose
  // becomes the motion's first frame and the robot on the gantry starts there.
  bool enable_dance(const planner::MotionPlan& motion, const stack::StackConfig& config,
                    hal::TimeNs plan_latency_ns = 4'000'000) {
    const model::Model& m = test_model();
    const char* error = nullptr;
    if (!dance_init(dance(), planner(), channels(), m, config, fw().config, motion, error)) {
      ADD_FAILURE() << error;
      return false;
    }
    dance_standing_pose(fw(), motion);
    controller_.inner.dance = &dance();
    plan_latency_ns_ = plan_latency_ns;
    dynamics::ConfigVector q0 = motion.q[0];
    control::place_on_ground(m, fw().standing.data, q0);
    plant_->reset(q0, dynamics::VelocityVector::Zero());
    return true;
  }
  void stop_planner(bool stopped = true) { planner_stopped_ = stopped; }
  // Test-only shortcut, kept for comparison with the CSP binding (LegBinding::kCsp): the
  // firmware's joint law copied into the plant's drive model, bypassing the wire.
  void set_leg_pd_in_drive(bool on) { leg_pd_in_drive_ = on; }
  // From now on every plan published carries a NaN (in one knot's joint reference); once:
  // only the next one.
  void corrupt_plans(bool every) { corrupt_ = every ? 2 : 1; }
  std::size_t planner_allocations() const { return planner_allocations_; }
  // Wall-clock compute times (this machine, not real time): the firmware's part of each
  // tick in dance (receive, cycle with the stack's tick, send) and each planner iteration.
  const std::vector<double>& dance_cycle_us() const { return cycle_us_; }
  const std::vector<double>& plan_ms() const { return plan_ms_; }
  RobotIo& io() { return *io_; }
  emu::RuiwoEmulator* ruiwo(std::size_t b) { return ruiwo_[b].get(); }
  emu::Cia402Emulator* drives(std::size_t b) { return drives_[b].get(); }
  Wire& wire(std::size_t b) { return *wires_[b]; }
  std::size_t buses() const { return wires_.size(); }
  InjectingController& controller() { return controller_; }
  const hal::CommandFrame& command() const { return out_; }
  const WireCheck& wire_check() const { return check_; }
  const sim::Plant& plant() const { return *plant_; }
  hal::TimeNs now_ns() const { return now_; }
  std::uint64_t cycle() const { return cycle_; }
  bool ok() const { return ok_; }
  std::size_t allocations_in_cycle() const { return allocations_; }
  bool plant_failed() const { return plant_failed_; }
  void stop_imu() { imu_stopped_ = true; }  // the IMU stream ends (cable, device)
  hal::TimeNs ready_at_ns() const { return ready_at_ns_; }
  std::uint64_t binding_failures() const { return binding_failures_ + leg_loop_.failures; }
  bool csp_legs() const { return csp_legs_; }
  std::uint64_t drive_loop_saturations() const { return leg_loop_.saturations; }
  std::uint64_t csp_holds() const {
    std::uint64_t n = 0;
    for (const auto& c : io_->canopen) n += c.csp_holds;
    return n;
  }

  // One 2 ms tick of the whole loop.
  void tick(CycleInputs in = {}) {
    const sim::PlantTruth& truth = plant_->truth();
    emu::PlantJoints pj;
    for (int j = 0; j < model::kNumJoints; ++j) {
      pj.position_rad[j] = truth.q[7 + j];
      pj.velocity_rad_s[j] = truth.v[6 + j];
    }
    // Devices sample the plant; drives answer last tick's SYNC.
    for (std::size_t b = 0; b < buses(); ++b) {
      if (ruiwo_[b]) {
        emu::write_ruiwo_motors(io_->ruiwo[b], pj, *ruiwo_[b]);
        continue;
      }
      emu::Cia402Emulator& e = *drives_[b];
      // A fallen robot's ankle may leave the linkage's reach: counted, the
      // drives then report their last position (the firmware is in damping by then).
      for (const auto& leg : legs_) binding_failures_ += emu::write_leg_drives(leg, pj, e) != d::DriverError::kOk;
      for (int i = 0; i < e.count; ++i) {
        const int slot = io_->canopen[b].slot[i];
        if (slot == model::kLeftArmFirst || slot == model::kRightArmFirst) {
          e.drives[i].position_rad = pj.position_rad[slot];
          e.drives[i].velocity_rad_s = pj.velocity_rad_s[slot];
        }
      }
      const std::uint32_t before = e.frames_in;
      emu::serve_rt(e, wires_[b]->device, now_);
      inspect_drives(b, e.frames_in - before);
    }
    // The firmware: receive, cycle, send -- the real-time part, counted by the trap.
    imu_.sample(truth, now_, imu_frame_);
    // The planning task's result lands its latency after the state it used.
    if (publish_at_ns_ >= 0 && now_ >= publish_at_ns_) {
      if (corrupt_ > 0) {
        PlanMessage& m = channels().plan.back_rt();
        m.plan.knots[m.plan.count / 2].joint_position_rad[3] = std::numeric_limits<double>::quiet_NaN();
        if (corrupt_ == 1) corrupt_ = 0;
      }
      channels().plan.publish_rt();
      publish_at_ns_ = -1;
    }
    const rtos::TimeNs wall0_ns = rtos::now_ns();
    {
      kuavo::test::AllocTrap trap;
      robot_receive_rt(*io_, cycle_, now_, 0);
      if (!imu_stopped_) io_->sensors.imu = imu_frame_.imu;  // no MTi emulator: the sensor model's IMU
      in.watch.bus = io_->status;
      if (controller_.inner.dance != nullptr) dance_before_cycle_rt(dance(), fw(), now_, in);
      firmware_cycle_rt(fw(), io_->sensors, in, now_, controller_, out_);
      robot_send_rt(*io_, cycle_, out_, now_);
      allocations_ += trap.count();
    }

    const rtos::TimeNs wall1_ns = rtos::now_ns();
    if (FirmwareLoop::fw().mode.mode == Mode::kDance) cycle_us_.push_back(1e-3 * static_cast<double>(wall1_ns - wall0_ns));
    // The planning task, released on its period with the latest request.
    if (controller_.inner.dance != nullptr && !planner_stopped_ && now_ % fw().config.planner_period_ns == 0) {
      bool planned = false;
      {
        kuavo::test::AllocTrap trap;
        planned = dance_plan_rt(planner(), channels());
        planner_allocations_ += trap.count();
      }
      if (planned) {
        publish_at_ns_ = now_ + plan_latency_ns_;
        plan_ms_.push_back(1e-6 * static_cast<double>(rtos::now_ns() - wall1_ns));
      }
    }
    // Ruiwo boards answer this tick's commands (read next Ruiwo cycle).
    for (std::size_t b = 0; b < buses(); ++b) {
      if (!ruiwo_[b]) continue;
      const std::uint32_t before = ruiwo_[b]->frames_in;
      emu::serve_rt(*ruiwo_[b], wires_[b]->device);
      inspect_ruiwo(b, ruiwo_[b]->frames_in - before);
    }
    // Motor torques -> plant.
    if (!gantry_) advance_plant(pj);
    now_ += kTick_ns;
    ++cycle_;
  }

  // Ticks until the firmware is in `m` (nominal requests on the way); bounded.
  bool reach(Mode m, int max_ticks = 5000) {
    for (int i = 0; i < max_ticks && fw().mode.mode != m; ++i) {
      CycleInputs in;
      const Mode cur = fw().mode.mode;
      if (cur == Mode::kDamping) in.request = Request::kStandUp;
      if (cur == Mode::kReady && m != Mode::kReady) in.request = m == Mode::kFinish ? Request::kFinish : Request::kDance;
      tick(in);
    }
    return fw().mode.mode == m;
  }

  // Brings the robot up to ready on the gantry, releases it, lets it settle.
  bool bring_up(hal::TimeNs settle_ns = 200'000'000) {
    if (!reach(Mode::kReady)) return false;
    ready_at_ns_ = now_;
    gantry_ = false;
    for (hal::TimeNs t = 0; t < settle_ns; t += kTick_ns) tick();
    return fw().mode.mode == Mode::kReady;
  }

  // Ticks until the command is damping on every joint; returns the virtual
  // time from now until then, or -1 within max_ns.
  hal::TimeNs ticks_to_damping(hal::TimeNs max_ns, CycleInputs in = {}) {
    const hal::TimeNs start = now_;
    for (hal::TimeNs t = 0; t <= max_ns; t += kTick_ns) {
      tick(in);
      if (all_damping(out_)) return now_ - kTick_ns - start;
    }
    return -1;
  }

  double tilt_deg() const {
    const auto& q = plant_->truth().q;
    hal::ImuSample s;
    s.orientation_xyzw = {q[3], q[4], q[5], q[6]};
    return tilt_rad(s) * 180.0 / M_PI;
  }

 private:
  void advance_plant(const emu::PlantJoints& pj) {
    std::array<double, model::kNumJoints> tau{};
    hal::CommandFrame applied;  // what the motors do, in joint space
    for (std::size_t b = 0; b < buses(); ++b) {
      if (ruiwo_[b]) {
        // A Ruiwo board closes its MIT law at its own (kHz) rate: hand the law
        // the board decoded from the wire to the plant's continuous drive model
        // rather than a torque sampled every 2 ms (which would chatter on the
        // light wrist links).
        const d::ruiwo::Bus& wiring = io_->ruiwo[b];
        for (int i = 0; i < ruiwo_[b]->count; ++i) {
          const emu::EmulatedRuiwoMotor& mo = ruiwo_[b]->motors[i];
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
        for (const auto& leg : legs_) binding_failures_ += emu::add_leg_torques(leg, pj, *drives_[b], tau) != d::DriverError::kOk;
      }
      for (int i = 0; i < drives_[b]->count; ++i) {
        const int slot = io_->canopen[b].slot[i];
        if (slot == model::kLeftArmFirst || slot == model::kRightArmFirst) tau[slot] += emu::drive_torque_Nm(drives_[b]->drives[i]);
      }
    }
    // CiA 402 drives in CST: the torque the firmware computed, held for the tick.
    for (std::size_t b = 0; b < buses(); ++b) {
      if (!drives_[b]) continue;
      for (int i = 0; i < drives_[b]->count; ++i) {
        for (int j : drive_joints(b, i)) {
          applied.joints[j] = hal::JointCommand{};  // kDisabled: CSP leg torques come from leg_loop_
          if (csp_legs_ && j < 2 * model::kLegJoints) continue;
          applied.joints[j].mode = hal::JointMode::kPdTorque;
          applied.joints[j].torque_ff_Nm = tau[j];
        }
      }
    }
    if (leg_pd_in_drive_) {
      // The leg drives as impedance drives: the firmware's joint PD law, run continuously by
      // the drive (as the sim's drive model does), instead of the CST torque the firmware
      // evaluated from last tick's sample. Bypasses the wire: the CSP binding is the real one.
      for (int j = 0; j < 2 * model::kLegJoints; ++j) applied.joints[j] = out_.joints[j];
    }
    plant_->set_command(applied);
    plant_->set_torque_source(csp_legs_ ? &leg_loop_ : nullptr);
    if (plant_->advance(1e-9 * static_cast<double>(kTick_ns)) != sim::PlantError::kOk) plant_failed_ = true;
  }

  // The joints a drive's torque acts on: its slot (the ankle pair's slots are
  // the two ankle joints, which the linkage couples).
  std::array<int, 1> drive_joints(std::size_t b, int i) const { return {io_->canopen[b].slot[i]}; }

  void bad(const std::string& what) {
    ++check_.bad_values;
    if (check_.first_bad.empty()) check_.first_bad = what + " at t=" + std::to_string(now_);
  }

  void inspect_ruiwo(std::size_t b, std::uint32_t frames) {
    check_.frames_inspected += frames;
    const model::Model& m = test_model();
    const d::ruiwo::Bus& bus = io_->ruiwo[b];
    // One wire quantum of each field (ruiwo_codec.h ranges and bit widths).
    const double q_quantum = 25.0 / 65535.0, tau_quantum = 100.0 / 4095.0, gain_quantum = 250.0 / 4095.0;
    for (int i = 0; i < ruiwo_[b]->count; ++i) {
      const d::ruiwo::PtmCommand& c = ruiwo_[b]->motors[i].command;
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

  void inspect_drives(std::size_t b, std::uint32_t frames) {
    check_.frames_inspected += frames;
    const emu::Cia402Emulator& e = *drives_[b];
    for (int i = 0; i < e.count; ++i) {
      const d::canopen::DriveConfig& c = e.drives[i].config;
      const double tau = e.drives[i].target_torque_permille * c.rated_torque_Nm / 1000.0;
      if (std::abs(tau) > c.torque_limit_Nm + c.rated_torque_Nm / 1000.0) {
        bad("drive torque above limit, node " + std::to_string(c.node_id));
      }
    }
  }

  d::DriversConfig config_;
  std::unique_ptr<RobotIo> io_;
  std::vector<std::unique_ptr<Wire>> wires_;
  std::vector<std::unique_ptr<emu::RuiwoEmulator>> ruiwo_;
  std::vector<std::unique_ptr<emu::Cia402Emulator>> drives_;
  std::array<emu::LegWiring, 2> legs_{};
  std::unique_ptr<LogSink> log_;
  std::unique_ptr<sim::Plant> plant_;
  sim::SensorModel imu_{7};
  hal::SensorFrame imu_frame_{};
  InjectingController controller_{CycleController{nullptr, nullptr}};
  hal::CommandFrame out_{};
  WireCheck check_{};
  hal::TimeNs now_ = 0;
  std::uint64_t cycle_ = 0;
  bool gantry_ = true;
  bool ok_ = false;
  bool plant_failed_ = false;
  std::size_t allocations_ = 0;
  hal::TimeNs ready_at_ns_ = -1;
  std::uint64_t binding_failures_ = 0;
  bool imu_stopped_ = false;
  hal::TimeNs plan_latency_ns_ = 4'000'000;
  hal::TimeNs publish_at_ns_ = -1;
  bool planner_stopped_ = false;
  int corrupt_ = 0;
  bool leg_pd_in_drive_ = false;
  bool csp_legs_ = false;
  LegDriveLoop leg_loop_{legs_, drives_};
  std::size_t planner_allocations_ = 0;
  std::vector<double> cycle_us_, plan_ms_;
};

}  // namespace kuavo::firmware::test_support
