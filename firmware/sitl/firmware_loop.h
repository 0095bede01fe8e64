// Firmware in the loop (the simulator binding of kuavo_fw_sim and the firmware tests): the
// firmware's task bodies (firmware/control_task.h) and its drivers binding
// (firmware/robot_io.h) talk over socketpairs to the drivers' bus emulators, which are bound
// to the Simbody plant; all in lockstep virtual time, 2 ms per tick. The plant is held
// (robot on its gantry) until the firmware reaches ready, then integrated. After every
// emulator pass the loop inspects what the emulated motors and drives decoded from the
// wire: every frame they received.
//
// With enable_dance() the firmware's dance mode runs the online stack; the planning task
// is called in the same virtual time: released every planner period (on the firmware
// clock), its plan published a fixed modelled latency later -- the lockstep scheduler's
// rule in sim/ -- so runs are deterministic: same configuration and seed, same bytes.
//
// The firmware's state (Firmware, DanceControl, DancePlanner, DanceChannels) is static, as
// on the robot: one FirmwareLoop at a time per process.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "controllers/planner/motion_plan.h"
#include "controllers/stack/online_stack.h"
#include "drivers/config/drivers_config.h"
#include "drivers/emulator/cia402_emulator.h"
#include "drivers/emulator/plant_binding.h"
#include "drivers/emulator/ruiwo_emulator.h"
#include "firmware/control_task.h"
#include "firmware/emulated_buses.h"
#include "sim/ground_contact.h"
#include "sim/plant.h"
#include "sim/sensor_model.h"

namespace kuavo::firmware::sitl {

inline constexpr hal::TimeNs kTick_ns = 2'000'000;

// The leg drives' CiA 402 mode (firmware/README.md, leg binding).
enum class LegBinding { kCst, kCsp };
bool parse_leg_binding(const char* text, LegBinding& out);  // "cst" | "csp"
const char* to_string(LegBinding b);
// The robot image's default (kuavo_fw --legs csp): kuavo_fw_sim's and the retarget check's.
inline constexpr LegBinding kImageLegBinding = LegBinding::kCsp;

struct LoopConfig {
  FirmwareConfig firmware{};
  LegBinding legs = LegBinding::kCst;
  // The ankle motors' clamp: <= 0 keeps the drivers configuration's (kuavo.json's ankle
  // peak applied per motor, 27 N m).
  double ankle_motor_limit_Nm = 0.0;
  sim::GroundParams ground = sim::kFloor;
  sim::Push push{};
  std::uint64_t seed = 7;  // the IMU model's noise and the emulators' fault injection
  // The drivers configuration (a kuavo_fw --config overlay); nullptr: the defaults.
  const drivers::DriversConfig* drivers = nullptr;
};

// A controller fault for tests and fault drills, off by default: one field of one joint's
// command overwritten from now on (a buggy controller), before the safety filter.
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

// The CSP drives' loop (the legs', and the shoulder pitches' given by add_shoulder), closed
// by the emulated drives on the plant's state at every force evaluation (continuous, as a
// drive's fast loop): the targets, offsets and gains are those the emulator decoded from the
// wire (RPDO1, SDO 0x2010).
class LegDriveLoop : public sim::JointTorqueSource {
 public:
  LegDriveLoop(const std::array<drivers::emulator::LegWiring, 2>& legs,
               const std::vector<std::unique_ptr<drivers::emulator::Cia402Emulator>>& drives)
      : legs_(legs), drives_(drives) {}
  void add_joint_torques(const std::array<double, model::kNumJoints>& q, const std::array<double, model::kNumJoints>& v,
                         std::array<double, model::kNumJoints>& tau) const noexcept override;
  // A shoulder pitch drive in CSP (1:1): drive `index` of the emulator on bus `bus`, its joint.
  void add_shoulder(std::size_t bus, int index, int slot) noexcept {
    if (shoulder_count_ < 2) shoulders_[shoulder_count_++] = ShoulderDrive{bus, index, slot};
  }
  mutable std::uint64_t failures = 0;     // force evaluations at an unsolvable ankle
  mutable std::uint32_t saturations = 0;  // drive-evaluations at the drive's torque limit

 private:
  struct ShoulderDrive {
    std::size_t bus = 0;
    int index = 0;
    int slot = 0;
  };
  std::array<ShoulderDrive, 2> shoulders_{};
  int shoulder_count_ = 0;
  const std::array<drivers::emulator::LegWiring, 2>& legs_;
  const std::vector<std::unique_ptr<drivers::emulator::Cia402Emulator>>& drives_;
};

// Allocations made by the calling thread so far (a counting allocator's), or nullptr: not
// counted. Set by whoever links one (the tests' trap, kuavo_fw_sim).
using AllocationCounter = std::size_t (*)();

class FirmwareLoop {
 public:
  FirmwareLoop(const model::Model& model, const LoopConfig& config = LoopConfig{});
  ~FirmwareLoop();
  FirmwareLoop(const FirmwareLoop&) = delete;
  FirmwareLoop& operator=(const FirmwareLoop&) = delete;

  static Firmware& fw();
  static DanceControl& dance();    // the control task's dance state (~0.4 MB)
  static DancePlanner& planner();  // the MPC workspace (~15 MB)
  static DanceChannels& channels();

  // Loads the motion into the firmware's dance mode (before bring-up): the standing pose
  // becomes the motion's first frame and the robot on the gantry starts there.
  bool enable_dance(const planner::MotionPlan& motion, const stack::StackConfig& config,
                    hal::TimeNs plan_latency_ns = 4'000'000);

  // One 2 ms tick of the whole loop: devices sample the plant, the control task, the
  // planning task (on its period), devices answer, the plant advances (off the gantry).
  void tick(CycleInputs in = {});
  // Ticks until the firmware is in `m` (nominal requests on the way); bounded.
  bool reach(Mode m, int max_ticks = 5000);
  // Brings the robot up to ready on the gantry, releases it, lets it settle.
  bool bring_up(hal::TimeNs settle_ns = 200'000'000);
  // Ticks until the command is damping on every joint; the virtual time from now until
  // then, or -1 within max_ns.
  hal::TimeNs ticks_to_damping(hal::TimeNs max_ns, CycleInputs in = {});

  void set_allocation_counter(AllocationCounter counter) { count_allocations_ = counter; }
  void stop_planner(bool stopped = true) { planner_stopped_ = stopped; }
  // Test-only shortcut, kept for comparison with the CSP binding: the firmware's joint law
  // copied into the plant's drive model, bypassing the wire.
  void set_leg_pd_in_drive(bool on) { leg_pd_in_drive_ = on; }
  // From now on every plan published carries a NaN (in one knot's joint reference); once:
  // only the next one.
  void corrupt_plans(bool every) { corrupt_ = every ? 2 : 1; }
  void stop_imu() { imu_stopped_ = true; }  // the IMU stream ends (cable, device)

  bool ok() const { return ok_; }
  const std::string& error() const { return error_; }
  const model::Model& model() const { return model_; }
  const drivers::DriversConfig& drivers_config() const { return config_; }
  RobotIo& io() { return *io_; }
  const RobotIo& io() const { return *io_; }
  drivers::emulator::RuiwoEmulator* ruiwo(std::size_t b) { return buses_.ruiwo(b); }
  drivers::emulator::Cia402Emulator* drives(std::size_t b) { return buses_.drives(b); }
  const drivers::emulator::RuiwoEmulator* ruiwo(std::size_t b) const { return buses_.ruiwo(b); }
  const drivers::emulator::Cia402Emulator* drives(std::size_t b) const { return buses_.drives(b); }
  drivers::CanPort& device_port(std::size_t b) { return buses_.device_port(b); }
  std::size_t buses() const { return buses_.buses(); }
  InjectingController& controller() { return controller_; }
  const hal::CommandFrame& command() const { return control_.command; }
  const ControlTask& control_task() const { return control_; }
  const WireCheck& wire_check() const { return check_; }
  const sim::Plant& plant() const { return *plant_; }
  hal::TimeNs now_ns() const { return now_; }
  std::uint64_t cycle() const { return cycle_; }
  bool on_gantry() const { return gantry_; }
  void release_gantry() {  // the plant integrates from now on
    gantry_ = false;
    ready_at_ns_ = now_;
  }
  // The gantry takes the robot again where it stands, at rest (the plant holds still from
  // now on): the end of a show, before finish fades the gains out.
  void hang_on_gantry();
  std::size_t allocations_in_cycle() const { return allocations_; }
  std::size_t planner_allocations() const { return planner_allocations_; }
  bool plant_failed() const { return plant_failed_; }
  const char* plant_error() const { return plant_->last_error(); }
  hal::TimeNs ready_at_ns() const { return ready_at_ns_; }
  std::uint64_t binding_failures() const { return binding_failures_ + leg_loop_.failures; }
  bool csp_legs() const { return csp_legs_; }
  std::uint64_t drive_loop_saturations() const { return leg_loop_.saturations; }
  std::uint64_t csp_holds() const;
  // Wall-clock compute times (this machine, not real time, never in a log): the control
  // task's part of each tick in dance and each planner iteration.
  const std::vector<double>& dance_cycle_us() const { return cycle_us_; }
  const std::vector<double>& plan_ms() const { return plan_ms_; }
  double tilt_deg() const;

 private:
  void advance_plant(const drivers::emulator::PlantJoints& pj);
  void bad(const std::string& what);
  void inspect_ruiwo(std::size_t b, std::uint32_t frames);
  void inspect_drives(std::size_t b, std::uint32_t frames);

  const model::Model& model_;
  drivers::DriversConfig config_;
  std::unique_ptr<RobotIo> io_;
  EmulatedBuses buses_;
  std::unique_ptr<LogSink> log_;
  std::unique_ptr<sim::Plant> plant_;
  sim::SensorModel imu_;
  hal::SensorFrame imu_frame_{};
  ControlTask control_{};
  InjectingController controller_{CycleController{nullptr, nullptr}};
  WireCheck check_{};
  hal::TimeNs now_ = 0;
  std::uint64_t cycle_ = 0;
  bool gantry_ = true;
  bool ok_ = false;
  std::string error_;
  bool plant_failed_ = false;
  AllocationCounter count_allocations_ = nullptr;
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
  LegDriveLoop leg_loop_{buses_.legs(), buses_.all_drives()};
  std::size_t planner_allocations_ = 0;
  std::vector<double> cycle_us_, plan_ms_;
};

}  // namespace kuavo::firmware::sitl
