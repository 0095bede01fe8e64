// The safety filter refuses (never clamps) every non-finite or out-of-limit
// field, names the joint, and passes the standing controller's output.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "firmware/safety_filter.h"
#include "tests/firmware/firmware_test_support.h"

namespace kuavo::firmware {
namespace {

using test_support::test_model;

hal::CommandFrame valid_pd(const model::Model& m) {
  hal::CommandFrame c;
  for (int j = 0; j < model::kNumJoints; ++j) {
    c.joints[j].mode = hal::JointMode::kPdTorque;
    c.joints[j].position_ref_rad = 0.5 * (m.limits.position_min_rad[j] + m.limits.position_max_rad[j]);
    c.joints[j].kp_Nm_per_rad = 100.0;
    c.joints[j].kd_Nm_s_per_rad = 2.0;
    c.joints[j].torque_ff_Nm = 0.5 * m.limits.peak_torque_Nm[j];
  }
  return c;
}

TEST(SafetyFilter, PassesAValidCommandAndDamping) {
  const model::Model& m = test_model();
  const FirmwareConfig cfg;
  EXPECT_EQ(check_command_rt(m, cfg, valid_pd(m)).fault, Fault::kNone);
  hal::CommandFrame damping;
  damping_command_rt(cfg, 0, damping);
  EXPECT_EQ(check_command_rt(m, cfg, damping).fault, Fault::kNone);
  hal::CommandFrame off;
  disabled_command_rt(0, off);
  EXPECT_EQ(check_command_rt(m, cfg, off).fault, Fault::kNone);
}

TEST(SafetyFilter, RefusesEachBadFieldAndNamesTheJoint) {
  const model::Model& m = test_model();
  const FirmwareConfig cfg;
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  struct Case {
    const char* what;
    void (*mutate)(hal::JointCommand&, const model::Model&, int, double, double);
    Fault expected;
  };
  const Case cases[] = {
      {"nan tau", [](hal::JointCommand& c, const model::Model&, int, double n, double) { c.torque_ff_Nm = n; }, Fault::kCommandNonFinite},
      {"inf q", [](hal::JointCommand& c, const model::Model&, int, double, double i) { c.position_ref_rad = i; }, Fault::kCommandNonFinite},
      {"nan v", [](hal::JointCommand& c, const model::Model&, int, double n, double) { c.velocity_ref_rad_s = n; }, Fault::kCommandNonFinite},
      {"nan kp", [](hal::JointCommand& c, const model::Model&, int, double n, double) { c.kp_Nm_per_rad = n; }, Fault::kCommandNonFinite},
      {"-inf kd", [](hal::JointCommand& c, const model::Model&, int, double, double i) { c.kd_Nm_s_per_rad = -i; }, Fault::kCommandNonFinite},
      {"q above max", [](hal::JointCommand& c, const model::Model& m, int j, double, double) { c.position_ref_rad = m.limits.position_max_rad[j] + 1e-6; }, Fault::kCommandPositionLimit},
      {"q below min", [](hal::JointCommand& c, const model::Model& m, int j, double, double) { c.position_ref_rad = m.limits.position_min_rad[j] - 1e-6; }, Fault::kCommandPositionLimit},
      {"tau above peak", [](hal::JointCommand& c, const model::Model& m, int j, double, double) { c.torque_ff_Nm = -(m.limits.peak_torque_Nm[j] + 1e-6); }, Fault::kCommandTorqueLimit},
      {"kp negative", [](hal::JointCommand& c, const model::Model&, int, double, double) { c.kp_Nm_per_rad = -1.0; }, Fault::kCommandGainRange},
      {"kp too high", [](hal::JointCommand& c, const model::Model&, int, double, double) { c.kp_Nm_per_rad = 1000.1; }, Fault::kCommandGainRange},
      {"kd too high", [](hal::JointCommand& c, const model::Model&, int, double, double) { c.kd_Nm_s_per_rad = 50.1; }, Fault::kCommandGainRange},
      {"mode unknown", [](hal::JointCommand& c, const model::Model&, int, double, double) { c.mode = static_cast<hal::JointMode>(7); }, Fault::kCommandMode},
  };
  for (const Case& k : cases) {
    for (int j : {0, 3, 11, 12, 25, 27}) {
      hal::CommandFrame c = valid_pd(m);
      const hal::JointCommand before = c.joints[j];
      k.mutate(c.joints[j], m, j, nan, inf);
      const hal::JointCommand refused = c.joints[j];
      const FilterResult r = check_command_rt(m, cfg, c);
      EXPECT_EQ(r.fault, k.expected) << k.what << " joint " << j;
      EXPECT_EQ(r.joint, j) << k.what;
      // Refused, not repaired: the frame is left as it was.
      EXPECT_EQ(std::memcmp(&refused, &c.joints[j], sizeof refused), 0) << k.what;
      (void)before;
    }
  }
}

TEST(SafetyFilter, PositionAndTorqueAreOnlyCheckedWherePdUsesThem) {
  // In damping the drivers ignore q_ref and tau_ff (kDamping: -kd v).
  const model::Model& m = test_model();
  const FirmwareConfig cfg;
  hal::CommandFrame c;
  damping_command_rt(cfg, 0, c);
  c.joints[4].position_ref_rad = 100.0;
  EXPECT_EQ(check_command_rt(m, cfg, c).fault, Fault::kNone);
  c.joints[4].position_ref_rad = std::nan("");  // but never a NaN
  EXPECT_EQ(check_command_rt(m, cfg, c).fault, Fault::kCommandNonFinite);
}

}  // namespace
}  // namespace kuavo::firmware
