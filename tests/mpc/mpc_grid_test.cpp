// The MPC's horizon grid with a coarse tail (MpcConfig::fine_horizon_s, tail_stride): stage
// count and lengths against their closed forms, the coarse stages' dynamics against Newton's
// law over their own length, the warm start's shift through coarse stages against a trajectory
// linear in time (which interpolation reproduces exactly), the tail's stages ending at the
// window's contact switches (against the closed-form count) and the warm start across a grid
// that moved, and the plan handed to the WBC against the uniform grid's.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>

#include "tests/mpc/mpc_fixture.h"

namespace kuavo::test {
namespace {

using mpc::MpcStatus;

mpc::MpcConfig tail_config(int stride, double fine_s = 0.4, double horizon_s = 1.2) {
  mpc::MpcConfig c;
  c.horizon_s = horizon_s;
  c.fine_horizon_s = fine_s;
  c.tail_stride = stride;
  return c;
}

// A trajectory linear in time on the workspace's current grid, written as the previous
// solution; check() then compares the warm start of the next build (one knot later) against
// it: on the same line at the new stage times (exact for linear interpolation), inputs of the
// old stage each new stage starts in, past the old horizon the last state repeated. Returns
// how many new stages start inside an old one.
struct LinearWarmStart {
  int T_old = 0;
  std::array<int, mpc::kMaxStages + 1> old_knot{};
  mpc::StateVector base, slope;
  std::array<mpc::StateVector, mpc::kMaxStages + 1> old_x{};
  std::array<mpc::InputVector, mpc::kMaxStages + 1> old_u{};

  explicit LinearWarmStart(MpcFixture& f) : T_old(f.ws.horizon), old_knot(f.ws.stage_knot), base(f.ws.x[0]) {
    slope = mpc::StateVector::Constant(1e-3);
    slope[mpc::kXEuler] = 2e-3;
    for (int k = 0; k <= T_old; ++k) {
      f.ws.x[k] = base + (old_knot[k] * f.config.dt_s) * slope;
      f.ws.u[k] = f.ws.u_ref[k] + mpc::InputVector::Constant(0.01 * k);
      old_x[k] = f.ws.x[k];
      old_u[k] = f.ws.u[k];
    }
  }

  int check(const MpcFixture& f) const {
    const int T = f.ws.horizon;
    int interpolated = 0;
    for (int k = 1; k <= T; ++k) {
      const int tau = f.ws.stage_knot[k] + 1;
      if (tau >= old_knot[T_old]) {
        EXPECT_EQ(f.ws.x[k], old_x[T_old]) << k;
        continue;
      }
      int j = 0;
      while (old_knot[j + 1] <= tau) ++j;
      interpolated += old_knot[j] != tau ? 1 : 0;
      EXPECT_LT((f.ws.x[k] - (base + (tau * f.config.dt_s) * slope)).cwiseAbs().maxCoeff(), 1e-14) << k;
      if (k < T) {
        EXPECT_EQ(f.ws.u[k], old_u[j]) << k;
      }
    }
    return interpolated;
  }
};

TEST(MpcGrid, StageCountsAndLengthsAreTheClosedForms) {
  struct Case {
    int stride;
    double fine_s, horizon_s;
    int fine, stages;  // fine stages, all stages: f + ⌈(n − f) / stride⌉ with n = horizon / 0.02
  };
  for (const Case& c : {Case{1, 0.4, 1.2, 60, 60}, Case{2, 0.4, 1.2, 20, 40}, Case{2, 0.4, 1.3, 20, 43},
                        Case{3, 0.3, 1.2, 15, 30}, Case{4, 0.2, 1.4, 10, 25}, Case{2, 1.4, 1.2, 60, 60}}) {
    const mpc::MpcConfig cfg = tail_config(c.stride, c.fine_s, c.horizon_s);
    ASSERT_EQ(mpc::mpc_validate_config(cfg), nullptr) << c.stride << " " << c.horizon_s;
    const int n = static_cast<int>(std::lround(c.horizon_s / 0.02));
    EXPECT_EQ(mpc::mpc_window_knots(cfg), n + 1);
    ASSERT_EQ(mpc::mpc_num_stages(cfg), c.stages) << c.stride << " " << c.horizon_s;
    MpcFixture& f = mpc_fixture(cfg);
    ASSERT_EQ(f.ws.horizon, c.stages);
    double total = 0.0;
    for (int k = 0; k < c.stages; ++k) {
      const double expected = k < c.fine ? 0.02 : 0.02 * std::min(c.stride, n - f.ws.stage_knot[k]);
      EXPECT_NEAR(f.ws.stage_dt_s[k], expected, 1e-15) << k;
      EXPECT_EQ(f.ws.stage_knot[k], k < c.fine ? k : c.fine + (k - c.fine) * c.stride) << k;
      total += f.ws.stage_dt_s[k];
    }
    EXPECT_EQ(f.ws.stage_knot[c.stages], n);
    EXPECT_NEAR(total, c.horizon_s, 1e-12);
  }
  mpc::MpcConfig bad = tail_config(5);
  EXPECT_NE(mpc::mpc_validate_config(bad), nullptr);
  bad = tail_config(0);
  EXPECT_NE(mpc::mpc_validate_config(bad), nullptr);
  bad = tail_config(2, 0.1);  // the plan's 0.2 s would reach into the tail
  EXPECT_NE(mpc::mpc_validate_config(bad), nullptr);
  bad.plan_output = false;    // offline windows read no plan
  EXPECT_EQ(mpc::mpc_validate_config(bad), nullptr);
  bad = tail_config(2, std::nan(""));
  EXPECT_NE(mpc::mpc_validate_config(bad), nullptr);
  // The swing row over an 80 ms stage: 1 − k·dt_k = −0.6 at 20/s, −1.4 (growing) at 30/s.
  bad = tail_config(4);
  EXPECT_EQ(mpc::mpc_validate_config(bad), nullptr);
  bad.swing_position_gain_1_s = 30.0;
  EXPECT_NE(mpc::mpc_validate_config(bad), nullptr);
  bad.tail_stride = 2;
  EXPECT_EQ(mpc::mpc_validate_config(bad), nullptr);
}

// Converged on a pushed standing state, every stage, fine or coarse, obeys Newton's law over
// its own length: Δṙ = dt_k (Σf / m − g), and each joint moves by dt_k times its velocity input.
TEST(MpcGrid, CoarseStagesIntegrateOverTheirOwnLength) {
  MpcFixture& f = mpc_fixture(tail_config(2));
  standing_window(f, 0);
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  v[1] = 0.2;
  for (int it = 0; it < 12; ++it) {
    ASSERT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v, f.window, f.plan), MpcStatus::kOk);
  }
  ASSERT_LT(f.plan.constraint_violation, 1e-8);
  const double m = f.model.total_mass_kg;
  double worst = 0.0, worst_joint = 0.0, coarse_change = 0.0;
  for (int k = 0; k < f.ws.horizon; ++k) {
    const double dt = f.ws.stage_dt_s[k];
    mpc::Vec3 force = mpc::Vec3::Zero();
    for (int c = 0; c < mpc::kNumPoints; ++c) force += f.ws.u[k].segment<3>(mpc::kUForces + 3 * c);
    const mpc::Vec3 expected = dt * (force / m - model::kGravity_m_s2 * mpc::Vec3::UnitZ());
    const mpc::Vec3 change = f.ws.x[k + 1].segment<3>(mpc::kXComVelocity) - f.ws.x[k].segment<3>(mpc::kXComVelocity);
    worst = std::max(worst, (change - expected).cwiseAbs().maxCoeff());
    const auto dq = f.ws.x[k + 1].segment<mpc::kNumMpcJoints>(mpc::kXJoints) - f.ws.x[k].segment<mpc::kNumMpcJoints>(mpc::kXJoints);
    worst_joint = std::max(worst_joint, (dq - dt * f.ws.u[k].segment<mpc::kNumMpcJoints>(mpc::kUJointVelocity)).cwiseAbs().maxCoeff());
    if (dt > 0.03) coarse_change = std::max(coarse_change, change.cwiseAbs().maxCoeff());
  }
  std::printf("Newton over the stages: worst %.2e m/s (largest coarse-stage change %.2e m/s), joints %.2e rad\n",
              worst, coarse_change, worst_joint);
  EXPECT_LT(worst, 1e-8);
  EXPECT_LT(worst_joint, 1e-8);
  EXPECT_GT(coarse_change, 1e-5);  // the tail does carry part of the recovery
}

// The warm start's shift: a trajectory linear in time, shifted by one knot, lands on the same
// line at the new stage times (exact for linear interpolation); inputs are held over the old
// stage each new stage starts in; past the old horizon the last state repeats.
TEST(MpcGrid, WarmStartShiftInterpolatesAlongCoarseStages) {
  MpcFixture& f = mpc_fixture(tail_config(2));
  standing_window(f, 0);
  const dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  ASSERT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v, f.window, f.plan), MpcStatus::kOk);
  const LinearWarmStart previous(f);
  standing_window(f, 20'000'000);
  ASSERT_EQ(mpc::mpc_build_qp_rt(f.model, f.config, f.ws, f.q0, v, f.window), MpcStatus::kOk);
  const int interpolated = previous.check(f);
  EXPECT_EQ(interpolated, 20);  // each of the 20 coarse stages now starts inside an old one
}

// The tail's grid follows the window's contact switches: every knot of a stage has its first
// knot's contacts, each switch past the fine part is a stage boundary, no stage is longer
// than the stride, and the count is the closed form Σ ⌈segment / stride⌉ over the tail's
// segments between switches. Stepping in place (0.3 s stance, 0.4 s swing) at 0.4 s × 4.
TEST(MpcGrid, TailStagesEndAtContactSwitches) {
  constexpr int kStride = 4, kFine = 20, kLast = 60;
  MpcFixture& f = mpc_fixture(tail_config(kStride));
  const dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  int checked_switches = 0;
  for (int call = 0; call < 12; ++call) {
    stepping_window(f, static_cast<hal::TimeNs>(call) * 20'000'000, SteppingPlan{});
    ASSERT_EQ(mpc::mpc_build_qp_rt(f.model, f.config, f.ws, f.q0, v, f.window), MpcStatus::kOk) << call;
    const int T = f.ws.horizon;
    const auto& knots = f.window.knots;
    // The closed form, from the window's own flags.
    int expected_T = kFine;
    for (int j = kFine; j < kLast;) {
      int next = j + 1;
      while (next < kLast && knots[next].in_contact == knots[j].in_contact) ++next;
      expected_T += (next - j + kStride - 1) / kStride;
      j = next;
    }
    ASSERT_EQ(T, expected_T) << call;
    ASSERT_EQ(f.ws.stage_knot[T], kLast);
    for (int k = 0; k < T; ++k) {
      const int a = f.ws.stage_knot[k], b = f.ws.stage_knot[k + 1];
      ASSERT_GT(b, a) << k;
      ASSERT_LE(b - a, k < kFine ? 1 : kStride) << k;
      EXPECT_NEAR(f.ws.stage_dt_s[k], 0.02 * (b - a), 1e-15) << k;
      for (int i = a + 1; i < b; ++i) EXPECT_EQ(knots[i].in_contact, knots[a].in_contact) << call << " " << k << " " << i;
    }
    for (int i = kFine + 1; i < kLast; ++i) {
      if (knots[i].in_contact == knots[i - 1].in_contact) continue;
      EXPECT_EQ(f.ws.stage_knot[first_stage_from(f, i)], i) << call << " switch at knot " << i;
      ++checked_switches;
    }
  }
  std::printf("contact switches in the tail, over 12 windows: %d\n", checked_switches);
  EXPECT_GE(checked_switches, 24);  // two per window (a touchdown and a lift-off 0.3 s apart)
}

// A grid that moved between builds (the switches came one knot closer) still warm-starts from
// the previous grid: a trajectory linear in time lands on the same line at the new stage
// times, inputs come from the old stage each new stage starts in, past the old horizon the
// last state repeats.
TEST(MpcGrid, WarmStartFollowsTheGridAcrossContactSwitches) {
  MpcFixture& f = mpc_fixture(tail_config(4));
  const dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  stepping_window(f, 0, SteppingPlan{});
  ASSERT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v, f.window, f.plan), MpcStatus::kOk);
  const LinearWarmStart previous(f);
  stepping_window(f, 20'000'000, SteppingPlan{});
  ASSERT_EQ(mpc::mpc_build_qp_rt(f.model, f.config, f.ws, f.q0, v, f.window), MpcStatus::kOk);
  const int T = f.ws.horizon;
  bool moved = T != previous.T_old;
  for (int k = 0; k <= T; ++k) moved = moved || f.ws.stage_knot[k] != previous.old_knot[k];
  ASSERT_TRUE(moved);  // else this tests nothing beyond WarmStartShiftInterpolatesAlongCoarseStages
  const int interpolated = previous.check(f);
  std::printf("grid %d -> %d stages, %d new stages inside an old one\n", previous.T_old, T, interpolated);
  EXPECT_GT(interpolated, 0);
}

// The coarse tail changes what lies beyond the plan, not the plan: pushed sideways at 0.2 m/s
// and converged, the first 0.2 s the WBC receives is within 2 % of the push's own
// response of the uniform grid's.
TEST(MpcGrid, PlanMatchesTheUniformGrids) {
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  v[1] = 0.2;
  std::array<mpc::MpcPlan, 2> plans;
  for (int grid = 0; grid < 2; ++grid) {  // uniform, 0.4 s × 4 (mpc.h)
    MpcFixture& f = mpc_fixture(grid == 0 ? tail_config(1) : tail_config(4));
    standing_window(f, 0);
    for (int it = 0; it < 12; ++it) {
      ASSERT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v, f.window, f.plan), MpcStatus::kOk);
    }
    plans[grid] = f.plan;
  }
  double dv = 0.0, response_v = 0.0, df = 0.0, response_f = 0.0;
  for (int i = 0; i < mpc::kMpcPlanKnots; ++i) {
    const auto& a = plans[0].knots[i];
    const auto& b = plans[1].knots[i];
    dv = std::max(dv, (a.com_velocity_m_s - b.com_velocity_m_s).cwiseAbs().maxCoeff());
    response_v = std::max(response_v, std::abs(a.com_velocity_m_s.y() - plans[0].knots[0].com_velocity_m_s.y()));
    df = std::max(df, (a.momentum_rate - b.momentum_rate).cwiseAbs().maxCoeff());
    response_f = std::max(response_f, std::abs(a.momentum_rate.y()));
  }
  std::printf("plan, 0.4 s x 4 vs uniform: CoM velocity %.2e of %.2e m/s, momentum rate %.2f of %.2f N\n", dv,
              response_v, df, response_f);
  EXPECT_GT(response_v, 0.02);
  EXPECT_LT(dv, 0.02 * response_v);
  EXPECT_LT(df, 0.02 * response_f);
}

}  // namespace
}  // namespace kuavo::test
