// The words of `kuavo simulate --engine both`: where the two simulators disagree.
#include <gtest/gtest.h>

#include "sim/engine_compare.h"

namespace kuavo::test {
namespace {

sim::MotionSummary danced(double legs_rad, double arms_rad, int steps) {
  sim::MotionSummary s;
  s.run.sim_time_s = 33.8;
  s.tracking_rms_legs_rad = legs_rad;
  s.tracking_rms_arms_rad = arms_rad;
  s.steps = steps;
  return s;
}

TEST(EngineCompare, TheBuiltInDanceAgrees) {
  // The figures of the built-in dance on the floor (the commit that added --engine both).
  const auto c = sim::compare_engines(danced(0.0187, 0.0125, 42), danced(0.0221, 0.0162, 41));
  EXPECT_TRUE(c.agree);
  EXPECT_TRUE(c.disagreements.empty());
  EXPECT_NE(sim::engine_comparison_json(c, "{\n}\n", "{\n}\n").find("\"agree\": true"), std::string::npos);
}

TEST(EngineCompare, AFallInOneWorldOnlyIsSaid) {
  auto mujoco = danced(0.025, 0.02, 20);
  mujoco.run.fell = true;
  mujoco.run.fell_at_s = 12.5;
  const auto c = sim::compare_engines(danced(0.0187, 0.0125, 42), mujoco);
  ASSERT_FALSE(c.agree);
  EXPECT_EQ(c.disagreements[0], "simbody: stayed up to the end (33.80 s); mujoco: fell at 12.50 s");
  // Also the lift-offs (42 vs 20); the legs' 0.025 vs 0.0187 rad are within 1.5x.
  EXPECT_EQ(c.disagreements.size(), 2u);
  const std::string json = sim::engine_comparison_json(c, "{\n  \"a\": 1\n}\n", "{\n  \"b\": 2\n}\n");
  EXPECT_NE(json.find("\"agree\": false"), std::string::npos);
  EXPECT_NE(json.find("\"mujoco\": {\n  \"b\": 2\n}\n}"), std::string::npos) << json;
}

TEST(EngineCompare, FallsAFewTenthsApartAgreeFallsSecondsApartDoNot) {
  auto a = danced(0.05, 0.05, 10), b = danced(0.05, 0.05, 10);
  a.run.fell = b.run.fell = true;
  a.run.fell_at_s = 7.0;
  b.run.fell_at_s = 7.0 + 0.9 * sim::kFallTimesApart_s;
  EXPECT_TRUE(sim::compare_engines(a, b).agree);
  b.run.fell_at_s = 7.0 + 1.1 * sim::kFallTimesApart_s;
  EXPECT_FALSE(sim::compare_engines(a, b).agree);
}

TEST(EngineCompare, TrackingRatioCountsOnlyAboveTheFloor) {
  // 3x apart but both below the floor: both track well.
  EXPECT_TRUE(sim::compare_engines(danced(0.005, 0.01, 4), danced(0.015, 0.01, 4)).agree);
  const auto c = sim::compare_engines(danced(0.02, 0.01, 4), danced(0.031, 0.01, 4));
  ASSERT_FALSE(c.agree);
  EXPECT_NE(c.disagreements[0].find("legs tracking RMS"), std::string::npos) << c.disagreements[0];
}

TEST(EngineCompare, AFailedSimulationIsSaid) {
  auto b = danced(0.0, 0.0, 0);
  b.run.ok = false;
  b.run.error = "MuJoCo warning 2";
  const auto c = sim::compare_engines(danced(0.02, 0.01, 4), b);
  ASSERT_FALSE(c.agree);
  EXPECT_NE(c.disagreements[0].find("the simulation failed (MuJoCo warning 2)"), std::string::npos);
}

}  // namespace
}  // namespace kuavo::test
