// Firmware in the loop, dancing: the firmware cycle with its dance mode (the online stack:
// estimator -> MPC at 50 Hz -> WBC at 500 Hz) and the drivers binding, against the bus
// emulators bound to the Simbody plant, in lockstep virtual time (the planner released
// every 20 ms, its plan landing 4 ms later). The motions are prefixes of the built-in
// dance, retargeted and balance-filtered as `kuavo retarget` + `kuavo_fw --dance` do:
// 1.95 s (weight shifts, arm swings: both feet down) and 5.95 s (plus eight side steps).
//
// Oracles independent of the controller: the plant's truth (base height, tilt, joint
// angles against the motion's frames), the frames the emulated devices decoded, the
// allocation trap around the real-time parts (control cycle and planning task).
//
// Finding (see firmware/README.md): on the CST leg binding -- the firmware evaluates the
// legs' PD at 500 Hz from last tick's TPDO sample, the drive applies the torque from the
// next SYNC, held for the tick -- the swing ankle goes unstable within ~40 ms of the first
// lift-off (ankle roll ±90 rad/s at ~125 Hz, then a reference past its stop: fault 31).
// Tried, none enough: ankle output kd ×0…2, kp ×0…1, all leg kd ×0.3 (fails at 2.2–2.7 s);
// ankle kp = kd = 0 (gets to 4.2 s, tilting 19°); the RPDO torque applied in the same tick
// (no change); the PD extrapolated over the sample's age (no change). The cure is the CSP
// binding: the leg drives close the PD in their own loop (gains written by SDO at start-up),
// the firmware sends target position + torque offset on RPDO1, the emulated drives decode
// them and the plant runs their loop continuously. The side steps are danced through it;
// the CST twin stays DISABLED_ as the record, and the test-only shortcut
// set_leg_pd_in_drive (the joint law copied into the plant) is kept for comparison.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "firmware/sitl/sitl_run.h"
#include "tests/firmware/dance_prefix.h"
#include "tests/firmware/firmware_loop.h"

namespace kuavo::firmware {
namespace {

using test_support::FirmwareLoop;
using test_support::make_dance_prefix;
using test_support::kTick_ns;

// Both feet stay down until the first side step lifts at 2.0 s; the side steps end at
// 5.9 s (the last swing: 5.5 s + 0.4 s) and the next step lifts at 6.0 s.
constexpr double kBeforeSteps_s = 1.95;
constexpr double kWithSideSteps_s = 5.95;

const planner::MotionPlan& before_steps() {
  static const planner::MotionPlan* plan = make_dance_prefix(kBeforeSteps_s);
  return *plan;
}
const planner::MotionPlan& with_side_steps() {
  static const planner::MotionPlan* plan = make_dance_prefix(kWithSideSteps_s);
  return *plan;
}

// What the robot image runs (kuavo_fw, kuavo_fw_sim).
stack::StackConfig mpc_stack() { return firmware_stack_config(FirmwareConfig{}); }

void expect_clean_wire(const FirmwareLoop& loop) {
  EXPECT_EQ(loop.wire_check().bad_values, 0u) << loop.wire_check().first_bad;
  EXPECT_EQ(loop.wire_check().nonfinite_clamps, 0u);
  EXPECT_GT(loop.wire_check().frames_inspected, 1000u);
  EXPECT_FALSE(loop.plant_failed());
}

bool command_finite(const hal::CommandFrame& c) {
  for (const hal::JointCommand& j : c.joints) {
    if (!std::isfinite(j.position_ref_rad) || !std::isfinite(j.velocity_ref_rad_s) || !std::isfinite(j.torque_ff_Nm) ||
        !std::isfinite(j.kp_Nm_per_rad) || !std::isfinite(j.kd_Nm_s_per_rad)) {
      return false;
    }
  }
  return true;
}

// The torque the command's law gives at the measured joint state.
dynamics::JointVector effective_torque(const hal::CommandFrame& c, const hal::SensorFrame& s) {
  dynamics::JointVector tau = dynamics::JointVector::Zero();
  for (int j = 0; j < model::kNumJoints; ++j) {
    const hal::JointCommand& k = c.joints[j];
    if (k.mode != hal::JointMode::kPdTorque) continue;
    tau[j] = k.torque_ff_Nm + k.kp_Nm_per_rad * (k.position_ref_rad - s.joints[j].position_rad) +
             k.kd_Nm_s_per_rad * (k.velocity_ref_rad_s - s.joints[j].velocity_rad_s);
  }
  return tau;
}

// Brings the loop to ready with the dance loaded and asks for the dance.
void start_dance(FirmwareLoop& loop, const planner::MotionPlan& motion) {
  ASSERT_TRUE(loop.ok());
  ASSERT_TRUE(loop.enable_dance(motion, mpc_stack()));
  ASSERT_TRUE(loop.bring_up()) << to_string(FirmwareLoop::fw().mode.latched);
  CycleInputs in;
  in.request = Request::kDance;
  loop.tick(in);
  ASSERT_EQ(FirmwareLoop::fw().mode.mode, Mode::kDance);
  ASSERT_TRUE(FirmwareLoop::dance().running);
}

// Stand up, ready, dance to the end, finish, damping; every assertion of a good dance.
void dance_end_to_end(const char* name, const planner::MotionPlan& motion, bool leg_pd_in_drive,
                      test_support::LegBinding legs = test_support::LegBinding::kCst) {
  const model::Model& m = test_support::test_model();
  FirmwareLoop loop(FirmwareConfig{}, legs);
  ASSERT_TRUE(loop.ok());
  ASSERT_EQ(loop.csp_legs(), legs == test_support::LegBinding::kCsp);
  loop.set_leg_pd_in_drive(leg_pd_in_drive);
  ASSERT_TRUE(loop.enable_dance(motion, mpc_stack()));
  ASSERT_TRUE(loop.bring_up()) << to_string(FirmwareLoop::fw().mode.latched);

  // The last ready ticks: the tick-to-tick change of the applied torque law, for scale.
  double ready_step_Nm = 0.0;
  dynamics::JointVector tau_prev = effective_torque(loop.command(), loop.io().sensors);
  for (int i = 0; i < 50; ++i) {
    loop.tick();
    const dynamics::JointVector tau = effective_torque(loop.command(), loop.io().sensors);
    ready_step_Nm = std::max(ready_step_Nm, (tau - tau_prev).cwiseAbs().maxCoeff());
    tau_prev = tau;
  }

  const std::size_t allocs_before = loop.allocations_in_cycle();
  const std::size_t planner_allocs_before = loop.planner_allocations();
  // Stand-up and ready: the idle planner rehearsed the opening each period (dance.h), every
  // one solved, without the heap, and the dance's first plan is unchanged by them
  // (Dance.RehearsalsBeforeTheDanceLeaveItsFirstPlanUnchanged).
  const std::uint64_t rehearsals = FirmwareLoop::planner().rehearsals;
  std::printf("[ figures  ] %s: %llu rehearsals of the opening before the dance, %zu planner allocations\n", name,
              static_cast<unsigned long long>(rehearsals), planner_allocs_before);
  EXPECT_GE(rehearsals, 100u);  // the 2 s stand-up alone is 100 planner periods
  EXPECT_EQ(FirmwareLoop::planner().rehearsal_failures, 0u);
  EXPECT_EQ(planner_allocs_before, 0u) << "heap use in the planning task's rehearsals";
  const DanceControl& d = FirmwareLoop::dance();
  // The control task rehearsed the dance's first tick in each stand-up and ready tick
  // (dance_rehearse_rt), every one solved, and none of those cycles touched the heap.
  EXPECT_GE(d.rehearsals, 1000u);  // the 2 s stand-up alone is 1000 control ticks
  EXPECT_EQ(d.rehearsal_failures, 0u);
  EXPECT_EQ(allocs_before, 0u) << "heap use in the control task's cycles before the dance";
  static dynamics::Data data;
  planner::PlanKnot knot;
  double sq_legs = 0.0, sq_arms = 0.0, min_base_z = 1e9, max_tilt_deg = 0.0, entry_step_Nm = 0.0;
  std::uint64_t samples = 0;
  CycleInputs in;
  in.request = Request::kDance;
  const double motion_s = planner::motion_plan_duration_s(motion);
  const hal::TimeNs max_ns = static_cast<hal::TimeNs>(std::llround((motion_s + 2.0) * 1e9));
  for (hal::TimeNs t = 0; t < max_ns; t += kTick_ns) {
    loop.tick(t == 0 ? in : CycleInputs{});
    if (FirmwareLoop::fw().mode.mode != Mode::kDance) break;
    if (t == 0) entry_step_Nm = (effective_torque(loop.command(), loop.io().sensors) - tau_prev).cwiseAbs().maxCoeff();
    // Truth against the motion at the plant's time.
    const sim::PlantTruth& truth = loop.plant().truth();
    planner::motion_plan_sample_rt(m, data, motion, loop.now_ns() - d.start_ns, knot);
    const auto e = (truth.q.tail<model::kNumJoints>() - knot.q.tail<model::kNumJoints>()).eval();
    sq_legs += e.head<2 * model::kLegJoints>().squaredNorm() / (2 * model::kLegJoints);
    sq_arms += e.segment<2 * model::kArmJoints>(model::kLeftArmFirst).squaredNorm() / (2 * model::kArmJoints);
    ++samples;
    min_base_z = std::min(min_base_z, truth.q[2]);
    max_tilt_deg = std::max(max_tilt_deg, loop.tilt_deg());
  }
  const double dance_s = 1e-9 * static_cast<double>(loop.now_ns() - d.start_ns);
  const std::size_t dance_allocs = loop.allocations_in_cycle() - allocs_before;
  const std::size_t planner_allocs = loop.planner_allocations() - planner_allocs_before;
  const double rms_legs = std::sqrt(sq_legs / std::max<std::uint64_t>(1, samples));
  const double rms_arms = std::sqrt(sq_arms / std::max<std::uint64_t>(1, samples));
  std::printf("[ figures  ] %s: %.2f s in dance (motion %.2f s), joint RMS legs %.4f rad, arms %.4f rad, min base z %.3f m, "
              "max tilt %.2f deg; plans taken %llu, rejected %llu, kinematic fallbacks %llu, WBC not-ok ticks %llu, "
              "MPC failures %llu; applied torque step: ready %.2f, dance entry %.2f N m; allocations %zu (control) %zu "
              "(planner); torques clipped at peak %llu (largest demand %.3f x peak), references put on a stop %llu\n",
              name, dance_s, motion_s, rms_legs, rms_arms, min_base_z, max_tilt_deg,
              static_cast<unsigned long long>(d.counters.plans_taken), static_cast<unsigned long long>(d.counters.plans_rejected),
              static_cast<unsigned long long>(d.counters.kinematic_fallbacks),
              static_cast<unsigned long long>(d.counters.wbc_not_ok_ticks),
              static_cast<unsigned long long>(FirmwareLoop::planner().ws.mpc_failures), ready_step_Nm, entry_step_Nm,
              dance_allocs, planner_allocs, static_cast<unsigned long long>(d.counters.torques_saturated),
              d.counters.max_torque_demand_x, static_cast<unsigned long long>(d.counters.references_limited));

  const auto pct = [](std::vector<double> v, double f) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(f * static_cast<double>(v.size() - 1) + 0.5)];
  };
  std::printf("[ figures  ] %s, wall clock on this machine: firmware tick in dance p50 %.0f us, p99 %.0f us, max %.0f us; "
              "planner iteration p50 %.2f ms, p99 %.2f ms, max %.2f ms\n",
              name, pct(loop.dance_cycle_us(), 0.5), pct(loop.dance_cycle_us(), 0.99), pct(loop.dance_cycle_us(), 1.0),
              pct(loop.plan_ms(), 0.5), pct(loop.plan_ms(), 0.99), pct(loop.plan_ms(), 1.0));

  EXPECT_EQ(FirmwareLoop::fw().mode.latched, Fault::kNone) << to_string(FirmwareLoop::fw().mode.latched);
  ASSERT_EQ(FirmwareLoop::fw().mode.mode, Mode::kFinish);
  // Finish came from the motion's end (plus the settle), not from a timeout.
  EXPECT_GE(dance_s, motion_s);
  EXPECT_LE(dance_s, motion_s + 1e-9 * static_cast<double>(d.settle_ns) + 0.01);
  EXPECT_GT(min_base_z, 0.7);  // stands at 0.86 m; a fall ends near the ground
  EXPECT_LT(max_tilt_deg, 10.0);
  // The simulator's bound for the whole dance (tests/loop/mpc_loop_test.cpp).
  EXPECT_LT(rms_legs, 0.05);
  EXPECT_LT(rms_arms, 0.05);
  EXPECT_EQ(dance_allocs, 0u) << "heap use in the control cycle while dancing";
  EXPECT_EQ(planner_allocs, 0u) << "heap use in the planning task while dancing";
  // 50 Hz over the dance, every one taken; the planner never late, never failing.
  EXPECT_GE(d.counters.plans_taken, static_cast<std::uint64_t>(dance_s * 50.0) - 2);
  EXPECT_EQ(d.counters.plans_rejected, 0u);
  EXPECT_EQ(d.counters.kinematic_fallbacks, 0u);
  EXPECT_EQ(FirmwareLoop::planner().ws.mpc_failures, 0u);
  EXPECT_EQ(d.counters.wbc_not_ok_ticks, 0u);
  // The hand-over: the applied torque law changes on entering dance no more than it does
  // from one standing tick to the next (the cross-fade starts at the standing law).
  EXPECT_LT(entry_step_Nm, std::max(1.0, 2.0 * ready_step_Nm));

  // Finish: the gains fade out, then damping, still without a fault; the planner idles.
  for (int i = 0; i < 600 && FirmwareLoop::fw().mode.mode == Mode::kFinish; ++i) loop.tick();
  EXPECT_EQ(FirmwareLoop::fw().mode.mode, Mode::kDamping);
  loop.tick();
  std::printf("[ figures  ] %s, finish: references put on a stop %llu\n", name,
              static_cast<unsigned long long>(d.counters.finish_references_limited));
  EXPECT_EQ(FirmwareLoop::fw().mode.latched, Fault::kNone);
  EXPECT_FALSE(FirmwareLoop::dance().running);
  expect_clean_wire(loop);
  // The leg drives: what the wire carried and what they did with it.
  // Torque (CST) or torque offset (CSP) clamped at the motor limit before packing, per leg
  // slot 0..5 summed over both legs (counted by the drivers, never silent).
  std::uint64_t refused = 0;
  std::array<std::uint64_t, 6> clamps{};
  for (const auto& c : loop.io().canopen) {
    for (std::size_t i = 0; i < c.st.size(); ++i) {
      if (c.slot[i] < 2 * model::kLegJoints) clamps[static_cast<std::size_t>(c.slot[i] % model::kLegJoints)] += c.st[i].torque_clamps;
      refused += c.st[i].refused_commands;
    }
  }
  std::printf("[ figures  ] %s, drives: torque (offset) clamps per leg slot %llu %llu %llu %llu %llu %llu, drive loop at "
              "its limit in %llu force evaluations, refused targets %llu, CSP holds %llu, binding failures %llu\n",
              name, static_cast<unsigned long long>(clamps[0]), static_cast<unsigned long long>(clamps[1]),
              static_cast<unsigned long long>(clamps[2]), static_cast<unsigned long long>(clamps[3]),
              static_cast<unsigned long long>(clamps[4]), static_cast<unsigned long long>(clamps[5]),
              static_cast<unsigned long long>(loop.drive_loop_saturations()), static_cast<unsigned long long>(refused),
              static_cast<unsigned long long>(loop.csp_holds()), static_cast<unsigned long long>(loop.binding_failures()));
  EXPECT_EQ(refused, 0u);
  // The WBC plans the ankle motors' torques at the drives' sample (τ through the linkage plus
  // the CSP drives' damping on the velocity error) inside their limits, and on CSP the hips'
  // and knees' too: the drivers never clamp them.
  EXPECT_EQ(clamps[4] + clamps[5], 0u);
  if (legs == test_support::LegBinding::kCsp) {
    for (int k = 0; k < 4; ++k) EXPECT_EQ(clamps[static_cast<std::size_t>(k)], 0u) << "leg slot " << k;
  }
  EXPECT_EQ(loop.csp_holds(), 0u);
  EXPECT_EQ(loop.binding_failures(), 0u);
  if (legs == test_support::LegBinding::kCsp) {
    // Every leg and shoulder pitch drive really runs CSP with the gains from the wire (the
    // emulator's decoded object dictionary, not the firmware's configuration).
    int csp_drives = 0;
    for (std::size_t b = 0; b < loop.buses(); ++b) {
      const auto* e = loop.drives(b);
      if (e == nullptr) continue;
      for (int i = 0; i < e->count; ++i) {
        const auto& dr = e->drives[i];
        EXPECT_EQ(dr.mode, drivers::canopen::kModeCyclicSyncPosition);
        EXPECT_EQ(dr.rpdo1_torque_object, drivers::canopen::kObjTorqueOffset);
        EXPECT_GT(dr.kp_register, 0u);
        ++csp_drives;
      }
    }
    EXPECT_EQ(csp_drives, 14);
  }
}

TEST(FirmwareDance, DancesThroughTheDriversUntilTheFirstStep) {
  dance_end_to_end("FIL dance, 1.95 s, CST legs", before_steps(), false);
}

TEST(FirmwareDance, DancesTheSideStepsWithThePdInTheLegDrives) {
  dance_end_to_end("FIL dance, 5.95 s, leg PD in the drives", with_side_steps(), true);
}

// The leg drives in CSP: the firmware's leg law reaches the plant only through RPDO1
// (target position, torque offset) and the position-loop gains written by SDO at start-up;
// the emulated drives close their loop on the plant continuously.
TEST(FirmwareDance, DancesTheSideStepsThroughTheCspLegDrives) {
  dance_end_to_end("FIL dance, 5.95 s, CSP legs", with_side_steps(), false, test_support::LegBinding::kCsp);
}

// The CST leg binding: fails at the first lift-off (see the file comment). Kept, disabled,
// as the record of the finding.
TEST(FirmwareDance, DISABLED_DancesTheSideStepsThroughTheCstLegDrives) {
  dance_end_to_end("FIL dance, 5.95 s, CST legs", with_side_steps(), false);
}

// kuavo_fw_sim's whole run (stand-up, dance, finish, damping): the robot goes back on its
// gantry as finish begins, so the fade to damping ends with it where the dance left it. Left
// standing it folds as the gains fade: 0.5 s into damping its base has sunk (oracle: the
// log's last row, the plant's truth).
TEST(FirmwareDance, KuavoFwSimEndsTheDanceOnTheGantry) {
  sitl::SitlConfig c;
  c.loop.legs = test_support::LegBinding::kCsp;
  c.loop.seed = 1;
  c.log_path = ::testing::TempDir() + "firmware_dance_end.csv";
  const sitl::SitlSummary s = sitl::run_firmware_sim(test_support::test_model(), &before_steps(), c);
  ASSERT_TRUE(s.motion.run.ok) << s.motion.run.error;
  EXPECT_TRUE(s.danced_to_end);
  EXPECT_TRUE(s.faults.empty());
  EXPECT_EQ(s.final_mode, std::string(to_string(Mode::kDamping)));
  std::FILE* f = std::fopen(c.log_path.c_str(), "r");
  ASSERT_NE(f, nullptr);
  char line[16384], last[16384] = "";
  while (std::fgets(line, sizeof line, f) != nullptr) std::snprintf(last, sizeof last, "%s", line);
  std::fclose(f);
  double t_s = 0.0, x = 0.0, y = 0.0, z = 0.0;
  int mode = -1, fault = -1;
  ASSERT_EQ(std::sscanf(last, "%lf,%d,%d,%lf,%lf,%lf", &t_s, &mode, &fault, &x, &y, &z), 6) << last;
  std::printf("[ figures  ] kuavo_fw_sim, 1.95 s: ends at %.3f s in mode %d, fault %d, base z %.3f m\n", t_s, mode, fault, z);
  EXPECT_EQ(mode, static_cast<int>(Mode::kDamping));
  EXPECT_GT(z, 0.75);  // dances at ~0.78 m
}

// The planner stops delivering mid-dance: the control task bridges on the motion's own
// knots once the plan is plan_stale_ns old, then the watchdog latches fault 16 at
// plan_max_age_ns and the cycle sends damping.
TEST(FirmwareDance, StalePlanFallsBackThenFaultsToDamping) {
  FirmwareLoop loop;
  start_dance(loop, before_steps());
  for (int i = 0; i < 500; ++i) loop.tick();  // 1 s of dance
  ASSERT_EQ(FirmwareLoop::fw().mode.mode, Mode::kDance);
  const DanceControl& d = FirmwareLoop::dance();
  const FirmwareConfig& c = FirmwareLoop::fw().config;
  loop.stop_planner();
  const hal::TimeNs stamp = d.plan_stamp_ns;  // refreshed once more by a plan in flight, if any
  hal::TimeNs fallback_at = -1, damping_at = -1, last_stamp = stamp;
  for (int i = 0; i < 100 && damping_at < 0; ++i) {
    loop.tick();
    const hal::TimeNs t = loop.now_ns() - kTick_ns;  // the tick just run
    last_stamp = d.plan_stamp_ns;
    EXPECT_TRUE(command_finite(loop.command()));
    if (fallback_at < 0 && d.counters.kinematic_fallbacks > 0) fallback_at = t;
    if (test_support::all_damping(loop.command())) damping_at = t;
  }
  std::printf("[ figures  ] stale plan: last plan's state at %.3f s; kinematic knots after %.1f ms, damping after %.1f ms "
              "(fault %s), tilt %.2f deg\n",
              1e-9 * static_cast<double>(last_stamp), 1e-6 * static_cast<double>(fallback_at - last_stamp),
              1e-6 * static_cast<double>(damping_at - last_stamp), to_string(FirmwareLoop::fw().mode.latched), loop.tilt_deg());
  ASSERT_GE(fallback_at, 0);
  ASSERT_GE(damping_at, 0);
  EXPECT_EQ(d.counters.kinematic_fallbacks, 1u);
  EXPECT_GT(fallback_at - last_stamp, c.plan_stale_ns);
  EXPECT_LE(fallback_at - last_stamp, c.plan_stale_ns + kTick_ns);
  EXPECT_GT(damping_at - last_stamp, c.plan_max_age_ns);
  EXPECT_LE(damping_at - last_stamp, c.plan_max_age_ns + kTick_ns);
  EXPECT_EQ(FirmwareLoop::fw().mode.latched, Fault::kPlanStale);
  EXPECT_LT(loop.tilt_deg(), 10.0);
  expect_clean_wire(loop);
}

// One plan with a NaN is dropped, the motion's knots bridge to the next, the dance goes
// on; a planner that keeps sending NaN is a planner that delivers nothing: fault 16,
// damping. No NaN ever reaches a motor.
TEST(FirmwareDance, NanInThePlanNeverReachesAMotor) {
  for (const bool every : {false, true}) {
    FirmwareLoop loop;
    start_dance(loop, before_steps());
    for (int i = 0; i < 250; ++i) loop.tick();
    loop.corrupt_plans(every);
    int damping_ticks = 0;
    for (int i = 0; i < 500 && damping_ticks < 25; ++i) {
      loop.tick();
      ASSERT_TRUE(command_finite(loop.command())) << "tick " << i;
      if (FirmwareLoop::fw().mode.mode == Mode::kDamping) ++damping_ticks;
    }
    const DanceControl& d = FirmwareLoop::dance();
    std::printf("[ figures  ] NaN in %s: plans rejected %llu, mode %s, fault %s\n", every ? "every plan" : "one plan",
                static_cast<unsigned long long>(d.counters.plans_rejected), to_string(FirmwareLoop::fw().mode.mode),
                to_string(FirmwareLoop::fw().mode.latched));
    if (every) {
      EXPECT_GE(d.counters.plans_rejected, 2u);
      EXPECT_EQ(FirmwareLoop::fw().mode.latched, Fault::kPlanStale);
      EXPECT_TRUE(test_support::all_damping(loop.command()));
    } else {
      EXPECT_EQ(d.counters.plans_rejected, 1u);
      EXPECT_EQ(d.counters.kinematic_fallbacks, 1u);  // bridged until the next plan
      EXPECT_EQ(FirmwareLoop::fw().mode.latched, Fault::kNone);
      EXPECT_EQ(FirmwareLoop::fw().mode.mode, Mode::kDance);
    }
    expect_clean_wire(loop);
  }
}

}  // namespace
}  // namespace kuavo::firmware
