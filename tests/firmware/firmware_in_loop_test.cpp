// Firmware in the loop: the firmware cycle and its drivers binding against
// the bus emulators bound to the Simbody plant, with faults injected on the
// buses and in the controller's output. Every test asserts: damping within
// 20 ms of virtual time, no out-of-limit or non-finite value in any frame the
// emulators decoded, and bounded loops (each run has a fixed tick budget).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "drivers/emulator/bus_fault.h"
#include "tests/firmware/firmware_loop.h"

namespace kuavo::firmware {
namespace {

using test_support::FirmwareLoop;
using test_support::kDampingBudget_ns;
namespace emu = drivers::emulator;

// Bus indices of the default plan (drivers/README.md): can1 = L-leg knee+ankle,
// can5 = Ruiwo L-arm + head.
constexpr std::size_t kLegBus = 1, kArmBus = 5;
constexpr hal::TimeNs kWatch_ns = 100'000'000;  // tick budget after an injection

void expect_clean_wire(const FirmwareLoop& loop) {
  EXPECT_EQ(loop.wire_check().bad_values, 0u) << loop.wire_check().first_bad;
  EXPECT_EQ(loop.wire_check().nonfinite_clamps, 0u);
  EXPECT_GT(loop.wire_check().frames_inspected, 1000u);
  EXPECT_FALSE(loop.plant_failed());
  EXPECT_EQ(loop.allocations_in_cycle(), 0u) << "heap use in the real-time cycle";
}

// While the robot stands, the plant's ankles stay inside the linkage's reach.
void expect_standing_binding(const FirmwareLoop& loop) { EXPECT_EQ(loop.binding_failures(), 0u); }

void report(const char* what, const FirmwareLoop& loop, hal::TimeNs to_damping_ns) {
  std::printf("[ figures  ] %-24s damping after %5.1f ms, fault %u (%s), frames inspected %llu\n", what,
              1e-6 * static_cast<double>(to_damping_ns), static_cast<unsigned>(FirmwareLoop::fw().mode.latched),
              to_string(FirmwareLoop::fw().mode.latched),
              static_cast<unsigned long long>(loop.wire_check().frames_inspected));
}

// Runs `inject` on a loop standing in ready, then expects damping in budget.
template <class Inject>
hal::TimeNs inject_and_time(FirmwareLoop& loop, Inject inject) {
  EXPECT_TRUE(loop.bring_up()) << to_string(FirmwareLoop::fw().mode.latched);
  inject(loop);
  return loop.ticks_to_damping(kWatch_ns);
}

TEST(FirmwareInLoop, BringsUpAndStandsThroughTheDrivers) {
  FirmwareLoop loop;
  ASSERT_TRUE(loop.ok());
  ASSERT_TRUE(loop.bring_up(1'000'000'000)) << to_string(FirmwareLoop::fw().mode.latched);
  EXPECT_EQ(FirmwareLoop::fw().mode.latched, Fault::kNone);
  EXPECT_LT(loop.tilt_deg(), 5.0);
  expect_standing_binding(loop);
  std::printf("[ figures  ] ready at %.3f s; after 1 s released: tilt %.2f deg, base z %.3f m, frames %llu\n",
              1e-9 * static_cast<double>(loop.ready_at_ns()), loop.tilt_deg(), loop.plant().truth().q[2],
              static_cast<unsigned long long>(loop.wire_check().frames_inspected));
  expect_clean_wire(loop);
}

TEST(FirmwareInLoop, SilentArmMotor) {
  FirmwareLoop loop;
  const hal::TimeNs t = inject_and_time(loop, [](FirmwareLoop& l) {
    ASSERT_TRUE(emu::set_silent(*l.ruiwo(kArmBus), l.io().ruiwo[kArmBus].motors[2].motor_id, true));
  });
  report("silent Ruiwo motor", loop, t);
  EXPECT_GE(t, 0);
  EXPECT_LE(t, kDampingBudget_ns);
  EXPECT_TRUE(FirmwareLoop::fw().mode.latched == Fault::kMotorSilent ||
              FirmwareLoop::fw().mode.latched == Fault::kSensorStale);
  expect_clean_wire(loop);
}

TEST(FirmwareInLoop, SilentLegDrive) {
  FirmwareLoop loop;
  const hal::TimeNs t = inject_and_time(loop, [](FirmwareLoop& l) {
    ASSERT_TRUE(emu::set_drive_silent(*l.drives(kLegBus), l.drives(kLegBus)->drives[0].config.node_id, true));
  });
  report("silent leg drive", loop, t);
  EXPECT_GE(t, 0);
  EXPECT_LE(t, kDampingBudget_ns);
  expect_clean_wire(loop);
}

TEST(FirmwareInLoop, BusOff) {
  for (std::size_t bus : {kLegBus, kArmBus}) {
    FirmwareLoop loop;
    const hal::TimeNs t = inject_and_time(loop, [bus](FirmwareLoop& l) {
      const emu::FaultInjection& f = l.ruiwo(bus) ? l.ruiwo(bus)->faults : l.drives(bus)->faults;
      ASSERT_TRUE(emu::inject_bus_fault(f, l.device_port(bus), emu::BusFault::kBusOff));
    });
    report(bus == kLegBus ? "bus-off (leg bus)" : "bus-off (arm bus)", loop, t);
    EXPECT_GE(t, 0);
    EXPECT_LE(t, kDampingBudget_ns);
    EXPECT_EQ(FirmwareLoop::fw().mode.latched, Fault::kBusOff);
    expect_clean_wire(loop);
  }
}

TEST(FirmwareInLoop, NanCommandFromTheController) {
  FirmwareLoop loop;
  const hal::TimeNs t = inject_and_time(loop, [](FirmwareLoop& l) {
    l.controller().joint = 3;  // left knee
    l.controller().field = &hal::JointCommand::torque_ff_Nm;
    l.controller().value = std::numeric_limits<double>::quiet_NaN();
  });
  report("NaN command", loop, t);
  EXPECT_EQ(t, 0);  // refused in the cycle that produced it
  EXPECT_EQ(FirmwareLoop::fw().mode.latched, Fault::kCommandNonFinite);
  expect_clean_wire(loop);
}

TEST(FirmwareInLoop, OutOfLimitCommandsFromTheController) {
  const model::Model& m = test_support::test_model();
  struct Case {
    const char* what;
    int joint;
    double hal::JointCommand::*field;
    double value;
    Fault fault;
  };
  const Case cases[] = {
      {"position beyond limit", 14, &hal::JointCommand::position_ref_rad, m.limits.position_max_rad[14] + 0.3,
       Fault::kCommandPositionLimit},
      {"torque beyond peak", 2, &hal::JointCommand::torque_ff_Nm, 1.5 * m.limits.peak_torque_Nm[2],
       Fault::kCommandTorqueLimit},
      {"kp beyond range", 20, &hal::JointCommand::kp_Nm_per_rad, 5000.0, Fault::kCommandGainRange},
  };
  for (const Case& k : cases) {
    FirmwareLoop loop;
    const hal::TimeNs t = inject_and_time(loop, [&k](FirmwareLoop& l) {
      l.controller().joint = k.joint;
      l.controller().field = k.field;
      l.controller().value = k.value;
    });
    report(k.what, loop, t);
    EXPECT_EQ(t, 0) << k.what;
    EXPECT_EQ(FirmwareLoop::fw().mode.latched, k.fault) << k.what;
    expect_clean_wire(loop);
  }
}

TEST(FirmwareInLoop, EstopInReadyAndDance) {
  for (Mode m : {Mode::kReady, Mode::kDance}) {
    FirmwareLoop loop;
    ASSERT_TRUE(loop.bring_up());
    ASSERT_TRUE(loop.reach(m));
    CycleInputs in;
    in.estop = true;
    const hal::TimeNs t = loop.ticks_to_damping(kWatch_ns, in);
    report(m == Mode::kReady ? "e-stop in ready" : "e-stop in dance", loop, t);
    EXPECT_EQ(t, 0);
    EXPECT_EQ(FirmwareLoop::fw().mode.latched, Fault::kEstop);
    expect_clean_wire(loop);
  }
}

TEST(FirmwareInLoop, ImuStreamStops) {
  FirmwareLoop loop;
  const hal::TimeNs t = inject_and_time(loop, [](FirmwareLoop& l) { l.stop_imu(); });
  report("IMU stream stops", loop, t);
  EXPECT_GE(t, 0);
  EXPECT_LE(t, kDampingBudget_ns);
  EXPECT_EQ(FirmwareLoop::fw().mode.latched, Fault::kImuStale);
  expect_clean_wire(loop);
}

// The estimator and MPC watchdogs with their inputs driven directly (the dance
// tests, firmware_dance_test.cpp, drive them from the running stack).
TEST(FirmwareInLoop, EstimatorDivergenceAndStalePlan) {
  for (int which = 0; which < 2; ++which) {
    FirmwareLoop loop;
    ASSERT_TRUE(loop.bring_up());
    CycleInputs in;
    if (which == 0) {
      in.watch.estimator_diverged = true;
    } else {
      in.watch.planner_running = true;
      in.watch.plan_stamp_ns = loop.now_ns();  // the last plan arrived now, then none
    }
    const hal::TimeNs t = loop.ticks_to_damping(kWatch_ns, in);
    report(which == 0 ? "estimator diverged" : "MPC result stale", loop, t);
    EXPECT_GE(t, 0);
    // Divergence: the cycle that sees it. Plan: its age threshold (2 MPC periods + 10 ms).
    EXPECT_LE(t, which == 0 ? 0 : FirmwareConfig{}.plan_max_age_ns + 2'000'000);
    EXPECT_EQ(FirmwareLoop::fw().mode.latched, which == 0 ? Fault::kEstimatorDiverged : Fault::kPlanStale);
    expect_clean_wire(loop);
  }
}

// 1 % of the reply frames lost on every bus: below every watchdog's threshold
// (4 consecutive misses at 1 % ~ 1e-8), so the robot keeps standing.
TEST(FirmwareInLoop, OnePercentFrameLossIsTolerated) {
  FirmwareLoop loop;
  ASSERT_TRUE(loop.bring_up());
  for (std::size_t b = 0; b < loop.buses(); ++b) {
    emu::FaultInjection& f = loop.ruiwo(b) ? loop.ruiwo(b)->faults : loop.drives(b)->faults;
    ASSERT_TRUE(emu::set_frame_faults(f, 0.01, 0.0));
  }
  for (int i = 0; i < 1000; ++i) loop.tick();  // 2 s, bounded
  std::uint64_t dropped = 0;
  for (std::size_t b = 0; b < loop.buses(); ++b) dropped += loop.ruiwo(b) ? loop.ruiwo(b)->replies_dropped : 0;
  std::printf("[ figures  ] 1 %% loss, 2 s: mode %s, fault %s, Ruiwo replies dropped %llu, tilt %.2f deg\n",
              to_string(FirmwareLoop::fw().mode.mode), to_string(FirmwareLoop::fw().mode.latched),
              static_cast<unsigned long long>(dropped), loop.tilt_deg());
  EXPECT_GT(dropped, 0u);
  EXPECT_EQ(FirmwareLoop::fw().mode.mode, Mode::kReady) << to_string(FirmwareLoop::fw().mode.latched);
  expect_standing_binding(loop);
  expect_clean_wire(loop);
}

// 1 % of the reply frames with a flipped bit: the decoders reject what they
// can; a corruption they cannot see (a plausible wrong value) may make a
// watchdog trip. Either way: standing or damping with a latched fault,
// never a bad value on the wire, never a hang.
TEST(FirmwareInLoop, OnePercentCorruptedFrames) {
  FirmwareLoop loop;
  ASSERT_TRUE(loop.bring_up());
  for (std::size_t b = 0; b < loop.buses(); ++b) {
    emu::FaultInjection& f = loop.ruiwo(b) ? loop.ruiwo(b)->faults : loop.drives(b)->faults;
    ASSERT_TRUE(emu::set_frame_faults(f, 0.0, 0.01));
  }
  // 2 s, or until 50 ms after damping (a damped robot sits down; no need to watch it).
  int after_damping = 0;
  for (int i = 0; i < 1000 && after_damping < 25; ++i) {
    loop.tick();
    if (FirmwareLoop::fw().mode.mode == Mode::kDamping) ++after_damping;
  }
  const Mode mode = FirmwareLoop::fw().mode.mode;
  std::printf("[ figures  ] 1 %% corrupted, 2 s: mode %s, fault %s, tilt %.2f deg\n", to_string(mode),
              to_string(FirmwareLoop::fw().mode.latched), loop.tilt_deg());
  EXPECT_TRUE(mode == Mode::kReady || (mode == Mode::kDamping && FirmwareLoop::fw().mode.latched != Fault::kNone));
  if (mode == Mode::kDamping) {
    EXPECT_TRUE(test_support::all_damping(loop.command()));
  }
  expect_clean_wire(loop);
}

}  // namespace
}  // namespace kuavo::firmware

namespace kuavo::firmware {
namespace {

// The CSP leg binding: stands up and stands through it, then a controller fault (NaN on the
// left knee) is refused in the same cycle and damping reaches the leg drives on the wire:
// every leg drive decodes a zero torque offset (damping kd 3 = the hip/knee drives' kd, the
// ankle's feedback is its own) and a target at a position it reported, so the drive's loop
// only damps. Checked on what the emulated drives decoded, against the plant's motion.
TEST(FirmwareInLoop, CspLegDrivesStandAndFaultToDampingOnTheWire) {
  FirmwareLoop loop(FirmwareConfig{}, test_support::LegBinding::kCsp);
  ASSERT_TRUE(loop.ok());
  ASSERT_TRUE(loop.csp_legs());
  ASSERT_TRUE(loop.bring_up(1'000'000'000)) << to_string(FirmwareLoop::fw().mode.latched);
  EXPECT_LT(loop.tilt_deg(), 5.0);
  // Standing on the standing controller's stiff gains (400/150), made up from the sample on
  // the hips and knees, the ankle on its drives' own gains: the plant's legs at the pose.
  double worst_rad = 0.0;
  for (int j = 0; j < 2 * model::kLegJoints; ++j) {
    worst_rad = std::max(worst_rad, std::abs(loop.plant().truth().q[7 + j] - loop.command().joints[j].position_ref_rad));
  }
  std::printf("[ figures  ] CSP legs standing: tilt %.2f deg, base z %.3f m, worst leg joint off its reference %.4f rad\n",
              loop.tilt_deg(), loop.plant().truth().q[2], worst_rad);
  EXPECT_LT(worst_rad, 0.01);
  // The shoulder pitch drives run CSP too: decoded from the wire, each drive's own law at the
  // sample its frame was written against (one of its last two reports) is the joint law of
  // the command the firmware sent, evaluated here at that sample. The left one is moving: its
  // reference 0.15 rad off for 20 ticks (a legitimate command), so the law has a position
  // error and a velocity to carry.
  loop.controller().joint = model::kLeftArmFirst;
  loop.controller().field = &hal::JointCommand::position_ref_rad;
  loop.controller().value = loop.plant().truth().q[7 + model::kLeftArmFirst] + 0.15;
  for (int k = 0; k < 20; ++k) loop.tick();
  const hal::CommandFrame sent = loop.command();
  loop.tick();  // this tick's start decodes the frames sent with `sent`
  loop.controller().joint = -1;
  int shoulders = 0;
  for (std::size_t b = 0; b < loop.buses(); ++b) {
    const emu::Cia402Emulator* e = loop.drives(b);
    if (e == nullptr) continue;
    for (int i = 0; i < e->count; ++i) {
      const int slot = loop.io().canopen[b].slot[static_cast<std::size_t>(i)];
      if (slot != model::kLeftArmFirst && slot != model::kRightArmFirst) continue;
      const emu::EmulatedDrive& d = e->drives[i];
      ASSERT_EQ(d.config.mode, drivers::canopen::kModeCyclicSyncPosition);
      ASSERT_EQ(sent.joints[slot].mode, hal::JointMode::kPdTorque);
      ++shoulders;
      const hal::JointCommand& c = sent.joints[slot];
      double off = 1e9;
      for (int r = 0; r < 2; ++r) {
        const double q = d.reported_position_rad[r], v = d.reported_velocity_rad_s[r];
        const double law = c.torque_ff_Nm + c.kp_Nm_per_rad * (c.position_ref_rad - q) + c.kd_Nm_s_per_rad * (c.velocity_ref_rad_s - v);
        off = std::min(off, std::abs(emu::drive_torque_at_Nm(d, q, v) - law));
      }
      // The offset's per-mille and the target's count.
      EXPECT_LE(off, d.config.rated_torque_Nm / 1000.0 + c.kp_Nm_per_rad * 1e-5) << "slot " << slot;
      if (slot == model::kLeftArmFirst) {
        std::printf("[ figures  ] CSP left shoulder: %.3f rad off its reference at %.3f rad/s; the drive's law within "
                    "%.1e N m of the command's\n",
                    c.position_ref_rad - d.reported_position_rad[0], d.reported_velocity_rad_s[0], off);
        EXPECT_GT(std::abs(c.position_ref_rad - d.reported_position_rad[0]), 0.02);
      }
    }
  }
  EXPECT_EQ(shoulders, 2);
  for (int k = 0; k < 500; ++k) loop.tick();  // standing again, the arm at rest
  const hal::TimeNs t = inject_and_time(loop, [](FirmwareLoop& l) {
    l.controller().joint = 3;
    l.controller().field = &hal::JointCommand::torque_ff_Nm;
    l.controller().value = std::numeric_limits<double>::quiet_NaN();
  });
  report("CSP legs: NaN command", loop, t);
  EXPECT_EQ(t, 0);
  EXPECT_EQ(FirmwareLoop::fw().mode.latched, Fault::kCommandNonFinite);
  loop.tick();  // the damping frames sent at the fault are decoded at this tick's start
  int csp_drives = 0;
  for (std::size_t b = 0; b < loop.buses(); ++b) {
    const emu::Cia402Emulator* e = loop.drives(b);
    if (e == nullptr) continue;
    for (int i = 0; i < e->count; ++i) {
      const emu::EmulatedDrive& d = e->drives[i];
      if (d.config.mode != drivers::canopen::kModeCyclicSyncPosition) continue;
      ++csp_drives;
      const int slot = loop.io().canopen[b].slot[static_cast<std::size_t>(i)];
      if (slot < 2 * model::kLegJoints) {
        EXPECT_EQ(d.target_torque_permille, 0) << "node " << int(d.config.node_id);
      } else {
        // A shoulder: damping's −kd_c·v made up from the sample, −(kd_c − kd_d)·v_s (1:1).
        const double kd_gap = std::abs(loop.command().joints[slot].kd_Nm_s_per_rad - d.config.csp_kd_Nm_s_per_rad);
        const double v_s = std::max(std::abs(d.reported_velocity_rad_s[0]), std::abs(d.reported_velocity_rad_s[1]));
        EXPECT_LE(std::abs(d.target_torque_permille * d.config.rated_torque_Nm / 1000.0),
                  kd_gap * v_s + d.config.rated_torque_Nm / 1000.0)
            << "node " << int(d.config.node_id);
      }
      // The target is where the drive was one tick ago: within a tick's motion (+ a count).
      const double target = drivers::canopen::counts_to_rad(d.config, d.target_position_counts);
      EXPECT_LE(std::abs(target - d.position_rad), std::abs(d.velocity_rad_s) * 4e-3 + 1e-4) << "node " << int(d.config.node_id);
    }
  }
  EXPECT_EQ(csp_drives, 14);  // 12 leg drives and the two shoulder pitches
  for (const auto& c : loop.io().canopen) {
    for (const auto& st : c.st) EXPECT_EQ(st.refused_commands, 0u);
  }
  EXPECT_EQ(loop.csp_holds(), 0u);
  expect_standing_binding(loop);
  expect_clean_wire(loop);
}

}  // namespace
}  // namespace kuavo::firmware
