#include "sim/motion_loop.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <type_traits>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/standing/standing_controller.h"
#include "rtos_shim/clock.h"
#include "rtos_shim/lockstep_scheduler.h"
#include "sim/mujoco_plant.h"
#include "sim/run_log.h"
#include "sim/sensor_model.h"
#include "controllers/planner/support_polygon.h"

namespace kuavo::sim {
namespace {

// A foot carries load when its corners push this hard together; the centre of pressure
// is defined once all contacts push this hard (light touches would make it jump).
constexpr double kFootLoaded_N = 20.0;
constexpr double kCopDefined_N = 50.0;
constexpr int kCornersPerFoot = planner::kCornersPerFoot;
constexpr double kAtEdge_m = 1e-3;

std::string log_header(const model::Model& model) {
  std::string h = "time_s,base_x_m,base_y_m,base_z_m,base_qx,base_qy,base_qz,base_qw";
  for (int j = 0; j < model::kNumJoints; ++j) h += std::string(",q_") + model::joint_name(model, j);
  for (int j = 0; j < model::kNumJoints; ++j) h += std::string(",tau_") + model::joint_name(model, j);
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    for (const char* a : {"x", "y", "z"}) h += std::string(",f_") + model::frame_name(model, c) + "_" + a;
  }
  for (int j = 0; j < model::kNumJoints; ++j) h += std::string(",qref_") + model::joint_name(model, j);
  h += ",com_x_m,com_y_m,com_z_m,comref_x_m,comref_y_m,comref_z_m,zmp_x_m,zmp_y_m,zmp_margin_m";
  h += ",est_x_m,est_y_m,est_z_m,est_vx_m_s,est_vy_m_s,est_vz_m_s,wbc_status\n";
  return h;
}

}  // namespace

Balance balance_of(const PlantTruth& t) {
  Balance b;
  std::array<Eigen::Vector2d, model::kNumContactPoints> corners{};
  int n = 0;
  double fz_total = 0.0;
  Eigen::Vector2d moment = Eigen::Vector2d::Zero();
  for (int foot = 0; foot < 2; ++foot) {
    double fz = 0.0;
    for (int c = foot * kCornersPerFoot; c < (foot + 1) * kCornersPerFoot; ++c) fz += t.contact_force_N[c].z();
    if (fz < kFootLoaded_N) continue;
    for (int c = foot * kCornersPerFoot; c < (foot + 1) * kCornersPerFoot; ++c) {
      corners[n++] = t.contact_point_m[c].head<2>();
      fz_total += t.contact_force_N[c].z();
      moment += t.contact_force_N[c].z() * t.contact_point_m[c].head<2>();
    }
  }
  if (fz_total < kCopDefined_N || n < 3) return b;
  b.defined = true;
  b.cop = moment / fz_total;
  const auto hull = planner::convex_hull<model::kNumContactPoints>(corners, n);
  b.margin_m = planner::signed_margin(hull, b.cop);
  b.lo = b.hi = corners[0];
  for (int i = 1; i < n; ++i) b.lo = b.lo.cwiseMin(corners[i]), b.hi = b.hi.cwiseMax(corners[i]);
  return b;
}

Percentiles percentiles(std::vector<double> samples) {
  Percentiles p;
  if (samples.empty()) return p;
  std::sort(samples.begin(), samples.end());
  auto at = [&](double f) { return samples[std::min(samples.size() - 1, static_cast<std::size_t>(f * (samples.size() - 1) + 0.5))]; };
  p.p50 = at(0.5);
  p.p99 = at(0.99);
  p.max = samples.back();
  return p;
}

namespace {

// The loop over either plant (Plant, MujocoPlant): the same stack, sensors, log and figures.
template <class PlantT>
MotionSummary motion_run(const model::Model& model, const planner::MotionPlan& motion, const MotionRunConfig& config,
                         MotionTrace* trace) {
  MotionSummary out;
  RunSummary& run = out.run;
  run.engine = config.run.engine;
  out.planner = stack::to_string(config.stack.planner);
  out.motion_duration_s = planner::motion_plan_duration_s(motion);
  if (const char* why = stack::stack_validate_config(config.stack)) {
    run.ok = false;
    run.error = why;
    return out;
  }
  // Controller state in blocks allocated before the loop (static storage in the firmware).
  auto control = std::make_unique<stack::ControlWorkspace>();
  auto planner_ws = std::make_unique<stack::PlannerWorkspace>();
  auto pending = std::make_unique<planner::ReferencePlan>();
  auto metrics_data = std::make_unique<dynamics::Data>();

  // The plant's robot: the controller's model unless a perturbation is drawn.
  const PlantPerturbation& perturb = config.perturbation;
  auto plant_model = std::make_unique<model::Model>(model);
  if (perturb.active) {
    if (const char* why = validate_perturbation_set(perturb.set)) {
      run.ok = false;
      run.error = std::string("perturbation set: ") + why;
      return out;
    }
    perturbed_model(model, perturb, *plant_model);
    out.perturbation_json = perturbation_json(perturb, *plant_model);
  }
  // The ankle pairs as the robot has them (RunConfig::ankle_motors): the plant clips each
  // pair's two motors at the default drivers configuration's clamps, and the controller is
  // told each tick, as the firmware's binding tells it (drivers/transmission/ankle_motors.h).
  drivers::AnkleMotors ankle_motors = run_ankle_motors(model, config.run);
  const drivers::AnkleMotors* plant_ankles = ankle_motors.active ? &ankle_motors : nullptr;
  std::unique_ptr<PlantT> plant_owner;
  dynamics::ConfigVector q0 = motion.q[0];
  control::place_on_ground(model, *metrics_data, q0);
  if constexpr (std::is_same_v<PlantT, MujocoPlant>) {
    if (perturb.active) {
      run.ok = false;
      run.error = "perturbations (--perturb) apply to the simbody engine only";
      return out;
    }
    MujocoPlantConfig plant_cfg;
    plant_cfg.ground = config.run.ground;
    plant_cfg.ankle_motors = plant_ankles;
    plant_owner = std::make_unique<MujocoPlant>(model, plant_cfg);
    if (!plant_owner->ok()) {
      run.ok = false;
      run.error = plant_owner->last_error();
      return out;
    }
    reset_on_floor(*plant_owner, q0);
  } else {
    PlantConfig plant_cfg;
    plant_cfg.ground = perturbed_ground(config.run.ground, perturb);
    plant_cfg.integrator = config.run.integrator;
    plant_cfg.relative_tolerance = config.run.relative_tolerance;
    plant_cfg.absolute_tolerance = 0.1 * config.run.relative_tolerance;
    if (perturb.active) plant_cfg.actuation = &perturb.actuation;
    plant_cfg.ankle_motors = plant_ankles;
    plant_owner = std::make_unique<Plant>(*plant_model, plant_cfg);
    plant_owner->reset(q0, dynamics::VelocityVector::Zero());
  }
  PlantT& plant = *plant_owner;
  const GroundParams ground = perturbed_ground(config.run.ground, perturb);
  if (ground.terrain != nullptr) {
    // Raise the robot until its lowest corner touches the uneven ground (the others hang
    // above it and the robot settles: the stage is not the controller's flat floor).
    double lift_m = -1e9;
    for (const Vec3& c : plant.truth().contact_point_m) {
      lift_m = std::max(lift_m, terrain_height_m(*ground.terrain, c.x(), c.y()) - c.z());
    }
    q0[2] += lift_m;
    plant.reset(q0, dynamics::VelocityVector::Zero());
  }
  plant.set_push(config.run.push);

  SensorNoise noise;
  if (config.ideal_sensors) noise = SensorNoise{0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  SensorModel sensors(config.run.seed, noise);
  if (!config.imu_tilt_rad.isZero(0.0)) sensors.add_tilt(config.imu_tilt_rad.x(), config.imu_tilt_rad.y());
  if (perturb.active) sensors.set_errors(&perturb.sensors);
  // Command latency jitter: each tick's command reaches the drives a drawn delay into the
  // plant interval (the previous one acts until then); its own generator, so the other
  // draws of the run do not depend on it.
  const bool jitter = perturb.active && perturb.command_jitter_s.hi > 0.0;
  std::mt19937_64 jitter_rng(perturb.seed ^ 0x6a09e667f3bcc909ULL);
  hal::CommandFrame arriving_command;
  bool command_arriving = false;
  RunLog log(config.run.log_path);
  if (log.failed_to_open(config.run.log_path)) {
    run.ok = false;
    run.error = "cannot write log '" + config.run.log_path + "'";
    return out;
  }
  log.write(log_header(model));

  hal::SensorFrame frame;
  sensors.sample(plant.truth(), 0, frame);
  if (!stack::stack_start(model, config.stack, *control, *planner_ws, motion, frame, 0)) {
    run.ok = false;
    run.error = "the online stack did not start (estimator reset or configuration)";
    return out;
  }

  const rtos::TimeNs period_ns = static_cast<rtos::TimeNs>(std::llround(config.stack.wbc.dt_s * 1e9));
  const rtos::TimeNs plan_period_ns = static_cast<rtos::TimeNs>(std::llround(config.stack.plan_period_s * 1e9));
  const double duration_s = config.run.duration_s > 0.0 ? config.run.duration_s : out.motion_duration_s + config.settle_s;
  rtos::LockstepConfig sched_cfg;
  sched_cfg.control_period_ns = period_ns;
  sched_cfg.plan_period_ns = plan_period_ns;
  sched_cfg.plan_delay_ns = rtos::round_up_to_multiple_ns(
      static_cast<rtos::TimeNs>(std::llround(std::max(0.0, config.plan_latency_s) * 1e9)), period_ns);
  sched_cfg.stop_ns = static_cast<rtos::TimeNs>(std::llround(duration_s * 1e9));
  rtos::LockstepScheduler sched;
  if (const auto err = sched.reset(sched_cfg); err != rtos::LockstepError::kOk) {
    run.ok = false;
    run.error = rtos::describe(err);
    return out;
  }

  const auto ticks = static_cast<std::size_t>(duration_s / config.stack.wbc.dt_s) + 2;
  std::vector<double> wbc_us, plan_ms, qp_iterations;
  wbc_us.reserve(ticks);
  qp_iterations.reserve(ticks);
  plan_ms.reserve(ticks / 5 + 2);
  std::vector<hal::CommandFrame> in_flight(static_cast<std::size_t>(std::max(0, config.run.command_latency_ticks)) + 1);
  std::size_t slot = 0;
  hal::CommandFrame command;
  planner::PlanKnot motion_now;  // the motion at this tick (metrics)
  double sq_legs = 0.0, sq_arms = 0.0, sq_vel = 0.0, sq_tilt = 0.0;
  std::uint64_t tracked = 0;
  bool have_com = false;
  Vec3 com_before = Vec3::Zero(), com_plan_before = Vec3::Zero();
  std::array<bool, 2> foot_loaded{true, true};
  std::array<double, 2> foot_loaded_at_s{-1.0, -1.0};
  out.zmp_margin_m_min = 1e9;
  wbc::WbcStatus last_status = wbc::WbcStatus::kOk;
  run.min_base_height_m = plant.truth().q[2];
  if (trace != nullptr) {
    const int stride = trace->stride;
    *trace = MotionTrace{};
    trace->stride = stride;
  }
  char row[16384];

  const rtos::TimeNs wall_start = rtos::now_ns();
  rtos::SimEvent ev;
  rtos::TimeNs next_progress_ns = 0;
  while (sched.next(ev)) {
    if (ev.kind == rtos::SimEventKind::kPlanApply) {
      stack::stack_apply_plan_rt(*control, *pending);
    } else if (ev.kind == rtos::SimEventKind::kControlTick) {
      if (config.on_progress && ev.time_ns >= next_progress_ns) {
        config.on_progress(1e-9 * static_cast<double>(ev.time_ns));
        next_progress_ns += static_cast<rtos::TimeNs>(MotionRunConfig::kProgressPeriod_s * 1e9);
      }
      const PlantTruth& truth = plant.truth();
      sensors.sample(truth, ev.time_ns, frame);
      stack::StateOverride state;
      if (config.use_truth_state) state = {&truth.q, &truth.v};
      const rtos::TimeNs t0 = rtos::now_ns();
      if (ankle_motors.active) drivers::map_ankle_motors_rt(ankle_motors, frame, control->wbc.ankle_motor_limits);
      last_status = stack::stack_control_tick_rt(model, config.stack, *control, frame, ev.time_ns, state, command);
      const double us = static_cast<double>(rtos::now_ns() - t0) * 1e-3;
      wbc_us.push_back(us);
      qp_iterations.push_back(control->wbc.diagnostics.qp_iterations);
      if (us * 1e3 > static_cast<double>(period_ns)) ++out.deadline_misses;
      if (last_status != wbc::WbcStatus::kOk) ++out.wbc_not_ok_ticks;
      in_flight[slot] = command;
      slot = (slot + 1) % in_flight.size();
      if (jitter) {
        arriving_command = in_flight[slot];
        command_arriving = true;
      } else {
        plant.set_command(in_flight[slot]);
      }
      ++run.control_ticks;
    } else if (ev.kind == rtos::SimEventKind::kPlanRequest) {
      const bool truth_state = config.use_truth_state;
      const dynamics::ConfigVector& q = truth_state ? plant.truth().q : control->estimate.q;
      const dynamics::VelocityVector& v = truth_state ? plant.truth().v : control->estimate.v;
      const rtos::TimeNs t0 = rtos::now_ns();
      planner_ws->mpc.ankle_motor_limits = control->wbc.ankle_motor_limits;  // the last tick's map
      stack::stack_plan_rt(model, config.stack, *planner_ws, motion, q, v, ev.time_ns, *pending);
      const rtos::TimeNs spent_ns = rtos::now_ns() - t0;
      plan_ms.push_back(static_cast<double>(spent_ns) * 1e-6);
      if (spent_ns > plan_period_ns) ++out.deadline_misses;
      if (config.measured_plan_latency) sched.set_plan_delay_ns(rtos::round_up_to_multiple_ns(spent_ns, period_ns));
    } else if (ev.kind == rtos::SimEventKind::kPlantStep) {
      double step_s = static_cast<double>(ev.dt_ns) * 1e-9;
      if (command_arriving) {
        // Whole microseconds: no sliver intervals for the integrator.
        const double delay_s = std::min(step_s, std::floor(uniform_from_bits(jitter_rng(), perturb.command_jitter_s) * 1e6) * 1e-6);
        if (delay_s > 0.0 && plant.advance(delay_s) != PlantError::kOk) {
          run.ok = false;
          run.error = plant.last_error();
          break;
        }
        plant.set_command(arriving_command);
        command_arriving = false;
        step_s -= delay_s;
      }
      if (step_s > 0.0 && plant.advance(step_s) != PlantError::kOk) {
        run.ok = false;
        run.error = plant.last_error();
        break;
      }
      const double t_s = static_cast<double>(ev.time_ns + ev.dt_ns) * 1e-9;
      const PlantTruth& t = plant.truth();
      // The motion at its own clock: behind the wall clock by the lift-off hold's lag.
      planner::motion_plan_sample_rt(model, *metrics_data, motion, ev.time_ns + ev.dt_ns - planner_ws->liftoff.lag_ns,
                                     motion_now);
      const Balance bal = balance_of(t);
      record_plant_state(t, t_s, run);
      const Eigen::Quaterniond base(t.q[6], t.q[3], t.q[4], t.q[5]);
      const Vec3 v_world = base * t.v.head<3>();
      const estimator::EstimateOutput& est = control->estimate;
      if (!run.fell) {
        const auto e = (t.q.tail<model::kNumJoints>() - motion_now.q.tail<model::kNumJoints>()).eval();
        sq_legs += e.head<2 * model::kLegJoints>().squaredNorm() / (2 * model::kLegJoints);
        sq_arms += e.segment<2 * model::kArmJoints>(model::kLeftArmFirst).squaredNorm() / (2 * model::kArmJoints);
        sq_vel += (est.base_velocity_world_m_s - v_world).squaredNorm();
        sq_tilt += std::pow(tilt_error_deg(est.q, t.q), 2);
        out.com_over_feet_err_m_end = com_over_feet_error_m(control->wbc, t);
        ++tracked;
        out.com_err_m_max = std::max(out.com_err_m_max, (t.com_m - motion_now.com_position_m).norm());
        if (have_com) {
          out.com_path_m += (t.com_m - com_before).norm();
          out.com_path_plan_m += (motion_now.com_position_m - com_plan_before).norm();
        }
        have_com = true;
        com_before = t.com_m;
        com_plan_before = motion_now.com_position_m;
        for (int foot = 0; foot < 2; ++foot) {
          double fz = 0.0;
          for (int c = 4 * foot; c < 4 * foot + 4; ++c) fz += t.contact_force_N[c].z();
          if (foot_loaded[foot] && fz < kUnloaded_N) {
            out.steps += t_s - foot_loaded_at_s[foot] >= kMinStance_s;  // shorter: a bump before the lift
            foot_loaded[foot] = false;
          }
          if (!foot_loaded[foot] && fz > kLoaded_N) foot_loaded[foot] = true, foot_loaded_at_s[foot] = t_s;
        }
        if (bal.defined) out.zmp_margin_m_min = std::min(out.zmp_margin_m_min, bal.margin_m);
        std::array<double, model::kNumJoints> ratio;
        for (int j = 0; j < model::kNumJoints; ++j) ratio[j] = std::abs(t.joint_torque_Nm[j]) / model.limits.peak_torque_Nm[j];
        for (int leg = 0; leg < 2 && ankle_motors.active; ++leg) {  // the ankle slots: their motors, as the plant clips them
          const int j = (leg == 0 ? model::kLeftLegFirst : model::kRightLegFirst) + 4;
          Eigen::Vector2d motor;
          if (drivers::ankle_motor_torques_rt(ankle_motors, leg, Eigen::Vector2d(t.q[7 + j], t.q[8 + j]),
                                              Eigen::Vector2d(t.joint_torque_Nm[j], t.joint_torque_Nm[j + 1]), motor)) {
            for (int k = 0; k < 2; ++k) ratio[j + k] = std::abs(motor[k]) / ankle_motors.limit_Nm[leg](k);
          }
        }
        for (const double r : ratio) out.torque_ratio_max = std::max(out.torque_ratio_max, r);
        if (bal.defined && bal.margin_m < kAtEdge_m) out.zmp_at_edge_s += static_cast<double>(ev.dt_ns) * 1e-9;
        const double pos_err = (est.q.head<2>() - t.q.head<2>()).norm();
        out.estimator_position_err_m_max = std::max(out.estimator_position_err_m_max, pos_err);
        out.estimator_position_drift_m = pos_err;
      }
      int n = std::snprintf(row, sizeof row, "%.3f", t_s);
      for (int i = 0; i < model::kNq; ++i) n += std::snprintf(row + n, sizeof row - n, ",%.9g", t.q[i]);
      for (int j = 0; j < model::kNumJoints; ++j) n += std::snprintf(row + n, sizeof row - n, ",%.6g", t.joint_torque_Nm[j]);
      for (const auto& f : t.contact_force_N) n += std::snprintf(row + n, sizeof row - n, ",%.6g,%.6g,%.6g", f.x(), f.y(), f.z());
      for (int j = 0; j < model::kNumJoints; ++j) n += std::snprintf(row + n, sizeof row - n, ",%.9g", motion_now.q[7 + j]);
      n += std::snprintf(row + n, sizeof row - n, ",%.9g,%.9g,%.9g,%.9g,%.9g,%.9g", t.com_m.x(), t.com_m.y(), t.com_m.z(),
                         motion_now.com_position_m.x(), motion_now.com_position_m.y(), motion_now.com_position_m.z());
      if (bal.defined) {
        n += std::snprintf(row + n, sizeof row - n, ",%.6g,%.6g,%.6g", bal.cop.x(), bal.cop.y(), bal.margin_m);
      } else {
        n += std::snprintf(row + n, sizeof row - n, ",,,");
      }
      n += std::snprintf(row + n, sizeof row - n, ",%.9g,%.9g,%.9g,%.6g,%.6g,%.6g,%d\n", est.q[0], est.q[1], est.q[2],
                         est.base_velocity_world_m_s.x(), est.base_velocity_world_m_s.y(), est.base_velocity_world_m_s.z(),
                         static_cast<int>(last_status));
      log.write(row, static_cast<std::size_t>(n));

      if (trace != nullptr && (ev.index % static_cast<std::uint64_t>(std::max(1, trace->stride))) == 0) {
        trace->time_s.push_back(t_s);
        trace->com.push_back({t.com_m.x(), t.com_m.y(), t.com_m.z()});
        trace->com_ref.push_back({motion_now.com_position_m.x(), motion_now.com_position_m.y(), motion_now.com_position_m.z()});
        const double nan = std::nan("");
        trace->zmp.push_back(bal.defined ? std::array<double, 2>{bal.cop.x(), bal.cop.y()} : std::array<double, 2>{nan, nan});
        trace->zmp_margin_m.push_back(bal.defined ? bal.margin_m : nan);
        trace->support_lo.push_back(bal.defined ? std::array<double, 2>{bal.lo.x(), bal.lo.y()} : std::array<double, 2>{nan, nan});
        trace->support_hi.push_back(bal.defined ? std::array<double, 2>{bal.hi.x(), bal.hi.y()} : std::array<double, 2>{nan, nan});
        std::array<double, model::kNumJoints> qa{}, qr{};
        for (int j = 0; j < model::kNumJoints; ++j) qa[j] = t.q[7 + j], qr[j] = motion_now.q[7 + j];
        trace->q.push_back(qa);
        trace->q_ref.push_back(qr);
        trace->base_velocity.push_back({v_world.x(), v_world.y(), v_world.z()});
        std::array<double, 2> load{};
        for (int c = 0; c < model::kNumContactPoints; ++c) load[c < kCornersPerFoot ? 0 : 1] += t.contact_force_N[c].z();
        trace->foot_force_z_N.push_back(load);
        std::array<double, 4> feet{};
        for (int c = 0; c < model::kNumContactPoints; ++c) {
          const int foot = c < kCornersPerFoot ? 0 : 2;
          feet[foot] += t.contact_point_m[c].x() / kCornersPerFoot;
          feet[foot + 1] += t.contact_point_m[c].y() / kCornersPerFoot;
        }
        trace->foot_xy_m.push_back(feet);
        trace->base_velocity_est.push_back(
            {est.base_velocity_world_m_s.x(), est.base_velocity_world_m_s.y(), est.base_velocity_world_m_s.z()});
      }
      if (run.fell && t_s > run.fell_at_s + 0.5) break;  // nothing left to learn
    }
  }
  finish_run_summary(plant, static_cast<double>(rtos::now_ns() - wall_start) * 1e-9, log.digest(), run);
  if (tracked > 0) {
    out.tracking_rms_legs_rad = std::sqrt(sq_legs / tracked);
    out.tracking_rms_arms_rad = std::sqrt(sq_arms / tracked);
    out.estimator_velocity_rms_m_s = std::sqrt(sq_vel / tracked);
    out.estimator_tilt_err_deg_rms = std::sqrt(sq_tilt / tracked);
  }
  out.estimator_gated_corner_ticks = control->estimator.gated_corner_ticks;
  out.estimator_unloaded_foot_ticks = control->estimator_unloaded_foot_ticks;
  out.lean_trim = config.stack.lean_trim.enabled;
  out.lean_trim_opening = config.stack.lean_trim.learn == stack::LeanTrimLearn::kOpening;
  out.planner_sole_inset_m = config.stack.planner == stack::PlannerKind::kMpc ? config.stack.planner_sole_inset_m : 0.0;
  out.stance_sink_m = config.stack.estimator.stance_sink_m;
  out.recovery_fast_swing_s = config.stack.planner == stack::PlannerKind::kMpc && config.stack.recovery.enabled
                                  ? config.stack.recovery.fast_swing_s
                                  : 0.0;
  out.lean_trim_roll_deg = control->lean_trim.theta_rad.x() * 180.0 / 3.14159265358979323846;
  out.lean_trim_pitch_deg = control->lean_trim.theta_rad.y() * 180.0 / 3.14159265358979323846;
  out.lean_trim_integrated_ticks = control->lean_trim.integrated_ticks;
  out.lean_trim_saturated_ticks = control->lean_trim.saturated_ticks;
  if (out.zmp_margin_m_min > 1e8) out.zmp_margin_m_min = 0.0;
  out.wbc_us = percentiles(wbc_us);
  out.wbc_qp_iterations = percentiles(qp_iterations);
  out.mpc_ms = percentiles(plan_ms);
  out.plans_applied = sched.stats().plans_applied;
  out.plans_skipped = sched.stats().plans_skipped;
  copy_planner_counters(*planner_ws, out);
  return out;
}

}  // namespace

double tilt_error_deg(const dynamics::ConfigVector& believed_q, const dynamics::ConfigVector& true_q) {
  const Eigen::Quaterniond believed(believed_q[6], believed_q[3], believed_q[4], believed_q[5]);
  const Eigen::Quaterniond truth(true_q[6], true_q[3], true_q[4], true_q[5]);
  const double cos_tilt = std::clamp((believed * Vec3::UnitZ()).dot(truth * Vec3::UnitZ()), -1.0, 1.0);
  return std::acos(cos_tilt) * 180.0 / 3.14159265358979323846;
}

double com_over_feet_error_m(const wbc::WbcWorkspace& wbc, const PlantTruth& truth) {
  Vec3 feet_believed = Vec3::Zero(), feet_true = Vec3::Zero();
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    feet_believed += wbc.point_position_m.segment<3>(3 * c) / model::kNumContactPoints;
    feet_true += truth.contact_point_m[c] / model::kNumContactPoints;
  }
  return ((wbc.data.com_m - feet_believed) - (truth.com_m - feet_true)).head<2>().norm();
}

void copy_planner_counters(const stack::PlannerWorkspace& ws, MotionSummary& out) {
  out.mpc_failures = ws.mpc_failures;
  out.plan_positions_on_a_stop = ws.plan_positions_on_a_stop;
  out.recovery_steps = ws.recovery.steps;
  out.recovery_declined = ws.recovery.declined;
  out.recovery_fast_steps = ws.recovery.fast_steps;
  out.recovery_early_touchdowns = ws.recovery.early_touchdowns;
  out.liftoff_holds = ws.liftoff.holds;
  out.liftoff_released = ws.liftoff.released;
  out.motion_lag_s_max = 1e-9 * static_cast<double>(ws.liftoff.lag_max_ns);
  out.motion_lag_s_end = 1e-9 * static_cast<double>(ws.liftoff.lag_ns);
  out.anchor_reanchors = ws.anchor.reanchors;
  out.anchor_refused = ws.anchor.refused;
  out.anchor_offset_m_max = ws.anchor.offset_max_m;
}

MotionSummary run_motion(const model::Model& model, const planner::MotionPlan& motion, const MotionRunConfig& config,
                         MotionTrace* trace) {
  if (config.run.engine == Engine::kMujoco) return motion_run<MujocoPlant>(model, motion, config, trace);
  return motion_run<Plant>(model, motion, config, trace);
}

std::string motion_summary_json(const MotionSummary& s) {
  std::string base = summary_json(s.run);
  base.resize(base.rfind('}'));  // reopen the object
  while (!base.empty() && (base.back() == '\n' || base.back() == ' ')) base.pop_back();
  char buf[4096];
  std::snprintf(buf, sizeof buf,
                ",\n  \"planner\": \"%s\",\n  \"motion_duration_s\": %.3f,\n"
                "  \"tracking_rms_rad\": {\"legs\": %.5f, \"arms\": %.5f},\n"
                "  \"com_err_m_max\": %.5f,\n  \"com_path_m\": %.4f,\n  \"com_path_plan_m\": %.4f,\n  \"steps\": %d,\n"
                "  \"zmp_margin_m_min\": %.5f,\n  \"zmp_at_edge_s\": %.3f,\n"
                "  \"torque_ratio_max\": %.4f,\n"
                "  \"mpc_ms\": {\"p50\": %.4f, \"p99\": %.4f, \"max\": %.4f},\n"
                "  \"wbc_us\": {\"p50\": %.2f, \"p99\": %.2f, \"max\": %.2f},\n"
                "  \"wbc_qp_iterations\": {\"p50\": %.0f, \"p99\": %.0f, \"max\": %.0f},\n"
                "  \"deadline_misses\": %llu,\n  \"wbc_not_ok_ticks\": %llu,\n"
                "  \"plans_applied\": %llu,\n  \"plans_skipped\": %llu,\n  \"mpc_failures\": %llu,\n"
                "  \"plan_positions_on_a_stop\": %llu,\n  \"recovery_steps\": %llu,\n  \"recovery_declined\": %llu,\n  \"recovery_early_touchdowns\": %llu,\n"
                "  \"liftoff_holds\": %llu,\n  \"liftoff_released\": %llu,\n  \"motion_lag_s\": {\"max\": %.3f, \"end\": %.3f},\n"
                "  \"plan_anchor\": {\"reanchors\": %llu, \"refused\": %llu, \"offset_m_max\": %.4f},\n"
                "  \"estimator\": {\"velocity_rms_m_s\": %.5f, \"position_drift_m\": %.5f, \"position_err_m_max\": %.5f, \"gated_corner_ticks\": %llu, \"unloaded_foot_ticks\": %llu, \"tilt_err_deg_rms\": %.4f, \"com_over_feet_err_m_end\": %.5f}\n}\n",
                s.planner.c_str(), s.motion_duration_s, s.tracking_rms_legs_rad, s.tracking_rms_arms_rad, s.com_err_m_max,
                s.com_path_m, s.com_path_plan_m, s.steps, s.zmp_margin_m_min, s.zmp_at_edge_s, s.torque_ratio_max, s.mpc_ms.p50, s.mpc_ms.p99, s.mpc_ms.max, s.wbc_us.p50, s.wbc_us.p99, s.wbc_us.max,
                s.wbc_qp_iterations.p50, s.wbc_qp_iterations.p99, s.wbc_qp_iterations.max,
                static_cast<unsigned long long>(s.deadline_misses), static_cast<unsigned long long>(s.wbc_not_ok_ticks),
                static_cast<unsigned long long>(s.plans_applied), static_cast<unsigned long long>(s.plans_skipped), static_cast<unsigned long long>(s.mpc_failures),
                static_cast<unsigned long long>(s.plan_positions_on_a_stop), static_cast<unsigned long long>(s.recovery_steps),
                static_cast<unsigned long long>(s.recovery_declined), static_cast<unsigned long long>(s.recovery_early_touchdowns), static_cast<unsigned long long>(s.liftoff_holds),
                static_cast<unsigned long long>(s.liftoff_released), s.motion_lag_s_max, s.motion_lag_s_end,
                static_cast<unsigned long long>(s.anchor_reanchors), static_cast<unsigned long long>(s.anchor_refused),
                s.anchor_offset_m_max, s.estimator_velocity_rms_m_s, s.estimator_position_drift_m, s.estimator_position_err_m_max,
                static_cast<unsigned long long>(s.estimator_gated_corner_ticks),
                static_cast<unsigned long long>(s.estimator_unloaded_foot_ticks), s.estimator_tilt_err_deg_rms,
                s.com_over_feet_err_m_end);
  std::string json = base + buf;
  // One more key before the closing brace.
  const auto append = [&json](const std::string& key_and_value) {
    json.resize(json.rfind('}'));
    while (!json.empty() && (json.back() == '\n' || json.back() == ' ')) json.pop_back();
    json += ",\n  " + key_and_value + "\n}\n";
  };
  if (s.lean_trim) {
    std::snprintf(buf, sizeof buf,
                  "\"lean_trim\": {\"learn\": \"%s\", \"roll_deg\": %.4f, \"pitch_deg\": %.4f, \"integrated_ticks\": %llu, "
                  "\"saturated_ticks\": %llu}",
                  s.lean_trim_opening ? "opening" : "always", s.lean_trim_roll_deg, s.lean_trim_pitch_deg,
                  static_cast<unsigned long long>(s.lean_trim_integrated_ticks),
                  static_cast<unsigned long long>(s.lean_trim_saturated_ticks));
    append(buf);
  }
  if (s.planner_sole_inset_m > 0.0) {
    std::snprintf(buf, sizeof buf, "\"planner_sole_inset_m\": %.4f", s.planner_sole_inset_m);
    append(buf);
  }
  if (s.stance_sink_m > 0.0) {
    std::snprintf(buf, sizeof buf, "\"surface_sink_m\": %.4f", s.stance_sink_m);
    append(buf);
  }
  if (s.recovery_fast_swing_s > 0.0) {
    std::snprintf(buf, sizeof buf, "\"recovery_fast_swing\": {\"swing_s\": %.3f, \"steps\": %llu}", s.recovery_fast_swing_s,
                  static_cast<unsigned long long>(s.recovery_fast_steps));
    append(buf);
  }
  if (!s.perturbation_json.empty()) append("\"perturbation\": " + s.perturbation_json);
  return json;
}

}  // namespace kuavo::sim
