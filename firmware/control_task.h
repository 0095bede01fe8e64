// The firmware's two task bodies, the same in the robot image (kuavo_fw, on rtos_shim's
// PeriodicTask), in the firmware-in-the-loop binary (kuavo_fw_sim, in lockstep virtual
// time) and in the firmware tests. Only the binding differs: CAN sockets and the MTi on the
// robot, socketpairs to the bus emulators and the simulator's IMU model on the desk.
//
// Control task, per 2 ms cycle: drivers receive -> dance hand-over -> firmware cycle
// (watchdogs, modes, controller, ramp, safety filter) -> drivers send.
// Planning task, per 20 ms: the latest estimate -> one MPC iteration -> the plan (the caller
// publishes it: at once on the robot, after a modelled latency in lockstep).
#pragma once

#include <cstdint>

#include "controllers/hal/types.h"
#include "firmware/control_cycle.h"
#include "firmware/dance.h"
#include "firmware/robot_io.h"

namespace kuavo::firmware {

// Damping is sent this long after an e-stop or the end of a dance before the image exits.
inline constexpr hal::TimeNs kExitAfterDamping_ns = 500'000'000;

struct ControlTask {
  Firmware* firmware = nullptr;
  RobotIo* io = nullptr;
  DanceControl* dance = nullptr;  // nullptr without a motion
  bool stand = false;             // ask for stand-up once the self-check has passed
  bool dance_pending = false;     // ask for the dance once ready
  hal::TimeNs estop_since_ns = -1;
  hal::TimeNs danced_until_ns = -1;  // the dance's finish ended in damping without a fault
  bool done = false;                 // the image may exit (damping held kExitAfterDamping_ns)
  hal::CommandFrame command{};       // this cycle's, as sent
  // The timing command's stamps (firmware/timing.h): rtos_shim's clock, nullptr off.
  stack::StageClock stage_clock = nullptr;
  struct Stamps {
    std::int64_t start_ns = 0, received_ns = 0, cycled_ns = 0, sent_ns = 0;
  } stamps{};
};

// One control cycle at `now_ns`. `in` carries what the caller knows (e-stop, an operator's
// request, test overrides of watchdog inputs); the task adds the bus status, its own
// stand-up/dance requests and the dance's inputs. `imu` non-null replaces the IMU sample
// the drivers read (simulation: no MTi on the wire). `controller` is the firmware's
// CycleController, or a test's wrapper of it.
template <class Controller>
void control_task_step_rt(ControlTask& t, std::uint64_t cycle, hal::TimeNs now_ns, CycleInputs in,
                          const hal::ImuSample* imu, Controller& controller) noexcept {
  if (t.stage_clock != nullptr) t.stamps.start_ns = t.stage_clock();
  robot_receive_rt(*t.io, cycle, now_ns, 0);
  if (t.stage_clock != nullptr) t.stamps.received_ns = t.stage_clock();
  if (imu != nullptr) t.io->sensors.imu = *imu;
  in.watch.bus = t.io->status;
  const Mode mode = t.firmware->mode.mode;
  if (in.request == Request::kNone && t.stand && mode == Mode::kDamping && t.firmware->mode.latched == Fault::kNone) {
    in.request = Request::kStandUp;
    t.stand = false;
  }
  if (in.request == Request::kNone && t.dance_pending && mode == Mode::kReady) {
    in.request = Request::kDance;
    t.dance_pending = false;
  }
  if (t.dance != nullptr) dance_before_cycle_rt(*t.dance, *t.firmware, now_ns, in);
  firmware_cycle_rt(*t.firmware, t.io->sensors, in, now_ns, controller, t.command);
  if (t.stage_clock != nullptr) t.stamps.cycled_ns = t.stage_clock();
  robot_send_rt(*t.io, cycle, t.command, now_ns);
  if (t.stage_clock != nullptr) t.stamps.sent_ns = t.stage_clock();
  // The command is out: before the first dance, its first tick rehearses (dance.h).
  if (t.dance != nullptr) dance_rehearse_rt(*t.dance, t.firmware->mode.mode, t.io->sensors);
  if (in.estop && t.estop_since_ns < 0) t.estop_since_ns = now_ns;
  if (mode == Mode::kFinish && t.firmware->mode.mode == Mode::kDamping && t.dance != nullptr &&
      t.firmware->mode.latched == Fault::kNone) {
    t.danced_until_ns = now_ns;
  }
  // After a fault the robot stays in damping until the operator ends the run.
  if (t.estop_since_ns >= 0 && now_ns - t.estop_since_ns > kExitAfterDamping_ns) t.done = true;
  if (t.danced_until_ns >= 0 && now_ns - t.danced_until_ns > kExitAfterDamping_ns) t.done = true;
}

// The firmware's own controller.
inline void control_task_step_rt(ControlTask& t, std::uint64_t cycle, hal::TimeNs now_ns, const CycleInputs& in,
                                 const hal::ImuSample* imu) noexcept {
  CycleController controller{t.firmware, t.dance};
  control_task_step_rt(t, cycle, now_ns, in, imu, controller);
}

// The planning task's body: true if a plan waits in channels.plan's back slot.
inline bool planning_task_step_rt(DancePlanner& planner, DanceChannels& channels) noexcept {
  return dance_plan_rt(planner, channels);
}

}  // namespace kuavo::firmware
