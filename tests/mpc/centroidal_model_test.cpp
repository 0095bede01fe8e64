// The MPC model against independent oracles: values against the rigid-body library (A_G with
// a quaternion base in world axes, integrate()), analytic derivatives against central finite
// differences of the model itself, on seeded random states, both robot variants.
#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "controllers/mpc/centroidal_model.h"
#include "controllers/wbc/wbc_reference.h"

namespace kuavo::test {
namespace {

using mpc::CentroidalPoint;
using mpc::InputVector;
using mpc::StateVector;

constexpr double kStep = 1e-6;       // central differences: error ~ε² f''' + 1e-16·|f|/ε
constexpr double kDerivTol = 1e-6;   // relative (max |a − b| / max(1, |b|))
constexpr double kValueTol = 1e-9;
constexpr int kSamples = 6;

double rel(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(1.0, b.cwiseAbs().maxCoeff());
}

struct Sample {
  StateVector x;
  InputVector u;
  mpc::HeadVector head;
};

Sample random_sample(const model::Model& m, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> s(-1.0, 1.0);
  Sample out;
  StateVector& x = out.x;
  for (int i = 0; i < 3; ++i) x[mpc::kXComVelocity + i] = 0.5 * s(rng);
  for (int i = 0; i < 3; ++i) x[mpc::kXMomentum + i] = 5.0 * s(rng);
  for (int i = 0; i < 3; ++i) x[mpc::kXBasePosition + i] = s(rng);
  x[mpc::kXEuler] = 3.0 * s(rng);
  x[mpc::kXEuler + 1] = 0.6 * s(rng);
  x[mpc::kXEuler + 2] = 0.6 * s(rng);
  for (int j = 0; j < mpc::kNumMpcJoints; ++j) {
    const double lo = m.limits.position_min_rad[j], hi = m.limits.position_max_rad[j];
    x[mpc::kXJoints + j] = lo + (hi - lo) * 0.5 * (s(rng) + 1.0);
  }
  for (int i = 0; i < 24; ++i) out.u[i] = 150.0 * s(rng);
  for (int j = 0; j < mpc::kNumMpcJoints; ++j) out.u[mpc::kUJointVelocity + j] = 2.0 * s(rng);
  out.head << 0.5 * s(rng), 0.3 * s(rng);
  return out;
}

struct Fixture {
  model::Model model;
  CentroidalPoint point, plus, minus;
  dynamics::Data data;
};

Fixture& fixture(model::Variant variant) {
  static auto s45 = std::make_unique<Fixture>();
  static auto s42 = std::make_unique<Fixture>();
  Fixture& f = variant == model::Variant::kS45 ? *s45 : *s42;
  if (f.model.tables == nullptr) {
    EXPECT_EQ(model::build_model(variant, model::kDefaultTotalMass_kg, f.model), model::ModelError::kOk);
  }
  return f;
}

class CentroidalModel : public ::testing::TestWithParam<model::Variant> {};

TEST_P(CentroidalModel, ValuesMatchTheRigidBodyLibrary) {
  Fixture& f = fixture(GetParam());
  std::mt19937_64 rng(11);
  for (int n = 0; n < kSamples; ++n) {
    const Sample s = random_sample(f.model, rng);
    mpc::centroidal_evaluate(f.model, s.x, s.u, s.head, f.point);
    const dynamics::ConfigVector q = mpc::configuration_from_state(s.x, s.head);
    dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
    v.head<6>() = f.point.base_twist;
    v.segment<mpc::kNumMpcJoints>(6) = s.u.segment<mpc::kNumMpcJoints>(mpc::kUJointVelocity);
    dynamics::compute_all_terms(f.model, f.data, q, v);
    // The recovered base twist reproduces the state's momentum through the world A_G.
    dynamics::Vec6 h_expected;
    h_expected << f.data.total_mass_kg * s.x.segment<3>(mpc::kXComVelocity), s.x.segment<3>(mpc::kXMomentum);
    const dynamics::Vec6 h = f.data.centroidal_matrix * v;
    EXPECT_LT(rel(h, h_expected), kValueTol);
    // ḣ = Σ (cᵢ − r) × fᵢ with world kinematics.
    mpc::Vec3 hdot = mpc::Vec3::Zero();
    for (int c = 0; c < mpc::kNumPoints; ++c) {
      hdot += (dynamics::frame_position(f.model, f.data, c) - f.data.com_m).cross(s.u.segment<3>(3 * c));
    }
    EXPECT_LT(rel(f.point.f.segment<3>(mpc::kXMomentum), hdot), kValueTol);
    // ṗ and ė against the SE(3) integration of the base twist.
    const dynamics::ConfigVector qp = dynamics::integrate(q, v, kStep), qm = dynamics::integrate(q, v, -kStep);
    const mpc::Vec3 pdot = (qp.head<3>() - qm.head<3>()) / (2 * kStep);
    EXPECT_LT(rel(f.point.f.segment<3>(mpc::kXBasePosition), pdot), 1e-7);
    auto euler = [](const dynamics::ConfigVector& c) {
      return wbc::euler_zyx_from_rotation(Eigen::Quaterniond(c[6], c[3], c[4], c[5]).toRotationMatrix());
    };
    mpc::Vec3 edot = euler(qp) - euler(qm);
    edot[0] = std::remainder(edot[0], 2 * M_PI);
    EXPECT_LT(rel(f.point.f.segment<3>(mpc::kXEuler), edot / (2 * kStep)), 1e-7);
    // The round trip through the MPC state.
    StateVector x_back;
    mpc::state_from_configuration(f.model, f.data, q, v, x_back);
    StateVector d = x_back - s.x;
    d[mpc::kXEuler] = std::remainder(d[mpc::kXEuler], 2 * M_PI);
    EXPECT_LT(d.cwiseAbs().maxCoeff(), 1e-9);
  }
}

TEST_P(CentroidalModel, MomentumDerivativeMatchesFiniteDifferences) {
  Fixture& f = fixture(GetParam());
  std::mt19937_64 rng(12);
  for (int n = 0; n < kSamples; ++n) {
    const Sample s = random_sample(f.model, rng);
    mpc::centroidal_evaluate(f.model, s.x, s.u, s.head, f.point);
    // A_G v at fixed v with the base at the origin (base axes), from the library.
    dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
    v.head<6>() = f.point.base_twist;
    v.segment<mpc::kNumMpcJoints>(6) = s.u.segment<mpc::kNumMpcJoints>(mpc::kUJointVelocity);
    auto momentum = [&](const StateVector& x) {
      StateVector xl = x;
      xl.segment<6>(mpc::kXBasePosition).setZero();
      const dynamics::ConfigVector q = mpc::configuration_from_state(xl, s.head);
      dynamics::compute_all_terms(f.model, f.data, q, v);
      return dynamics::Vec6(f.data.centroidal_matrix * v);
    };
    Eigen::Matrix<double, 6, mpc::kNumMpcJoints> fd;
    for (int j = 0; j < mpc::kNumMpcJoints; ++j) {
      StateVector xp = s.x, xm = s.x;
      xp[mpc::kXJoints + j] += kStep;
      xm[mpc::kXJoints + j] -= kStep;
      fd.col(j) = (momentum(xp) - momentum(xm)) / (2 * kStep);
    }
    EXPECT_LT(rel(f.point.momentum_dq, fd), kDerivTol) << "sample " << n;
  }
}

// Central differences of a vector function of (x, u) against its analytic Jacobians.
template <int R, class Fn>
void check_jacobians(Fixture& f, const Sample& s, Fn value, const Eigen::Matrix<double, R, mpc::kNx>& dx,
                     const Eigen::Matrix<double, R, mpc::kNu>& du, const char* what) {
  Eigen::Matrix<double, R, mpc::kNx> fdx;
  Eigen::Matrix<double, R, mpc::kNu> fdu;
  for (int i = 0; i < mpc::kNx; ++i) {
    Sample p = s, m = s;
    p.x[i] += kStep;
    m.x[i] -= kStep;
    fdx.col(i) = (value(f, p) - value(f, m)) / (2 * kStep);
  }
  for (int i = 0; i < mpc::kNu; ++i) {
    Sample p = s, m = s;
    p.u[i] += kStep;
    m.u[i] -= kStep;
    fdu.col(i) = (value(f, p) - value(f, m)) / (2 * kStep);
  }
  EXPECT_LT(rel(dx, fdx), kDerivTol) << what << " d/dx";
  EXPECT_LT(rel(du, fdu), kDerivTol) << what << " d/du";
}

TEST_P(CentroidalModel, DynamicsAndBaseVelocityDerivativesMatchFiniteDifferences) {
  Fixture& f = fixture(GetParam());
  std::mt19937_64 rng(13);
  for (int n = 0; n < kSamples; ++n) {
    const Sample s = random_sample(f.model, rng);
    mpc::centroidal_evaluate(f.model, s.x, s.u, s.head, f.point);
    const mpc::StateJacobian fx = f.point.fx;
    const mpc::InputJacobian fu = f.point.fu;
    const mpc::MotionRowsX tdx = f.point.base_twist_dx;
    const mpc::MotionRowsU tdu = f.point.base_twist_du;
    check_jacobians<mpc::kNx>(
        f, s,
        [](Fixture& fx_, const Sample& p) {
          mpc::centroidal_evaluate(fx_.model, p.x, p.u, p.head, fx_.plus);
          return StateVector(fx_.plus.f);
        },
        fx, fu, "f");
    check_jacobians<6>(
        f, s,
        [](Fixture& fx_, const Sample& p) {
          mpc::centroidal_evaluate(fx_.model, p.x, p.u, p.head, fx_.plus);
          return mpc::Vec6(fx_.plus.base_twist);
        },
        tdx, tdu, "base twist");
  }
}

TEST_P(CentroidalModel, PointMotionDerivativesMatchFiniteDifferences) {
  Fixture& f = fixture(GetParam());
  std::mt19937_64 rng(14);
  for (int n = 0; n < kSamples; ++n) {
    const Sample s = random_sample(f.model, rng);
    for (const int corner : {0, 6}) {
      const int body = f.model.frames[corner].body;
      mpc::centroidal_evaluate(f.model, s.x, s.u, s.head, f.point);
      // A point fixed on the foot: its body-frame offset is held while q changes.
      const dynamics::Mat3 rb = f.point.data.rotation[body];
      const mpc::Vec3 offset = rb.transpose() * (dynamics::frame_position(f.model, f.point.data, corner) -
                                                 f.point.data.position_m[body]);
      mpc::Vec6 motion;
      mpc::MotionRowsX dx;
      mpc::MotionRowsU du;
      mpc::point_motion(f.model, f.point, body, dynamics::frame_position(f.model, f.point.data, corner), motion, dx, du);
      // Value: the world frame velocity from the library, rotated to base axes.
      dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
      v.head<6>() = f.point.base_twist;
      v.segment<mpc::kNumMpcJoints>(6) = s.u.segment<mpc::kNumMpcJoints>(mpc::kUJointVelocity);
      dynamics::forward_kinematics(f.model, f.data, mpc::configuration_from_state(s.x, s.head));
      dynamics::forward_velocities(f.model, f.data, v);
      const mpc::Vec6 world = dynamics::frame_velocity(f.model, f.data, corner);
      const dynamics::Mat3 r = f.data.rotation[0];
      EXPECT_LT(rel(motion.head<3>(), r.transpose() * world.head<3>()), kValueTol);
      EXPECT_LT(rel(motion.tail<3>(), r.transpose() * world.tail<3>()), kValueTol);
      check_jacobians<6>(
          f, s,
          [body, offset](Fixture& fx_, const Sample& p) {
            mpc::centroidal_evaluate(fx_.model, p.x, p.u, p.head, fx_.plus);
            const mpc::Vec3 point = fx_.plus.data.position_m[body] + fx_.plus.data.rotation[body] * offset;
            mpc::Vec6 m;
            mpc::MotionRowsX a;
            mpc::MotionRowsU b;
            mpc::point_motion(fx_.model, fx_.plus, body, point, m, a, b);
            return m;
          },
          dx, du, "point motion");
      // Position Jacobian.
      Eigen::Matrix<double, 3, mpc::kNumMpcJoints> jp, fd;
      mpc::point_position_jacobian(f.model, f.point, body, dynamics::frame_position(f.model, f.point.data, corner), jp);
      for (int j = 0; j < mpc::kNumMpcJoints; ++j) {
        Sample p = s, m = s;
        p.x[mpc::kXJoints + j] += kStep;
        m.x[mpc::kXJoints + j] -= kStep;
        mpc::centroidal_evaluate(f.model, p.x, p.u, p.head, f.plus);
        mpc::centroidal_evaluate(f.model, m.x, m.u, m.head, f.minus);
        fd.col(j) = (dynamics::frame_position(f.model, f.plus.data, corner) -
                     dynamics::frame_position(f.model, f.minus.data, corner)) / (2 * kStep);
      }
      EXPECT_LT(rel(jp, fd), kDerivTol);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Variants, CentroidalModel, ::testing::Values(model::Variant::kS45, model::Variant::kS42),
                         [](const auto& info) { return std::string(model::to_string(info.param)); });

}  // namespace
}  // namespace kuavo::test
