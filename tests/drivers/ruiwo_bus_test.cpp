// Ruiwo bus: configuration validation, joint<->motor sign/offset, joint-limit
// clamps, reply matching and reply-timeout tracking.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>

#include "controllers/model/model.h"
#include "drivers/ruiwo/ruiwo_bus.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::drivers::ruiwo {
namespace {

model::Model s45() {
  model::Model m;
  EXPECT_EQ(model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, m), model::ModelError::kOk);
  return m;
}

MotorConfig motor(std::uint8_t id, int joint, int sign, double offset = 0.0) {
  MotorConfig m;
  m.motor_id = id;
  m.joint = joint;
  m.sign = sign;
  m.zero_offset_rad = offset;
  m.position_min_rad = -1.0;
  m.position_max_rad = 2.0;
  m.velocity_max_rad_s = 5.0;
  m.torque_max_Nm = 20.0;
  return m;
}

TEST(RuiwoBus, DefaultLayoutFollowsLejuConfig) {
  const model::Model m = s45();
  const std::vector<MotorConfig> motors = default_motors(m);
  ASSERT_EQ(motors.size(), 14u);
  Bus bus;
  std::string msg;
  ASSERT_EQ(build_bus(motors, bus, msg), DriverError::kOk) << msg;
  // FACTS.md §5.2: L-arm joints 2-7 = 0x01-0x06, R-arm 0x07-0x0C, head 0x0D/0x0E.
  EXPECT_EQ(motors[0].motor_id, 0x01);
  EXPECT_EQ(motors[0].joint, model::kLeftArmFirst + 1);
  EXPECT_EQ(motors[6].motor_id, 0x07);
  EXPECT_EQ(motors[6].joint, model::kRightArmFirst + 1);
  EXPECT_EQ(motors[12].motor_id, 0x0D);
  EXPECT_EQ(motors[12].joint, model::kHeadFirst);
  // long_arm_config.yaml negtive_address: 0x0D 0x04 0x08 0x0A 0x0B 0x09 0x05 0x0C 0x02.
  for (const MotorConfig& c : motors) {
    const std::uint8_t neg[] = {0x0D, 0x04, 0x08, 0x0A, 0x0B, 0x09, 0x05, 0x0C, 0x02};
    const bool is_neg = std::find(std::begin(neg), std::end(neg), c.motor_id) != std::end(neg);
    EXPECT_EQ(c.sign, is_neg ? -1 : 1) << int(c.motor_id);
  }
}

TEST(RuiwoBus, RefusesBadConfigurations) {
  Bus bus;
  std::string msg;
  EXPECT_EQ(build_bus({motor(1, 13, 1), motor(1, 14, 1)}, bus, msg), DriverError::kDuplicateId);
  EXPECT_NE(msg.find("0x01"), std::string::npos) << msg;
  EXPECT_EQ(build_bus({motor(0, 13, 1)}, bus, msg), DriverError::kBadConfig);
  EXPECT_EQ(build_bus({motor(2, 13, 0)}, bus, msg), DriverError::kBadConfig);
  EXPECT_EQ(build_bus({motor(2, 28, 1)}, bus, msg), DriverError::kBadConfig);
  EXPECT_EQ(build_bus({motor(2, 13, 1, 11.0)}, bus, msg), DriverError::kBadConfig);  // 2 + 11 > 12.5
  MotorConfig nan = motor(2, 13, 1);
  nan.torque_max_Nm = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(build_bus({nan}, bus, msg), DriverError::kBadConfig);
}

TEST(RuiwoBus, SignAndOffsetMapJointToMotorAndBack) {
  Bus bus;
  std::string msg;
  ASSERT_EQ(build_bus({motor(4, 15, -1, 0.25)}, bus, msg), DriverError::kOk) << msg;
  hal::JointCommand cmd;
  cmd.mode = hal::JointMode::kPdTorque;
  cmd.position_ref_rad = 0.5;
  cmd.velocity_ref_rad_s = 1.0;
  cmd.torque_ff_Nm = 3.0;
  cmd.kp_Nm_per_rad = 30;
  cmd.kd_Nm_s_per_rad = 2;
  can_frame f;
  EXPECT_EQ(encode_command_rt(bus, 0, cmd, f), 0);
  PtmCommand wire;
  ASSERT_EQ(decode_ptm_rt(f, wire), DriverError::kOk);
  EXPECT_NEAR(wire.position_rad, -0.5 + 0.25, 25.0 / 65535);
  EXPECT_NEAR(wire.velocity_rad_s, -1.0, 20.0 / 4095);
  EXPECT_NEAR(wire.torque_Nm, -3.0, 100.0 / 4095);
  EXPECT_NEAR(wire.kp_Nm_per_rad, 30, 250.0 / 4095);

  // The reply maps back through the same sign and offset.
  Status st{4, -0.75 + 0.25, -2.0, 1.5, 30, 0};
  can_frame reply;
  encode_status_rt(st, reply);
  hal::SensorFrame sensors;
  ASSERT_EQ(handle_reply_rt(bus, reply, 1234, sensors), DriverError::kOk);
  EXPECT_NEAR(sensors.joints[15].position_rad, 0.75, 25.0 / 65535);
  EXPECT_NEAR(sensors.joints[15].velocity_rad_s, 2.0, 20.0 / 4095);
  EXPECT_NEAR(sensors.joints[15].torque_Nm, -1.5, 100.0 / 4095);
  EXPECT_EQ(sensors.joints[15].stamp_ns, 1234);
  EXPECT_TRUE(sensors.joints[15].valid);
}

TEST(RuiwoBus, JointLimitsClampBeforeTheWireAndAreReported) {
  Bus bus;
  std::string msg;
  ASSERT_EQ(build_bus({motor(3, 14, 1)}, bus, msg), DriverError::kOk);
  hal::JointCommand cmd;
  cmd.mode = hal::JointMode::kPdTorque;
  cmd.position_ref_rad = 2.5;     // max 2.0
  cmd.torque_ff_Nm = -25.0;       // limit 20
  cmd.velocity_ref_rad_s = 4.0;   // fine
  can_frame f;
  const std::uint8_t flags = encode_command_rt(bus, 0, cmd, f);
  EXPECT_EQ(flags, kClampPosition | kClampTorque);
  EXPECT_EQ(bus.state[0].clamp_events, 1u);
  PtmCommand wire;
  decode_ptm_rt(f, wire);
  EXPECT_NEAR(wire.position_rad, 2.0, 25.0 / 65535);
  EXPECT_NEAR(wire.torque_Nm, -20.0, 100.0 / 4095);
}

TEST(RuiwoBus, NonFiniteJointCommandIsNeutralisedAndReported) {
  Bus bus;
  std::string msg;
  ASSERT_EQ(build_bus({motor(3, 14, -1, 0.2)}, bus, msg), DriverError::kOk);
  hal::JointCommand cmd;
  cmd.mode = hal::JointMode::kPdTorque;
  cmd.position_ref_rad = std::numeric_limits<double>::quiet_NaN();
  cmd.kp_Nm_per_rad = 80;
  cmd.kd_Nm_s_per_rad = 2;
  cmd.torque_ff_Nm = std::numeric_limits<double>::infinity();
  can_frame f;
  const std::uint8_t flags = encode_command_rt(bus, 0, cmd, f);
  EXPECT_TRUE(flags & kNonFinite);
  PtmCommand wire;
  ASSERT_EQ(decode_ptm_rt(f, wire), DriverError::kOk);
  EXPECT_EQ(wire.kp_Nm_per_rad, 0.0);
  EXPECT_NEAR(wire.torque_Nm, 0.0, 100.0 / 4095);
  EXPECT_NEAR(wire.kd_Nm_s_per_rad, 2.0, 50.0 / 4095);
}

TEST(RuiwoBus, DampingAndDisabledModesSendNoStiffness) {
  Bus bus;
  std::string msg;
  ASSERT_EQ(build_bus({motor(3, 14, 1)}, bus, msg), DriverError::kOk);
  hal::JointCommand cmd;
  cmd.mode = hal::JointMode::kDamping;
  cmd.position_ref_rad = 1.0;
  cmd.kp_Nm_per_rad = 100;
  cmd.kd_Nm_s_per_rad = 3;
  cmd.torque_ff_Nm = 5;
  can_frame f;
  encode_command_rt(bus, 0, cmd, f);
  PtmCommand wire;
  decode_ptm_rt(f, wire);
  EXPECT_EQ(wire.kp_Nm_per_rad, 0.0);
  EXPECT_NEAR(wire.kd_Nm_s_per_rad, 3.0, 50.0 / 4095);
  EXPECT_NEAR(wire.torque_Nm, 0.0, 100.0 / 4095);
  cmd.mode = hal::JointMode::kDisabled;
  encode_command_rt(bus, 0, cmd, f);
  decode_ptm_rt(f, wire);
  EXPECT_EQ(wire.kp_Nm_per_rad, 0.0);
  EXPECT_EQ(wire.kd_Nm_s_per_rad, 0.0);
}

TEST(RuiwoBus, ReplyTimeoutMakesAMotorSilentAfterFourMisses) {
  Bus bus;
  std::string msg;
  ASSERT_EQ(build_bus({motor(1, 13, 1), motor(2, 14, 1)}, bus, msg), DriverError::kOk);
  hal::SensorFrame sensors;
  sensors.joints[13].valid = sensors.joints[14].valid = true;
  const hal::TimeNs cycle = 4'000'000;
  can_frame reply;
  const int n = static_cast<int>(kMaxConsecutiveMisses);
  for (int k = 0; k < n; ++k) {
    const hal::TimeNs t = k * cycle;
    note_sent_rt(bus, 0, t);
    note_sent_rt(bus, 1, t);
    encode_status_rt(Status{2, 0, 0, 0, 0, 0}, reply);  // only motor 2 answers
    ASSERT_EQ(handle_reply_rt(bus, reply, t + 200'000, sensors), DriverError::kOk);
    EXPECT_EQ(check_timeouts_rt(bus, t + 2'000'000, sensors), 0) << "not yet due";
    const int silent = check_timeouts_rt(bus, t + kReplyTimeout_ns + 1, sensors);
    EXPECT_EQ(silent, k == n - 1 ? 1 : 0);
  }
  EXPECT_TRUE(bus.state[0].silent);
  EXPECT_FALSE(sensors.joints[13].valid);
  EXPECT_TRUE(sensors.joints[14].valid);
  EXPECT_EQ(bus.state[0].total_misses, kMaxConsecutiveMisses);
  // One good reply clears the silence.
  encode_status_rt(Status{1, 0, 0, 0, 0, 0}, reply);
  ASSERT_EQ(handle_reply_rt(bus, reply, 13 * cycle, sensors), DriverError::kOk);
  EXPECT_FALSE(bus.state[0].silent);
  EXPECT_TRUE(sensors.joints[13].valid);
}

TEST(RuiwoBus, UnknownAndFaultyReplies) {
  Bus bus;
  std::string msg;
  ASSERT_EQ(build_bus({motor(1, 13, 1)}, bus, msg), DriverError::kOk);
  hal::SensorFrame sensors;
  can_frame reply;
  encode_status_rt(Status{9, 0, 0, 0, 0, 0}, reply);
  EXPECT_EQ(handle_reply_rt(bus, reply, 1, sensors), DriverError::kUnknownMotor);
  EXPECT_EQ(bus.unknown_replies, 1u);
  encode_status_rt(Status{1, 0, 0, 0, 0, 0x11}, reply);
  EXPECT_EQ(handle_reply_rt(bus, reply, 1, sensors), DriverError::kMotorFault);
  EXPECT_EQ(bus.state[0].last.fault_code, 0x11);
}

TEST(RuiwoBus, CycleDoesNotAllocate) {
  const model::Model m = s45();
  Bus bus;
  std::string msg;
  ASSERT_EQ(build_bus(default_motors(m), bus, msg), DriverError::kOk);
  hal::CommandFrame cmds;
  hal::SensorFrame sensors;
  can_frame f;
  test::AllocTrap trap;
  for (int i = 0; i < bus.count; ++i) {
    encode_command_rt(bus, i, cmds.joints[bus.motors[i].joint], f);
    note_sent_rt(bus, i, 0);
    encode_status_rt(Status{bus.motors[i].motor_id, 0.1, 0, 0, 0, 0}, f);
    (void)handle_reply_rt(bus, f, 10, sensors);
  }
  (void)check_timeouts_rt(bus, 5'000'000, sensors);
  EXPECT_EQ(trap.count(), 0u);
}

}  // namespace
}  // namespace kuavo::drivers::ruiwo
