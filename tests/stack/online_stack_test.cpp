// The online stack's two step functions over 10⁵ control ticks (200 s of stepping in
// place at 500 Hz, the planner every 10th tick): no heap allocation, every command
// finite and in PD-torque mode, the WBC solving every tick, and the estimator following
// the motion the synthetic sensors describe (the motion itself is the oracle).
#include "controllers/stack/online_stack.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

#include "controllers/dynamics/rigid_body.h"
#include "tests/support/test_robot.h"
#include "controllers/planner/step_in_place.h"
#include "controllers/standing/standing_controller.h"
#include "sim/ideal_sensors.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::stack {
namespace {

const model::Model& robot() { return kuavo::test::s45_robot(); }

// The stack's workspaces and a motion, once per process (large: never on the stack).
struct Rig {
  std::unique_ptr<planner::MotionPlan> plan = std::make_unique<planner::MotionPlan>();
  std::unique_ptr<ControlWorkspace> control = std::make_unique<ControlWorkspace>();
  std::unique_ptr<PlannerWorkspace> planner_ws = std::make_unique<PlannerWorkspace>();
  std::unique_ptr<planner::ReferencePlan> pending = std::make_unique<planner::ReferencePlan>();
  std::unique_ptr<dynamics::Data> data = std::make_unique<dynamics::Data>();
};
Rig& the_rig() {
  static Rig rig;
  return rig;
}

// The rig's plan: stepping in place from the standing configuration (make_step_in_place's
// message, or nullptr).
const char* rig_steps_in_place(int steps, double rate_hz = planner::StepInPlaceConfig{}.rate_hz) {
  planner::StepInPlaceConfig gait;
  gait.steps = steps;
  gait.rate_hz = rate_hz;
  return planner::make_step_in_place(robot(), kuavo::test::standing_configuration(), gait, *the_rig().plan);
}

// The rig's plan run through the stack for `ticks` control ticks on sensors that replay it
// (ideal, the plan as the truth), the planner every 10th tick and its plan applied at once,
// under the allocation trap. on_tick(truth, command) sees each tick's oracle and output.
struct TickCounts {
  bool started = false;
  std::size_t allocations = 0;
  int not_ok = 0;  // ticks whose WBC status was not kOk
};
template <class OnTick>
TickCounts run_on_plan(const StackConfig& cfg, int ticks, OnTick on_tick) {
  const model::Model& m = robot();
  auto& [plan, control, planner_ws, pending, data] = the_rig();
  static hal::SensorFrame frame;
  static hal::CommandFrame command;
  static planner::PlanKnot truth;
  TickCounts out;
  planner::motion_plan_sample_rt(m, *data, *plan, 0, truth);
  sim::ideal_sensor_frame(truth, Eigen::Vector3d::Zero(), 0, frame);
  out.started = stack_start(m, cfg, *control, *planner_ws, *plan, frame, 0);
  if (!out.started) return out;
  constexpr hal::TimeNs kPeriod_ns = 2'000'000;
  kuavo::test::AllocTrap trap;
  for (int tick = 0; tick < ticks; ++tick) {
    const hal::TimeNs now = tick * kPeriod_ns;
    sim::ideal_sensor_frame_on_plan(m, *data, *plan, now, truth, frame);  // truth: the test's oracle
    if (stack_control_tick_rt(m, cfg, *control, frame, now, StateOverride{}, command) != wbc::WbcStatus::kOk) ++out.not_ok;
    on_tick(truth, command);
    if (tick % 10 == 0) {  // the 50 Hz planner, its result applied at once
      stack_plan_rt(m, cfg, *planner_ws, *plan, control->estimate.q, control->estimate.v, now, *pending);
      stack_apply_plan_rt(*control, *pending);
    }
  }
  out.allocations = trap.count();
  return out;
}

TEST(OnlineStack, HundredThousandTicksWithoutAllocationAndWithFiniteCommands) {
  auto& [plan, control, planner_ws, pending, data] = the_rig();
  ASSERT_EQ(rig_steps_in_place(124, 50.0), nullptr);  // 200 s within the plan's frame capacity

  constexpr int kTicks = 100'000;
  int bad_commands = 0;
  double worst_position_error = 0.0;
  const TickCounts run = run_on_plan(StackConfig{}, kTicks, [&](const planner::PlanKnot& truth, const hal::CommandFrame& command) {
    for (const auto& c : command.joints) {
      const bool finite = std::isfinite(c.torque_ff_Nm) && std::isfinite(c.position_ref_rad) &&
                          std::isfinite(c.velocity_ref_rad_s) && std::isfinite(c.kp_Nm_per_rad) &&
                          std::isfinite(c.kd_Nm_s_per_rad);
      if (!finite || c.mode != hal::JointMode::kPdTorque) ++bad_commands;
    }
    worst_position_error = std::max(worst_position_error, (control->estimate.q.head<3>() - truth.q.head<3>()).norm());
  });
  ASSERT_TRUE(run.started);
  std::printf("100000 ticks: %zu allocations, %d not-ok WBC ticks, %d bad commands, estimator position error <= %.4f m\n",
              run.allocations, run.not_ok, bad_commands, worst_position_error);
  EXPECT_EQ(run.allocations, 0u);
  EXPECT_EQ(run.not_ok, 0);
  EXPECT_EQ(bad_commands, 0);
  EXPECT_LT(worst_position_error, 0.01);
  EXPECT_EQ(control->ticks, static_cast<std::uint64_t>(kTicks));
}

// The opt-in lean trim (lean_trim.h) in the same loop, learning through the whole run
// (kAlways) and in the opening stand only (kOpening): its observer and trim allocate nothing.
// The sensors replay the kinematic plan (no physics), whose motion the WBC's forces need not
// quite produce, so the trim moves a little: kAlways 0.062° at the time of writing, held under
// 0.15°; kOpening, learning six times faster before the rig's first step, 0.20°, unsaturated.
TEST(OnlineStack, LeanTrimTicksWithoutAllocation) {
  auto& [plan, control, planner_ws, pending, data] = the_rig();
  ASSERT_EQ(rig_steps_in_place(10, 50.0), nullptr);
  for (const LeanTrimLearn learn : {LeanTrimLearn::kAlways, LeanTrimLearn::kOpening}) {
    StackConfig cfg;
    cfg.lean_trim.enabled = true;
    cfg.lean_trim.learn = learn;
    constexpr int kTicks = 8'000;  // 16 s, within the plan's 18
    const TickCounts run = run_on_plan(cfg, kTicks, [](const planner::PlanKnot&, const hal::CommandFrame&) {});
    ASSERT_TRUE(run.started);
    const double trim_deg = control->lean_trim.theta_rad.norm() * 180.0 / 3.14159265358979323846;
    std::printf("%d ticks with the lean trim (%s): %zu allocations, trim %.4f deg over %llu ticks\n", kTicks,
                learn == LeanTrimLearn::kAlways ? "always" : "opening", run.allocations, trim_deg,
                static_cast<unsigned long long>(control->lean_trim.integrated_ticks));
    EXPECT_EQ(run.allocations, 0u);
    EXPECT_EQ(run.not_ok, 0);
    EXPECT_GT(control->lean_trim.integrated_ticks, 0u);
    EXPECT_EQ(control->lean_trim.saturated_ticks, 0u);
    if (learn == LeanTrimLearn::kAlways) {
      EXPECT_LT(trim_deg, 0.15);
    } else {
      EXPECT_TRUE(control->lean_trim.opening_over);  // the rig steps: the trim held from its first lift-off
      EXPECT_LT(control->lean_trim.integrated_ticks, 1000u);
    }
  }
}

// stack_start is a fresh start: after running (warm MPC, WBC working set, estimator
// history), a second start from the same inputs replays the first bit for bit. Without it
// a run's result would depend on what ran before it in the same process.
TEST(OnlineStack, StartIsAFreshStartWithTheMpc) {
  const model::Model& m = robot();
  Rig& rig = the_rig();
  auto& [plan, control, planner_ws, pending, data] = rig;
  ASSERT_EQ(rig_steps_in_place(2), nullptr);
  StackConfig cfg;
  cfg.planner = PlannerKind::kMpc;
  constexpr int kTicks = 300;
  static std::array<std::array<double, model::kNumJoints>, kTicks> first{};
  int mismatches = 0, first_mismatch = -1;
  for (int pass = 0; pass < 2; ++pass) {
    static hal::SensorFrame frame;
    static hal::CommandFrame command;
    static planner::PlanKnot truth;
    sim::ideal_sensor_frame_on_plan(m, *data, *plan, 0, truth, frame);
    ASSERT_TRUE(stack_start(m, cfg, *control, *planner_ws, *plan, frame, 0));
    for (int tick = 0; tick < kTicks; ++tick) {
      const hal::TimeNs now = tick * 2'000'000LL;
      sim::ideal_sensor_frame_on_plan(m, *data, *plan, now, truth, frame);
      if (tick % 10 == 0) {
        stack_plan_rt(m, cfg, *planner_ws, *plan, control->estimate.q, control->estimate.v, now, *pending);
        stack_apply_plan_rt(*control, *pending);
      }
      stack_control_tick_rt(m, cfg, *control, frame, now, StateOverride{}, command);
      for (int j = 0; j < model::kNumJoints; ++j) {
        if (pass == 0) {
          first[tick][j] = command.joints[j].torque_ff_Nm;
        } else if (command.joints[j].torque_ff_Nm != first[tick][j]) {
          ++mismatches;
          if (first_mismatch < 0) first_mismatch = tick;
        }
      }
    }
  }
  EXPECT_EQ(mismatches, 0) << "first at tick " << first_mismatch;
}

// A new plan takes over linearly over plan_blend_s: the reference at the k-th tick after
// the hand-over is the blend (k+1)/(blend/dt + 1) of the new plan with the old; the new
// plan's contact flags hold from the first tick; after the blend, the new plan alone.
TEST(OnlineStack, ANewPlanTakesOverLinearlyOverTheBlendTime) {
  const model::Model& m = robot();
  Rig& rig = the_rig();
  auto& [plan, control, planner_ws, pending, data] = rig;
  ASSERT_EQ(rig_steps_in_place(1), nullptr);
  StackConfig cfg;  // kinematic planner
  cfg.plan_blend_s = 0.02;
  static hal::SensorFrame frame;
  static hal::CommandFrame command;
  static planner::PlanKnot truth;
  sim::ideal_sensor_frame_on_plan(m, *data, *plan, 0, truth, frame);
  ASSERT_TRUE(stack_start(m, cfg, *control, *planner_ws, *plan, frame, 0));
  constexpr hal::TimeNs kDt = 2'000'000;
  stack_control_tick_rt(m, cfg, *control, frame, 0, StateOverride{}, command);
  // The new plan: the old one with every joint reference 0.1 rad higher, one point lifted.
  static planner::ReferencePlan old_plan, new_plan;
  old_plan = control->active;
  new_plan = old_plan;
  for (int k = 0; k < new_plan.count; ++k) {
    new_plan.knots[k].joint_position_rad.array() += 0.1;
    new_plan.knots[k].in_contact[0] = false;
  }
  stack_apply_plan_rt(*control, new_plan);
  const int blend_ticks = static_cast<int>(std::lround(cfg.plan_blend_s / cfg.wbc.dt_s));
  static wbc::WbcReference old_ref;
  for (int k = 0; k <= blend_ticks + 2; ++k) {
    const hal::TimeNs now = (k + 1) * kDt;
    stack_control_tick_rt(m, cfg, *control, frame, now, StateOverride{}, command);
    ASSERT_TRUE(planner::reference_plan_at_rt(old_plan, now, old_ref));
    const double expected = std::min(1.0, double(k + 1) / double(blend_ticks + 1));
    const Eigen::VectorXd moved = control->reference.joint_position_rad - old_ref.joint_position_rad;
    EXPECT_NEAR(moved.minCoeff(), 0.1 * expected, 1e-12) << "tick " << k;
    EXPECT_NEAR(moved.maxCoeff(), 0.1 * expected, 1e-12) << "tick " << k;
    EXPECT_FALSE(control->reference.in_contact[0]) << "tick " << k;
  }
  // Blend off: the switch is immediate.
  StackConfig at_once;
  at_once.plan_blend_s = 0.0;
  stack_apply_plan_rt(*control, old_plan);
  stack_control_tick_rt(m, at_once, *control, frame, 20 * kDt, StateOverride{}, command);
  ASSERT_TRUE(planner::reference_plan_at_rt(old_plan, 20 * kDt, old_ref));
  EXPECT_EQ((control->reference.joint_position_rad - old_ref.joint_position_rad).cwiseAbs().maxCoeff(), 0.0);
}

TEST(OnlineStack, RefusesABadConfiguration) {
  StackConfig cfg;
  cfg.plan_period_s = 0.0;
  EXPECT_NE(stack_validate_config(cfg), nullptr);
  cfg = StackConfig{};
  cfg.plan_blend_s = 0.03;  // longer than the plan period
  EXPECT_NE(stack_validate_config(cfg), nullptr);
  cfg = StackConfig{};
  for (const double bad : {-1.0, 2000.0, std::nan("")}) {
    cfg.estimator_unloaded_foot_N = bad;
    EXPECT_NE(stack_validate_config(cfg), nullptr) << bad;
  }
  cfg = StackConfig{};
  cfg.estimator_unloaded_foot_N = 50.0;
  EXPECT_EQ(stack_validate_config(cfg), nullptr);
  cfg = StackConfig{};
  cfg.lean_trim.time_constant_s = 0.0;
  EXPECT_EQ(stack_validate_config(cfg), nullptr);  // off: not read
  cfg.lean_trim.enabled = true;
  EXPECT_NE(stack_validate_config(cfg), nullptr);
  cfg = StackConfig{};
  cfg.planner = PlannerKind::kMpc;
  for (const double bad : {-0.001, 0.041, std::nan("")}) {
    cfg.planner_sole_inset_m = bad;
    EXPECT_NE(stack_validate_config(cfg), nullptr) << bad;
  }
  cfg.planner_sole_inset_m = 0.04;
  EXPECT_EQ(stack_validate_config(cfg), nullptr);
  cfg = StackConfig{};
  EXPECT_EQ(stack_validate_config(cfg), nullptr);
  PlannerKind k;
  EXPECT_TRUE(parse_planner("kinematic", k));
  EXPECT_EQ(k, PlannerKind::kKinematic);
  EXPECT_FALSE(parse_planner("magic", k));
}

// The estimator's stance set less a foot the WBC has let go of (estimator_unloaded_foot_N):
// the foot whose corners' normal forces sum below the threshold leaves it, the other stays;
// nothing changes when both feet are light (no foot to trust more), when the threshold is
// off, or for tangential forces alone. Expected flags written out by hand from the corners'
// forces (corners 0-3 the left sole, 4-7 the right; 3 forces per corner, z last).
TEST(OnlineStack, AnUnloadedFootLeavesTheEstimatorsStanceSet) {
  wbc::ForceVector f = wbc::ForceVector::Zero();
  const auto set_normal = [&f](int corner, double fz, double ft) {
    f[3 * corner] = ft;
    f[3 * corner + 1] = -ft;
    f[3 * corner + 2] = fz;
  };
  for (int c = 0; c < 4; ++c) set_normal(c, 100.0, 10.0);  // left: 400 N
  for (int c = 4; c < 8; ++c) set_normal(c, 5.0, 40.0);    // right: 20 N normal, large tangential
  const estimator::ContactFlags all{true, true, true, true, true, true, true, true};
  estimator::ContactFlags flags = all;
  EXPECT_EQ(estimator_drop_unloaded_foot_rt(f, 50.0, flags), 1);
  EXPECT_EQ(flags, (estimator::ContactFlags{true, true, true, true, false, false, false, false}));
  flags = all;
  EXPECT_EQ(estimator_drop_unloaded_foot_rt(f, 0.0, flags), 0);  // off
  EXPECT_EQ(flags, all);
  flags = all;
  EXPECT_EQ(estimator_drop_unloaded_foot_rt(f, 19.0, flags), 0);  // 20 N is not below 19 N
  EXPECT_EQ(flags, all);
  // The right foot already planned off the ground: nothing to take out.
  flags = {true, true, true, true, false, false, false, false};
  EXPECT_EQ(estimator_drop_unloaded_foot_rt(f, 50.0, flags), 0);
  // The mirror case: the left foot light.
  for (int c = 0; c < 4; ++c) set_normal(c, 2.0, 0.0);
  for (int c = 4; c < 8; ++c) set_normal(c, 120.0, 0.0);
  flags = all;
  EXPECT_EQ(estimator_drop_unloaded_foot_rt(f, 50.0, flags), 1);
  EXPECT_EQ(flags, (estimator::ContactFlags{false, false, false, false, true, true, true, true}));
  // Both light (8 N and 40 N under 50 N): the plan's flags stay.
  for (int c = 4; c < 8; ++c) set_normal(c, 10.0, 0.0);
  flags = all;
  EXPECT_EQ(estimator_drop_unloaded_foot_rt(f, 50.0, flags), 0);
  EXPECT_EQ(flags, all);
}

// The MPC keeps joint limits by a relaxed barrier, so its knots may pass a stop; the plan
// the stack hands to the WBC holds the model's hard limits, and counts what it put on a
// stop. Here the left knee's upper limit is set below the standing knee (a robot whose
// measured state is past a stop): every knee position handed over is on the limit, and
// the real limits need nothing.
TEST(OnlineStack, MpcKnotsPastAStopAreHandedOverOnTheStop) {
  const model::Model& m = robot();
  Rig& rig = the_rig();
  auto& [plan, control, planner_ws, pending, data] = rig;
  const dynamics::ConfigVector q0 = kuavo::test::standing_configuration();
  ASSERT_EQ(rig_steps_in_place(4), nullptr);
  StackConfig cfg;
  cfg.planner = PlannerKind::kMpc;
  const int knee = model::kLeftLegFirst + 3;
  auto tight = std::make_unique<model::Model>(m);
  tight->limits.position_max_rad[knee] = q0[7 + knee] - 0.1;
  for (const model::Model* mm : {&m, static_cast<const model::Model*>(tight.get())}) {
    ASSERT_TRUE(stack_prepare(*mm, cfg, *control, *planner_ws));
    stack_plan_rt(*mm, cfg, *planner_ws, *plan, q0, dynamics::VelocityVector::Zero(), plan->start_ns, *pending);
    ASSERT_EQ(planner_ws->last_mpc_status, mpc::MpcStatus::kOk);
    ASSERT_GT(pending->count, 0);
    if (mm == &m) {
      EXPECT_EQ(planner_ws->plan_positions_on_a_stop, 0u);
      continue;
    }
    EXPECT_GE(planner_ws->plan_positions_on_a_stop, static_cast<std::uint64_t>(pending->count));
    for (int k = 0; k < pending->count; ++k) {
      EXPECT_LE(pending->knots[k].joint_position_rad[knee], tight->limits.position_max_rad[knee]) << "knot " << k;
    }
  }
}

// StackConfig::planner_sole_inset_m: stack_prepare gives the planner the robot with its sole
// corners inset (the oracle: model::inset_sole_corners on a copy, frame for frame; the torque
// limits kept); an inset of 0 plans bit for bit as the robot itself does (a workspace that was
// never given a planning model), and an inset the MPC plans differently with.
TEST(OnlineStack, ThePlannerPlansOnTheInsetSoles) {
  const model::Model& m = robot();
  Rig& rig = the_rig();
  auto& [plan, control, planner_ws, pending, data] = rig;
  ASSERT_EQ(rig_steps_in_place(2), nullptr);
  const hal::TimeNs t = plan->start_ns + 600'000'000;  // 0.6 s into the stepping
  const dynamics::ConfigVector q = plan->q[planner::motion_plan_frame_at(*plan, t)];
  const auto plan_with = [&](double inset_m, bool prepared, planner::ReferencePlan& out) {
    StackConfig cfg;
    cfg.planner = PlannerKind::kMpc;
    cfg.planner_sole_inset_m = inset_m;
    EXPECT_TRUE(stack_prepare(m, cfg, *control, *planner_ws));
    if (!prepared) planner_ws->planning_model_set = false;
    stack_plan_rt(m, cfg, *planner_ws, *plan, q, dynamics::VelocityVector::Zero(), t, out);
    EXPECT_EQ(planner_ws->last_mpc_status, mpc::MpcStatus::kOk);
  };
  auto robot_plan = std::make_unique<planner::ReferencePlan>();
  auto zero_plan = std::make_unique<planner::ReferencePlan>();
  auto inset_plan = std::make_unique<planner::ReferencePlan>();
  plan_with(0.0, false, *robot_plan);
  plan_with(0.0, true, *zero_plan);
  plan_with(0.02, true, *inset_plan);
  auto expected = std::make_unique<model::Model>(m);
  model::inset_sole_corners(*expected, 0.02);
  ASSERT_TRUE(planner_ws->planning_model_set);
  for (int f = 0; f < model::kNumFrames; ++f) {
    EXPECT_EQ(planner_ws->planning_model.frames[f].position_m, expected->frames[f].position_m) << "frame " << f;
  }
  EXPECT_EQ(planner_ws->planning_model.limits.torque_Nm, m.limits.torque_Nm);
  ASSERT_GT(robot_plan->count, 0);
  ASSERT_EQ(zero_plan->count, robot_plan->count);
  int same = 0, moved = 0;
  for (int k = 0; k < robot_plan->count; ++k) {
    const wbc::WbcReference& a = robot_plan->knots[k];
    same += a.com_position_m == zero_plan->knots[k].com_position_m &&
            a.joint_position_rad == zero_plan->knots[k].joint_position_rad &&
            a.contact_force_N == zero_plan->knots[k].contact_force_N;
    moved += (a.contact_force_N - inset_plan->knots[k].contact_force_N).norm() > 1.0;
  }
  EXPECT_EQ(same, robot_plan->count);
  EXPECT_GT(moved, 0);
}

}  // namespace
}  // namespace kuavo::stack
