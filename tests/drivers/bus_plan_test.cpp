// Bus load: frame sizes from the worst-case stuffing formula, the default plan
// under 70 % on every bus, and refusal of overloaded or inconsistent plans.
#include <gtest/gtest.h>

#include "controllers/model/model_tables.h"
#include "drivers/bus/bus_load.h"
#include "drivers/bus/bus_plan.h"
#include "drivers/bus/open_buses.h"

#include <sys/socket.h>
#include <unistd.h>

namespace kuavo::drivers {
namespace {

TEST(BusLoad, ClassicFrameBitsMatchPublishedWorstCase) {
  // Davis et al. 2007: 135 bit for 8 data bytes, 11-bit ID; 160 with a 29-bit ID.
  EXPECT_EQ(classic_frame_bits_worst(8, false), 135);
  EXPECT_EQ(classic_frame_bits_worst(8, true), 160);
  // 0 bytes: 47 fixed + floor(33/4) = 8 stuff bits.
  EXPECT_EQ(classic_frame_bits_worst(0, false), 55);
  EXPECT_EQ(classic_frame_bits_worst(1, false), 65);
  EXPECT_EQ(classic_frame_bits_worst(7, false), 125);
  EXPECT_DOUBLE_EQ(classic_frame_time_us(8, false, 1e6), 135.0);
  EXPECT_DOUBLE_EQ(classic_frame_time_us(8, false, 500e3), 270.0);
}

TEST(BusLoad, FdFrameTimeIsPlausible) {
  const double fd8 = fd_frame_time_us(8, false, 1e6, 5e6);
  const double fd64 = fd_frame_time_us(64, false, 1e6, 5e6);
  EXPECT_LT(fd8, classic_frame_time_us(8, false, 1e6));  // the data phase is 5x faster
  EXPECT_GT(fd64, fd8);
  // With data rate = nominal rate FD cannot be shorter than a classic frame.
  EXPECT_GT(fd_frame_time_us(8, false, 1e6, 1e6), classic_frame_time_us(8, false, 1e6));
}

TEST(BusPlan, DefaultPlanFitsAndMatchesHandComputedLoads) {
  const BusPlan plan = default_bus_plan();
  BusLoadReport rep;
  std::string msg;
  ASSERT_EQ(check_bus_plan(plan, rep, msg), DriverError::kOk) << msg;
  ASSERT_EQ(plan.buses.size(), 7u);
  // Every actuator slot has exactly one device.
  EXPECT_EQ(plan.devices.size(), static_cast<std::size_t>(model::kNumJoints));
  // Leg bus: 3 drives x (135 + 135 + 125) bit x 500 Hz + SYNC 55 bit x 500 Hz
  //          + 3 heartbeats x 65 bit x 50 Hz = 629 750 bit/s at 1 Mbit/s.
  const double leg = (3 * (135 + 135 + 125) * 500.0 + 55 * 500.0 + 3 * 65 * 50.0) / 1e6;
  for (int b = 0; b < 4; ++b) EXPECT_NEAR(rep.load[b], leg, 1e-12) << plan.buses[b].interface;
  // Shoulder bus: 2 drives.
  EXPECT_NEAR(rep.load[4], (2 * 395 * 500.0 + 55 * 500.0 + 2 * 65 * 50.0) / 1e6, 1e-12);
  // Ruiwo: 8 motors (left arm + head) and 6 motors, 2 x 135 bit at 250 Hz each.
  EXPECT_NEAR(rep.load[5], 8 * 2 * 135 * 250.0 / 1e6, 1e-12);
  EXPECT_NEAR(rep.load[6], 6 * 2 * 135 * 250.0 / 1e6, 1e-12);
  for (double l : rep.load) EXPECT_LT(l, kMaxBusLoad);
}

TEST(BusPlan, LejuSingleRuiwoBusAt250HzIsRefused) {
  BusLoadReport rep;
  std::string msg;
  // 14 motors x 2 frames x 135 bit x 250 Hz = 945 kbit/s (FACTS.md §5.2 estimate).
  EXPECT_EQ(check_bus_plan(single_ruiwo_bus_plan(250.0), rep, msg), DriverError::kBusOverloaded);
  EXPECT_NE(msg.find("can0"), std::string::npos) << msg;
  EXPECT_NE(msg.find("94.5 %"), std::string::npos) << msg;
  // At 180 Hz it is 68.0 % and accepted.
  EXPECT_EQ(check_bus_plan(single_ruiwo_bus_plan(180.0), rep, msg), DriverError::kOk) << msg;
  EXPECT_NEAR(rep.load[0], 0.6804, 1e-9);
}

TEST(BusPlan, LegDrivesAt1kHzAreRefused) {
  BusPlan plan = default_bus_plan();
  plan.buses[0].cycle_rate_hz = 1000.0;
  BusLoadReport rep;
  std::string msg;
  EXPECT_EQ(check_bus_plan(plan, rep, msg), DriverError::kBusOverloaded);
  EXPECT_NE(msg.find(plan.buses[0].interface), std::string::npos) << msg;
}

TEST(BusPlan, InconsistentPlansAreRefused) {
  BusLoadReport rep;
  std::string msg;
  BusPlan dup_id = default_bus_plan();
  dup_id.devices[1].id = dup_id.devices[0].id;
  EXPECT_EQ(check_bus_plan(dup_id, rep, msg), DriverError::kDuplicateId);
  BusPlan dup_slot = default_bus_plan();
  dup_slot.devices[1].slot = dup_slot.devices[0].slot;
  EXPECT_EQ(check_bus_plan(dup_slot, rep, msg), DriverError::kDuplicateId);
  BusPlan bad_bus = default_bus_plan();
  bad_bus.devices[0].bus = 99;
  EXPECT_EQ(check_bus_plan(bad_bus, rep, msg), DriverError::kBadConfig);
  BusPlan dup_if = default_bus_plan();
  dup_if.buses[1].interface = dup_if.buses[0].interface;
  EXPECT_EQ(check_bus_plan(dup_if, rep, msg), DriverError::kDuplicateId);
  BusPlan mixed = default_bus_plan();
  mixed.devices.back().bus = 0;  // a Ruiwo motor onto a leg bus
  EXPECT_EQ(check_bus_plan(mixed, rep, msg), DriverError::kBadConfig);
  EXPECT_NE(msg.find("Ruiwo motors and CiA 402 drives"), std::string::npos) << msg;
  BusPlan bad_fd = default_bus_plan();
  bad_fd.buses[0].fd = true;
  bad_fd.buses[0].data_bitrate_bps = 0;
  EXPECT_EQ(check_bus_plan(bad_fd, rep, msg), DriverError::kBadConfig);
}

TEST(OpenBuses, FailsCleanlyWithoutKernelCan) {
  const int probe = socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (probe >= 0) {
    close(probe);
    GTEST_SKIP() << "this kernel has AF_CAN";
  }
  std::vector<CanPort> ports;
  std::string msg;
  EXPECT_EQ(open_buses(default_bus_plan(), ports, msg), DriverError::kNoCanSupport);
  EXPECT_TRUE(ports.empty());
  EXPECT_EQ(msg.rfind("can0: socket(AF_CAN) failed", 0), 0u) << msg;
}

}  // namespace
}  // namespace kuavo::drivers
