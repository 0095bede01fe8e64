// Drivers configuration: defaults from FACTS.md / kuavo.json, JSON overrides
// with strict keys, and validation that refuses inconsistent robots.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>

#include "drivers/config/drive_defaults.h"
#include "drivers/config/drivers_config.h"
#include "drivers/config/drivers_config_json.h"

namespace kuavo::drivers {
namespace {

class DriversConfigTest : public ::testing::Test {
 protected:
  model::Model model;
  DriversConfig config;
  BusLoadReport report;
  std::string msg;
  void SetUp() override {
    ASSERT_EQ(model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, model), model::ModelError::kOk);
    config = default_drivers_config(model);
  }
};

TEST_F(DriversConfigTest, DefaultsAreValid) {
  ASSERT_EQ(validate_drivers_config(config, report, msg), DriverError::kOk) << msg;
  EXPECT_EQ(config.drives.size(), 14u);
  EXPECT_EQ(config.ruiwo_motors.size(), 14u);
  EXPECT_EQ(ruiwo_motors_on_bus(config, 5).size(), 8u);  // left arm + head
  EXPECT_EQ(ruiwo_motors_on_bus(config, 6).size(), 6u);
  EXPECT_EQ(config.imu_device, "/dev/ttyUSB0");
  EXPECT_EQ(config.legs[0].serial[3].ratio_motor_per_joint, -1.0);
}

TEST_F(DriversConfigTest, DriveDefaultsFollowKuavoJson) {
  // Knee: PA100_18, 2^17 x 18 counts, 94.5 Nm continuous, 135 Nm peak.
  const canopen::DriveConfig knee = default_drive_config(3, 4, 500.0, 50.0);
  EXPECT_DOUBLE_EQ(knee.counts_per_rev, 131072.0 * 18);
  EXPECT_DOUBLE_EQ(knee.rated_torque_Nm, 94.5);
  EXPECT_DOUBLE_EQ(knee.torque_limit_Nm, 135.0);
  EXPECT_EQ(knee.cycle_period_us, 2000u);
  EXPECT_EQ(knee.heartbeat_period_ms, 20);
  EXPECT_EQ(knee.heartbeat_timeout_ns, 60'000'000);
  EXPECT_EQ(knee.tpdo_timeout_ns, 8'000'000);  // 4 cycles at 500 Hz
  // Right ankle motor B (slot 11): CK, 2^17 x 36.
  EXPECT_DOUBLE_EQ(default_drive_config(11, 12, 500.0, 50.0).counts_per_rev, 131072.0 * 36);
  EXPECT_DOUBLE_EQ(default_drive_config(model::kRightArmFirst, 14, 500.0, 50.0).torque_limit_Nm, 66.67);
}

TEST_F(DriversConfigTest, JsonOverridesApply) {
  const char* text = R"({
    "ruiwo_motors": [{"id": 5, "sign": 1, "zero_offset_rad": 0.02}],
    "drives": [{"slot": 4, "rated_torque_Nm": 20.0}],
    "knee_ratio_motor_per_joint": -1.0,
    "ankle_motor_offset_rad": [-0.2618, -0.2618],
    "imu": {"device": "/dev/xsens", "baud": 921600}
  })";
  ASSERT_EQ(apply_drivers_json(text, config, msg), DriverError::kOk) << msg;
  ASSERT_EQ(validate_drivers_config(config, report, msg), DriverError::kOk) << msg;
  for (const auto& m : config.ruiwo_motors) {
    if (m.motor_id == 5) {
      EXPECT_EQ(m.sign, 1);
      EXPECT_DOUBLE_EQ(m.zero_offset_rad, 0.02);
    }
  }
  for (const auto& d : config.drives) {
    if (d.slot == 4) {
      EXPECT_DOUBLE_EQ(d.config.rated_torque_Nm, 20.0);
    }
  }
  EXPECT_DOUBLE_EQ(config.legs[1].ankle_motor[1].motor_offset_rad, -0.2618);
  EXPECT_EQ(config.imu_device, "/dev/xsens");
  EXPECT_EQ(config.imu_baud, 921600);
}

TEST_F(DriversConfigTest, JsonErrorsNameTheKeyAndChangeNothing) {
  const DriversConfig before = config;
  struct Case {
    const char* text;
    const char* expected;
  };
  const Case cases[] = {
      {"{ not json", "not valid JSON at line 1, column "},
      {"{\n  \"imu\": {\"device\": \"/dev/x\",}\n}", "not valid JSON at line 2, column 30"},  // the } where a key belongs
      // A key given twice: refused, not the last one silently taken.
      {R"({"imu": {"device": "/dev/a", "device": "/dev/b"}})", "duplicate key 'device' given twice in 'imu'"},
      {R"({"imu": {}, "imu": {}})", "duplicate key 'imu' given twice in 'drivers configuration'"},
      {R"({"ruiwo_motor": []})", "unknown key 'ruiwo_motor'"},
      {R"({"ruiwo_motors": [{"id": 99, "sign": 1}]})", "no Ruiwo motor with ID 99"},
      {R"({"ruiwo_motors": [{"id": 5, "sign": "minus"}]})", "ruiwo_motors[0].sign: expected an integer"},
      {R"({"drives": [{"slot": 20, "rated_torque_Nm": 1}]})", "no CiA 402 drive on slot 20"},
      {R"({"imu": {"device": "/dev/x", "bauds": 1}})", "imu: unknown key 'bauds'"},
      {R"({"ankle_motor_offset_rad": [0.1]})", "ankle_motor_offset_rad"},
      {R"({"devices": [{"bus": 0, "kind": "ethercat", "id": 1, "slot": 0}]})", "devices[0].kind"},
      // A literal no double holds threw json::out_of_range out of the loader (kuavo_fuzz,
      // parse:config, seed 22 case 2134): now a refusal naming the literal.
      {R"({"knee_ratio_motor_per_joint": 1e999})", "not valid JSON: number overflow parsing '1e999'"},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(apply_drivers_json(c.text, config, msg), DriverError::kBadConfig) << c.text;
    EXPECT_NE(msg.find(c.expected), std::string::npos) << c.text << " -> " << msg;
  }
  EXPECT_EQ(config.ruiwo_motors[4].sign, before.ruiwo_motors[4].sign);
  EXPECT_EQ(config.plan.devices.size(), before.plan.devices.size());
}

// Numbers no real robot has (issue 22): each parses, and validation refuses it.
TEST_F(DriversConfigTest, ValidationRefusesPhysicallyAbsurdNumbers) {
  const char* cases[] = {
      R"({"knee_ratio_motor_per_joint": -1e308})",
      R"({"knee_ratio_motor_per_joint": 1e-320})",
      R"({"ankle_motor_offset_rad": [1e308, 0]})",
      R"({"ankle_motor_offset_rad": [0, 100]})",
      R"({"drives": [{"slot": 3, "torque_limit_Nm": 1e308}]})",
      R"({"drives": [{"slot": 3, "counts_per_rev": 0.5}]})",
      R"({"imu": {"device": "/dev/ttyUSB0\u0000/etc/passwd"}})",
      R"({"imu": {"device": "ttyUSB0"}})",
      R"({"imu": {"baud": 1}})",
      R"({"ruiwo_motors": [{"id": 5, "torque_max_Nm": 1e308}]})",
      R"({"ruiwo_motors": [{"id": 5, "velocity_max_rad_s": 1e9}]})",
      R"({"ruiwo_motors": [{"id": 5, "zero_offset_rad": 1e308}]})",
      R"({"ruiwo_motors": [{"id": 5, "zero_offset_rad": 100}]})",
  };
  for (const char* text : cases) {
    DriversConfig c = config;
    ASSERT_EQ(apply_drivers_json(text, c, msg), DriverError::kOk) << text << " -> " << msg;
    EXPECT_EQ(validate_drivers_config(c, report, msg), DriverError::kBadConfig) << text;
  }
  // Each message names the rule with its unit.
  DriversConfig ruiwo = config;
  ASSERT_EQ(apply_drivers_json(R"({"ruiwo_motors": [{"id": 5, "torque_max_Nm": 1e308}]})", ruiwo, msg), DriverError::kOk);
  EXPECT_EQ(validate_drivers_config(ruiwo, report, msg), DriverError::kBadConfig);
  EXPECT_NE(msg.find("Ruiwo motor 0x05: velocity limit 7 rad/s and torque limit 1e+308 N·m must be in (0, 10] rad/s and (0, 50] N·m"),
            std::string::npos) << msg;
  // Bus numbers the load check let through (1e308 bit/s loads nothing) or that overflow the
  // drives' u32 cycle period / u16 heartbeat time.
  const std::function<void(BusConfig&)> bad_buses[] = {
      [](BusConfig& b) { b.bitrate_bps = 1e308; },
      [](BusConfig& b) { b.bitrate_bps = 5e3; },
      [](BusConfig& b) { b.cycle_rate_hz = 1e-9; },
      [](BusConfig& b) { b.heartbeat_rate_hz = 1e-9; },
      [](BusConfig& b) { b.fd = true, b.data_bitrate_bps = 1e12; },
  };
  for (const auto& bad : bad_buses) {
    DriversConfig c = config;
    bad(c.plan.buses[0]);
    sync_drives_with_plan(c);
    EXPECT_EQ(validate_drivers_config(c, report, msg), DriverError::kBadConfig) << msg;
    EXPECT_NE(msg.find("bitrate must be 10 kbit/s..1 Mbit/s"), std::string::npos) << msg;
  }
  // The defaults and the documented knee ratio still pass.
  DriversConfig c = config;
  ASSERT_EQ(apply_drivers_json(R"({"knee_ratio_motor_per_joint": -1.0})", c, msg), DriverError::kOk) << msg;
  EXPECT_EQ(validate_drivers_config(c, report, msg), DriverError::kOk) << msg;
}

TEST_F(DriversConfigTest, ValidationRefusesInconsistentRobots) {
  DriversConfig c = config;
  ASSERT_EQ(apply_drivers_json(R"({"ruiwo_motors": [{"id": 3, "sign": 0}]})", c, msg), DriverError::kOk);
  EXPECT_EQ(validate_drivers_config(c, report, msg), DriverError::kBadConfig);
  EXPECT_NE(msg.find("0x03"), std::string::npos) << msg;

  c = config;
  c.ruiwo_motors[0].joint = 14;  // disagrees with the plan's slot
  EXPECT_EQ(validate_drivers_config(c, report, msg), DriverError::kBadConfig);
  EXPECT_NE(msg.find("slot"), std::string::npos) << msg;

  c = config;
  c.legs[0].serial[3].ratio_motor_per_joint = 0.0;
  EXPECT_EQ(validate_drivers_config(c, report, msg), DriverError::kBadConfig);

  c = config;
  c.drives[0].config.torque_limit_Nm = 1e6;  // beyond the int16 per-mille range
  EXPECT_EQ(validate_drivers_config(c, report, msg), DriverError::kBadConfig);
}

TEST_F(DriversConfigTest, JsonPlanReplacesBusesAndResyncsDrives) {
  // Leju's wiring: all Ruiwo motors on one bus at 250 Hz -> refused at validation.
  std::string devices;
  for (const DeviceConfig& d : config.plan.devices) {
    const bool ruiwo = d.kind == DeviceKind::kRuiwoMotor;
    const int bus = ruiwo ? 5 : d.bus;
    devices += std::string(devices.empty() ? "" : ",") + R"({"bus": )" + std::to_string(bus) + R"(, "kind": ")" +
               (ruiwo ? "ruiwo" : "cia402") + R"(", "id": )" + std::to_string(d.id) + R"(, "slot": )" +
               std::to_string(d.slot) + "}";
  }
  const std::string text = R"({"buses": [{"interface": "can0"}, {"interface": "can1"}, {"interface": "can2"},
      {"interface": "can3"}, {"interface": "can4"}, {"interface": "can5", "cycle_rate_hz": 250}],
      "devices": [)" + devices + "]}";
  ASSERT_EQ(apply_drivers_json(text, config, msg), DriverError::kOk) << msg;
  EXPECT_EQ(validate_drivers_config(config, report, msg), DriverError::kBusOverloaded);
  EXPECT_NE(msg.find("can5"), std::string::npos) << msg;
  EXPECT_NE(msg.find("94.5 %"), std::string::npos) << msg;
  EXPECT_EQ(config.drives.size(), 14u);
}

TEST_F(DriversConfigTest, LoadFromFile) {
  // A missing file and a directory are configuration problems, named as such.
  EXPECT_EQ(load_drivers_config("/nonexistent/drivers.json", model, config, report, msg),
            DriverError::kConfigUnreadable);
  EXPECT_NE(msg.find("/nonexistent/drivers.json: cannot read the drivers configuration: no such file"),
            std::string::npos)
      << msg;
  EXPECT_EQ(load_drivers_config(KUAVO_BINARY_DIR, model, config, report, msg), DriverError::kConfigUnreadable);
  EXPECT_NE(msg.find("not a regular file"), std::string::npos) << msg;
  const std::string path = std::string(KUAVO_BINARY_DIR) + "/drivers_config_test.json";
  {
    std::ofstream out(path);
    out << R"({"imu": {"device": "/dev/ttyUSB1"}})";
  }
  DriversConfig loaded;
  ASSERT_EQ(load_drivers_config(path, model, loaded, report, msg), DriverError::kOk) << msg;
  EXPECT_EQ(loaded.imu_device, "/dev/ttyUSB1");
  EXPECT_EQ(report.load.size(), 7u);
  // A file far larger than any configuration is refused by its size, before it is read.
  std::filesystem::resize_file(path, (1u << 20) + 1);
  EXPECT_EQ(load_drivers_config(path, model, loaded, report, msg), DriverError::kBadConfig);
  EXPECT_NE(msg.find("1048577 bytes, more than a drivers configuration holds (1 MiB)"), std::string::npos) << msg;
  std::remove(path.c_str());
}

}  // namespace
}  // namespace kuavo::drivers

namespace kuavo::drivers {
namespace {

// The CSP binding's start-up mapping: every leg drive in CSP with its joint gain on the
// motor side (serial joints kp / r^2: the knee's r = -1 keeps it), the ankle motors sharing
// k = (kp_pitch + kp_roll) / trace(J^T J) at the zero pose; the shoulders (1:1) with their
// own gains, by their own call; the validation refuses gains the registers cannot hold.
TEST_F(DriversConfigTest, CspDrivesGetMotorSideGains) {
  const std::array<double, kLegActuators> kp{60, 61, 62, 63, 30, 30}, kd{3, 3.1, 3.2, 3.3, 1.5, 1.5};
  ASSERT_TRUE(use_csp_leg_drives(config, kp, kd, msg)) << msg;
  ASSERT_EQ(validate_drivers_config(config, report, msg), DriverError::kOk) << msg;
  std::array<double, 2> tr{};  // trace(J^T J) = sum of J's squared entries, per leg (they differ a little)
  for (int side = 0; side < 2; ++side) {
    Vec2 crank;
    ASSERT_TRUE(ankle_motor_from_joint_rt(config.legs[side].ankle, Vec2::Zero(), crank));
    const Mat2 J = ankle_jacobian_rt(config.legs[side].ankle, Vec2::Zero(), crank);
    tr[side] = J(0, 0) * J(0, 0) + J(0, 1) * J(0, 1) + J(1, 0) * J(1, 0) + J(1, 1) * J(1, 1);
  }
  int csp = 0;
  for (const DriveEntry& e : config.drives) {
    if (e.slot >= 2 * model::kLegJoints) {
      EXPECT_EQ(e.config.mode, canopen::kModeCyclicSyncTorque) << e.slot;
      continue;
    }
    ++csp;
    const int k = e.slot % model::kLegJoints;
    EXPECT_EQ(e.config.mode, canopen::kModeCyclicSyncPosition);
    if (k < 4) {
      EXPECT_DOUBLE_EQ(e.config.csp_kp_Nm_per_rad, kp[k]);  // |r| = 1 on the 4Pro (knee -1)
      EXPECT_DOUBLE_EQ(e.config.csp_kd_Nm_s_per_rad, kd[k]);
    } else {
      EXPECT_NEAR(e.config.csp_kp_Nm_per_rad, 60.0 / tr[e.slot / model::kLegJoints], 1e-12);
      EXPECT_NEAR(e.config.csp_kd_Nm_s_per_rad, 3.0 / tr[e.slot / model::kLegJoints], 1e-12);
    }
  }
  EXPECT_EQ(csp, 12);
  ASSERT_TRUE(use_csp_shoulder_drives(config, 30.0, 2.0, msg)) << msg;
  ASSERT_EQ(validate_drivers_config(config, report, msg), DriverError::kOk) << msg;
  int shoulders = 0;
  for (const DriveEntry& e : config.drives) {
    if (e.slot != model::kLeftArmFirst && e.slot != model::kRightArmFirst) continue;
    ++shoulders;
    EXPECT_EQ(e.config.mode, canopen::kModeCyclicSyncPosition);
    EXPECT_DOUBLE_EQ(e.config.csp_kp_Nm_per_rad, 30.0);
    EXPECT_DOUBLE_EQ(e.config.csp_kd_Nm_s_per_rad, 2.0);
  }
  EXPECT_EQ(shoulders, 2);
  EXPECT_FALSE(use_csp_shoulder_drives(config, 30.0, std::nan(""), msg));
  for (DriveEntry& e : config.drives) {
    if (e.slot == 3) e.config.csp_kd_Nm_s_per_rad = -1.0;
  }
  EXPECT_EQ(validate_drivers_config(config, report, msg), DriverError::kBadConfig);
}

}  // namespace
}  // namespace kuavo::drivers
