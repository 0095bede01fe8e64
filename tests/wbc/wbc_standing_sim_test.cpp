// The WBC stands the simulated robot: a WBC variant of the standing loop driving sim::Plant
// directly (as tests/sim/standing_test.cpp does), with a standing reference held at the
// start state. State from the plant's truth (the estimator is wired in by the online-stack
// loop, not here), 500 Hz lockstep.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <memory>

#include "controllers/standing/standing_controller.h"
#include "sim/closed_loop.h"
#include "sim/plant.h"
#include "tests/wbc/wbc_fixture.h"

namespace kuavo::test {
namespace {

struct WbcRun {
  bool ok = true;
  bool fell = false;
  double max_tilt_deg = 0.0;
  double min_base_height_m = 1e9;
  double max_com_error_m = 0.0;  // horizontal, from the reference CoM
  int ticks_ok = 0, ticks_not_ok = 0;
};

double tilt_deg(const dynamics::ConfigVector& q) {
  const Eigen::Quaterniond o(q[6], q[3], q[4], q[5]);
  return std::acos(std::clamp((o.toRotationMatrix() * Eigen::Vector3d::UnitZ()).z(), -1.0, 1.0)) * 180.0 /
         3.14159265358979323846;
}

WbcRun stand_with_wbc(double seconds, const sim::GroundParams& ground, const sim::Push& push = {}) {
  const model::Model& m = wbc_robot();
  wbc::WbcWorkspace& ws = wbc_workspace();
  const wbc::WbcConfig cfg;
  wbc::wbc_init(m, cfg, ws);
  dynamics::ConfigVector q0 = dynamics::neutral_configuration(m);
  q0.tail<model::kNumJoints>() = control::centred_standing_pose(m, ws.data, 0.78);
  control::place_on_ground(m, ws.data, q0);
  static wbc::WbcReference ref;
  wbc::wbc_reference_hold_state(m, ws, q0, 0, ref);

  sim::PlantConfig plant_cfg;
  plant_cfg.ground = ground;
  auto plant = std::make_unique<sim::Plant>(m, plant_cfg);
  plant->reset(q0, dynamics::VelocityVector::Zero());
  plant->set_push(push);
  static hal::CommandFrame command;
  WbcRun run;
  const int ticks = static_cast<int>(std::lround(seconds / cfg.dt_s));
  for (int tick = 0; tick < ticks; ++tick) {
    const hal::TimeNs now_ns = static_cast<hal::TimeNs>(tick) * 2'000'000;
    ref.stamp_ns = now_ns;  // the planner keeps the standing reference fresh
    const sim::PlantTruth& truth = plant->truth();
    const auto status = wbc::wbc_step_rt(m, cfg, ws, truth.q, truth.v, ref, now_ns, command);
    (status == wbc::WbcStatus::kOk ? run.ticks_ok : run.ticks_not_ok) += 1;
    plant->set_command(command);
    if (plant->advance(cfg.dt_s) != sim::PlantError::kOk) {
      run.ok = false;
      break;
    }
    const sim::PlantTruth& t = plant->truth();
    run.max_tilt_deg = std::max(run.max_tilt_deg, tilt_deg(t.q));
    run.min_base_height_m = std::min(run.min_base_height_m, t.q[2]);
    run.max_com_error_m = std::max(run.max_com_error_m, (t.com_m - ref.com_position_m).head<2>().norm());
    if (std::getenv("KUAVO_WBC_TRACE") != nullptr && tick % 100 == 0) {  // debugging aid, off by default
      const Eigen::Vector3d e = t.com_m - ref.com_position_m;
      double foot_err = 0.0;
      for (int c = 0; c < 8; ++c) foot_err = std::max(foot_err, (ws.point_position_m.segment<3>(3 * c) - ref.point_position_m.segment<3>(3 * c)).norm());
      std::printf("t %.1f com_err %+.4f %+.4f %+.4f tilt %.2f ypr %+.3f %+.3f %+.3f foot %.4f fz %.1f %.1f tau_ank %.1f %.1f it %d\n", tick * cfg.dt_s, e.x(), e.y(), e.z(), tilt_deg(t.q),
                  wbc::euler_zyx_from_rotation(ws.data.rotation[0])[0], wbc::euler_zyx_from_rotation(ws.data.rotation[0])[1], wbc::euler_zyx_from_rotation(ws.data.rotation[0])[2],
                  foot_err, ws.diagnostics.contact_force_N[2] + ws.diagnostics.contact_force_N[5] + ws.diagnostics.contact_force_N[8] + ws.diagnostics.contact_force_N[11],
                  ws.diagnostics.contact_force_N[14] + ws.diagnostics.contact_force_N[17] + ws.diagnostics.contact_force_N[20] + ws.diagnostics.contact_force_N[23],
                  ws.diagnostics.torque_Nm[4], ws.diagnostics.torque_Nm[5], ws.diagnostics.qp_iterations);
    }
    if (t.q[2] < sim::kFallHeight_m || tilt_deg(t.q) > sim::kFallTilt_deg) {
      run.fell = true;
      break;
    }
  }
  std::printf("%s %.0f s push %.0f N: fell %d, max tilt %.2f deg, min base z %.3f m, max CoM err %.1f mm, ticks ok %d, not ok %d\n",
              ground.name, seconds, push.force_N.norm(), run.fell, run.max_tilt_deg, run.min_base_height_m,
              1e3 * run.max_com_error_m, run.ticks_ok, run.ticks_not_ok);
  return run;
}

TEST(WbcStandingSim, TenSecondsOnTheFloor) {
  const WbcRun r = stand_with_wbc(10.0, sim::kFloor);
  ASSERT_TRUE(r.ok);
  EXPECT_FALSE(r.fell);
  EXPECT_EQ(r.ticks_not_ok, 0);
  EXPECT_LT(r.max_tilt_deg, 3.0);
  EXPECT_LT(r.max_com_error_m, 0.02);
}

TEST(WbcStandingSim, TenSecondsOnCarpet) {
  const WbcRun r = stand_with_wbc(10.0, sim::kCarpet);
  ASSERT_TRUE(r.ok);
  EXPECT_FALSE(r.fell);
  EXPECT_EQ(r.ticks_not_ok, 0);
  EXPECT_LT(r.max_tilt_deg, 5.0);
}

struct PushCase {
  const char* name;
  const sim::GroundParams* ground;
  double fx, fy;
};
class WbcTenNewtonSecondPush : public ::testing::TestWithParam<PushCase> {};

TEST_P(WbcTenNewtonSecondPush, IsSurvived) {
  const PushCase& c = GetParam();
  sim::Push push;
  push.start_s = 1.0;
  push.duration_s = 0.1;
  push.force_N = sim::Vec3(c.fx, c.fy, 0.0);  // 100 N for 0.1 s = 10 N·s
  const WbcRun r = stand_with_wbc(4.0, *c.ground, push);
  ASSERT_TRUE(r.ok);
  EXPECT_FALSE(r.fell) << c.name;
  EXPECT_GT(r.max_tilt_deg, 0.3) << c.name;  // it was a real push
}

const PushCase kPushes[] = {
    {"floor_forward", &sim::kFloor, 100, 0},   {"floor_backward", &sim::kFloor, -100, 0},
    {"floor_left", &sim::kFloor, 0, 100},      {"carpet_forward", &sim::kCarpet, 100, 0},
    {"carpet_backward", &sim::kCarpet, -100, 0}, {"carpet_right", &sim::kCarpet, 0, -100},
};
INSTANTIATE_TEST_SUITE_P(Directions, WbcTenNewtonSecondPush, ::testing::ValuesIn(kPushes),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(WbcStandingSim, ThirtyNewtonSecondsForwardIsBeyondStanding) {
  // The push tests must be able to fail: without stepping, this one topples it.
  sim::Push push;
  push.start_s = 1.0;
  push.duration_s = 0.1;
  push.force_N = sim::Vec3(300.0, 0.0, 0.0);
  EXPECT_TRUE(stand_with_wbc(3.0, sim::kFloor, push).fell);
}

}  // namespace
}  // namespace kuavo::test
