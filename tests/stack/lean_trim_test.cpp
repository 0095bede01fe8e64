// The lean trim's observer and integrator (controllers/stack/lean_trim.h) on synthetic ticks,
// against closed forms: a constant force the WBC did not plan is followed by the residual
// as the discrete first-order filter r_k = K·dt·Σ(d − r) predicts, the trim integrates
// r/(m·g·τ) per second once the quasi-static gate has held, and the gates, the bound and a
// failed QP do what they say.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

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
  // The horizontal force the WBC plans, all on the first point (the trim reads the sum).
  void plan(const Eigen::Vector2d& f) { forces.segment<2>(0) = f; }
};

TEST(LeanTrim, TheResidualFollowsAnUnplannedForceAndTheTrimIntegratesIt) {
  LeanTrimConfig cfg;
  cfg.enabled = true;
  ASSERT_EQ(cfg.learn, LeanTrimLearn::kAlways);  // learns in every quasi-static tick
  ASSERT_GT(cfg.residual_deadband_N, 0.0);
  LeanTrimState s;
  Ticks t;
  // Standing with the true CoM off the believed one: the ground pushes the CoM with d, the WBC
  // plans −d against it and the CoM stays (P constant): the residual reads the d it did not plan.
  const Eigen::Vector2d d(6.0, -3.0);
  t.plan(-d);
  // Discrete oracle: I_k = I_{k-1} + dt·(−d + r_{k-1}), P_k = P_0, r_k = K(P_k − P_0 − I_k), so
  // r_k = r_{k-1} + K·dt·(d − r_{k-1}); θ += dt·(r_y, r_x)·(−1, 1)/(m·g·τ) once the quiet time
  // (all ticks here are quasi-static: 6.7 N planned, the CoM still) has reached the hold.
  Eigen::Vector2d r = Eigen::Vector2d::Zero(), theta = Eigen::Vector2d::Zero();
  double quiet_s = 0.0;
  std::uint64_t integrated = 0;
  lean_trim_update_rt(cfg, s, t.data, t.points, t.forces, t.v, true, kG, kDt);  // primes
  for (int k = 1; k <= 1000; ++k) {
    lean_trim_update_rt(cfg, s, t.data, t.points, t.forces, t.v, true, kG, kDt);
    r += cfg.observer_gain_1_s * kDt * (d - r);
    quiet_s += kDt;
    if (quiet_s >= cfg.quasi_static_hold_s) {
      // Learned: r less the dead band, along r (|r| passes 3 N within 0.1 s here).
      const double kept = std::max(0.0, 1.0 - cfg.residual_deadband_N / r.norm());
      theta.x() -= kDt * kept * r.y() / (kMass * kG * cfg.time_constant_s);
      theta.y() += kDt * kept * r.x() / (kMass * kG * cfg.time_constant_s);
      ++integrated;
    }
    if (k == 50) {
      EXPECT_NEAR(s.residual_N.x(), d.x() * (1.0 - std::exp(-0.1 * cfg.observer_gain_1_s)), 0.05);
      EXPECT_EQ(s.integrated_ticks, 0u);  // 0.1 s quiet, the hold is 0.3 s
    }
  }
  EXPECT_NEAR((s.residual_N - r).norm(), 0.0, 1e-9);
  EXPECT_NEAR((s.residual_N - d).norm(), 0.0, 1e-6);
  EXPECT_NEAR((s.theta_rad - theta).norm(), 0.0, 1e-12);
  EXPECT_GT(s.theta_rad.y(), 0.0);  // CoM pushed forward (+x): the base trimmed pitched forward
  EXPECT_GT(s.theta_rad.x(), 0.0);  // pushed right (−y): rolled right (+x rotation)
  EXPECT_EQ(s.integrated_ticks, integrated);
  EXPECT_NEAR(static_cast<double>(integrated), 1000.0 - cfg.quasi_static_hold_s / kDt, 1.0);
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
  cfg.learn = LeanTrimLearn::kAlways;
  Ticks t;
  // The WBC plans −d against an unplanned d and the CoM stays: quasi-static while |d| ≤ 20 N.
  const auto run = [&](LeanTrimState& s, const Eigen::Vector2d& d, int ticks, bool ok) {
    t.plan(-d);
    for (int k = 0; k < ticks; ++k) lean_trim_update_rt(cfg, s, t.data, t.points, t.forces, t.v, ok, kG, kDt);
  };
  {  // a push moves the CoM: 100 N is over the 40 N gate once the residual has caught up
    LeanTrimConfig wide = cfg;  // the residual gate alone: the quasi-static gate wide open
    wide.quasi_static_force_N = 1e3;
    wide.quasi_static_speed_m_s = 10.0;
    wide.quasi_static_hold_s = 0.0;
    LeanTrimState s;
    t.plan(Eigen::Vector2d::Zero());
    for (int k = 0; k < 500; ++k) {
      t.v.x() += kDt * 100.0 / kMass;
      lean_trim_update_rt(wide, s, t.data, t.points, t.forces, t.v, true, kG, kDt);
    }
    t.v.setZero();
    EXPECT_GT(s.residual_N.x(), 99.0);
    EXPECT_GT(s.integrated_ticks, 0u);
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
  {  // a persistent 18 N reaches the 2° bound within 10 s and is held there, counted
    LeanTrimState s;
    run(s, Eigen::Vector2d(18.0, 0.0), 5000, true);
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

TEST(LeanTrim, OnlyQuasiStaticPhasesMoveTheTrim) {
  LeanTrimConfig cfg;
  cfg.enabled = true;
  cfg.learn = LeanTrimLearn::kAlways;
  Ticks t;
  const Eigen::Vector2d d(6.0, 0.0);  // an offset's unplanned force
  // After priming, 399 ticks of the first-order filter: r = d·(1 − (1 − K·dt)^399).
  const double settled = 1.0 - std::pow(1.0 - cfg.observer_gain_1_s * kDt, 399);
  const auto tick = [&](LeanTrimState& s) { lean_trim_update_rt(cfg, s, t.data, t.points, t.forces, t.v, true, kG, kDt); };
  {  // the WBC plans 30 N (> 20 N) and the CoM stays: the residual, −30 N, is inside the
     // 40 N gate and the CoM still, so only the force gate holds the trim
    LeanTrimState s;
    t.plan(Eigen::Vector2d(30.0, 0.0));
    for (int k = 0; k < 400; ++k) tick(s);
    EXPECT_NEAR(s.residual_N.x(), -30.0 * settled, 1e-9);
    EXPECT_EQ(s.integrated_ticks, 0u);
    EXPECT_TRUE(s.theta_rad.isZero(0.0));
  }
  {  // the CoM glides at 0.2 m/s (> 0.1) while the WBC plans −d: the residual is d, no trim
    LeanTrimState s;
    t.v.x() = 0.2;
    t.plan(-d);
    for (int k = 0; k < 400; ++k) tick(s);
    EXPECT_NEAR(s.residual_N.x(), d.x() * settled, 1e-9);
    EXPECT_EQ(s.integrated_ticks, 0u);
    t.v.x() = 0.099;  // under the speed gate: the trim moves after the hold
    for (int k = 0; k < 400; ++k) tick(s);
    EXPECT_GT(s.integrated_ticks, 0u);
    EXPECT_GT(s.theta_rad.y(), 0.0);
    t.v.setZero();
  }
  {  // the hold: 0.2 s quiet is not enough; one loud tick starts the count again
    LeanTrimState s;
    t.plan(-d);
    for (int k = 0; k < 100; ++k) tick(s);  // primes, then 0.198 s quiet
    EXPECT_EQ(s.integrated_ticks, 0u);
    t.plan(Eigen::Vector2d(-25.0, 0.0));
    tick(s);
    t.plan(-d);
    for (int k = 0; k < 140; ++k) tick(s);  // 0.28 s quiet since the loud tick
    EXPECT_EQ(s.integrated_ticks, 0u);
    for (int k = 0; k < 20; ++k) tick(s);  // 0.32 s: the trim moves from 0.30 s
    EXPECT_GT(s.integrated_ticks, 5u);
    EXPECT_LT(s.integrated_ticks, 15u);
  }
}

// kOpening learns as kAlways does, at its own time constant, until the plan first lifts a
// sole corner; from that tick the trim holds, whatever the residual, until a reset.
TEST(LeanTrim, TheOpeningLearnsUntilThePlanLiftsACornerAndThenHolds) {
  LeanTrimConfig opening;
  opening.enabled = true;
  opening.learn = LeanTrimLearn::kOpening;
  LeanTrimConfig always = opening;
  always.learn = LeanTrimLearn::kAlways;
  ASSERT_NE(opening.opening_time_constant_s, always.time_constant_s);
  Ticks t;
  t.plan(-Eigen::Vector2d(6.0, -3.0));
  planner::ContactFlags down;
  down.fill(true);
  LeanTrimState a, b;
  const auto tick = [&](const LeanTrimConfig& c, LeanTrimState& s, const planner::ContactFlags& planned) {
    lean_trim_note_plan_rt(c, s, planned);
    lean_trim_update_rt(c, s, t.data, t.points, t.forces, t.v, true, kG, kDt);
  };
  for (int k = 0; k < 1000; ++k) {
    tick(opening, a, down);
    tick(always, b, down);
  }
  // The same residuals and gates: the trims differ by the ratio of the time constants.
  EXPECT_FALSE(a.opening_over);
  EXPECT_EQ(a.integrated_ticks, b.integrated_ticks);
  EXPECT_GT(b.theta_rad.norm(), 1e-3);
  EXPECT_NEAR((a.theta_rad - b.theta_rad * (always.time_constant_s / opening.opening_time_constant_s)).norm(), 0.0,
              1e-12);
  // One corner lifted (the right heel) ends the opening; the trim holds from then on, with
  // the foot down again too.
  planner::ContactFlags lifted = down;
  lifted[model::kNumContactPoints - 1] = false;
  const Eigen::Vector2d learned = a.theta_rad;
  const std::uint64_t ticks = a.integrated_ticks;
  tick(opening, a, lifted);
  EXPECT_TRUE(a.opening_over);
  for (int k = 0; k < 500; ++k) tick(opening, a, down);
  EXPECT_EQ(a.theta_rad, learned);
  EXPECT_EQ(a.integrated_ticks, ticks);
  // kAlways goes on learning through a lift-off.
  const std::uint64_t b_ticks = b.integrated_ticks;
  for (int k = 0; k < 10; ++k) tick(always, b, lifted);
  EXPECT_EQ(b.integrated_ticks, b_ticks + 10);
  // A reset starts a new opening; off, the plan is not even noted.
  lean_trim_reset(a);
  EXPECT_FALSE(a.opening_over);
  opening.enabled = false;
  lean_trim_note_plan_rt(opening, a, lifted);
  EXPECT_FALSE(a.opening_over);
}

// A residual inside the dead band (what joint friction can hold) moves nothing; past it, only
// the excess is learned.
TEST(LeanTrim, TheDeadBandLearnsOnlyTheResidualFrictionCannotHold) {
  LeanTrimConfig cfg;
  cfg.enabled = true;
  cfg.learn = LeanTrimLearn::kAlways;
  Ticks t;
  LeanTrimState inside, past, open;
  const auto run = [&](const LeanTrimConfig& c, LeanTrimState& s, const Eigen::Vector2d& d) {
    t.plan(-d);
    for (int k = 0; k < 1000; ++k) lean_trim_update_rt(c, s, t.data, t.points, t.forces, t.v, true, kG, kDt);
  };
  run(cfg, inside, Eigen::Vector2d(0.0, 0.9 * cfg.residual_deadband_N));
  EXPECT_GT(inside.integrated_ticks, 0u);  // the gate let it learn; there was nothing to learn
  EXPECT_TRUE(inside.theta_rad.isZero(0.0));
  // 3·d: once the residual has settled (within 1e-6 N after 2 s), the trim's rate is 2/3 of
  // what the band-free trim learns from the same residual.
  LeanTrimConfig no_band = cfg;
  no_band.residual_deadband_N = 0.0;
  const Eigen::Vector2d d(3.0 * cfg.residual_deadband_N, 0.0);
  run(cfg, past, d);
  run(no_band, open, d);
  const Eigen::Vector2d before_past = past.theta_rad, before_open = open.theta_rad;
  run(cfg, past, d);
  run(no_band, open, d);
  EXPECT_GT((open.theta_rad - before_open).norm(), 1e-3);
  EXPECT_NEAR((past.theta_rad - before_past - (2.0 / 3.0) * (open.theta_rad - before_open)).norm(), 0.0, 1e-9);
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
    c = LeanTrimConfig{};
    c.quasi_static_force_N = bad == 1000.0 ? 1e5 : bad;
    EXPECT_NE(lean_trim_validate(c), nullptr) << bad;
    c = LeanTrimConfig{};
    c.quasi_static_speed_m_s = bad == 1000.0 ? 11.0 : bad;
    EXPECT_NE(lean_trim_validate(c), nullptr) << bad;
  }
  for (const double bad : {-0.1, 11.0, std::nan("")}) {
    LeanTrimConfig c;
    c.quasi_static_hold_s = bad;
    EXPECT_NE(lean_trim_validate(c), nullptr) << bad;
  }
  for (const double bad : {0.05, 101.0, std::nan("")}) {
    LeanTrimConfig c;
    c.opening_time_constant_s = bad;
    EXPECT_NE(lean_trim_validate(c), nullptr) << bad;
  }
  for (const double bad : {-0.1, 40.0, std::nan("")}) {  // 40 N: the residual gate
    LeanTrimConfig c;
    c.residual_deadband_N = bad;
    EXPECT_NE(lean_trim_validate(c), nullptr) << bad;
  }
  LeanTrimConfig unknown;
  unknown.learn = static_cast<LeanTrimLearn>(7);
  EXPECT_NE(lean_trim_validate(unknown), nullptr);
}

}  // namespace
}  // namespace kuavo::stack
