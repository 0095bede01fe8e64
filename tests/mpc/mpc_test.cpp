// The real-time iteration: configuration checks, the QP against its KKT conditions (computed
// here from the stage data), standing with the exact state, recovery from a CoM velocity
// disturbance, convergence of repeated iterations, no allocation.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "tests/mpc/mpc_fixture.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::test {
namespace {

using mpc::kNx;
using mpc::MpcStatus;

double total_fz(const mpc::InputVector& u) {
  double s = 0.0;
  for (int c = 0; c < mpc::kNumPoints; ++c) s += u[3 * c + 2];
  return s;
}

TEST(MpcConfig, DefaultsAreValidAndBadValuesAreRefused) {
  mpc::MpcConfig c;
  EXPECT_EQ(mpc::mpc_validate_config(c), nullptr);
  EXPECT_EQ(mpc::mpc_window_knots(c), 61);
  EXPECT_EQ(mpc::mpc_num_stages(c), 30);  // 20 of 20 ms, 10 of 80 ms without switches (MpcConfig::tail_stride)
  c.horizon_s = 1.5;
  EXPECT_NE(mpc::mpc_validate_config(c), nullptr);
  c = {};
  c.weight_force = 0.0;
  EXPECT_NE(mpc::mpc_validate_config(c), nullptr);
  c = {};
  c.friction_barrier_delta_N = std::nan("");
  EXPECT_NE(mpc::mpc_validate_config(c), nullptr);
  for (double h : {0.6, 0.8, 1.0, 1.4}) {
    c = {};
    c.horizon_s = h;
    EXPECT_EQ(mpc::mpc_validate_config(c), nullptr) << h;
  }
}

TEST(MpcStep, BadInputsGiveErrorValues) {
  MpcFixture& f = mpc_fixture();
  standing_window(f, 0);
  const dynamics::VelocityVector v0 = dynamics::VelocityVector::Zero();
  dynamics::ConfigVector q = f.q0;
  q[9] = std::nan("");
  EXPECT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, q, v0, f.window, f.plan), MpcStatus::kBadInput);
  EXPECT_EQ(f.plan.count, 0);
  standing_window(f, 0, 60);  // needs N + 1 = 61
  EXPECT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v0, f.window, f.plan), MpcStatus::kBadReference);
  standing_window(f, 0);
  f.window.dt_s = 0.01;
  EXPECT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v0, f.window, f.plan), MpcStatus::kBadReference);
  standing_window(f, 0);
  f.window.knots[30].q[10] = INFINITY;
  EXPECT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v0, f.window, f.plan), MpcStatus::kBadReference);
  mpc::MpcConfig bad;
  bad.horizon_s = 3.0;
  mpc::mpc_init(f.model, bad, f.ws);
  standing_window(f, 0);
  EXPECT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v0, f.window, f.plan), MpcStatus::kNotInitialized);
}

// KKT conditions of the OCP QP (ocp_qp.h sign conventions), from the stage data.
double kkt_residual(const mpc::Ocp& qp, const mpc::OcpSolution& s, double& primal) {
  const int T = qp.horizon;
  double stat = (s.x[0] - qp.x_initial).cwiseAbs().maxCoeff();
  primal = stat;
  for (int k = 0; k <= T; ++k) {
    const auto& st = qp.stages[k];
    Eigen::Matrix<double, kNx, 1> gx = st.Q * s.x[k] + st.q - s.costate[k];
    if (k < T) {
      const int ne = st.num_eq;
      gx += st.S.transpose() * s.u[k] + st.A.transpose() * s.costate[k + 1];
      Eigen::Matrix<double, mpc::kNu, 1> gu = st.R * s.u[k] + st.S * s.x[k] + st.r + st.B.transpose() * s.costate[k + 1];
      if (ne > 0) {
        gx += st.C.topRows(ne).transpose() * s.nu[k].head(ne);
        gu += st.D.topRows(ne).transpose() * s.nu[k].head(ne);
        primal = std::max(primal, (st.C.topRows(ne) * s.x[k] + st.D.topRows(ne) * s.u[k] - st.e.head(ne))
                                      .cwiseAbs()
                                      .maxCoeff());
      }
      primal = std::max(primal, (st.A * s.x[k] + st.B * s.u[k] + st.b - s.x[k + 1]).cwiseAbs().maxCoeff());
      stat = std::max(stat, gu.cwiseAbs().maxCoeff());
    }
    if (k > 0) stat = std::max(stat, gx.cwiseAbs().maxCoeff());
  }
  return stat;
}

TEST(MpcStep, OneIterationSolvesItsQpAndSatisfiesTheLinearizedConstraints) {
  MpcFixture& f = mpc_fixture();
  standing_window(f, 0);
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  v[1] = 0.2;  // sideways push: the QP has work to do
  ASSERT_EQ(mpc::mpc_build_qp_rt(f.model, f.config, f.ws, f.q0, v, f.window), MpcStatus::kOk);
  // The certificate needs the costates, which the real-time iteration does not compute
  // (OcpSettings::lq_costate; its x and u are the same either way, tests/qp).
  EXPECT_FALSE(f.ws.qp_settings.lq_costate);
  f.ws.qp_settings.lq_costate = true;
  const MpcStatus solved = mpc::mpc_solve_qp_rt(f.ws);
  f.ws.qp_settings.lq_costate = false;
  ASSERT_EQ(solved, MpcStatus::kOk);
  double primal = 0.0;
  const double stat = kkt_residual(f.ws.qp, f.ws.solution, primal);
  std::printf("KKT: stationarity %.2e, primal %.2e\n", stat, primal);
  EXPECT_LT(stat, 1e-8);
  EXPECT_LT(primal, 1e-9);
  // Every stance stage carried its 12 foot-twist rows.
  EXPECT_EQ(f.ws.qp.stages[0].num_eq, 12);
  EXPECT_EQ(f.ws.qp.stages[f.ws.horizon - 1].num_eq, 12);
}

TEST(MpcStep, StandingWithTheExactStateHoldsStill) {
  MpcFixture& f = mpc_fixture();
  standing_window(f, 1'000'000'000);
  const dynamics::VelocityVector v0 = dynamics::VelocityVector::Zero();
  ASSERT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v0, f.window, f.plan), MpcStatus::kOk);
  const double mg = f.model.total_mass_kg * model::kGravity_m_s2;
  // The last stages are left out: there the friction barrier's push on f_z is opposed only by
  // the terminal cost (an end effect, ~3 % of m g on the last input; the WBC reads knots 0–9).
  constexpr int kEndStages = 5;
  const double m = f.model.total_mass_kg;
  for (int k = 0; k < f.ws.horizon - kEndStages; ++k) {
    EXPECT_NEAR(total_fz(f.ws.u[k]), mg, 0.01 * mg) << k;
    EXPECT_LT(f.ws.x[k].segment<3>(mpc::kXComVelocity).cwiseAbs().maxCoeff(), 1e-3) << k;  // m/s
    EXPECT_LT(f.ws.x[k].segment<3>(mpc::kXMomentum).cwiseAbs().maxCoeff() / m, 1e-4) << k;  // m²/s
    // Not exactly 0: the joint-limit barrier moves the elbows (reference 0.116 rad inside
    // their limit) ~0.4 mrad away from it; that settles at a few mrad/s over the first stages.
    EXPECT_LT(f.ws.u[k].tail<mpc::kNumMpcJoints>().cwiseAbs().maxCoeff(), 5e-3) << k;
  }
  ASSERT_EQ(f.plan.count, mpc::kMpcPlanKnots);
  EXPECT_EQ(f.plan.stamp_ns, 1'000'000'000);
  EXPECT_EQ(f.plan.knots[3].stamp_ns, 1'060'000'000);
  for (int i = 0; i < f.plan.count; ++i) {
    const auto& r = f.plan.knots[i];
    EXPECT_LT(r.momentum_rate.cwiseAbs().maxCoeff(), 0.01 * mg);
    EXPECT_LT((r.com_position_m - f.window.knots[0].com_position_m).norm(), 1e-4);
    EXPECT_LT((r.point_position_m - f.window.knots[0].point_position_m).cwiseAbs().maxCoeff(), 1e-4);
    EXPECT_LT(r.joint_velocity_rad_s.cwiseAbs().maxCoeff(), 5e-3);
  }
  std::printf("standing: cost %.3e, violation %.2e\n", f.plan.cost, f.plan.constraint_violation);
}

TEST(MpcStep, RepeatedIterationsOnAFixedStateConverge) {
  // Same state, same stamps: each call is one more SQP iteration on the same problem. The
  // full-step SQP converges quadratically once close: violation ~1e-1 → 1e-3 → 1e-5 → 1e-7 …
  MpcFixture& f = mpc_fixture();
  standing_window(f, 0);
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  v[1] = 0.2;
  constexpr int kIterations = 12;
  std::array<double, kIterations> violation{}, cost{};
  for (int it = 0; it < kIterations; ++it) {
    ASSERT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v, f.window, f.plan), MpcStatus::kOk) << it;
    violation[it] = f.plan.constraint_violation;  // at this call's linearization point
    cost[it] = f.plan.cost;
    std::printf("iteration %2d: cost %.9e, violation %.2e\n", it, cost[it], violation[it]);
  }
  for (int it = 1; it < kIterations && violation[it - 1] > 1e-12; ++it) EXPECT_LT(violation[it], violation[it - 1]) << it;
  EXPECT_LT(violation[10], 1e-6);
  EXPECT_LT(std::abs(cost[kIterations - 1] - cost[kIterations - 2]), 1e-9 * cost[kIterations - 1]);
  EXPECT_GT(std::abs(cost[1] - cost[0]), 1e-6 * cost[0]);  // it did have to move
}

TEST(MpcStep, SidewaysVelocityDisturbanceIsBroughtBackWithinTheHorizon) {
  MpcFixture& f = mpc_fixture();
  standing_window(f, 0);
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  v[1] = 0.2;  // base axes = world here (identity orientation): 0.2 m/s to the left
  for (int it = 0; it < 5; ++it) {
    ASSERT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v, f.window, f.plan), MpcStatus::kOk);
  }
  const int T = f.ws.horizon;
  const double y0 = f.window.knots[0].q[1];
  double max_dev = 0.0;
  int k_max = 0;
  for (int k = 0; k <= T; ++k) {
    const double dev = std::abs(f.ws.x[k][mpc::kXBasePosition + 1] - y0);
    if (dev > max_dev) {
      max_dev = dev;
      k_max = k;
    }
  }
  const double end_dev = std::abs(f.ws.x[T][mpc::kXBasePosition + 1] - y0);
  std::printf("push 0.2 m/s: CoM vy(0) %.3f, vy(T) %.4f, base y dev max %.1f mm at k=%d, at T %.1f mm\n",
              f.ws.x[0][1], f.ws.x[T][1], 1e3 * max_dev, k_max, 1e3 * end_dev);
  EXPECT_NEAR(f.ws.x[0][1], 0.2, 0.02);                // the disturbance is in the initial state
  EXPECT_LT(std::abs(f.ws.x[T][mpc::kXComVelocity + 1]), 0.05);  // velocity taken out
  EXPECT_LT(end_dev, 0.5 * max_dev);                   // and the excursion coming back
  EXPECT_LT(k_max, T / 2);
  // Friction cones within the barrier's relaxation (δ = 5 N), unilateral forces.
  double worst = 1e9;
  for (int k = 0; k < T; ++k) {
    for (int c = 0; c < mpc::kNumPoints; ++c) {
      const mpc::Vec3 fc = f.ws.u[k].segment<3>(3 * c);
      worst = std::min({worst, f.config.friction_coefficient * fc.z() - std::abs(fc.x()),
                        f.config.friction_coefficient * fc.z() - std::abs(fc.y())});
    }
  }
  std::printf("friction: min (mu fz - |ft|) %.2f N\n", worst);
  EXPECT_GT(worst, -f.config.friction_barrier_delta_N);
}

TEST(MpcStep, NoAllocationOverAHundredCalls) {
  MpcFixture& f = mpc_fixture();
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  v[1] = 0.1;
  standing_window(f, 0);
  ASSERT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v, f.window, f.plan), MpcStatus::kOk);
  std::size_t allocations = 0;
  int ok = 0;
  for (int call = 1; call <= 100; ++call) {
    // The planner's part, outside the trap; the second half steps in place (swing rows).
    if (call <= 50) {
      standing_window(f, static_cast<hal::TimeNs>(call) * 20'000'000);
    } else {
      stepping_window(f, static_cast<hal::TimeNs>(call) * 20'000'000, SteppingPlan{});
    }
    AllocTrap trap;
    ok += mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v, f.window, f.plan) == MpcStatus::kOk ? 1 : 0;
    allocations += trap.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(ok, 100);
}

// The build's shortcuts against the plain build: the reference of a knot met again is taken
// from the previous call, and Q, R, C, D are cleared only where the last build wrote. A second
// workspace runs the same calls with its reference cache emptied and every stage matrix zeroed
// before each build (what the build did without the shortcuts); the QPs must be identical, bit
// for bit, through stepping (swing rows, swing x-y blocks) and back to standing, and when a
// window's knots change under the same stamps.
TEST(MpcStep, CachedReferenceAndPartialClearingBuildTheSameQp) {
  MpcFixture& f = mpc_fixture();
  static mpc::MpcWorkspace plain;
  mpc::mpc_init(f.model, f.config, plain);
  static mpc::MpcPlan plain_plan;
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  v[1] = 0.05;
  int compared = 0, expected = 0;
  for (int call = 0; call < 60; ++call) {
    const hal::TimeNs t = static_cast<hal::TimeNs>(call) * 20'000'000;
    if (call < 40) {
      stepping_window(f, t, SteppingPlan{});
    } else {
      standing_window(f, t);
    }
    if (call % 7 == 3) {  // another motion at the same stamps (a new dance): the cache must see it
      for (int k = 0; k < f.window.count; ++k) f.window.knots[k].q[7 + 14] += 0.02;
    }
    plain.reference_cached = 0;
    for (auto& st : plain.qp.stages) {
      st.Q.setZero();
      st.R.setZero();
      st.C.setZero();
      st.D.setZero();
      st.e.setZero();
    }
    ASSERT_EQ(mpc::mpc_build_qp_rt(f.model, f.config, f.ws, f.q0, v, f.window), MpcStatus::kOk);
    ASSERT_EQ(mpc::mpc_build_qp_rt(f.model, f.config, plain, f.q0, v, f.window), MpcStatus::kOk);
    for (int k = 0; k <= f.ws.horizon; ++k) {
      const auto& a = f.ws.qp.stages[k];
      const auto& b = plain.qp.stages[k];
      ASSERT_EQ(a.num_eq, b.num_eq) << call << " " << k;
      ASSERT_TRUE(a.Q == b.Q && a.q == b.q && a.R == b.R && a.r == b.r && a.S == b.S) << call << " " << k;
      ASSERT_TRUE(a.C == b.C && a.D == b.D && a.e == b.e) << call << " " << k;
      ASSERT_TRUE(a.A == b.A && a.B == b.B && a.b == b.b) << call << " " << k;
      ++compared;
    }
    expected += f.ws.horizon + 1;  // the tail's grid follows the contact switches
    ASSERT_EQ(mpc::mpc_solve_qp_rt(f.ws), MpcStatus::kOk);
    ASSERT_EQ(mpc::mpc_solve_qp_rt(plain), MpcStatus::kOk);
  }
  EXPECT_EQ(compared, expected);  // every stage of every build was compared
  EXPECT_GT(expected, 60 * (mpc::mpc_num_stages(f.config) + 1));  // stages were added at switches
}

// The build writes only the varying rows of A = I + dt·fx and B = dt·fu (the rest is mpc_init's
// identity / zero), and centroidal_evaluate writes only the non-structural blocks of fx, fu and
// the base twist derivatives (the rest keeps the zeros of construction). Through stepping and
// back to standing, every stage's A and B must equal the whole products of a freshly
// constructed point's evaluation, bit for bit, and the reused point must equal the fresh one;
// and A and B stay zero outside the row groups mpc_init declares to the Riccati.
TEST(MpcStep, StructuredDynamicsBlocksEqualTheWholeProducts) {
  MpcFixture& f = mpc_fixture();
  mpc::mpc_init(f.model, f.config, f.ws);
  static mpc::CentroidalPoint fresh;
  static mpc::StateJacobian a;
  static mpc::InputJacobian b;
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  v[1] = 0.05;
  int compared = 0;
  for (int call = 0; call < 50; ++call) {
    const hal::TimeNs t = static_cast<hal::TimeNs>(call) * 20'000'000;
    if (call < 35) {
      stepping_window(f, t, SteppingPlan{});
    } else {
      standing_window(f, t);
    }
    ASSERT_EQ(mpc::mpc_build_qp_rt(f.model, f.config, f.ws, f.q0, v, f.window), MpcStatus::kOk);
    for (int k = 0; k < f.ws.horizon; k += 7) {
      fresh = mpc::CentroidalPoint{};
      mpc::centroidal_evaluate(f.model, f.ws.x[k], f.ws.u[k], f.ws.head_rad[k], fresh);
      a = f.ws.stage_dt_s[k] * fresh.fx;  // the stage's own length (a coarse tail's, several dt)
      a.diagonal().array() += 1.0;
      b = f.ws.stage_dt_s[k] * fresh.fu;
      for (int c = 0; c < mpc::kNumPoints; ++c) {  // a swing corner's force is a fixed input (mpc.h)
        if (!f.window.knots[f.ws.stage_knot[k]].in_contact[c]) b.middleCols<3>(3 * c).setZero();
      }
      const auto& st = f.ws.qp.stages[k];
      ASSERT_TRUE(st.A == a) << call << " " << k;
      ASSERT_TRUE(st.B == b) << call << " " << k;
      ++compared;
    }
    // Every stage's A and B are zero outside the row groups mpc_init declares, and R outside
    // its force block and diagonal (ocp_qp.h): the Riccati does not read there.
    ASSERT_TRUE(f.ws.qp.ab_groups_declared);
    for (int k = 0; k < f.ws.horizon; ++k) {
      const auto& st = f.ws.qp.stages[k];
      ASSERT_EQ(st.r_dense, 3 * mpc::kNumPoints);
      Eigen::Matrix<double, mpc::kNu, mpc::kNu> outside = st.R;
      outside.topLeftCorner<3 * mpc::kNumPoints, 3 * mpc::kNumPoints>().setZero();
      outside.diagonal().setZero();
      ASSERT_EQ(outside.cwiseAbs().maxCoeff(), 0.0) << call << " " << k;
      for (int i = 0; i < mpc::kNx; ++i) {
        for (int j = 0; j < mpc::kNx; ++j) {
          if ((f.ws.qp.a_groups[j] >> (i / 4) & 1u) == 0) {
            ASSERT_EQ(st.A(i, j), 0.0) << call << " " << k;
          }
        }
        for (int j = 0; j < mpc::kNu; ++j) {
          if ((f.ws.qp.b_groups[j] >> (i / 4) & 1u) == 0) {
            ASSERT_EQ(st.B(i, j), 0.0) << call << " " << k;
          }
        }
      }
    }
    // The workspace's point was last evaluated at stage T − 1: reused, it must equal a fresh one.
    const int last = f.ws.horizon - 1;
    fresh = mpc::CentroidalPoint{};
    mpc::centroidal_evaluate(f.model, f.ws.x[last], f.ws.u[last], f.ws.head_rad[last], fresh);
    ASSERT_TRUE(f.ws.point.fx == fresh.fx && f.ws.point.fu == fresh.fu && f.ws.point.f == fresh.f) << call;
    ASSERT_TRUE(f.ws.point.base_twist_dx == fresh.base_twist_dx && f.ws.point.base_twist_du == fresh.base_twist_du)
        << call;
    ASSERT_EQ(mpc::mpc_solve_qp_rt(f.ws), MpcStatus::kOk);
  }
  EXPECT_EQ(compared, 50 * ((f.ws.horizon + 6) / 7));
}

// The swing x-y cost adds w·JᵀJ per swing corner on the 11 columns where J is nonzero (base x-y,
// Euler, the leg). Against the whole product of J written out here (dense, every column):
// the difference of Q between builds with and without the cost, at the same linearization point.
TEST(MpcStep, SwingXyHessianIsTheWholeGaussNewtonProduct) {
  MpcFixture& f = mpc_fixture();
  static mpc::MpcWorkspace with, without;
  mpc::MpcConfig off = f.config;
  off.weight_swing_xy = 0.0;
  mpc::mpc_init(f.model, f.config, with);
  mpc::mpc_init(f.model, off, without);
  stepping_window(f, 0, SteppingPlan{});
  const dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  ASSERT_EQ(mpc::mpc_build_qp_rt(f.model, f.config, with, f.q0, v, f.window), MpcStatus::kOk);
  ASSERT_EQ(mpc::mpc_build_qp_rt(f.model, off, without, f.q0, v, f.window), MpcStatus::kOk);
  static mpc::CentroidalPoint p;
  static mpc::StateJacobian expected;
  Eigen::Matrix<double, 3, mpc::kNumMpcJoints> jp;
  Eigen::Matrix<double, 2, kNx> j;
  int swing_stages = 0;
  for (int k = 0; k < with.horizon; ++k) {
    const double w = with.stage_dt_s[k] * f.config.weight_swing_xy;
    ASSERT_TRUE(with.x[k] == without.x[k] && with.u[k] == without.u[k]);
    mpc::centroidal_evaluate(f.model, with.x[k], with.u[k], with.head_rad[k], p);
    expected.setZero();
    bool swing = false;
    for (int c = 0; c < mpc::kNumPoints; ++c) {
      if (f.window.knots[with.stage_knot[k]].in_contact[c]) continue;
      swing = true;
      const int body = f.model.frames[c].body;
      const dynamics::Vec3 point = dynamics::frame_position(f.model, p.data, c);
      mpc::point_position_jacobian(f.model, p, body, point, jp);
      j.setZero();
      j(0, mpc::kXBasePosition) = 1.0;
      j(1, mpc::kXBasePosition + 1) = 1.0;
      for (int e = 0; e < 3; ++e) j.col(mpc::kXEuler + e) = (p.rotation_derivative[e] * point).head<2>();
      j.middleCols<mpc::kNumMpcJoints>(mpc::kXJoints) = p.rotation.topRows<2>() * jp;
      expected += w * j.transpose() * j;
    }
    swing_stages += swing ? 1 : 0;
    const mpc::StateJacobian diff = with.qp.stages[k].Q - without.qp.stages[k].Q;
    ASSERT_LE((diff - expected).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + expected.cwiseAbs().maxCoeff())) << k;
  }
  EXPECT_GT(swing_stages, 10);
}

}  // namespace
}  // namespace kuavo::test

namespace kuavo::test {
namespace {

// Standing facing yaw ≈ π: the measurement is on the other side of the ±π cut from the plan.
TEST(MpcStep, YawAcrossThePiCutIsTheSmallDifference) {
  MpcFixture& f = mpc_fixture();
  const dynamics::ConfigVector standing = f.q0;
  auto turned = [&](double yaw) {
    dynamics::ConfigVector q = standing;
    const Eigen::AngleAxisd turn(yaw, Eigen::Vector3d::UnitZ());
    q.head<3>() = turn * standing.head<3>();
    const Eigen::Quaterniond o = Eigen::Quaterniond(turn) * Eigen::Quaterniond(standing[6], standing[3], standing[4], standing[5]);
    q[3] = o.x();
    q[4] = o.y();
    q[5] = o.z();
    q[6] = o.w();
    return q;
  };
  f.q0 = turned(M_PI - 0.01);  // the plan
  standing_window(f, 0);
  const dynamics::ConfigVector measured = turned(-M_PI + 0.01);  // 0.02 rad further round
  for (int it = 0; it < 8; ++it) {
    ASSERT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, measured, dynamics::VelocityVector::Zero(), f.window, f.plan),
              MpcStatus::kOk);
  }
  f.q0 = standing;
  std::printf("yaw across the cut: x0 yaw %.4f, x_T yaw %.4f (reference %.4f), violation %.1e\n", f.ws.x[0][mpc::kXEuler],
              f.ws.x[f.ws.horizon][mpc::kXEuler], f.ws.x_ref[0][mpc::kXEuler], f.plan.constraint_violation);
  EXPECT_NEAR(f.ws.x[0][mpc::kXEuler], M_PI + 0.01, 1e-9);  // measurement unwrapped onto the plan's branch
  EXPECT_LT(f.plan.constraint_violation, 1e-6);
  // The feet are planted 0.02 rad round from the plan, so the base stays near the measurement
  // (turning back needs a step); what must not happen is a 2π excursion anywhere.
  for (int k = 0; k <= f.ws.horizon; ++k) {
    EXPECT_LT(std::abs(f.ws.x[k][mpc::kXEuler] - f.ws.x_ref[k][mpc::kXEuler]), 0.03) << k;
  }
  EXPECT_LT(std::abs(std::remainder(f.plan.knots[0].base_euler_zyx_rad[0] - (M_PI + 0.01), 2 * M_PI)), 1e-6);
}

}  // namespace
}  // namespace kuavo::test

namespace kuavo::test {
namespace {

// The standing pose translating at constant acceleration `accel` (no rotation), all feet in
// contact, one knot per MPC stage over the whole horizon. Returns the knot count.
int accelerating_window(MpcFixture& f, const dynamics::Vec3& accel) {
  const Eigen::Quaterniond base(f.q0[6], f.q0[3], f.q0[4], f.q0[5]);
  const int count = mpc::mpc_window_knots(f.config);
  f.window.count = count;
  f.window.dt_s = f.config.dt_s;
  for (int k = 0; k < count; ++k) {
    const double t = k * f.config.dt_s;
    dynamics::ConfigVector q = f.q0;
    q.head<3>() += 0.5 * accel * t * t;
    dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
    v.head<3>() = base.conjugate() * (accel * t);  // base twist in base axes
    planner::plan_knot_from_state(f.model, f.data, q, v, all_contacts(), static_cast<hal::TimeNs>(std::llround(t * 1e9)),
                                  f.window.knots[k]);
  }
  return count;
}

// MpcConfig::reference_forces_from_motion: the reference forces carry the reference's own
// wrench. Oracle: a whole robot translating at a constant acceleration a (joints still, no
// rotation) needs Σf = m (a + g e_z) and no moment about its CoM; the default (static) forces
// carry m g e_z alone whatever the motion does.
TEST(MpcReferenceForces, FromTheMotionTheyCarryItsAcceleration) {
  const dynamics::Vec3 accel(0.6, -0.4, 0.3);
  for (const bool from_motion : {false, true}) {
    mpc::MpcConfig cfg;
    cfg.reference_forces_from_motion = from_motion;
    MpcFixture& f = mpc_fixture(cfg);
    accelerating_window(f, accel);
    ASSERT_EQ(mpc::mpc_build_qp_rt(f.model, f.config, f.ws, f.window.knots[0].q, f.window.knots[0].v, f.window),
              MpcStatus::kOk);
    const double m = f.model.total_mass_kg;
    const dynamics::Vec3 expected =
        m * ((from_motion ? accel : dynamics::Vec3::Zero()) + dynamics::Vec3(0.0, 0.0, model::kGravity_m_s2));
    for (int k = 0; k <= f.ws.horizon; k += 3) {  // stages, fine and coarse
      dynamics::Vec3 sum = dynamics::Vec3::Zero(), moment = dynamics::Vec3::Zero();
      const planner::PlanKnot& knot = f.window.knots[f.ws.stage_knot[k]];
      for (int c = 0; c < mpc::kNumPoints; ++c) {
        const dynamics::Vec3 fc = f.ws.u_ref[k].segment<3>(3 * c);
        sum += fc;
        moment += (knot.point_position_m.segment<3>(3 * c) - knot.com_position_m).cross(fc);
      }
      EXPECT_LT((sum - expected).norm(), 1e-3) << (from_motion ? "motion" : "static") << " knot " << k << ": " << sum.transpose();
      EXPECT_LT(moment.norm(), 1e-3) << (from_motion ? "motion" : "static") << " knot " << k << ": " << moment.transpose();
    }
  }
}

// A reference accelerating sideways at 1.6 μ g asks the feet for more than friction gives:
// its forces must stay inside every corner's pyramid, and they are the best such forces
// (KKT of ½‖A f − w‖² + ½ε‖f‖² checked here from A and w built anew, with the solver's
// multipliers), so their sideways sum reaches the cone's edge, μ Σf_z, and no further.
TEST(MpcReferenceForces, AWrenchBeyondFrictionComesBackInsideThePyramids) {
  mpc::MpcConfig cfg;
  cfg.reference_forces_from_motion = true;
  MpcFixture& f = mpc_fixture(cfg);
  const double mu = cfg.friction_coefficient;
  const dynamics::Vec3 accel(0.0, 1.6 * mu * model::kGravity_m_s2, 0.0);
  const int count = accelerating_window(f, accel);
  ASSERT_EQ(mpc::mpc_build_qp_rt(f.model, f.config, f.ws, f.window.knots[0].q, f.window.knots[0].v, f.window),
            MpcStatus::kOk);
  EXPECT_EQ(f.ws.reference_wrench_failures, 0);
  const double m = f.model.total_mass_kg;
  for (int k = 0; k <= f.ws.horizon; k += 3) {  // stages, fine and coarse
    dynamics::Vec3 sum = dynamics::Vec3::Zero();
    for (int c = 0; c < mpc::kNumPoints; ++c) {
      const dynamics::Vec3 fc = f.ws.u_ref[k].segment<3>(3 * c);
      sum += fc;
      EXPECT_GE(fc.z(), -1e-9) << "knot " << k << " corner " << c;
      EXPECT_LE(std::abs(fc.x()), mu * fc.z() + 1e-6) << "knot " << k << " corner " << c;
      EXPECT_LE(std::abs(fc.y()), mu * fc.z() + 1e-6) << "knot " << k << " corner " << c;
    }
    // The wrench asked for is m (a + g) sideways beyond the cone: the sum stops at its edge.
    EXPECT_NEAR(sum.y(), mu * sum.z(), 1e-3 * m) << "knot " << k;
    EXPECT_LT(sum.y(), m * accel.y() - 0.2 * m * model::kGravity_m_s2) << "knot " << k;
  }
  // KKT of the last knot's QP (the last solved, the last stage's): stationarity from the
  // problem's own data.
  ASSERT_EQ(f.ws.stage_knot[f.ws.horizon], count - 1);
  const planner::PlanKnot& last = f.window.knots[count - 1];
  constexpr int kF = 3 * mpc::kNumPoints;
  Eigen::Matrix<double, 6, kF> a = Eigen::Matrix<double, 6, kF>::Zero();
  for (int c = 0; c < mpc::kNumPoints; ++c) {
    a.block<3, 3>(0, 3 * c).setIdentity();
    const dynamics::Vec3 r = last.point_position_m.segment<3>(3 * c) - last.com_position_m;
    a.block<3, 3>(3, 3 * c) << 0.0, -r.z(), r.y(), r.z(), 0.0, -r.x(), -r.y(), r.x(), 0.0;
  }
  const Eigen::Matrix<double, kF, 1> x = f.ws.wrench_qp_solution.x;
  const auto& z = f.ws.wrench_qp_solution.z_ineq;
  const auto& zb = f.ws.wrench_qp_solution.z_bound;
  const Eigen::Matrix<double, 6, 1> w = f.ws.reference_wrench[count - 1];
  EXPECT_NEAR(w[1], m * accel.y(), 1e-6 * m);
  Eigen::Matrix<double, kF, 1> grad = a.transpose() * (a * x - w) + 1e-6 * x;
  grad += f.ws.wrench_qp.C.transpose() * z + zb;
  EXPECT_LT(grad.lpNorm<Eigen::Infinity>(), 1e-6 * m) << grad.transpose();
  // Signs: z ≥ 0 only on a row at its upper side, ≤ 0 only at its lower side.
  const Eigen::Matrix<double, 4 * mpc::kNumPoints, 1> cx = f.ws.wrench_qp.C * x;
  for (int r = 0; r < 4 * mpc::kNumPoints; ++r) {
    if (z[r] > 1e-9) {
      EXPECT_NEAR(cx[r], f.ws.wrench_qp.c_upper[r], 1e-6) << r;
    }
    if (z[r] < -1e-9) {
      EXPECT_NEAR(cx[r], f.ws.wrench_qp.c_lower[r], 1e-6) << r;
    }
  }
  for (int i = 0; i < kF; ++i) {
    if (zb[i] < -1e-9) {
      EXPECT_NEAR(x[i], 0.0, 1e-6) << i;
    }
    EXPECT_LE(zb[i], 1e-9) << i;  // only f_z ≥ 0 is bounded, from below
  }
}

}  // namespace
}  // namespace kuavo::test
