// One firmware control cycle, the same in the robot's periodic task and in the
// firmware-in-the-loop tests: watchdogs -> mode machine -> controller (in the
// active modes) -> gain ramp -> safety filter -> the command for the drivers.
// A refused command never leaves: the same cycle latches the fault and sends
// damping instead, so command faults reach damping in 0 ms.
#pragma once

#include <array>
#include <cstdint>

#include "controllers/hal/types.h"
#include "controllers/model/model.h"
#include "controllers/standing/standing_controller.h"
#include "firmware/firmware_config.h"
#include "firmware/log_ring.h"
#include "firmware/mode_machine.h"
#include "firmware/safety_filter.h"
#include "firmware/watchdogs.h"

namespace kuavo::firmware {

struct CycleInputs {
  bool estop = false;
  Request request = Request::kNone;
  bool dance_done = false;
  WatchdogInputs watch{};
};

// Everything the cycle owns. Large (the controller's dynamics workspace):
// keep it in static storage or allocate it once before the loop.
struct Firmware {
  const model::Model* model = nullptr;
  FirmwareConfig config{};
  ModeState mode{};
  control::StandingState standing;
  std::array<double, model::kNumJoints> ramp_from_rad{};  // joint positions when stand-up began
  hal::CommandFrame controller_command{};                // the controller's raw output this cycle
  LogSink* log = nullptr;
  WatchdogResult last_watchdog{};
  FilterResult last_filter{};
  double max_tilt_rad = 0.0;  // since the last status record
  hal::TimeNs now_ns = 0;     // this cycle's time (for controllers that need it)
  std::uint64_t cycles = 0;
};

// Start-up: binds the model and configuration, initialises the standing controller.
void firmware_init(Firmware& fw, const model::Model& model, const FirmwareConfig& config, LogSink* log);

// The standing controller, the default for every active mode until MPC/WBC land.
struct StandingController {
  Firmware* fw;
  void operator()(const hal::SensorFrame& sensors, hal::CommandFrame& out) const noexcept {
    control::standing_step_rt(*fw->model, fw->standing, sensors, out);
  }
};

// --- The cycle, split where the controller runs (the controller is a template
// parameter: no virtual call, and tests can wrap it to inject bad commands). ---

// Watchdogs, self-check and the mode machine. Returns true if the controller must run.
bool cycle_begin_rt(Firmware& fw, const hal::SensorFrame& sensors, const CycleInputs& in,
                    hal::TimeNs now_ns) noexcept;

// Ramps fw.controller_command by the mode, filters it, writes `out` (damping
// if refused or if the controller did not run).
void cycle_end_rt(Firmware& fw, const hal::SensorFrame& sensors, bool controller_ran, hal::TimeNs now_ns,
                  hal::CommandFrame& out) noexcept;

template <class Controller>
void firmware_cycle_rt(Firmware& fw, const hal::SensorFrame& sensors, const CycleInputs& in, hal::TimeNs now_ns,
                       Controller& controller, hal::CommandFrame& out) noexcept {
  const bool run = cycle_begin_rt(fw, sensors, in, now_ns);
  if (run) controller(sensors, fw.controller_command);
  cycle_end_rt(fw, sensors, run, now_ns, out);
}

}  // namespace kuavo::firmware
