#include "firmware/dance.h"

#include <limits>

#include <algorithm>
#include <cmath>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/wbc/wbc_config.h"

namespace kuavo::firmware {

namespace {

template <class D>
bool finite(const Eigen::DenseBase<D>& m) noexcept {
  return m.allFinite();
}

bool reference_finite(const wbc::WbcReference& r) noexcept {
  return finite(r.base_euler_zyx_rad) && finite(r.base_angular_velocity_rad_s) &&
         finite(r.base_angular_acceleration_rad_s2) && finite(r.com_position_m) && finite(r.com_velocity_m_s) &&
         finite(r.momentum_rate) && finite(r.joint_position_rad) && finite(r.joint_velocity_rad_s) &&
         finite(r.joint_acceleration_rad_s2) && finite(r.point_position_m) && finite(r.point_velocity_m_s) &&
         finite(r.point_acceleration_m_s2) && finite(r.contact_force_N);
}

// The motion's own knots from motion time t_ns, made on the control task.
void kinematic_plan_rt(DanceControl& d, hal::TimeNs t_ns) noexcept {
  planner::kinematic_reference_plan_rt(*d.model, d.data, *d.motion, t_ns, d.config.plan_period_s, d.window,
                                       d.scratch_plan);
}

void publish_request_rt(DanceControl& d, std::uint32_t epoch, hal::TimeNs t_ns) noexcept {
  PlanRequest& r = d.channels->request.back_rt();
  r.epoch = epoch;
  r.sequence = ++d.sequence;
  r.t_state_ns = t_ns;
  r.q = d.stack.estimate.q;
  r.v = d.stack.estimate.v;
  r.ankle_motors = d.stack.wbc.ankle_motor_limits;
  d.channels->request.publish_rt();
}

}  // namespace

void blend_torque_laws_rt(const hal::CommandFrame& standing, double a, hal::CommandFrame& out) noexcept {
  for (int j = 0; j < model::kNumJoints; ++j) {
    const hal::JointCommand& s = standing.joints[j];
    hal::JointCommand& w = out.joints[j];
    if (s.mode != hal::JointMode::kPdTorque || w.mode != hal::JointMode::kPdTorque) continue;
    const double kp = (1.0 - a) * s.kp_Nm_per_rad + a * w.kp_Nm_per_rad;
    const double kd = (1.0 - a) * s.kd_Nm_s_per_rad + a * w.kd_Nm_s_per_rad;
    if (kp > 0.0) w.position_ref_rad = ((1.0 - a) * s.kp_Nm_per_rad * s.position_ref_rad + a * w.kp_Nm_per_rad * w.position_ref_rad) / kp;
    if (kd > 0.0) w.velocity_ref_rad_s = ((1.0 - a) * s.kd_Nm_s_per_rad * s.velocity_ref_rad_s + a * w.kd_Nm_s_per_rad * w.velocity_ref_rad_s) / kd;
    w.torque_ff_Nm = (1.0 - a) * s.torque_ff_Nm + a * w.torque_ff_Nm;
    w.kp_Nm_per_rad = kp;
    w.kd_Nm_s_per_rad = kd;
  }
}

namespace {

// A joint reference a little past a stop is the motion's, not a fault: the retargeting
// bounds its least squares by the limits (frames sit on a stop), the balance filter's leg
// re-solve does not (the built-in dance: the ankle roll 0.009 rad past), the WBC adds
// ½·q̈·dt² (≤ 0.001 rad), and an MPC plan starts from the measured state (a foot landing
// presses an ankle a few hundredths past its stop). Such a reference is put on the stop;
// one further out than this is garbage, left for the safety filter to refuse.
constexpr double kReferenceLimitSlack_rad = 0.05;

}  // namespace

void dance_set_ankle_motors(DanceControl& control, const drivers::DriversConfig& drivers) {
  control.ankle_motors = drivers::ankle_motors_from_config(drivers);
}

void dance_set_serial_leg_drives(DanceControl& control, const drivers::DriversConfig& drivers) {
  hal::SerialLegDriveLimits& s = control.serial_drives;
  s = hal::SerialLegDriveLimits{};
  int found = 0;
  for (int leg = 0; leg < 2; ++leg) {
    const int first = leg == 0 ? model::kLeftLegFirst : model::kRightLegFirst;
    for (int k = 0; k < hal::kSerialLegJoints; ++k) {
      for (const drivers::DriveEntry& e : drivers.drives) {
        if (e.slot != first + k || e.config.mode != drivers::canopen::kModeCyclicSyncPosition) continue;
        // Joint side through the ratio r (motor rad per joint rad): τ_j = r·τ_m, kd_j = r²·kd_m.
        const double r = drivers.legs[leg].serial[k].ratio_motor_per_joint;
        s.limit_Nm[leg][k] = std::abs(r) * e.config.torque_limit_Nm;
        s.velocity_gain_Nm_s_per_rad[leg][k] = r * r * e.config.csp_kd_Nm_s_per_rad;
        ++found;
      }
    }
  }
  s.active = found == 2 * hal::kSerialLegJoints;
  control.torque_cap_Nm.setConstant(qp::kInfinity);
  for (const drivers::ruiwo::MotorConfig& m : drivers.ruiwo_motors) {
    if (m.joint >= 0 && m.joint < model::kNumJoints) {
      control.torque_cap_Nm[m.joint] = std::min(control.torque_cap_Nm[m.joint], m.torque_max_Nm);
    }
  }
}

bool dance_use_csp_drives(drivers::DriversConfig& drivers, std::string& message) {
  const wbc::WbcConfig w;
  return drivers::use_csp_leg_drives(drivers, w.leg_kp, w.leg_kd, message) &&
         drivers::use_csp_shoulder_drives(drivers, w.arm_pd_kp, w.arm_pd_kd, message);
}

void limit_references_rt(const model::Model& m, double slack_rad, hal::CommandFrame& out,
                         std::uint64_t& limited) noexcept {
  for (int j = 0; j < model::kNumJoints; ++j) {
    double& q = out.joints[j].position_ref_rad;
    const double lo = m.limits.position_min_rad[j], hi = m.limits.position_max_rad[j];
    if (q > hi && q <= hi + slack_rad) q = hi, ++limited;
    if (q < lo && q >= lo - slack_rad) q = lo, ++limited;
  }
}

namespace {

// The WBC's torque comes from the equations of motion without the actuators' limits: in
// a hard move the 27 N·m ankles saturate (controllers/wbc/wbc_config.h), and the drives clip
// the torque at the joint's peak -- as the simulator's drive model does (sim/motor_model.h),
// where this same stack was tuned. The firmware clips the feed-forward the same way, so
// the safety filter sees what the drive would apply. A demand beyond kTorqueSaturation_x
// times the peak is not saturation but a broken solution: left for the filter to refuse.
constexpr double kTorqueSaturation_x = 1.5;

void saturate_torques_rt(const model::Model& m, hal::CommandFrame& out, DanceCounters& counters) noexcept {
  for (int j = 0; j < model::kNumJoints; ++j) {
    double& tau = out.joints[j].torque_ff_Nm;
    const double peak = m.limits.peak_torque_Nm[j];
    if (std::abs(tau) > peak) counters.max_torque_demand_x = std::max(counters.max_torque_demand_x, std::abs(tau) / peak);
    if (std::abs(tau) > peak && std::abs(tau) <= kTorqueSaturation_x * peak) {
      tau = std::copysign(peak, tau);
      ++counters.torques_saturated;
    }
  }
}

}  // namespace

bool estimator_diverged_rt(const DanceControl& d) noexcept {
  const estimator::EstimateOutput& e = d.stack.estimate;
  if (e.status != estimator::EstimatorStatus::kDiverged) return false;
  const double limit = d.stack.estimator.config.covariance_trace_limit;
  if (e.covariance_trace <= limit) return true;  // re-seeded after a non-finite state
  return d.stack.estimator.p.topLeftCorner<6, 6>().trace() > limit;
}

bool reference_plan_finite(const planner::ReferencePlan& plan) noexcept {
  if (plan.count < 0 || plan.count > planner::kReferencePlanKnots || !std::isfinite(plan.dt_s)) return false;
  for (int k = 0; k < plan.count; ++k) {
    if (!reference_finite(plan.knots[k])) return false;
  }
  return true;
}

stack::StackConfig firmware_stack_config(const FirmwareConfig& fw_config) {
  stack::StackConfig config;
  config.planner = stack::PlannerKind::kMpc;
  config.upper_body_delay_s = 1e-9 * static_cast<double>(fw_config.control_period_ns);
  return config;
}

bool dance_init(DanceControl& control, DancePlanner& planner, DanceChannels& channels, const model::Model& model,
                const stack::StackConfig& config, const FirmwareConfig& fw_config, const planner::MotionPlan& motion,
                const char*& error) {
  error = nullptr;
  if (const char* why = stack::stack_validate_config(config)) return error = why, false;
  if (std::llround(config.plan_period_s * 1e9) != fw_config.planner_period_ns) {
    return error = "the stack's plan period differs from the firmware's planner period", false;
  }
  if (std::llround(config.wbc.dt_s * 1e9) != fw_config.control_period_ns) {
    return error = "the WBC period differs from the firmware's control period", false;
  }
  if (motion.frame_count < 2 || !(motion.rate_hz > 0.0)) return error = "the motion has no frames", false;
  control.model = &model;
  control.config = config;
  control.motion = &motion;
  control.channels = &channels;
  control.blend_ns = fw_config.dance_blend_ns;
  control.settle_ns = fw_config.dance_settle_ns;
  control.stale_ns = fw_config.plan_stale_ns;
  control.duration_ns = static_cast<hal::TimeNs>(std::llround(planner::motion_plan_duration_s(motion) * 1e9));
  control.running = false;
  control.counters = DanceCounters{};
  control.danced = false;
  control.rehearsals = 0;
  control.rehearsal_failures = 0;
  kinematic_plan_rt(control, 0);
  control.first_plan = control.scratch_plan;
  planner.model = &model;
  planner.config = &control.config;
  planner.motion = &motion;
  planner.epoch = 0;
  planner.last_sequence = 0;
  planner.plans = 0;
  planner.rehearsals = 0;
  planner.rehearsal_failures = 0;
  if (!stack::stack_prepare(model, config, control.stack, planner.ws)) {
    return error = "the online stack could not be prepared (estimator configuration)", false;
  }
  return true;
}

void dance_standing_pose(Firmware& fw, const planner::MotionPlan& motion) {
  const model::Model& m = *fw.model;
  control::StandingState& s = fw.standing;
  // Just inside the stops: the stand-up ramp's rounding must not carry a reference that
  // sits on a stop (the retargeted first frame may) past it.
  constexpr double kInsideStops_rad = 1e-6;
  for (int j = 0; j < model::kNumJoints; ++j) {
    s.pose_rad[j] = std::clamp(motion.q[0][7 + j], m.limits.position_min_rad[j] + kInsideStops_rad,
                               m.limits.position_max_rad[j] - kInsideStops_rad);
  }
  // standing_step_rt's CoM over the feet, for the robot exactly at the first frame.
  dynamics::ConfigVector q = motion.q[0];
  q.head<3>().setZero();
  dynamics::forward_kinematics(m, s.data, q);
  dynamics::crba(m, s.data);
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    centre += dynamics::frame_position(m, s.data, c).head<2>() / model::kNumContactPoints;
  }
  s.com_ref_m = s.data.com_m.head<2>() - centre;
}

void dance_stop_rt(DanceControl& d) noexcept {
  if (!d.running) return;
  d.running = false;
  publish_request_rt(d, 0, 0);  // epoch 0: the planner idles
}

void dance_before_cycle_rt(DanceControl& d, const Firmware& fw, hal::TimeNs now_ns, CycleInputs& in) noexcept {
  if (d.running && fw.mode.mode != Mode::kDance && fw.mode.mode != Mode::kFinish) dance_stop_rt(d);
  if (!d.running) return;
  if (d.channels->plan.update_rt()) {
    const PlanMessage& m = d.channels->plan.front_rt();
    if (m.epoch != d.epoch) {
      ++d.counters.plans_old_epoch;
    } else if (m.plan.count <= 0 || !reference_plan_finite(m.plan)) {
      ++d.counters.plans_rejected;  // as if not delivered: it ages into the fallback and fault 16
    } else {
      stack::stack_apply_plan_rt(d.stack, m.plan);
      d.plan_stamp_ns = d.start_ns + m.plan.stamp_ns;
      d.on_kinematic_fallback = false;
      ++d.counters.plans_taken;
    }
  }
  if (!d.on_kinematic_fallback && now_ns - d.plan_stamp_ns > d.stale_ns) {
    kinematic_plan_rt(d, now_ns - d.start_ns);
    stack::stack_apply_plan_rt(d.stack, d.scratch_plan);
    d.on_kinematic_fallback = true;
    ++d.counters.kinematic_fallbacks;
  }
  in.watch.planner_running = true;
  in.watch.plan_stamp_ns = d.plan_stamp_ns;  // the planner's, never the fallback's
  in.watch.estimator_diverged = estimator_diverged_rt(d);
  in.dance_done = now_ns - d.start_ns >= d.duration_ns + d.settle_ns;
}

namespace {

// What the drives can deliver this tick, into the WBC's workspace: the ankle motors mapped at
// the sampled ankle angles, the serial leg drives' limits, the torque cap.
void bind_drive_limits_rt(DanceControl& d, const hal::SensorFrame& sensors) noexcept {
  if (d.ankle_motors.active) drivers::map_ankle_motors_rt(d.ankle_motors, sensors, d.stack.wbc.ankle_motor_limits);
  d.stack.wbc.serial_drive_limits = d.serial_drives;
  d.stack.wbc.torque_cap_Nm = d.torque_cap_Nm;
}

}  // namespace

bool dance_step_rt(DanceControl& d, control::StandingState& standing, const hal::SensorFrame& sensors,
                   hal::TimeNs now_ns, hal::CommandFrame& out) noexcept {
  if (!d.running) {
    if (!stack::stack_begin_rt(*d.model, d.config, d.stack, *d.motion, d.first_plan, sensors, 0)) {
      ++d.counters.begin_failures;
      return false;
    }
    d.running = true;
    d.danced = true;
    d.epoch = d.epoch + 1 == 0 ? 1 : d.epoch + 1;  // 0 means "idle"
    d.start_ns = now_ns;
    d.plan_stamp_ns = now_ns;  // the first plan (the motion's knots) counts as delivered now
    d.on_kinematic_fallback = false;
  }
  const hal::TimeNs t_ns = now_ns - d.start_ns;
  bind_drive_limits_rt(d, sensors);
  d.last_wbc = stack::stack_control_tick_rt(*d.model, d.config, d.stack, sensors, t_ns, stack::StateOverride{}, out);
  if (d.last_wbc != wbc::WbcStatus::kOk) ++d.counters.wbc_not_ok_ticks;
  // Finishing, the gains fade and the robot sags under the controller, which answers with
  // references that may run far past a stop (the ankles, seen at 0.052 rad in the
  // firmware-in-the-loop dance with the plan blend): they are put on the stop, counted apart.
  if (d.finishing) {
    limit_references_rt(*d.model, std::numeric_limits<double>::infinity(), out, d.counters.finish_references_limited);
  } else {
    limit_references_rt(*d.model, kReferenceLimitSlack_rad, out, d.counters.references_limited);
  }
  saturate_torques_rt(*d.model, out, d.counters);
  publish_request_rt(d, d.epoch, t_ns);
  if (t_ns < d.blend_ns) {
    control::standing_step_rt(*d.model, standing, sensors, d.standing_command);
    blend_torque_laws_rt(d.standing_command, static_cast<double>(t_ns) / static_cast<double>(d.blend_ns), out);
  }
  return true;
}

void dance_rehearse_rt(DanceControl& d, Mode mode, const hal::SensorFrame& sensors) noexcept {
  if (!d.rehearse || d.running || d.danced || d.model == nullptr) return;
  if (mode != Mode::kStandUp && mode != Mode::kReady) return;
  const stack::StageClock clock = d.stack.stage_clock;
  d.stack.stage_clock = nullptr;
  bool ok = stack::stack_begin_rt(*d.model, d.config, d.stack, *d.motion, d.first_plan, sensors, 0);
  if (ok) {
    bind_drive_limits_rt(d, sensors);
    ok = stack::stack_control_tick_rt(*d.model, d.config, d.stack, sensors, 0, stack::StateOverride{},
                                      d.rehearsal_command) == wbc::WbcStatus::kOk;
  }
  d.stack.started = false;
  d.stack.stage_clock = clock;
  ++d.rehearsals;
  if (!ok) ++d.rehearsal_failures;
}

namespace {

// DancePlanner's rehearsal: the opening planned from a cold start, the plan discarded.
void rehearse_opening_rt(DancePlanner& p) noexcept {
  // Before the dance only: afterwards the workspace keeps the dance's counters for the summary.
  // dance_init sets model, config and motion together.
  if (!p.rehearse || p.plans != 0 || p.motion == nullptr) return;
  if (p.config->planner != stack::PlannerKind::kMpc) return;
  stack::PlannerWorkspace& ws = p.ws;
  const auto failures = ws.mpc_failures;
  const auto on_a_stop = ws.plan_positions_on_a_stop;
  stack::stack_reset_planner_rt(*p.config, ws);
  stack::stack_plan_rt(*p.model, *p.config, ws, *p.motion, p.motion->q[0], dynamics::VelocityVector::Zero(), 0,
                       p.rehearsal_plan);
  ++p.rehearsals;
  p.rehearsal_failures += ws.mpc_failures - failures;
  ws.mpc_failures = failures;
  ws.plan_positions_on_a_stop = on_a_stop;
}

}  // namespace

bool dance_plan_rt(DancePlanner& p, DanceChannels& channels) noexcept {
  channels.request.update_rt();
  if (!channels.request.has_value() || channels.request.front_rt().epoch == 0) {
    p.epoch = 0;
    rehearse_opening_rt(p);
    return false;
  }
  const PlanRequest& r = channels.request.front_rt();
  if (r.epoch == p.epoch && r.sequence == p.last_sequence) return false;
  if (r.epoch != p.epoch) {
    stack::stack_reset_planner_rt(*p.config, p.ws);
    p.epoch = r.epoch;
  }
  p.last_sequence = r.sequence;
  p.ws.mpc.ankle_motor_limits = r.ankle_motors;
  PlanMessage& m = channels.plan.back_rt();
  m.epoch = r.epoch;
  stack::stack_plan_rt(*p.model, *p.config, p.ws, *p.motion, r.q, r.v, r.t_state_ns, m.plan);
  ++p.plans;
  return true;
}

void CycleController::operator()(const hal::SensorFrame& sensors, hal::CommandFrame& out) const noexcept {
  const Mode m = fw->mode.mode;
  if (dance != nullptr && (m == Mode::kDance || (m == Mode::kFinish && dance->running))) {
    dance->finishing = m == Mode::kFinish;
    if (dance_step_rt(*dance, fw->standing, sensors, fw->now_ns, out)) return;
    // The stack refused to start (sensors unusable for the estimator): keep standing and
    // try again next tick; the watchdogs judge the sensors.
  }
  control::standing_step_rt(*fw->model, fw->standing, sensors, out);
}

}  // namespace kuavo::firmware
