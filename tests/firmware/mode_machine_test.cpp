// The mode machine alone: the nominal sequence, e-stop and faults from every
// mode, latching and clearing.
#include <gtest/gtest.h>

#include "firmware/mode_machine.h"

namespace kuavo::firmware {
namespace {

constexpr hal::TimeNs kSelfCheckTimeout_ns = 3'000'000'000, kStandUp_ns = 2'000'000'000, kFinish_ns = 1'000'000'000;

bool step(ModeState& s, const ModeInputs& in, hal::TimeNs now) {
  return step_mode_rt(s, in, now, kSelfCheckTimeout_ns, kStandUp_ns, kFinish_ns);
}

// Drives a fresh machine into `target` along the nominal path; returns the time reached.
hal::TimeNs drive_to(ModeState& s, Mode target) {
  hal::TimeNs t = 0;
  ModeInputs in;
  while (s.mode != target) {
    in = ModeInputs{};
    in.self_check_passed = true;
    if (s.mode == Mode::kDamping) in.request = Request::kStandUp;
    if (s.mode == Mode::kReady) in.request = target == Mode::kFinish ? Request::kFinish : Request::kDance;
    if (s.mode == Mode::kDance) in.request = Request::kFinish;
    step(s, in, t);
    t += 2'000'000;
    if (t > 10'000'000'000) break;  // bounded
  }
  return t;
}

TEST(ModeMachine, NominalSequence) {
  ModeState s;
  ModeInputs in;
  EXPECT_EQ(s.mode, Mode::kBoot);
  EXPECT_TRUE(step(s, in, 0));
  EXPECT_EQ(s.mode, Mode::kSelfCheck);
  EXPECT_FALSE(step(s, in, 2'000'000));  // not passed yet
  in.self_check_passed = true;
  EXPECT_TRUE(step(s, in, 4'000'000));
  EXPECT_EQ(s.mode, Mode::kDamping);
  in = ModeInputs{};
  in.request = Request::kDance;  // does not fit damping: ignored
  EXPECT_FALSE(step(s, in, 6'000'000));
  in.request = Request::kStandUp;
  EXPECT_TRUE(step(s, in, 8'000'000));
  EXPECT_EQ(s.mode, Mode::kStandUp);
  in = ModeInputs{};
  EXPECT_FALSE(step(s, in, 8'000'000 + kStandUp_ns - 1));
  EXPECT_TRUE(step(s, in, 8'000'000 + kStandUp_ns));
  EXPECT_EQ(s.mode, Mode::kReady);
  in.request = Request::kDance;
  EXPECT_TRUE(step(s, in, 3'000'000'000));
  EXPECT_EQ(s.mode, Mode::kDance);
  in = ModeInputs{};
  in.dance_done = true;
  EXPECT_TRUE(step(s, in, 4'000'000'000));
  EXPECT_EQ(s.mode, Mode::kFinish);
  in = ModeInputs{};
  EXPECT_FALSE(step(s, in, 4'000'000'000 + kFinish_ns - 1));
  EXPECT_TRUE(step(s, in, 4'000'000'000 + kFinish_ns));
  EXPECT_EQ(s.mode, Mode::kDamping);
  EXPECT_EQ(s.latched, Fault::kNone);
  EXPECT_EQ(s.transitions, 7u);
}

TEST(ModeMachine, EstopFromEveryModeGoesToDampingAndLatches) {
  for (Mode m : {Mode::kBoot, Mode::kSelfCheck, Mode::kDamping, Mode::kStandUp, Mode::kReady, Mode::kDance,
                 Mode::kFinish}) {
    ModeState s;
    const hal::TimeNs t = drive_to(s, m);
    ASSERT_EQ(s.mode, m) << to_string(m);
    ModeInputs in;
    in.estop = true;
    in.request = Request::kStandUp;  // must not win over the e-stop
    step(s, in, t);
    EXPECT_EQ(s.mode, Mode::kDamping) << "from " << to_string(m);
    EXPECT_EQ(s.latched, Fault::kEstop);
    // Released but not cleared: stand-up refused.
    in = ModeInputs{};
    in.request = Request::kStandUp;
    step(s, in, t + 2'000'000);
    EXPECT_EQ(s.mode, Mode::kDamping);
    // Clear while still pressed: refused.
    in = ModeInputs{};
    in.estop = true;
    in.request = Request::kClearFaults;
    step(s, in, t + 4'000'000);
    EXPECT_EQ(s.latched, Fault::kEstop);
    // Released and cleared: stand-up allowed again.
    in = ModeInputs{};
    in.request = Request::kClearFaults;
    step(s, in, t + 6'000'000);
    EXPECT_EQ(s.latched, Fault::kNone);
    in.request = Request::kStandUp;
    step(s, in, t + 8'000'000);
    EXPECT_EQ(s.mode, Mode::kStandUp);
  }
}

TEST(ModeMachine, FaultFromEveryModeLatchesFirstCause) {
  for (Mode m : {Mode::kSelfCheck, Mode::kStandUp, Mode::kReady, Mode::kDance, Mode::kFinish}) {
    ModeState s;
    const hal::TimeNs t = drive_to(s, m);
    ModeInputs in;
    in.fault = Fault::kTiltExceeded;
    EXPECT_TRUE(step(s, in, t));
    EXPECT_EQ(s.mode, Mode::kDamping);
    EXPECT_EQ(s.latched, Fault::kTiltExceeded);
    EXPECT_EQ(s.latched_ns, t);
    in.fault = Fault::kSensorStale;  // a later fault does not overwrite the first
    EXPECT_FALSE(step(s, in, t + 2'000'000));
    EXPECT_EQ(s.latched, Fault::kTiltExceeded);
  }
}

TEST(ModeMachine, SelfCheckTimesOut) {
  ModeState s;
  ModeInputs in;
  step(s, in, 0);
  step(s, in, kSelfCheckTimeout_ns);
  EXPECT_EQ(s.mode, Mode::kSelfCheck);
  step(s, in, kSelfCheckTimeout_ns + 1);
  EXPECT_EQ(s.mode, Mode::kDamping);
  EXPECT_EQ(s.latched, Fault::kSelfCheckTimeout);
}

TEST(ModeMachine, FaultNumbersAreStable) {
  // Documented in fault.h; logs and fault records depend on these.
  EXPECT_EQ(static_cast<int>(Fault::kEstop), 1);
  EXPECT_EQ(static_cast<int>(Fault::kSensorStale), 10);
  EXPECT_EQ(static_cast<int>(Fault::kMotorSilent), 12);
  EXPECT_EQ(static_cast<int>(Fault::kBusOff), 13);
  EXPECT_EQ(static_cast<int>(Fault::kTiltExceeded), 18);
  EXPECT_EQ(static_cast<int>(Fault::kSensorImplausible), 21);
  EXPECT_EQ(static_cast<int>(Fault::kCommandNonFinite), 30);
  EXPECT_EQ(static_cast<int>(Fault::kCommandMode), 34);
  EXPECT_EQ(static_cast<int>(Mode::kDamping), 2);
  EXPECT_STREQ(to_string(Fault::kBusOff), "CAN bus-off");
}

}  // namespace
}  // namespace kuavo::firmware
