// The robot stands in the simulator under the standing controller: 30 s on both
// grounds, 10 N·s pushes, bit-identical logs for a seed, and a control step that
// never touches the heap.
#include <gtest/gtest.h>

#include <memory>

#include "controllers/standing/standing_controller.h"
#include "sim/closed_loop.h"
#include "sim/sensor_model.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::test {
namespace {

const model::Model& robot() {
  static model::Model m = [] {
    model::Model out;
    model::build_model(model::Variant::kS45, 55.0, out);
    return out;
  }();
  return m;
}

sim::RunSummary stand(double seconds, const sim::GroundParams& ground, const sim::Push& push = {},
                      std::uint64_t seed = 1) {
  sim::RunConfig cfg;
  cfg.duration_s = seconds;
  cfg.ground = ground;
  cfg.push = push;
  cfg.seed = seed;
  return sim::run_standing(robot(), cfg);
}

TEST(Standing, ThirtySecondsOnTheFloor) {
  const auto s = stand(30.0, sim::kFloor);
  ASSERT_TRUE(s.ok) << s.error;
  EXPECT_FALSE(s.fell);
  EXPECT_NEAR(s.sim_time_s, 30.0, 1e-9);
  EXPECT_EQ(s.control_ticks, 15000u);
  EXPECT_LT(s.max_tilt_deg, 3.0);
  EXPECT_LT(s.max_foot_sink_m, 0.001);  // a hard floor
  EXPECT_GT(s.min_base_height_m, 0.76);
}

TEST(Standing, ThirtySecondsOnCarpetSinksOneToTwoCentimetres) {
  const auto s = stand(30.0, sim::kCarpet);
  ASSERT_TRUE(s.ok) << s.error;
  EXPECT_FALSE(s.fell);
  EXPECT_LT(s.max_tilt_deg, 5.0);
  EXPECT_GT(s.max_foot_sink_m, 0.010);
  EXPECT_LT(s.max_foot_sink_m, 0.025);
}

struct PushCase {
  const char* name;
  const sim::GroundParams* ground;
  double fx, fy;
};

class TenNewtonSecondPush : public ::testing::TestWithParam<PushCase> {};

TEST_P(TenNewtonSecondPush, IsSurvived) {
  const PushCase& c = GetParam();
  sim::Push push;
  push.start_s = 2.0;
  push.duration_s = 0.1;
  push.force_N = sim::Vec3(c.fx, c.fy, 0.0);  // 100 N for 0.1 s = 10 N·s
  const auto s = stand(6.0, *c.ground, push);
  ASSERT_TRUE(s.ok) << s.error;
  EXPECT_FALSE(s.fell) << c.name;
  // It was a real push: the torso tilted visibly.
  EXPECT_GT(s.max_tilt_deg, 0.8) << c.name;
}

const PushCase kPushes[] = {
    {"floor_forward", &sim::kFloor, 100, 0},   {"floor_backward", &sim::kFloor, -100, 0},
    {"floor_left", &sim::kFloor, 0, 100},      {"carpet_backward", &sim::kCarpet, -100, 0},
    {"carpet_right", &sim::kCarpet, 0, -100},
};
INSTANTIATE_TEST_SUITE_P(Directions, TenNewtonSecondPush, ::testing::ValuesIn(kPushes),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(Standing, FifteenNewtonSecondsForwardIsBeyondTheAnkles) {
  // The test above must be able to fail: a push past what 27 Nm ankles can catch topples it.
  sim::Push push;
  push.start_s = 2.0;
  push.duration_s = 0.1;
  push.force_N = sim::Vec3(300.0, 0.0, 0.0);
  EXPECT_TRUE(stand(5.0, sim::kFloor, push).fell);
}

TEST(Determinism, SameSeedSameLogDifferentSeedDifferentLog) {
  const auto a = stand(2.0, sim::kFloor, {}, 7);
  const auto b = stand(2.0, sim::kFloor, {}, 7);
  const auto c = stand(2.0, sim::kFloor, {}, 8);
  ASSERT_TRUE(a.ok && b.ok && c.ok);
  EXPECT_EQ(a.log_sha256.size(), 64u);
  EXPECT_EQ(a.log_sha256, b.log_sha256);
  EXPECT_NE(a.log_sha256, c.log_sha256);
}

TEST(Determinism, TighterIntegrationChangesNothingThatMatters) {
  sim::RunConfig loose, tight;
  loose.duration_s = tight.duration_s = 2.0;
  loose.push.start_s = tight.push.start_s = 0.5;
  loose.push.duration_s = tight.push.duration_s = 0.1;
  loose.push.force_N = tight.push.force_N = sim::Vec3(0, 100, 0);
  tight.relative_tolerance = 1e-5;
  const auto a = sim::run_standing(robot(), loose);
  const auto b = sim::run_standing(robot(), tight);
  ASSERT_TRUE(a.ok && b.ok);
  EXPECT_NEAR(a.max_tilt_deg, b.max_tilt_deg, 0.05);
  EXPECT_NEAR(a.min_base_height_m, b.min_base_height_m, 0.001);
}

TEST(StandingController, ControlStepNeverAllocates) {
  static control::StandingState state;
  control::standing_init(robot(), control::StandingConfig{}, state);
  sim::PlantConfig cfg;
  sim::Plant plant(robot(), cfg);
  dynamics::ConfigVector q = dynamics::neutral_configuration(robot());
  q.tail<model::kNumJoints>() = state.pose_rad;
  control::place_on_ground(robot(), state.data, q);
  plant.reset(q, dynamics::VelocityVector::Zero());
  sim::SensorModel sensors(3);
  static hal::SensorFrame frame;
  static hal::CommandFrame command;
  std::size_t allocations = 0;
  for (int tick = 0; tick < 2000; ++tick) {
    sensors.sample(plant.truth(), static_cast<hal::TimeNs>(tick) * 2'000'000, frame);
    {
      AllocTrap trap;  // only the control step is real-time code
      control::standing_step_rt(robot(), state, frame, command);
      allocations += trap.count();
    }
    plant.set_command(command);
    ASSERT_EQ(plant.advance(0.002), sim::PlantError::kOk);
  }
  EXPECT_EQ(allocations, 0u);
  for (const auto& c : command.joints) EXPECT_TRUE(std::isfinite(c.torque_ff_Nm));
}

}  // namespace
}  // namespace kuavo::test
