// The firmware's operating modes and their transitions:
//
//   boot -> self-check -> damping -> stand-up -> ready -> dance -> finish -> damping
//
// E-stop and every fault are reachable from every mode: they latch and force
// damping. Leaving damping again needs an operator clear with the e-stop
// released; the latched fault is then forgotten (its record stays in the log).
// Pure logic over inputs and virtual/monotonic time: no I/O, real-time safe.
#pragma once

#include <cstdint>

#include "controllers/hal/types.h"
#include "firmware/fault.h"

namespace kuavo::firmware {

// Stable numbers (logged).
enum class Mode : std::uint8_t {
  kBoot = 0,       // configuration loaded; no command yet (motors disabled)
  kSelfCheck = 1,  // waiting for every sample to be valid and fresh (motors disabled)
  kDamping = 2,    // safe mode: tau = -kd v on every joint
  kStandUp = 3,    // standing controller with gains ramped 0 -> 1
  kReady = 4,      // standing controller
  kDance = 5,      // the dance controller (standing until MPC/WBC land)
  kFinish = 6,     // gains ramped 1 -> 0, then damping
};

const char* to_string(Mode m) noexcept;

// Operator requests (stable numbers). A request that does not fit the current
// mode is ignored.
enum class Request : std::uint8_t {
  kNone = 0,
  kStandUp = 1,      // damping -> stand-up
  kDance = 2,        // ready -> dance
  kFinish = 3,       // ready or dance -> finish
  kClearFaults = 4,  // in damping with the e-stop released: forget the latch
};

struct ModeInputs {
  bool estop = false;
  Request request = Request::kNone;
  bool self_check_passed = false;
  bool dance_done = false;  // the dance controller reached its end
  Fault fault = Fault::kNone;  // this cycle's first fault (watchdogs, safety filter)
};

struct ModeState {
  Mode mode = Mode::kBoot;
  hal::TimeNs since_ns = 0;      // when `mode` was entered
  Fault latched = Fault::kNone;  // first fault since the last clear
  hal::TimeNs latched_ns = 0;
  std::uint32_t transitions = 0;
};

// Advances the machine for the cycle at now_ns. Returns true if the mode changed.
bool step_mode_rt(ModeState& s, const ModeInputs& in, hal::TimeNs now_ns, hal::TimeNs self_check_timeout_ns,
                  hal::TimeNs stand_up_duration_ns, hal::TimeNs finish_duration_ns) noexcept;

// Latches `f` (if none is latched) and forces damping; for faults found after
// step_mode_rt in the same cycle (the safety filter). Returns true if the mode changed.
bool latch_fault_rt(ModeState& s, Fault f, hal::TimeNs now_ns) noexcept;

// Whether the motors are powered by the controller in this mode.
[[nodiscard]] constexpr bool is_active(Mode m) noexcept {
  return m == Mode::kStandUp || m == Mode::kReady || m == Mode::kDance || m == Mode::kFinish;
}

}  // namespace kuavo::firmware
