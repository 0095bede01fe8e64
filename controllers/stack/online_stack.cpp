#include "controllers/stack/online_stack.h"

#include <algorithm>
#include <cstring>

namespace kuavo::stack {

static_assert(planner::kReferencePlanKnots == mpc::kMpcPlanKnots, "the MPC hands over exactly one ReferencePlan");

const char* to_string(PlannerKind k) {
  switch (k) {
    case PlannerKind::kKinematic: return "kinematic";
    case PlannerKind::kMpc: return "mpc";
  }
  return "?";
}

bool parse_planner(const char* text, PlannerKind& out) {
  if (std::strcmp(text, "kinematic") == 0) return out = PlannerKind::kKinematic, true;
  if (std::strcmp(text, "mpc") == 0) return out = PlannerKind::kMpc, true;
  return false;
}

const char* stack_validate_config(const StackConfig& config) {
  if (!(config.estimator_touchdown_delay_s >= 0.0 && config.estimator_touchdown_delay_s <= 0.2)) {
    return "estimator touchdown delay outside 0..0.2 s";
  }
  if (!(config.estimator_unloaded_foot_N >= 0.0 && config.estimator_unloaded_foot_N <= 1000.0)) {
    return "estimator unloaded-foot threshold outside 0..1000 N";
  }
  if (config.lean_trim.enabled) {
    if (const char* why = lean_trim_validate(config.lean_trim)) return why;
  }
  if (!(config.plan_period_s >= config.wbc.dt_s && config.plan_period_s <= 0.1)) return "plan period outside [WBC period, 0.1 s]";
  if (!(config.plan_blend_s >= 0.0 && config.plan_blend_s <= config.plan_period_s)) return "plan blend outside [0, plan period]";
  if (!(config.upper_body_delay_s >= 0.0 && config.upper_body_delay_s <= 0.02)) return "upper-body delay outside 0..0.02 s";
  if (config.planner == PlannerKind::kMpc) {
    if (const char* why = mpc::mpc_validate_config(config.mpc)) return why;
    if (mpc::mpc_window_knots(config.mpc) > planner::kMaxWindowKnots) return "MPC horizon longer than the plan window";
    if (!(config.planner_sole_inset_m >= 0.0 && config.planner_sole_inset_m <= 0.04)) {
      return "planner sole inset outside 0..0.04 m (the soles are 0.095 m wide)";
    }
    if (const char* why = planner::recovery_step_validate(config.recovery)) return why;
    if (const char* why = planner::liftoff_hold_validate(config.liftoff_hold)) return why;
    if (const char* why = planner::plan_anchor_validate(config.anchor)) return why;
  }
  return wbc::wbc_validate_config(config.wbc);
}

bool stack_start(const model::Model& model, const StackConfig& config, ControlWorkspace& control,
                 PlannerWorkspace& planner_ws, const planner::MotionPlan& motion, const hal::SensorFrame& sensors,
                 hal::TimeNs now_ns) {
  if (motion.frame_count <= 0 || !stack_prepare(model, config, control, planner_ws)) return false;
  // The first plan goes straight to the control side: nothing else is running yet. It is
  // made from the motion's first frame at rest (the estimator has not run yet).
  const dynamics::ConfigVector& q0 = motion.q[0];
  stack_plan_rt(model, config, planner_ws, motion, q0, dynamics::VelocityVector::Zero(), now_ns, control.active);
  return stack_begin_rt(model, config, control, motion, control.active, sensors, now_ns);
}

wbc::WbcStatus stack_control_tick_rt(const model::Model& model, const StackConfig& config, ControlWorkspace& ws,
                                     const hal::SensorFrame& sensors, hal::TimeNs now_ns, const StateOverride& state,
                                     hal::CommandFrame& command) {
  if (ws.stage_clock != nullptr) ws.stamps.start_ns = ws.stage_clock();
  // The reference first: its contact flags are the estimator's contact schedule.
  planner::reference_plan_at_rt(ws.active, now_ns, ws.reference);
  if (ws.blend_pending) {
    ws.blend_pending = false;
    ws.blending = config.plan_blend_s > 0.0 && ws.previous.count > 0;
    ws.blend_start_ns = now_ns;
  }
  if (ws.blending) {
    // alpha reaches 1 at blend_start + plan_blend_s, the first blended tick already moves.
    const double alpha =
        (static_cast<double>(now_ns - ws.blend_start_ns) * 1e-9 + config.wbc.dt_s) / (config.plan_blend_s + config.wbc.dt_s);
    if (alpha >= 1.0) {
      ws.blending = false;
    } else {
      planner::reference_plan_at_rt(ws.previous, now_ns, ws.previous_reference);
      // The new plan's contact flags (the estimator's schedule, the WBC's constraints).
      wbc::wbc_interpolate_reference(ws.reference, ws.previous_reference, 1.0 - alpha, ws.reference);
    }
  }
  const double dt_s = static_cast<double>(now_ns - ws.last_tick_ns) * 1e-9;
  ws.last_tick_ns = now_ns;
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    ws.planned_contact_s[c] = ws.reference.in_contact[c] ? ws.planned_contact_s[c] + dt_s : 0.0;
    ws.estimator_contact[c] = ws.reference.in_contact[c] && ws.planned_contact_s[c] >= config.estimator_touchdown_delay_s;
  }
  if (config.estimator_unloaded_foot_N > 0.0 && ws.ticks > 0 && ws.wbc.diagnostics.status == wbc::WbcStatus::kOk) {
    ws.estimator_unloaded_foot_ticks += static_cast<std::uint64_t>(
        estimator_drop_unloaded_foot_rt(ws.wbc.diagnostics.contact_force_N, config.estimator_unloaded_foot_N,
                                        ws.estimator_contact));
  }
  estimator::estimator_step_rt(model, ws.estimator, sensors, ws.estimator_contact, dt_s, ws.estimate);
  const bool trim = config.lean_trim.enabled && state.q == nullptr;
  if (trim) lean_trim_apply_rt(config.lean_trim, ws.lean_trim, ws.estimate.q);
  const dynamics::ConfigVector& q = state.q != nullptr ? *state.q : ws.estimate.q;
  const dynamics::VelocityVector& v = state.v != nullptr ? *state.v : ws.estimate.v;
  ++ws.ticks;
  if (ws.stage_clock != nullptr) ws.stamps.estimator_done_ns = ws.stage_clock();
  const dynamics::ConfigVector* q_wbc = &q;
  if (config.upper_body_delay_s > 0.0) {
    const double d = config.upper_body_delay_s;
    ws.predicted_q = q;
    for (int j = model::kLeftArmFirst; j < model::kNumJoints; ++j) {
      ws.predicted_q[7 + j] += v[6 + j] * d;
      const double a = ws.reference.joint_acceleration_rad_s2[j];
      ws.reference.joint_position_rad[j] += (ws.reference.joint_velocity_rad_s[j] + 0.5 * a * d) * d;
      ws.reference.joint_velocity_rad_s[j] += a * d;
    }
    q_wbc = &ws.predicted_q;
  }
  const wbc::WbcStatus status = wbc::wbc_step_rt(model, config.wbc, ws.wbc, *q_wbc, v, ws.reference, now_ns, command);
  if (trim) {
    lean_trim_note_plan_rt(config.lean_trim, ws.lean_trim, ws.reference.in_contact);
    lean_trim_update_rt(config.lean_trim, ws.lean_trim, ws.wbc.data, ws.wbc.point_position_m,
                        ws.wbc.diagnostics.contact_force_N, v, status == wbc::WbcStatus::kOk, model::kGravity_m_s2, dt_s);
  }
  if (ws.stage_clock != nullptr) ws.stamps.wbc_done_ns = ws.stage_clock();
  return status;
}

void stack_plan_rt(const model::Model& robot, const StackConfig& config, PlannerWorkspace& ws,
                   const planner::MotionPlan& motion, const dynamics::ConfigVector& q,
                   const dynamics::VelocityVector& v, hal::TimeNs t_state_ns, planner::ReferencePlan& out) {
  const model::Model& model = ws.planning_model_set ? ws.planning_model : robot;
  if (config.planner == PlannerKind::kMpc) {
    const int knots = mpc::mpc_window_knots(config.mpc);
    const bool recovering = ws.recovery.foot[0].active || ws.recovery.foot[1].active;
    // The measured state's kinematics, once for the three that read it.
    if (config.liftoff_hold.enabled || config.recovery.enabled || config.anchor.enabled) {
      planner::plan_knot_measured(model, ws.data, q, v, t_state_ns, ws.measured);
    }
    planner::liftoff_hold_window_rt(model, config.liftoff_hold, ws.liftoff, motion, ws.measured, t_state_ns,
                                    config.mpc.dt_s, knots, !recovering, ws.window);
    // The anchor's offset as the previous call left it: this call's differs by a ramp step at
    // most, and not at all between re-anchorings.
    planner::recovery_step_rt(model, config.recovery, ws.recovery, motion, ws.measured, ws.window, ws.liftoff.lag_ns,
                              ws.anchor.offset);
    planner::plan_anchor_rt(config.anchor, ws.anchor, ws.measured, t_state_ns, ws.window);
    ws.last_mpc_status = mpc::mpc_step_rt(model, config.mpc, ws.mpc, q, v, ws.window, ws.mpc_plan);
    if (ws.last_mpc_status == mpc::MpcStatus::kOk && ws.mpc_plan.count > 0) {
      out.stamp_ns = ws.mpc_plan.stamp_ns;
      out.dt_s = ws.mpc_plan.dt_s;
      out.count = ws.mpc_plan.count;
      for (int k = 0; k < out.count; ++k) {
        out.knots[k] = ws.mpc_plan.knots[k];
        auto& q = out.knots[k].joint_position_rad;
        for (int j = 0; j < model::kNumJoints; ++j) {
          const double on_stop = std::clamp(q[j], model.limits.position_min_rad[j], model.limits.position_max_rad[j]);
          if (on_stop != q[j]) {
            q[j] = on_stop;
            ++ws.plan_positions_on_a_stop;
          }
        }
      }
      return;
    }
    ++ws.mpc_failures;
    mpc::mpc_reset(ws.mpc);
    // The fallback is the motion as it is: without the lift-off hold's lag, a recovery step's
    // rewrite or the plan anchor's offset (up to its bound, 0.25 m), until the MPC is back.
  }
  // Kinematic planner: the state does not enter (the WBC closes the loop).
  planner::kinematic_reference_plan_rt(model, ws.data, motion, t_state_ns, config.plan_period_s, ws.window, out);
}

bool stack_prepare(const model::Model& model, const StackConfig& config, ControlWorkspace& control,
                   PlannerWorkspace& planner_ws) {
  if (stack_validate_config(config) != nullptr) return false;
  if (!estimator::estimator_init(config.estimator, control.estimator)) return false;
  wbc::wbc_init(model, config.wbc, control.wbc);
  planner_ws.planning_model_set = false;
  if (config.planner == PlannerKind::kMpc) {
    planner_ws.planning_model = model;
    if (config.planner_sole_inset_m > 0.0) model::inset_sole_corners(planner_ws.planning_model, config.planner_sole_inset_m);
    planner_ws.planning_model_set = true;
    mpc::mpc_init(model, config.mpc, planner_ws.mpc);
    planner_ws.mpc_failures = 0;
    planner_ws.plan_positions_on_a_stop = 0;
    planner::recovery_step_reset(planner_ws.recovery);
    planner::liftoff_hold_reset(planner_ws.liftoff);
    planner::plan_anchor_reset(planner_ws.anchor);
  }
  control.started = false;
  return true;
}

int estimator_drop_unloaded_foot_rt(const wbc::ForceVector& force_N, double threshold_N,
                                    estimator::ContactFlags& contact) {
  static_assert(model::kNumContactPoints == 2 * planner::kCornersPerFoot, "two feet of kCornersPerFoot corners");
  static_assert(wbc::ForceVector::RowsAtCompileTime == 3 * model::kNumContactPoints, "3 forces per corner");
  if (!(threshold_N > 0.0)) return 0;
  constexpr int kCorners = planner::kCornersPerFoot;
  double normal_N[2] = {0.0, 0.0};
  for (int foot = 0; foot < 2; ++foot) {
    for (int k = 0; k < kCorners; ++k) normal_N[foot] += force_N[3 * (foot * kCorners + k) + 2];
  }
  for (int foot = 0; foot < 2; ++foot) {
    if (!(normal_N[foot] < threshold_N && normal_N[1 - foot] >= threshold_N)) continue;
    bool any = false;
    for (int k = 0; k < kCorners; ++k) {
      any = any || contact[foot * kCorners + k];
      contact[foot * kCorners + k] = false;
    }
    return any ? 1 : 0;
  }
  return 0;
}

bool stack_begin_rt(const model::Model& model, const StackConfig& config, ControlWorkspace& control,
                    const planner::MotionPlan& motion, const planner::ReferencePlan& first,
                    const hal::SensorFrame& sensors, hal::TimeNs now_ns) {
  control.started = false;
  if (motion.frame_count <= 0 || first.count <= 0) return false;
  // A clean filter (estimator_init only clears state) and a WBC without a held command.
  if (!estimator::estimator_init(config.estimator, control.estimator)) return false;
  const dynamics::ConfigVector& q0 = motion.q[0];
  if (estimator::estimator_reset(model, control.estimator, sensors, Eigen::Vector2d(q0[0], q0[1])) !=
      estimator::EstimatorStatus::kOk) {
    return false;
  }
  // The estimate is the robot as reset, not what the last run left: a planner that runs
  // before the first control tick plans from it.
  estimator::estimator_output(control.estimator, control.estimate);
  wbc::wbc_init(model, config.wbc, control.wbc);
  if (&first != &control.active) control.active = first;
  control.previous.count = 0;  // nothing to blend from
  control.blend_pending = control.blending = false;
  control.plans_applied = 1;
  control.last_tick_ns = now_ns - static_cast<hal::TimeNs>(config.wbc.dt_s * 1e9);
  control.planned_contact_s.fill(1.0);  // standing at the start: in contact for long
  control.started = true;
  control.ticks = 0;
  control.estimator_unloaded_foot_ticks = 0;
  lean_trim_reset(control.lean_trim);
  return true;
}

void stack_reset_planner_rt(const StackConfig& config, PlannerWorkspace& ws) {
  if (config.planner == PlannerKind::kMpc) {
    mpc::mpc_reset(ws.mpc);
    planner::recovery_step_reset(ws.recovery);
    planner::liftoff_hold_reset(ws.liftoff);
    planner::plan_anchor_reset(ws.anchor);
  }
}

void stack_apply_plan_rt(ControlWorkspace& ws, const planner::ReferencePlan& plan) {
  ws.previous = ws.active;
  ws.active = plan;
  ws.blend_pending = true;
  ++ws.plans_applied;
}

}  // namespace kuavo::stack
