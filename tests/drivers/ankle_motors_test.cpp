// The ankle pairs in motor space (drivers/transmission/ankle_motors.h): the motor torques
// against virtual work with a finite-difference Jacobian of the closed-form position map,
// the capacity FACTS.md §2.4 states (about 0.5·τ_pitch ± 1.1·τ_roll near the zero pose),
// each motor clipped at its clamp and no more, the map the WBC gets, and no heap.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "controllers/model/model.h"
#include "drivers/config/drivers_config.h"
#include "drivers/transmission/ankle_motors.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::drivers {
namespace {

constexpr double kPitchMin = -0.8727, kPitchMax = 0.3491;  // FACTS.md §2.2
constexpr double kRollMin = -0.2618, kRollMax = 0.2618;

const AnkleMotors& motors() {
  static const AnkleMotors a = [] {
    model::Model m;
    EXPECT_EQ(model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, m), model::ModelError::kOk);
    return ankle_motors_from_config(default_drivers_config(m));
  }();
  return a;
}

// d(motor angle)/d(joint angle) by central differences of the closed-form joint -> crank map
// and the motors' linear transmissions: independent of ankle_jacobian_rt.
Mat2 motor_jacobian_fd(const AnkleMotors& a, int leg, const Vec2& q) {
  const double h = 1e-6;
  Mat2 J;
  for (int c = 0; c < 2; ++c) {
    Vec2 plus, minus;
    EXPECT_TRUE(ankle_motor_from_joint_rt(a.legs[leg].ankle, q + h * Vec2::Unit(c), plus));
    EXPECT_TRUE(ankle_motor_from_joint_rt(a.legs[leg].ankle, q - h * Vec2::Unit(c), minus));
    for (int k = 0; k < 2; ++k) {
      J(k, c) = (motor_position_rad(a.legs[leg].ankle_motor[k], plus[k]) -
                 motor_position_rad(a.legs[leg].ankle_motor[k], minus[k])) / (2 * h);
    }
  }
  return J;
}

TEST(AnkleMotors, TheDefaultConfigurationClampsEachMotorAtKuavoJsonsPeak) {
  const AnkleMotors& a = motors();
  ASSERT_TRUE(a.active);
  for (int leg = 0; leg < 2; ++leg) {
    EXPECT_DOUBLE_EQ(a.limit_Nm[leg](0), 27.0);  // kuavo.json joint_peak_torque_limits, ankle slots
    EXPECT_DOUBLE_EQ(a.limit_Nm[leg](1), 27.0);
  }
}

TEST(AnkleMotors, MotorTorquesDoTheJointTorquesVirtualWork) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> up(kPitchMin, kPitchMax), ur(kRollMin, kRollMax), ut(-40.0, 40.0);
  for (int leg = 0; leg < 2; ++leg) {
    for (int n = 0; n < 40; ++n) {
      const Vec2 q(up(rng), ur(rng)), tau(ut(rng), ut(rng));
      Vec2 motor;
      ASSERT_TRUE(ankle_motor_torques_rt(motors(), leg, q, tau, motor));
      // τ_jointᵀ q̇ = τ_motorᵀ ṁ for every q̇: τ_joint = Jᵀ τ_motor.
      const Vec2 back = motor_jacobian_fd(motors(), leg, q).transpose() * motor;
      EXPECT_NEAR(back[0], tau[0], 1e-6 * 40.0) << "leg " << leg << " q " << q.transpose();
      EXPECT_NEAR(back[1], tau[1], 1e-6 * 40.0);
    }
  }
}

TEST(AnkleMotors, NearTheZeroPosePitchReachesAboutTwiceAndRollAboutOneMotor) {
  // FACTS.md §2.4: motor torques ≈ 0.5·τ_pitch ± 1.1·τ_roll near the zero pose, so pitch
  // alone reaches ≈ 27 / 0.5 = 54 N·m before a motor clamps, roll alone ≈ 27 / 1.1 = 24.5.
  for (int leg = 0; leg < 2; ++leg) {
    Vec2 pitch(100.0, 0.0), roll(0.0, 100.0);
    EXPECT_EQ(clip_ankle_torques_rt(motors(), leg, Vec2::Zero(), pitch), 2);
    EXPECT_EQ(clip_ankle_torques_rt(motors(), leg, Vec2::Zero(), roll), 2);
    EXPECT_NEAR(pitch[0], 54.0, 5.0);
    EXPECT_NEAR(pitch[1], 0.0, 1.0);
    EXPECT_NEAR(roll[1], 24.5, 2.5);
    EXPECT_NEAR(roll[0], 0.0, 1.0);
  }
}

TEST(AnkleMotors, ClippingKeepsEachMotorAtItsClampAndLeavesTorquesWithinItUntouched) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> up(kPitchMin, kPitchMax), ur(kRollMin, kRollMax), ut(-80.0, 80.0);
  int clipped_cases = 0;
  for (int leg = 0; leg < 2; ++leg) {
    for (int n = 0; n < 200; ++n) {
      const Vec2 q(up(rng), ur(rng)), asked(ut(rng), ut(rng));
      Vec2 motor_asked, motor_given, given = asked;
      ASSERT_TRUE(ankle_motor_torques_rt(motors(), leg, q, asked, motor_asked));
      const int clipped = clip_ankle_torques_rt(motors(), leg, q, given);
      ASSERT_TRUE(ankle_motor_torques_rt(motors(), leg, q, given, motor_given));
      int expected = 0;
      for (int k = 0; k < 2; ++k) {
        const double limit = motors().limit_Nm[leg](k);
        if (std::abs(motor_asked[k]) > limit) {
          ++expected;
          EXPECT_NEAR(motor_given[k], std::copysign(limit, motor_asked[k]), 1e-9);
        } else {
          EXPECT_NEAR(motor_given[k], motor_asked[k], 1e-9);
        }
      }
      EXPECT_EQ(clipped, expected);
      if (expected == 0) {
        EXPECT_EQ(given, asked);  // bit for bit
      }
      clipped_cases += expected > 0;
    }
  }
  EXPECT_GT(clipped_cases, 50);  // the sample reaches the clamps
}

TEST(AnkleMotors, TheWbcMapIsTheMotorTorqueOfUnitJointTorquesAndRefusesInvalidSamples) {
  AnkleMotors a = motors();
  hal::SensorFrame frame{};
  for (auto& j : frame.joints) j.valid = true;
  const int lp = model::kLeftLegFirst + 4, rp = model::kRightLegFirst + 4;
  frame.joints[lp].position_rad = -0.3, frame.joints[lp + 1].position_rad = 0.1;
  frame.joints[rp].position_rad = 0.2, frame.joints[rp + 1].position_rad = -0.15;
  hal::AnkleMotorLimits out;
  map_ankle_motors_rt(a, frame, out);
  ASSERT_TRUE(out.active);
  const Vec2 tau(12.0, -7.0);
  for (int leg = 0; leg < 2; ++leg) {
    const int p = leg == 0 ? lp : rp;
    Vec2 motor;
    ASSERT_TRUE(ankle_motor_torques_rt(a, leg, Vec2(frame.joints[p].position_rad, frame.joints[p + 1].position_rad), tau, motor));
    EXPECT_LT((out.joint_to_motor[leg] * tau - motor).norm(), 1e-9);
    EXPECT_EQ(out.limit_Nm[leg], a.limit_Nm[leg]);
  }
  EXPECT_EQ(a.unmapped_ticks, 0u);
  frame.joints[rp + 1].valid = false;
  map_ankle_motors_rt(a, frame, out);
  EXPECT_FALSE(out.active);
  EXPECT_EQ(a.unmapped_ticks, 1u);
}

TEST(AnkleMotors, MapAndClipDoNotTouchTheHeap) {
  AnkleMotors a = motors();
  hal::SensorFrame frame{};
  for (auto& j : frame.joints) j.valid = true;
  hal::AnkleMotorLimits out;
  Vec2 tau(60.0, 20.0);
  {
    test::AllocTrap trap;
    for (int i = 0; i < 1000; ++i) {
      map_ankle_motors_rt(a, frame, out);
      tau = Vec2(60.0, 20.0);
      clip_ankle_torques_rt(a, i % 2, Vec2(-0.001 * i / 10.0, 0.0), tau);
    }
    EXPECT_EQ(trap.count(), 0u);
  }
  EXPECT_TRUE(out.active);
}

}  // namespace
}  // namespace kuavo::drivers
