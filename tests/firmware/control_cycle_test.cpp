// The whole firmware cycle with synthetic sensors (a robot frozen in the
// standing pose): mode sequence through the real standing controller, e-stop
// from every mode, refused commands replaced by damping in the same cycle,
// the log ring, and no heap in the cycle.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "firmware/control_cycle.h"
#include "tests/firmware/firmware_test_support.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::firmware {
namespace {

using test_support::all_damping;
using test_support::restamp;
using test_support::standing_sensors;
using test_support::test_model;

constexpr hal::TimeNs kTick_ns = 2'000'000;

// Wraps the standing controller and corrupts its output on demand.
struct FaultyController {
  StandingController inner;
  int corrupt_joint = -1;
  double hal::JointCommand::*field = nullptr;
  double value = 0.0;
  void operator()(const hal::SensorFrame& s, hal::CommandFrame& out) const noexcept {
    inner(s, out);
    if (corrupt_joint >= 0) out.joints[corrupt_joint].*field = value;
  }
};

struct Rig {
  static Firmware& fw() {
    static Firmware f;
    return f;
  }
  static LogSink& log() {
    static LogSink l;
    return l;
  }
  hal::SensorFrame sensors;
  hal::CommandFrame out;
  hal::TimeNs now = 0;
  FaultyController controller{StandingController{&fw()}};

  Rig() {
    firmware_init(fw(), test_model(), FirmwareConfig{}, &log());
    LogWriter::drain(log(), nullptr);
    sensors = standing_sensors(fw().standing.pose_rad, 0);
  }
  void tick(const CycleInputs& in = {}) {
    restamp(sensors, now);
    firmware_cycle_rt(fw(), sensors, in, now, controller, out);
    now += kTick_ns;
  }
  // Runs until `m` or a bound; requests what the nominal path needs.
  bool reach(Mode m) {
    for (int i = 0; i < 5000 && fw().mode.mode != m; ++i) {
      CycleInputs in;
      const Mode cur = fw().mode.mode;
      if (cur == Mode::kDamping) in.request = Request::kStandUp;
      if (cur == Mode::kReady) in.request = m == Mode::kFinish ? Request::kFinish : Request::kDance;
      if (cur == Mode::kDance) in.request = Request::kFinish;
      tick(in);
    }
    return fw().mode.mode == m;
  }
};

TEST(ControlCycle, SequenceAndCommandsPerMode) {
  Rig rig;
  rig.tick();
  EXPECT_EQ(rig.fw().mode.mode, Mode::kSelfCheck);
  for (const hal::JointCommand& c : rig.out.joints) EXPECT_EQ(c.mode, hal::JointMode::kDisabled);
  rig.tick();
  EXPECT_EQ(rig.fw().mode.mode, Mode::kDamping);
  ASSERT_TRUE(rig.reach(Mode::kStandUp));
  rig.tick();
  // Early in the stand-up ramp the gains are a small fraction of the controller's.
  EXPECT_EQ(rig.out.joints[3].mode, hal::JointMode::kPdTorque);
  EXPECT_LT(rig.out.joints[3].kp_Nm_per_rad, 0.01 * rig.fw().controller_command.joints[3].kp_Nm_per_rad + 1e-9);
  ASSERT_TRUE(rig.reach(Mode::kReady));
  rig.tick();
  EXPECT_DOUBLE_EQ(rig.out.joints[3].kp_Nm_per_rad, rig.fw().controller_command.joints[3].kp_Nm_per_rad);
  ASSERT_TRUE(rig.reach(Mode::kDance));
  ASSERT_TRUE(rig.reach(Mode::kFinish));
  ASSERT_TRUE(rig.reach(Mode::kDamping));
  EXPECT_EQ(rig.fw().mode.latched, Fault::kNone);
  rig.tick();
  EXPECT_TRUE(all_damping(rig.out));
  // The log saw every transition: self-check, damping, stand-up, ready, dance, finish, damping.
  int modes = 0;
  LogRecord r;
  while (rig.log().ring.try_pop_rt(r)) modes += r.kind == LogKind::kModeChange ? 1 : 0;
  EXPECT_EQ(modes, 7);
}

TEST(ControlCycle, EstopFromEveryModeDampsInTheSameCycle) {
  for (Mode m : {Mode::kBoot, Mode::kSelfCheck, Mode::kDamping, Mode::kStandUp, Mode::kReady, Mode::kDance,
                 Mode::kFinish}) {
    Rig rig;
    ASSERT_TRUE(rig.reach(m)) << to_string(m);
    CycleInputs in;
    in.estop = true;
    rig.tick(in);
    EXPECT_EQ(rig.fw().mode.mode, Mode::kDamping) << "from " << to_string(m);
    EXPECT_EQ(rig.fw().mode.latched, Fault::kEstop);
    EXPECT_TRUE(all_damping(rig.out)) << "from " << to_string(m);
    rig.tick();  // released: still damping (latched)
    EXPECT_TRUE(all_damping(rig.out));
  }
}

TEST(ControlCycle, BadControllerOutputIsReplacedByDampingInTheSameCycle) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    double hal::JointCommand::*field;
    double value;
    Fault fault;
  };
  for (const Case& k : {Case{&hal::JointCommand::torque_ff_Nm, nan, Fault::kCommandNonFinite},
                        Case{&hal::JointCommand::position_ref_rad, 3.5, Fault::kCommandPositionLimit},
                        Case{&hal::JointCommand::torque_ff_Nm, 1e4, Fault::kCommandTorqueLimit},
                        Case{&hal::JointCommand::kp_Nm_per_rad, -5.0, Fault::kCommandGainRange}}) {
    for (Mode m : {Mode::kStandUp, Mode::kReady, Mode::kDance, Mode::kFinish}) {
      Rig rig;
      ASSERT_TRUE(rig.reach(m));
      rig.controller.corrupt_joint = 9;
      rig.controller.field = k.field;
      rig.controller.value = k.value;
      rig.tick();
      EXPECT_EQ(rig.fw().mode.mode, Mode::kDamping) << to_string(m);
      EXPECT_EQ(rig.fw().mode.latched, k.fault) << to_string(m);
      EXPECT_EQ(rig.fw().last_filter.joint, 9);
      EXPECT_TRUE(all_damping(rig.out));
      for (const hal::JointCommand& c : rig.out.joints) EXPECT_TRUE(std::isfinite(c.torque_ff_Nm));
      rig.controller.corrupt_joint = -1;
      CycleInputs in;
      in.request = Request::kStandUp;  // latched: refused
      rig.tick(in);
      EXPECT_EQ(rig.fw().mode.mode, Mode::kDamping);
    }
  }
}

TEST(ControlCycle, WatchdogTripsWithinOneTick) {
  Rig rig;
  ASSERT_TRUE(rig.reach(Mode::kReady));
  CycleInputs in;
  in.watch.estimator_diverged = true;
  rig.tick(in);
  EXPECT_EQ(rig.fw().mode.latched, Fault::kEstimatorDiverged);
  EXPECT_TRUE(all_damping(rig.out));
}

TEST(ControlCycle, NoHeapInTheCycle) {
  Rig rig;
  // Warm up through every mode first (first-touch paths), then count.
  ASSERT_TRUE(rig.reach(Mode::kReady));
  std::size_t allocations = 0;
  {
    kuavo::test::AllocTrap trap;
    for (int i = 0; i < 3000; ++i) {
      CycleInputs in;
      if (i == 1000) in.request = Request::kDance;
      if (i == 2000) in.request = Request::kFinish;
      rig.tick(in);
    }
    CycleInputs in;
    in.estop = true;
    rig.tick(in);
    allocations = trap.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(rig.fw().mode.mode, Mode::kDamping);
}

}  // namespace
}  // namespace kuavo::firmware
