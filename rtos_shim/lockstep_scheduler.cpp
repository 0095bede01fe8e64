#include "rtos_shim/lockstep_scheduler.h"

namespace kuavo::rtos {
namespace {

struct Candidate {
  TimeNs time_ns;
  SimEventKind kind;
};

// Total order on events: time, then kind (the documented same-time order).
constexpr bool before(const Candidate& a, const Candidate& b) noexcept {
  return a.time_ns < b.time_ns || (a.time_ns == b.time_ns && a.kind < b.kind);
}

}  // namespace

const char* describe(LockstepError error) noexcept {
  switch (error) {
    case LockstepError::kOk: return "ok";
    case LockstepError::kBadControlPeriod: return "control_period_ns must be > 0";
    case LockstepError::kBadPlanPeriod:
      return "plan_period_ns must be 0 (no planner) or a positive multiple of control_period_ns";
    case LockstepError::kBadPlanDelay: return "plan_delay_ns must be >= 0";
    case LockstepError::kBadPlantSteps:
      return "plant_steps_per_tick must be >= 1 and divide control_period_ns";
    case LockstepError::kBadStopTime: return "stop_ns must be >= start_ns";
    case LockstepError::kNotReset: return "scheduler used before a successful reset()";
  }
  return "unknown lockstep error";
}

LockstepError validate(const LockstepConfig& c) noexcept {
  if (c.control_period_ns <= 0) return LockstepError::kBadControlPeriod;
  // Planning releases on control ticks, so the planner always sees a freshly estimated state.
  if (c.plan_period_ns < 0 || c.plan_period_ns % c.control_period_ns != 0) {
    return LockstepError::kBadPlanPeriod;
  }
  if (c.plan_delay_ns < 0) return LockstepError::kBadPlanDelay;
  if (c.plant_steps_per_tick < 1 || c.control_period_ns % c.plant_steps_per_tick != 0) {
    return LockstepError::kBadPlantSteps;
  }
  if (c.stop_ns < c.start_ns) return LockstepError::kBadStopTime;
  return LockstepError::kOk;
}

LockstepError LockstepScheduler::reset(const LockstepConfig& config) noexcept {
  *this = LockstepScheduler{};
  const LockstepError error = validate(config);
  if (error != LockstepError::kOk) return error;
  config_ = config;
  clock_ = SimClock(config.start_ns);
  plant_dt_ns_ = config.control_period_ns / config.plant_steps_per_tick;
  next_tick_ns_ = config.start_ns;
  next_plant_ns_ = config.start_ns;
  next_request_ns_ = config.start_ns;
  ready_ = true;
  return LockstepError::kOk;
}

void LockstepScheduler::schedule_requested_plan() noexcept {
  plan_apply_ns_ = plan_state_ns_ + plan_delay_ns_;
  delay_open_ = false;
}

bool LockstepScheduler::set_plan_delay_ns(TimeNs delay_ns) noexcept {
  if (!delay_open_ || delay_ns < 0) return false;
  plan_delay_ns_ = delay_ns;
  return true;
}

bool LockstepScheduler::next(SimEvent& event) noexcept {
  if (!ready_) return false;
  if (delay_open_) schedule_requested_plan();

  const bool planning = config_.plan_period_ns > 0;
  Candidate best{};
  for (;;) {
    best = {next_tick_ns_, SimEventKind::kControlTick};
    const Candidate apply{plan_apply_ns_, SimEventKind::kPlanApply};
    if (plan_in_flight_ && before(apply, best)) best = apply;
    const Candidate request{next_request_ns_, SimEventKind::kPlanRequest};
    if (planning && before(request, best)) {
      // Earlier than a pending apply (which would have won otherwise): the
      // planner is still busy with the previous plan, so this release is lost,
      // as it would be on the robot's periodic planning thread.
      if (plan_in_flight_) {
        next_request_ns_ += config_.plan_period_ns;
        ++stats_.plans_skipped;
        continue;
      }
      best = request;
    }
    const Candidate plant{next_plant_ns_, SimEventKind::kPlantStep};
    if (before(plant, best)) best = plant;
    break;
  }
  if (best.time_ns >= config_.stop_ns) return false;

  clock_.advance_to_ns(best.time_ns);  // cannot go back: every source only moves forward
  event = SimEvent{};
  event.kind = best.kind;
  event.time_ns = best.time_ns;
  switch (best.kind) {
    case SimEventKind::kPlanApply:
      event.index = plan_index_;
      event.plan_state_ns = plan_state_ns_;
      plan_in_flight_ = false;
      ++stats_.plans_applied;
      break;
    case SimEventKind::kControlTick:
      event.dt_ns = config_.control_period_ns;
      event.index = stats_.control_ticks++;
      next_tick_ns_ += config_.control_period_ns;
      break;
    case SimEventKind::kPlanRequest:
      plan_index_ = stats_.plans_requested++;
      event.index = plan_index_;
      event.plan_state_ns = best.time_ns;
      plan_state_ns_ = best.time_ns;
      plan_delay_ns_ = config_.plan_delay_ns;
      plan_in_flight_ = true;
      delay_open_ = true;
      next_request_ns_ += config_.plan_period_ns;
      break;
    case SimEventKind::kPlantStep:
      event.dt_ns = plant_dt_ns_;
      event.index = stats_.plant_steps++;
      next_plant_ns_ += plant_dt_ns_;
      break;
  }
  return true;
}

}  // namespace kuavo::rtos
