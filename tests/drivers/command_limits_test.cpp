// Property: whatever the controller asks (NaN, Inf, huge, negative gains),
// nothing out of limit or non-finite reaches the bus. Random joint commands go
// through the real send path; the frames are decoded on the far side and
// checked against the configured limits.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <sys/socket.h>
#include <unistd.h>

#include "controllers/model/model.h"
#include "drivers/canopen/cia402_drive.h"
#include "drivers/cycle/ruiwo_io.h"

namespace kuavo::drivers {
namespace {

double wild(std::mt19937& rng) {
  switch (rng() % 8) {
    case 0: return std::numeric_limits<double>::quiet_NaN();
    case 1: return std::numeric_limits<double>::infinity();
    case 2: return -std::numeric_limits<double>::infinity();
    case 3: return std::uniform_real_distribution<double>(-1e6, 1e6)(rng);
    default: return std::uniform_real_distribution<double>(-20, 20)(rng);
  }
}

hal::JointCommand wild_command(std::mt19937& rng) {
  hal::JointCommand c;
  c.mode = static_cast<hal::JointMode>(rng() % 3);
  c.position_ref_rad = wild(rng);
  c.velocity_ref_rad_s = wild(rng);
  c.torque_ff_Nm = wild(rng);
  c.kp_Nm_per_rad = wild(rng);
  c.kd_Nm_s_per_rad = wild(rng);
  return c;
}

TEST(CommandLimits, RuiwoFramesStayInsideConfiguredLimits) {
  model::Model model;
  ASSERT_EQ(model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, model), model::ModelError::kOk);
  std::vector<ruiwo::MotorConfig> motors = ruiwo::default_motors(model);
  motors[1].zero_offset_rad = 0.4;
  ruiwo::Bus bus;
  std::string msg;
  ASSERT_EQ(ruiwo::build_bus(motors, bus, msg), DriverError::kOk) << msg;
  int fd[2];
  ASSERT_EQ(socketpair(AF_UNIX, SOCK_SEQPACKET, 0, fd), 0);
  CanPort host = attach_can_port(fd[0], false), dev = attach_can_port(fd[1], false);
  std::mt19937 rng(1234);
  hal::CommandFrame commands;
  const double lsb_position = 25.0 / 65535, lsb12 = 100.0 / 4095;
  for (int cycle = 0; cycle < 2000; ++cycle) {
    for (auto& c : commands.joints) c = wild_command(rng);
    const RuiwoSendReport sent = ruiwo_send_rt(host, bus, commands, cycle * 4'000'000LL);
    ASSERT_EQ(sent.sent, bus.count);
    RxFrame rx;
    can_frame f;
    while (receive_rt(dev, rx) == DriverError::kOk) {
      ASSERT_TRUE(as_classic(rx, f));
      const int i = bus.index_of_id[f.can_id];
      ASSERT_GE(i, 0);
      const ruiwo::MotorConfig& m = bus.motors[i];
      const hal::JointCommand& c = commands.joints[m.joint];
      ruiwo::PtmCommand w;
      ASSERT_EQ(ruiwo::decode_ptm_rt(f, w), DriverError::kOk);
      const double q_joint = ruiwo::joint_position_rad(m, w.position_rad);
      if (w.kp_Nm_per_rad > 0) {  // the position only matters with stiffness
        EXPECT_GE(q_joint, m.position_min_rad - lsb_position);
        EXPECT_LE(q_joint, m.position_max_rad + lsb_position);
        EXPECT_TRUE(std::isfinite(c.position_ref_rad)) << "stiffness on a non-finite target";
      }
      EXPECT_LE(std::abs(w.torque_Nm), m.torque_max_Nm + lsb12);
      EXPECT_LE(std::abs(w.velocity_rad_s), m.velocity_max_rad_s + 20.0 / 4095);
      if (c.mode != hal::JointMode::kPdTorque) {
        EXPECT_EQ(w.kp_Nm_per_rad, 0.0);
      }
      if (c.mode == hal::JointMode::kDisabled) {
        EXPECT_EQ(w.kd_Nm_s_per_rad, 0.0);
      }
    }
  }
  close(fd[0]);
  close(fd[1]);
}

TEST(CommandLimits, Cia402TorqueStaysInsideTheLimit) {
  canopen::DriveConfig cfg;
  cfg.node_id = 5;
  cfg.rated_torque_Nm = 50.4;
  cfg.torque_limit_Nm = 72.0;
  canopen::DriveState st;
  st.phase = canopen::DrivePhase::kOperational;
  st.nmt = canopen::NmtState::kOperational;
  st.power = canopen::Cia402State::kOperationEnabled;
  std::mt19937 rng(99);
  can_frame f;
  for (int k = 0; k < 20000; ++k) {
    const hal::TimeNs now = k * 2'000'000LL;
    st.heartbeat_ns = st.tpdo1_ns = now;
    st.have_tpdo1 = true;
    canopen::DriveCommand cmd{rng() % 4 != 0, wild(rng), wild(rng)};
    ASSERT_TRUE(canopen::step_rt(cfg, st, now, cmd, f));
    const auto permille = static_cast<std::int16_t>(canopen::get_u16(&f.data[2]));
    EXPECT_LE(std::abs(permille * cfg.rated_torque_Nm / 1000.0), cfg.torque_limit_Nm + cfg.rated_torque_Nm / 1000.0);
    if (!cmd.enable || !std::isfinite(cmd.torque_Nm)) {
      EXPECT_EQ(permille, 0);
    }
  }
}

}  // namespace
}  // namespace kuavo::drivers
