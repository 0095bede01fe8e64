// The built-in dance's first `seconds`, prepared as kuavo_fw --dance prepares a file
// (balance filter on): the firmware dance tests' motion.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "controllers/motion/load_motion.h"
#include "tests/firmware/firmware_test_support.h"
#include "tools/mocap/motion_plan_io.h"

namespace kuavo::firmware::test_support {

// 8.74 MB on the heap: callers keep it for the process (a function-local static).
inline planner::MotionPlan* make_dance_prefix(double seconds) {
  auto* plan = new planner::MotionPlan;
  const model::Model& robot = test_model();
  std::string error;
  EXPECT_TRUE(mocap::built_in_dance_plan(robot, *plan, error, seconds)) << error;
  planner::BalanceFilterReport report;
  EXPECT_TRUE(motion::prepare_motion(robot, {.balance_filter = true}, "built-in dance", *plan, report, error)) << error;
  return plan;
}

}  // namespace kuavo::firmware::test_support
