// MPC + WBC on the Simbody plant with the true state (no estimator): MPC at 50 Hz, WBC at
// 500 Hz interpolating the MPC's knots (wbc_interpolate_reference), lockstep. Each plan reaches
// the WBC kLatencyTicks after its measurement (the MPC's compute time on the robot, ~10 ms with
// the present solver); until then the WBC keeps interpolating the previous plan at "now".
// Standing with a 10 N·s push, and steps in place.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <memory>

#include "controllers/wbc/wbc.h"
#include "sim/closed_loop.h"
#include "sim/plant.h"
#include "tests/mpc/mpc_fixture.h"

namespace kuavo::test {
namespace {

using dynamics::Vec3;

struct LoopResult {
  bool plant_ok = true;
  bool fell = false;
  double max_tilt_deg = 0.0;
  double max_com_error_m = 0.0;     // horizontal, from the standing reference CoM
  double final_com_error_m = 0.0;
  double max_swing_height_m = 0.0;  // highest sole corner seen
  int mpc_failures = 0, wbc_not_ok = 0, mpc_calls = 0;
};

double tilt_deg(const dynamics::ConfigVector& q) {
  const Eigen::Quaterniond o(q[6], q[3], q[4], q[5]);
  return std::acos(std::clamp((o.toRotationMatrix() * Eigen::Vector3d::UnitZ()).z(), -1.0, 1.0)) * 180.0 / M_PI;
}

constexpr int kLatencyTicks = 5;  // 10 ms at 500 Hz

LoopResult run_loop(double seconds, const sim::Push& push, const SteppingPlan* stepping) {
  MpcFixture& f = mpc_fixture();
  static auto wbc_ws = std::make_unique<wbc::WbcWorkspace>();
  static mpc::MpcPlan active, pending;
  int pending_at_tick = -1;
  static wbc::WbcReference ref;
  static hal::CommandFrame command;
  const wbc::WbcConfig wcfg;
  wbc::wbc_init(f.model, wcfg, *wbc_ws);
  sim::PlantConfig pcfg;
  auto plant = std::make_unique<sim::Plant>(f.model, pcfg);
  plant->reset(f.q0, dynamics::VelocityVector::Zero());
  plant->set_push(push);
  standing_window(f, 0);
  const Vec3 com_ref = f.window.knots[0].com_position_m;
  LoopResult out;
  active.count = 0;
  const int ticks = static_cast<int>(std::lround(seconds / wcfg.dt_s));
  const int ticks_per_mpc = static_cast<int>(std::lround(f.config.dt_s / wcfg.dt_s));
  for (int tick = 0; tick < ticks; ++tick) {
    const hal::TimeNs now_ns = static_cast<hal::TimeNs>(tick) * 2'000'000;
    const sim::PlantTruth& truth = plant->truth();
    if (tick % ticks_per_mpc == 0) {
      if (stepping != nullptr && tick * wcfg.dt_s >= 0.5) {
        stepping_window(f, now_ns - 500'000'000, *stepping);  // steps start at 0.5 s
        for (int k = 0; k < f.window.count; ++k) f.window.knots[k].stamp_ns += 500'000'000;
      } else {
        standing_window(f, now_ns);
      }
      ++out.mpc_calls;
      if (mpc::mpc_step_rt(f.model, f.config, f.ws, truth.q, truth.v, f.window, f.plan) == mpc::MpcStatus::kOk) {
        pending = f.plan;
        pending_at_tick = tick == 0 ? 0 : tick + kLatencyTicks;  // the first plan before starting
      } else {
        ++out.mpc_failures;
      }
    }
    if (pending_at_tick >= 0 && tick >= pending_at_tick) {
      active = pending;
      pending_at_tick = -1;
    }
    if (active.count < 2) {
      out.plant_ok = false;
      break;
    }
    const double s = static_cast<double>(now_ns - active.stamp_ns) * 1e-9 / active.dt_s;
    const int i = std::clamp(static_cast<int>(std::floor(s)), 0, active.count - 2);
    wbc::wbc_interpolate_reference(active.knots[i], active.knots[i + 1], s - i, ref);
    if (wbc::wbc_step_rt(f.model, wcfg, *wbc_ws, truth.q, truth.v, ref, now_ns, command) != wbc::WbcStatus::kOk) {
      ++out.wbc_not_ok;
    }
    plant->set_command(command);
    if (plant->advance(wcfg.dt_s) != sim::PlantError::kOk) {
      out.plant_ok = false;
      break;
    }
    const sim::PlantTruth& t = plant->truth();
    out.max_tilt_deg = std::max(out.max_tilt_deg, tilt_deg(t.q));
    out.final_com_error_m = (t.com_m - com_ref).head<2>().norm();
    out.max_com_error_m = std::max(out.max_com_error_m, out.final_com_error_m);
    for (const auto& p : t.contact_point_m) out.max_swing_height_m = std::max(out.max_swing_height_m, p.z());
    if (std::getenv("KUAVO_MPC_TRACE") != nullptr && tick % 50 == 0) {
      std::printf("t %.2f com err %+.4f %+.4f tilt %.2f mpc viol %.1e fz L %.0f R %.0f zL %.3f zR %.3f\n", tick * wcfg.dt_s,
                  (t.com_m - com_ref).x(), (t.com_m - com_ref).y(), tilt_deg(t.q), active.constraint_violation,
                  t.contact_force_N[0].z() + t.contact_force_N[1].z() + t.contact_force_N[2].z() + t.contact_force_N[3].z(),
                  t.contact_force_N[4].z() + t.contact_force_N[5].z() + t.contact_force_N[6].z() + t.contact_force_N[7].z(),
                  t.contact_point_m[0].z(), t.contact_point_m[4].z());
    }
    if (t.q[2] < sim::kFallHeight_m || tilt_deg(t.q) > sim::kFallTilt_deg) {
      out.fell = true;
      break;
    }
  }
  std::printf("%.1f s, push %.0f N·s%s: fell %d, max tilt %.2f deg, CoM err max %.1f mm final %.1f mm, highest corner %.1f mm, "
              "MPC calls %d failed %d, WBC not ok %d\n",
              seconds, push.force_N.norm() * push.duration_s, stepping ? ", stepping" : "", out.fell, out.max_tilt_deg,
              1e3 * out.max_com_error_m, 1e3 * out.final_com_error_m, 1e3 * out.max_swing_height_m, out.mpc_calls,
              out.mpc_failures, out.wbc_not_ok);
  return out;
}

TEST(MpcClosedLoopSim, StandsFiveSecondsThroughATenNewtonSecondPush) {
  for (const Vec3& force : {Vec3(100.0, 0.0, 0.0), Vec3(0.0, 100.0, 0.0)}) {
    sim::Push push;
    push.start_s = 1.0;
    push.duration_s = 0.1;
    push.force_N = force;
    const LoopResult r = run_loop(5.0, push, nullptr);
    ASSERT_TRUE(r.plant_ok);
    EXPECT_FALSE(r.fell);
    EXPECT_EQ(r.mpc_failures, 0);
    EXPECT_EQ(r.wbc_not_ok, 0);
    EXPECT_GT(r.max_tilt_deg, 0.3);           // a real push
    EXPECT_LT(r.final_com_error_m, 0.02);     // and back over the feet
  }
}

TEST(MpcClosedLoopSim, StepsInPlace) {
  const SteppingPlan plan;
  const LoopResult r = run_loop(0.5 + 4 * (plan.stance_s + plan.swing_s) + 0.5, sim::Push{}, &plan);
  ASSERT_TRUE(r.plant_ok);
  EXPECT_FALSE(r.fell);
  EXPECT_EQ(r.mpc_failures, 0);
  EXPECT_GT(r.max_swing_height_m, 0.5 * plan.height_m);  // the feet really left the ground
  EXPECT_LT(r.max_tilt_deg, 10.0);
}

}  // namespace
}  // namespace kuavo::test
