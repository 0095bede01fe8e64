// The firmware tests' view of the firmware-in-the-loop rig (firmware/sitl/firmware_loop.h,
// the same one kuavo_fw_sim runs): the test model, the tests' allocation trap counting
// both tasks' heap use, and rig errors reported as test failures.
#pragma once

#include <gtest/gtest.h>

#include "firmware/sitl/firmware_loop.h"
#include "tests/firmware/firmware_test_support.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::firmware::test_support {

using sitl::kTick_ns;
using sitl::LegBinding;
inline constexpr hal::TimeNs kDampingBudget_ns = 20'000'000;  // issue 7

inline sitl::LoopConfig loop_config(const FirmwareConfig& fw_config, LegBinding legs) {
  sitl::LoopConfig c;
  c.firmware = fw_config;
  c.legs = legs;  // the ankle motors at the drivers configuration's 27 N m, as kuavo_fw runs them
  return c;
}

class FirmwareLoop : public sitl::FirmwareLoop {
 public:
  explicit FirmwareLoop(const FirmwareConfig& fw_config = FirmwareConfig{}, LegBinding legs = LegBinding::kCst)
      : sitl::FirmwareLoop(test_model(), loop_config(fw_config, legs)) {
    EXPECT_TRUE(ok()) << error();
    set_allocation_counter(&kuavo::test::thread_allocation_count);
  }
  bool enable_dance(const planner::MotionPlan& motion, const stack::StackConfig& config,
                    hal::TimeNs plan_latency_ns = 4'000'000) {
    const bool enabled = sitl::FirmwareLoop::enable_dance(motion, config, plan_latency_ns);
    if (!enabled) ADD_FAILURE() << error();
    return enabled;
  }
};

}  // namespace kuavo::firmware::test_support
