// Lockstep scheduler for the simulator: the 500 Hz control task, the 50 Hz
// planning task and the plant integration run in virtual time, one event at a
// time, in an order that depends only on the configuration -- no threads, no
// wall clock, so two runs are identical.
//
//   LockstepScheduler sched;
//   if (sched.reset(config) != LockstepError::kOk) ...;
//   SimEvent ev;
//   while (sched.next(ev)) {
//     switch (ev.kind) {
//       case SimEventKind::kPlanApply:   controller.use_plan(pending_plan); break;
//       case SimEventKind::kControlTick: cmd = controller.step(plant.sense(ev.time_ns)); break;
//       case SimEventKind::kPlanRequest: pending_plan = planner.solve(controller.state());
//                                        sched.set_plan_delay_ns(...);  // optional
//                                        break;
//       case SimEventKind::kPlantStep:   plant.advance(cmd, ev.time_ns, ev.dt_ns); break;
//     }
//   }
//
// Planner latency model: the result of the plan requested at time t (from the
// state at t) is applied at t + delay, where delay is config.plan_delay_ns or,
// if the caller calls set_plan_delay_ns() right after the kPlanRequest event,
// that value (e.g. measured compute time rounded up to control ticks). As on the
// robot, where the planner is one periodic thread, at most one plan is in flight:
// a planning release that falls before the previous result is applied is
// skipped (counted in stats().plans_skipped). So the caller needs a single
// pending-plan slot between kPlanRequest and kPlanApply.
//
// Order of events at the same virtual time (the SimEventKind numbers):
// kPlanApply, kControlTick, kPlanRequest, kPlantStep. A result due at t is seen
// by the tick at t; the planner sees the state the tick at t has just estimated;
// the plant then integrates over [t, t + dt) with the new command.
#pragma once

#include <cstdint>
#include <limits>

#include "controllers/hal/types.h"
#include "rtos_shim/sim_clock.h"

namespace kuavo::rtos {

using hal::TimeNs;

// Stable numbers; also the order of events that share a time.
enum class SimEventKind : std::uint8_t {
  kPlanApply = 0,    // a planner result becomes visible to the control task
  kControlTick = 1,  // run the control step on the state at time_ns
  kPlanRequest = 2,  // run the planner on the state at time_ns
  kPlantStep = 3,    // integrate the plant from time_ns over dt_ns
};

struct SimEvent {
  SimEventKind kind = SimEventKind::kControlTick;
  TimeNs time_ns = 0;        // virtual time of the event (== scheduler now_ns())
  TimeNs dt_ns = 0;          // kPlantStep: step length; kControlTick: control period
  std::uint64_t index = 0;   // tick number, plan number (request and apply share it) or plant step number
  TimeNs plan_state_ns = 0;  // kPlanRequest / kPlanApply: time of the state the plan is computed from
};

struct LockstepConfig {
  TimeNs start_ns = 0;
  TimeNs stop_ns = std::numeric_limits<TimeNs>::max();  // no event at or after this time
  TimeNs control_period_ns = 2'000'000;                 // 500 Hz
  TimeNs plan_period_ns = 20'000'000;                   // 50 Hz; 0 disables planning
  // Default planner latency: one planning period, the most a 50 Hz planner can
  // take without skipping releases -- the pessimistic case the controller must handle.
  TimeNs plan_delay_ns = 20'000'000;
  int plant_steps_per_tick = 1;  // plant sub-steps between two control ticks
};

// Stable numbers.
enum class LockstepError : std::uint8_t {
  kOk = 0,
  kBadControlPeriod = 1,  // control_period_ns <= 0
  kBadPlanPeriod = 2,     // plan_period_ns < 0 or not a multiple of control_period_ns
  kBadPlanDelay = 3,      // plan_delay_ns < 0
  kBadPlantSteps = 4,     // plant_steps_per_tick < 1 or does not divide control_period_ns
  kBadStopTime = 5,       // stop_ns < start_ns
  kNotReset = 6,          // next() before a successful reset()
};

[[nodiscard]] const char* describe(LockstepError error) noexcept;
[[nodiscard]] LockstepError validate(const LockstepConfig& config) noexcept;

// Smallest multiple of step_ns that is >= value_ns (value_ns >= 0, step_ns > 0),
// e.g. a measured planner compute time rounded up to control ticks.
[[nodiscard]] constexpr TimeNs round_up_to_multiple_ns(TimeNs value_ns, TimeNs step_ns) noexcept {
  return (value_ns + step_ns - 1) / step_ns * step_ns;
}

struct LockstepStats {
  std::uint64_t control_ticks = 0;
  std::uint64_t plans_requested = 0;
  std::uint64_t plans_applied = 0;
  std::uint64_t plans_skipped = 0;  // planning releases that fell while a plan was in flight
  std::uint64_t plant_steps = 0;
};

class LockstepScheduler {
 public:
  // Validates and (re)starts at config.start_ns. On error the scheduler stays
  // stopped (next() returns false). Start-up only.
  [[nodiscard]] LockstepError reset(const LockstepConfig& config) noexcept;

  // Produces the next event and advances virtual time to it; false once the
  // next event would be at or after stop_ns (or before reset()). No allocation.
  [[nodiscard]] bool next(SimEvent& event) noexcept;

  // Latency of the plan just requested: call after a kPlanRequest event and
  // before the next next(). Returns false (default delay kept) at any other
  // time or for delay_ns < 0.
  bool set_plan_delay_ns(TimeNs delay_ns) noexcept;

  [[nodiscard]] TimeNs now_ns() const noexcept { return clock_.now_ns(); }
  [[nodiscard]] const SimClock& clock() const noexcept { return clock_; }
  [[nodiscard]] const LockstepConfig& config() const noexcept { return config_; }
  [[nodiscard]] const LockstepStats& stats() const noexcept { return stats_; }

 private:
  void schedule_requested_plan() noexcept;

  LockstepConfig config_{};
  SimClock clock_{};
  LockstepStats stats_{};
  bool ready_ = false;
  TimeNs plant_dt_ns_ = 0;
  TimeNs next_tick_ns_ = 0;
  TimeNs next_plant_ns_ = 0;
  TimeNs next_request_ns_ = 0;
  // The plan in flight (requested, not yet applied).
  bool plan_in_flight_ = false;
  bool delay_open_ = false;  // last event was its kPlanRequest: delay may still be set
  TimeNs plan_delay_ns_ = 0;
  TimeNs plan_state_ns_ = 0;
  TimeNs plan_apply_ns_ = 0;
  std::uint64_t plan_index_ = 0;
};

}  // namespace kuavo::rtos
