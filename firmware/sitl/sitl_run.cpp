#include "firmware/sitl/sitl_run.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "drivers/bus/bus_plan.h"
#include "rtos_shim/clock.h"
#include "sim/closed_loop.h"
#include "sim/run_log.h"

namespace kuavo::firmware::sitl {
namespace {

// A run that cannot reach ready in this long has failed its stand-up (it takes ~2.5 s:
// boot, self-check, the 2 s stand-up ramp).
constexpr hal::TimeNs kBringUpMax_ns = 10'000'000'000;
// After a fault or a fall the run goes on this long (damping on the wire), then ends.
constexpr hal::TimeNs kAfterEnd_ns = 500'000'000;
// Beyond the motion: the settle (0.5 s), the finish fade (1 s), damping (0.5 s) and slack.
constexpr hal::TimeNs kDanceSlack_ns = 5'000'000'000;
// A tick is a deadline miss if the control task took longer than its period, a planner
// iteration if it took longer than its own (wall clock on this machine, not real time).
constexpr double kUs_per_ns = 1e-3;

std::string log_header(const model::Model& m) {
  std::string h = "time_s,mode,fault,base_x_m,base_y_m,base_z_m,base_qx,base_qy,base_qz,base_qw";
  for (int j = 0; j < model::kNumJoints; ++j) h += std::string(",q_") + model::joint_name(m, j);
  for (int j = 0; j < model::kNumJoints; ++j) h += std::string(",qref_") + model::joint_name(m, j);
  for (int j = 0; j < model::kNumJoints; ++j) h += std::string(",tau_") + model::joint_name(m, j);
  h += ",com_x_m,com_y_m,com_z_m\n";
  return h;
}

// Reply frames the emulators have not sent so far (lost or silenced).
std::uint64_t frames_not_sent(const FirmwareLoop& loop) {
  std::uint64_t n = 0;
  for (std::size_t b = 0; b < loop.buses(); ++b) {
    n += loop.ruiwo(b) != nullptr ? loop.ruiwo(b)->replies_dropped : loop.drives(b)->frames_dropped;
  }
  return n;
}

// One row per tick: virtual time, the firmware's mode and latched fault, the plant's truth,
// the command's position references (what went to the output stage) and the joint torques.
void write_row(double t_s, const Firmware& f, const sim::PlantTruth& truth, const hal::CommandFrame& cmd, sim::RunLog& log) {
  char row[16384];
  int n = std::snprintf(row, sizeof row, "%.3f,%d,%d", t_s, static_cast<int>(f.mode.mode), static_cast<int>(f.mode.latched));
  for (int i = 0; i < model::kNq; ++i) n += std::snprintf(row + n, sizeof row - n, ",%.9g", truth.q[i]);
  for (const hal::JointCommand& c : cmd.joints) n += std::snprintf(row + n, sizeof row - n, ",%.9g", c.position_ref_rad);
  for (int j = 0; j < model::kNumJoints; ++j) n += std::snprintf(row + n, sizeof row - n, ",%.6g", truth.joint_torque_Nm[j]);
  n += std::snprintf(row + n, sizeof row - n, ",%.9g,%.9g,%.9g\n", truth.com_m.x(), truth.com_m.y(), truth.com_m.z());
  log.write(row, static_cast<std::size_t>(n));
}

}  // namespace

SitlSummary run_firmware_sim(const model::Model& m, const planner::MotionPlan* motion, const SitlConfig& config) {
  SitlSummary out;
  sim::MotionSummary& ms = out.motion;
  sim::RunSummary& run = ms.run;
  out.legs = to_string(config.loop.legs);
  ms.planner = motion != nullptr ? "mpc" : "standing";
  ms.motion_duration_s = motion != nullptr ? planner::motion_plan_duration_s(*motion) : 0.0;

  auto loop = std::make_unique<FirmwareLoop>(m, config.loop);
  loop->set_allocation_counter(config.count_allocations);
  out.allocations_counted = config.count_allocations != nullptr;
  if (!loop->ok()) {
    run.ok = false;
    run.error = loop->error();
    return out;
  }
  stack::StackConfig stack_config = firmware_stack_config(config.loop.firmware);  // as kuavo_fw runs it
  planner::set_holdable_soles(stack_config.recovery, config.holdable_soles);
  stack_config.recovery.fast_swing_s = config.recovery_fast_swing_s;
  stack_config.estimator.stance_sink_m = config.surface_sink_m;
  if (motion != nullptr && !loop->enable_dance(*motion, stack_config, config.plan_latency_ns)) {
    run.ok = false;
    run.error = "dance: " + loop->error();
    return out;
  }
  sim::RunLog log(config.log_path);
  if (log.failed_to_open(config.log_path)) {
    run.ok = false;
    run.error = "cannot write log '" + config.log_path + "'";
    return out;
  }
  log.write(log_header(m));

  Firmware& f = FirmwareLoop::fw();
  const DanceControl& dc = FirmwareLoop::dance();
  auto metrics_data = std::make_unique<dynamics::Data>();
  planner::PlanKnot knot;
  double sq_legs = 0.0, sq_arms = 0.0, sq_vel = 0.0, sq_tilt = 0.0;
  std::uint64_t tracked = 0;
  ms.zmp_margin_m_min = 1e9;
  run.min_base_height_m = loop->plant().truth().q[2];
  std::vector<double> qp_iterations;
  qp_iterations.reserve(1 << 16);
  std::size_t allocs_before = 0, planner_allocs_before = 0;
  bool dance_requested = false;
  hal::TimeNs end_at_ns = -1;  // the run ends at this time (fault, fall, done)
  InjectionReport& injection = out.injection;
  out.injected = config.inject_fault && motion != nullptr;
  injection.requested = config.inject;
  const hal::TimeNs inject_after_ns = static_cast<hal::TimeNs>(std::llround(config.inject.at_s * 1e9));
  hal::TimeNs armed_ns = -1;
  std::uint64_t not_sent_before = 0;
  const hal::TimeNs t0_ns = loop->now_ns();
  const rtos::TimeNs wall_start = rtos::now_ns();

  auto step = [&](CycleInputs in) {
    loop->tick(in);
    const double t_s = 1e-9 * static_cast<double>(loop->now_ns());
    const sim::PlantTruth& truth = loop->plant().truth();
    ++run.control_ticks;
    // Once the dance has ended in damping (on the gantry since finish) the run waits out
    // kuavo_fw's 0.5 s of damping: nothing after that is the dance's.
    const bool dance_over = loop->control_task().danced_until_ns >= 0;
    if (!loop->on_gantry() && !dance_over) sim::record_plant_state(truth, t_s, run);
    if (!dance_over && f.mode.latched != Fault::kNone && (out.faults.empty() || out.faults.back() != f.mode.latched)) {
      out.faults.push_back(f.mode.latched);
      if (out.fault_at_s < 0.0) out.fault_at_s = t_s;
    }
    if (f.mode.mode == Mode::kDance && motion != nullptr) {
      qp_iterations.push_back(dc.stack.wbc.diagnostics.qp_iterations);
      if (!run.fell) {
        // The motion at its own clock: behind by the planner's lift-off hold lag (liftoff_hold.h).
        planner::motion_plan_sample_rt(m, *metrics_data, *motion,
                                       loop->now_ns() - dc.start_ns - FirmwareLoop::planner().ws.liftoff.lag_ns, knot);
        const auto e = (truth.q.tail<model::kNumJoints>() - knot.q.tail<model::kNumJoints>()).eval();
        sq_legs += e.head<2 * model::kLegJoints>().squaredNorm() / (2 * model::kLegJoints);
        sq_arms += e.segment<2 * model::kArmJoints>(model::kLeftArmFirst).squaredNorm() / (2 * model::kArmJoints);
        const Eigen::Quaterniond base(truth.q[6], truth.q[3], truth.q[4], truth.q[5]);
        const sim::Vec3 v_world = base * truth.v.head<3>();
        const estimator::EstimateOutput& est = dc.stack.estimate;
        sq_vel += (est.base_velocity_world_m_s - v_world).squaredNorm();
        sq_tilt += std::pow(sim::tilt_error_deg(est.q, truth.q), 2);
        ms.com_over_feet_err_m_end = sim::com_over_feet_error_m(dc.stack.wbc, truth);
        ++tracked;
        ms.com_err_m_max = std::max(ms.com_err_m_max, (truth.com_m - knot.com_position_m).norm());
        const sim::Balance bal = sim::balance_of(truth);
        if (bal.defined) ms.zmp_margin_m_min = std::min(ms.zmp_margin_m_min, bal.margin_m);
        if (bal.defined && bal.margin_m < 1e-3) ms.zmp_at_edge_s += 1e-9 * static_cast<double>(kTick_ns);
        const double pos_err = (est.q.head<2>() - truth.q.head<2>()).norm();
        ms.estimator_position_err_m_max = std::max(ms.estimator_position_err_m_max, pos_err);
        ms.estimator_position_drift_m = pos_err;
      }
    }
    // The drill's outcome: the first fault latched from the tick it was armed before, and the
    // first tick from then whose command damps every joint under that fault (a dance that
    // ends in finish also reaches damping, with no fault: not the drill's).
    if (armed_ns >= 0) {
      if (injection.fault == Fault::kNone) injection.fault = f.mode.latched;
      if (injection.latency_to_damping_ms < 0.0 && injection.fault != Fault::kNone && hal::all_damping(loop->command())) {
        injection.latency_to_damping_ms = 1e-6 * static_cast<double>(loop->now_ns() - kTick_ns - armed_ns);
      }
    }
    write_row(t_s, f, truth, loop->command(), log);
    if (loop->plant_failed()) {
      run.ok = false;
      run.error = loop->plant_error();
    }
  };

  // Boot, self-check, stand-up on the gantry.
  while (f.mode.mode != Mode::kReady && loop->now_ns() - t0_ns < kBringUpMax_ns && f.mode.latched == Fault::kNone) {
    CycleInputs in;
    if (f.mode.mode == Mode::kDamping) in.request = Request::kStandUp;
    step(in);
  }
  if (f.mode.mode != Mode::kReady) {
    run.ok = run.ok && f.mode.latched != Fault::kNone;  // a fault is a result, a timeout is not
    if (f.mode.latched == Fault::kNone) run.error = "did not reach ready";
  } else {
    loop->release_gantry();
    const hal::TimeNs released_ns = loop->now_ns();
    const hal::TimeNs stand_ns = static_cast<hal::TimeNs>(std::llround(config.stand_s * 1e9));
    const hal::TimeNs limit_ns =
        motion != nullptr ? released_ns + config.settle_ns + static_cast<hal::TimeNs>(ms.motion_duration_s * 1e9) + kDanceSlack_ns
                          : released_ns + stand_ns;
    while (run.ok && loop->now_ns() < limit_ns) {
      CycleInputs in;
      if (motion != nullptr && !dance_requested && loop->now_ns() - released_ns >= config.settle_ns && f.mode.mode == Mode::kReady) {
        in.request = Request::kDance;
        dance_requested = true;
        allocs_before = loop->allocations_in_cycle();
        planner_allocs_before = loop->planner_allocations();
      }
      if (out.injected && armed_ns < 0 && injection.error.empty() && f.mode.mode == Mode::kDance &&
          loop->now_ns() - dc.start_ns >= inject_after_ns) {
        injection.armed = arm_fault_drill(*loop, config.inject.kind, injection.target, injection.error);
        if (!injection.armed) {
          run.ok = false;
          run.error = std::string("inject ") + to_string(config.inject.kind) + ": " + injection.error;
          break;
        }
        armed_ns = loop->now_ns();
        not_sent_before = frames_not_sent(*loop);
        injection.armed_at_s = 1e-9 * static_cast<double>(armed_ns);
      }
      step(in);
      // A show ends as it began, on the gantry: finish fades every gain and the feed-forward
      // to damping, which no free-standing robot survives (left standing, the built-in
      // dance's finish folded the robot into a squat, ankles 0.2 rad past their stops at
      // 0.93 s of the 1 s fade: fault 21).
      if (motion != nullptr && f.mode.mode == Mode::kFinish && !loop->on_gantry()) loop->hang_on_gantry();
      if (end_at_ns < 0 && (f.mode.latched != Fault::kNone || run.fell)) end_at_ns = loop->now_ns() + kAfterEnd_ns;
      if (loop->control_task().done || (end_at_ns >= 0 && loop->now_ns() >= end_at_ns)) break;
    }
  }
  const double wall_s = 1e-9 * static_cast<double>(rtos::now_ns() - wall_start);
  sim::finish_run_summary(loop->plant(), wall_s, log.digest(), run);
  run.sim_time_s = 1e-9 * static_cast<double>(loop->now_ns());  // the plant's clock stops on the gantry
  run.real_time_factor = wall_s > 0.0 ? run.sim_time_s / wall_s : 0.0;

  if (tracked > 0) {
    ms.tracking_rms_legs_rad = std::sqrt(sq_legs / static_cast<double>(tracked));
    ms.tracking_rms_arms_rad = std::sqrt(sq_arms / static_cast<double>(tracked));
    ms.estimator_velocity_rms_m_s = std::sqrt(sq_vel / static_cast<double>(tracked));
    ms.estimator_tilt_err_deg_rms = std::sqrt(sq_tilt / static_cast<double>(tracked));
  }
  if (ms.zmp_margin_m_min > 1e8) ms.zmp_margin_m_min = 0.0;
  ms.wbc_us = sim::percentiles(loop->dance_cycle_us());
  ms.mpc_ms = sim::percentiles(loop->plan_ms());
  ms.wbc_qp_iterations = sim::percentiles(qp_iterations);
  for (double us : loop->dance_cycle_us()) ms.deadline_misses += us > kUs_per_ns * static_cast<double>(f.config.control_period_ns);
  for (double ms_ : loop->plan_ms()) ms.deadline_misses += ms_ * 1e6 > static_cast<double>(f.config.planner_period_ns);
  ms.wbc_not_ok_ticks = dc.counters.wbc_not_ok_ticks;
  ms.plans_applied = dc.counters.plans_taken;
  ms.plans_skipped = dc.counters.plans_rejected + dc.counters.plans_old_epoch;
  sim::copy_planner_counters(FirmwareLoop::planner().ws, ms);
  ms.recovery_fast_swing_s = motion != nullptr && stack_config.recovery.enabled ? stack_config.recovery.fast_swing_s : 0.0;
  ms.stance_sink_m = motion != nullptr ? stack_config.estimator.stance_sink_m : 0.0;

  out.final_mode = to_string(f.mode.mode);
  if (dance_requested && dc.start_ns > 0) out.dance_started_at_s = 1e-9 * static_cast<double>(dc.start_ns);
  out.danced_to_end = motion != nullptr && loop->control_task().danced_until_ns >= 0 && out.faults.empty() && !run.fell;
  out.dance = dc.counters;
  out.rehearsals = FirmwareLoop::planner().rehearsals;
  out.rehearsal_failures = FirmwareLoop::planner().rehearsal_failures;
  out.control_rehearsals = dc.rehearsals;
  out.control_rehearsal_failures = dc.rehearsal_failures;
  for (const CanopenBusIo& c : loop->io().canopen) {
    for (std::size_t i = 0; i < c.st.size(); ++i) {
      if (c.slot[i] < 2 * model::kLegJoints) out.leg_torque_clamps[static_cast<std::size_t>(c.slot[i] % model::kLegJoints)] += c.st[i].torque_clamps;
      out.refused_commands += c.st[i].refused_commands;
    }
  }
  for (const auto& r : loop->io().ruiwo) {
    for (int i = 0; i < r.count; ++i) out.ruiwo_clamp_events += r.state[i].clamp_events;
  }
  if (armed_ns >= 0) injection.frames_lost = frames_not_sent(*loop) - not_sent_before;
  out.csp_holds = loop->csp_holds();
  out.drive_loop_saturations = loop->drive_loop_saturations();
  out.binding_failures = loop->binding_failures();
  out.wire = loop->wire_check();
  if (dance_requested) {
    out.allocations_control = loop->allocations_in_cycle() - allocs_before;
    out.allocations_planner = loop->planner_allocations() - planner_allocs_before;
  }
  const drivers::BusLoadReport load = drivers::compute_bus_load(loop->drivers_config().plan);
  const double seconds = std::max(1e-9, 1e-9 * static_cast<double>(loop->now_ns()));
  for (std::size_t b = 0; b < loop->buses(); ++b) {
    BusFigures bf;
    bf.interface = loop->drivers_config().plan.buses[b].interface;
    bf.planned_load = b < load.load.size() ? load.load[b] : 0.0;
    const double frames = loop->ruiwo(b) != nullptr ? loop->ruiwo(b)->frames_in + loop->ruiwo(b)->replies_out
                                                    : loop->drives(b)->frames_in + loop->drives(b)->frames_out;
    bf.frames_per_s = frames / seconds;
    out.buses.push_back(bf);
  }
  return out;
}

std::string sitl_summary_json(const SitlSummary& s) {
  std::string j = sim::motion_summary_json(s.motion);
  j.resize(j.rfind('}'));  // reopen the object
  while (!j.empty() && (j.back() == '\n' || j.back() == ' ')) j.pop_back();
  char buf[1024];
  auto add = [&](const char* fmt, auto... args) {
    std::snprintf(buf, sizeof buf, fmt, args...);
    j += buf;
  };
  const auto u = [](std::uint64_t v) { return static_cast<unsigned long long>(v); };
  add(",\n  \"legs\": \"%s\",\n  \"final_mode\": \"%s\",\n  \"danced_to_end\": %s,\n  \"faults\": [", s.legs.c_str(),
      s.final_mode.c_str(), s.danced_to_end ? "true" : "false");
  for (std::size_t i = 0; i < s.faults.size(); ++i) {
    add("%s{\"number\": %d, \"name\": \"%s\"}", i ? ", " : "", static_cast<int>(s.faults[i]), to_string(s.faults[i]));
  }
  add("],\n  \"fault_at_s\": %.3f,\n  \"dance_started_at_s\": %.3f,\n", s.fault_at_s, s.dance_started_at_s);
  add("  \"planner_rehearsals\": {\"runs\": %llu, \"failures\": %llu},\n", u(s.rehearsals), u(s.rehearsal_failures));
  add("  \"control_rehearsals\": {\"runs\": %llu, \"failures\": %llu},\n", u(s.control_rehearsals),
      u(s.control_rehearsal_failures));
  add("  \"output_stage\": {\"references_put_on_a_stop\": %llu, \"finish_references_put_on_a_stop\": %llu, "
      "\"torques_clipped_at_peak\": %llu, \"max_torque_demand_x_peak\": %.3f},\n",
      u(s.dance.references_limited), u(s.dance.finish_references_limited), u(s.dance.torques_saturated),
      s.dance.max_torque_demand_x);
  add("  \"drivers\": {\"leg_torque_clamps_per_slot\": [%llu, %llu, %llu, %llu, %llu, %llu], \"refused_commands\": %llu, "
      "\"csp_holds\": %llu, \"drive_loop_saturations\": %llu, \"ruiwo_clamp_events\": %llu, \"binding_failures\": %llu},\n",
      u(s.leg_torque_clamps[0]), u(s.leg_torque_clamps[1]), u(s.leg_torque_clamps[2]), u(s.leg_torque_clamps[3]),
      u(s.leg_torque_clamps[4]), u(s.leg_torque_clamps[5]), u(s.refused_commands), u(s.csp_holds),
      u(s.drive_loop_saturations), u(s.ruiwo_clamp_events), u(s.binding_failures));
  add("  \"wire\": {\"frames_inspected\": %llu, \"bad_values\": %llu, \"nonfinite_repairs\": %llu},\n",
      u(s.wire.frames_inspected), u(s.wire.bad_values), u(s.wire.nonfinite_clamps));
  if (s.injected) {
    const InjectionReport& r = s.injection;
    add("  \"injection\": {\"kind\": \"%s\", \"at_dance_s\": %.3f, \"armed\": %s, \"target\": \"%s\", \"armed_at_s\": %.3f, ",
        to_string(r.requested.kind), r.requested.at_s, r.armed ? "true" : "false", r.target.c_str(), r.armed_at_s);
    if (r.fault != Fault::kNone) {
      add("\"fault\": {\"number\": %d, \"name\": \"%s\"}, ", static_cast<int>(r.fault), to_string(r.fault));
    } else {
      j += "\"fault\": null, ";
    }
    if (r.latency_to_damping_ms >= 0.0) {
      add("\"latency_to_damping_ms\": %.1f, ", r.latency_to_damping_ms);
    } else {
      j += "\"latency_to_damping_ms\": null, ";
    }
    add("\"frames_lost\": %llu},\n", u(r.frames_lost));
  }
  if (s.allocations_counted) {
    add("  \"allocations_while_dancing\": {\"control\": %zu, \"planner\": %zu},\n", s.allocations_control, s.allocations_planner);
  }
  j += "  \"buses\": [";
  for (std::size_t b = 0; b < s.buses.size(); ++b) {
    add("%s\n    {\"interface\": \"%s\", \"planned_load\": %.4f, \"frames_per_s\": %.1f}", b ? "," : "",
        s.buses[b].interface.c_str(), s.buses[b].planned_load, s.buses[b].frames_per_s);
  }
  j += "\n  ]\n}\n";
  return j;
}

}  // namespace kuavo::firmware::sitl
