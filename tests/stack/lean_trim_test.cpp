// The lean trim's observer and integrator (controllers/stack/lean_trim.h) on synthetic ticks,
// against closed forms: a constant force the WBC did not plan is followed by the residual
// as the discrete first-order filter r_k = K·dt·Σ(d − r) predicts, the trim integrates
// r/(m·g·τ) per second, and the gate, the bound and a failed QP do what they say.
#include <gtest/gtest.h>

#include <cmath>

#include "controllers/model/model.h"
#include "controllers/stack/lean_trim.h"

namespace kuavo::stack {
namespace {

constexpr double kMass = 50.0, kG = model::kGravity_m_s2, kDt = 0.002;

struct Ticks {
  dynamics::Data data;
  wbc::ForceVector points = wbc::ForceVector::Zero();
  wbc::ForceVector forces = wbc::ForceVector::Zero();
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  Ticks() {
    data.total_mass_kg = kMass;
    data.com_m = Eigen::Vector3d(0.0, 0.0, 0.8);
    data.momentum_matrix_ref.setZero();
    for (int k = 0; k < 3; ++k) data.momentum_matrix_ref(k, k) = kMass;  // P = m·v_base
    set_weight_share(1.0);
  }
  void set_weight_share(double share) {
    forces.setZero();
    for (int p = 0; p < model::kNumContactPoints; ++p) forces[3 * p + 2] = share * kMass * kG / model::kNumContactPoints;
  }
};

TEST(LeanTrim, TheResidualFollowsAnUnplannedForceAndTheTrimIntegratesIt) {
  LeanTrimConfig cfg;
  cfg.enabled = true;
  LeanTrimState s;
  Ticks t;
  const Eigen::Vector2d d(6.0, -3.0);  // N: pushes the CoM, the WBC plans no horizontal force
  // Discrete oracle: I_k = I_{k-1} + dt·r_{k-1}, P_k = P_{k-1} + dt·d, r_k = K(P_k − I_k), so
  // r_k = r_{k-1} + K·dt·(d − r_{k-1}) and θ += dt·(r_y, r_x)·(−1, 1)/(m·g·τ) after each.
  Eigen::Vector2d r = Eigen::Vector2d::Zero(), theta = Eigen::Vector2d::Zero();
  lean_trim_update_rt(cfg, s, t.data, t.points, t.forces, t.v, true, kG, kDt);  // primes
  for (int k = 1; k <= 1000; ++k) {
    t.v.head<2>() += kDt * d / kMass;
    lean_trim_update_rt(cfg, s, t.data, t.points, t.forces, t.v, true, kG, kDt);
    r += cfg.observer_gain_1_s * kDt * (d - r);
    theta.x() -= kDt * r.y() / (kMass * kG * cfg.time_constant_s);
    theta.y() += kDt * r.x() / (kMass * kG * cfg.time_constant_s);
    if (k == 50) {
      EXPECT_NEAR(s.residual_N.x(), d.x() * (1.0 - std::exp(-0.1 * cfg.observer_gain_1_s)), 0.05);
    }
  }
  EXPECT_NEAR((s.residual_N - r).norm(), 0.0, 1e-9);
  EXPECT_NEAR((s.residual_N - d).norm(), 0.0, 1e-6);
  EXPECT_NEAR((s.theta_rad - theta).norm(), 0.0, 1e-12);
  EXPECT_GT(s.theta_rad.y(), 0.0);  // CoM pushed forward (+x): the base trimmed pitched forward
  EXPECT_GT(s.theta_rad.x(), 0.0);  // pushed right (−y): rolled right (+x rotation)
  EXPECT_EQ(s.integrated_ticks, 1000u);
  EXPECT_EQ(s.saturated_ticks, 0u);

  // Applied to a level base: the rotation (roll about x, then pitch about y) of the trim.
  dynamics::ConfigVector q = dynamics::ConfigVector::Zero();
  q[6] = 1.0;
  lean_trim_apply_rt(cfg, s, q);
  const Eigen::Quaterniond got(q[6], q[3], q[4], q[5]);
  const Eigen::Quaterniond want = Eigen::AngleAxisd(s.theta_rad.x(), Eigen::Vector3d::UnitX()) *
                                  Eigen::AngleAxisd(s.theta_rad.y(), Eigen::Vector3d::UnitY());
  EXPECT_NEAR(got.angularDistance(want), 0.0, 1e-12);
}

TEST(LeanTrim, TheGateTheBoundAndAFailedQpHoldTheTrim) {
  LeanTrimConfig cfg;
  cfg.enabled = true;
  Ticks t;
  const auto run = [&](LeanTrimState& s, const Eigen::Vector2d& d, int ticks, bool ok) {
    for (int k = 0; k < ticks; ++k) {
      t.v.head<2>() += kDt * d / kMass;
      lean_trim_update_rt(cfg, s, t.data, t.points, t.forces, t.v, ok, kG, kDt);
    }
  };
  {  // a push: 100 N is over the 40 N gate once the residual has caught up with it
    LeanTrimState s;
    run(s, Eigen::Vector2d(100.0, 0.0), 500, true);
    EXPECT_GT(s.residual_N.x(), 99.0);
    EXPECT_LT(s.integrated_ticks, 60u);  // only while the residual rose through 40 N
  }
  {  // the feet carry a third of the weight (a jump, a fall): nothing moves
    LeanTrimState s;
    t.set_weight_share(0.3);
    run(s, Eigen::Vector2d(6.0, 0.0), 500, true);
    EXPECT_EQ(s.integrated_ticks, 0u);
    EXPECT_TRUE(s.theta_rad.isZero(0.0));
    t.set_weight_share(1.0);
  }
  {  // the QP did not answer: the observer starts again, the trim holds
    LeanTrimState s;
    run(s, Eigen::Vector2d(6.0, 0.0), 500, true);
    const Eigen::Vector2d held = s.theta_rad;
    run(s, Eigen::Vector2d(6.0, 0.0), 100, false);
    EXPECT_FALSE(s.primed);
    EXPECT_EQ(s.theta_rad, held);
  }
  {  // a persistent 30 N reaches the 2° bound within 2 s and is held there, counted
    LeanTrimState s;
    run(s, Eigen::Vector2d(30.0, 0.0), 5000, true);
    EXPECT_DOUBLE_EQ(s.theta_rad.y(), cfg.max_rad);
    EXPECT_GT(s.saturated_ticks, 0u);
  }
  {  // off: nothing at all
    LeanTrimState s;
    cfg.enabled = false;
    run(s, Eigen::Vector2d(6.0, 0.0), 100, true);
    EXPECT_FALSE(s.primed);
    dynamics::ConfigVector q = dynamics::ConfigVector::Zero();
    q[6] = 1.0;
    s.theta_rad = Eigen::Vector2d(0.01, 0.01);
    lean_trim_apply_rt(cfg, s, q);
    EXPECT_EQ(q[6], 1.0);
  }
}

TEST(LeanTrim, RefusesABadConfiguration) {
  EXPECT_EQ(lean_trim_validate(LeanTrimConfig{}), nullptr);
  for (const double bad : {0.0, -1.0, 1000.0, std::nan("")}) {
    LeanTrimConfig c;
    c.time_constant_s = bad;
    EXPECT_NE(lean_trim_validate(c), nullptr) << bad;
    c = LeanTrimConfig{};
    c.observer_gain_1_s = bad;
    EXPECT_NE(lean_trim_validate(c), nullptr) << bad;
    c = LeanTrimConfig{};
    c.max_rad = bad;
    EXPECT_NE(lean_trim_validate(c), nullptr) << bad;
  }
}

}  // namespace
}  // namespace kuavo::stack
