// Rigid-body algorithms on the 28-DoF Kuavo 4Pro, ours beside Simbody computing
// the same quantity in the same run. Run pinned: taskset -c 1 build/bench/dynamics_bench
#include <benchmark/benchmark.h>

#include <memory>
#include <random>

#include "controllers/dynamics/rigid_body.h"
#include "sim/simbody_model.h"

namespace {

using namespace kuavo;

struct Fixture {
  model::Model robot;
  dynamics::Data data;
  std::array<dynamics::ConfigVector, 16> q;
  std::array<dynamics::VelocityVector, 16> v;
  Fixture() {
    model::build_model(model::Variant::kS45, 55.0, robot);
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int i = 0; i < 16; ++i) {
      q[i] = dynamics::neutral_configuration(robot);
      Eigen::Quaterniond quat(1.0, 0.1 * u(rng), 0.1 * u(rng), 0.1 * u(rng));
      quat.normalize();
      q[i].segment<4>(3) << quat.x(), quat.y(), quat.z(), quat.w();
      for (int j = 0; j < model::kNumJoints; ++j) {
        q[i][7 + j] = 0.5 * (robot.limits.position_min_rad[j] + robot.limits.position_max_rad[j]) + 0.1 * u(rng);
      }
      for (int k = 0; k < model::kNv; ++k) v[i][k] = u(rng);
    }
  }
};

Fixture& fixture() {
  static Fixture f;  // static storage, as in the controllers
  return f;
}

void BM_ForwardKinematics(benchmark::State& st) {
  auto& f = fixture();
  int i = 0;
  for (auto _ : st) {
    dynamics::forward_kinematics(f.robot, f.data, f.q[i++ & 15]);
    benchmark::DoNotOptimize(f.data.position_m[6]);
  }
}
BENCHMARK(BM_ForwardKinematics);

void BM_Crba(benchmark::State& st) {
  auto& f = fixture();
  dynamics::forward_kinematics(f.robot, f.data, f.q[0]);
  for (auto _ : st) {
    dynamics::crba(f.robot, f.data);
    benchmark::DoNotOptimize(f.data.mass_matrix(7, 7));
  }
}
BENCHMARK(BM_Crba);

void BM_Rnea(benchmark::State& st) {
  auto& f = fixture();
  dynamics::forward_kinematics(f.robot, f.data, f.q[0]);
  dynamics::forward_velocities(f.robot, f.data, f.v[0]);
  for (auto _ : st) {
    dynamics::rnea(f.robot, f.data, f.v[1], true);
    benchmark::DoNotOptimize(f.data.tau[7]);
  }
}
BENCHMARK(BM_Rnea);

void BM_CentroidalMomentumMatrixAndBias(benchmark::State& st) {
  auto& f = fixture();
  dynamics::forward_kinematics(f.robot, f.data, f.q[0]);
  dynamics::forward_velocities(f.robot, f.data, f.v[0]);
  dynamics::crba(f.robot, f.data);
  for (auto _ : st) {
    dynamics::centroidal_dynamics(f.robot, f.data);
    benchmark::DoNotOptimize(f.data.centroidal_bias[0]);
  }
}
BENCHMARK(BM_CentroidalMomentumMatrixAndBias);

// The per-tick bundle: FK + velocities + CRBA + RNEA (b) + CMM + Ȧv, from scratch.
void BM_AllTerms_CrbaRneaCmm(benchmark::State& st) {
  auto& f = fixture();
  int i = 0;
  for (auto _ : st) {
    dynamics::compute_all_terms(f.robot, f.data, f.q[i & 15], f.v[i & 15]);
    ++i;
    benchmark::DoNotOptimize(f.data.mass_matrix(7, 7));
    benchmark::DoNotOptimize(f.data.centroidal_bias[0]);
  }
}
BENCHMARK(BM_AllTerms_CrbaRneaCmm);

void BM_EightContactJacobiansAndBias(benchmark::State& st) {
  auto& f = fixture();
  static dynamics::FrameJacobian j;
  dynamics::forward_kinematics(f.robot, f.data, f.q[0]);
  dynamics::forward_velocities(f.robot, f.data, f.v[0]);
  for (auto _ : st) {
    dynamics::bias_accelerations(f.robot, f.data);
    for (int c = 0; c < model::kNumContactPoints; ++c) {
      dynamics::frame_jacobian(f.robot, f.data, c, j);
      benchmark::DoNotOptimize(j(0, 0));
      benchmark::DoNotOptimize(dynamics::frame_bias_acceleration(f.robot, f.data, c));
    }
  }
}
BENCHMARK(BM_EightContactJacobiansAndBias);

// ---- Simbody computing the same quantities on the same robot ----
struct SimbodyFixture {
  sim::SimbodyRobot robot{fixture().robot, true};
  SimTK::State state;
  SimbodyFixture() {
    state = robot.system().getDefaultState();
    robot.set_state(state, fixture().q[0], fixture().v[0]);
    robot.system().realize(state, SimTK::Stage::Dynamics);
  }
};

SimbodyFixture& simbody() {
  static SimbodyFixture s;
  return s;
}

void BM_Simbody_MassMatrix(benchmark::State& st) {
  auto& s = simbody();
  SimTK::Matrix m;
  for (auto _ : st) {
    s.robot.matter().calcM(s.state, m);
    benchmark::DoNotOptimize(m(7, 7));
  }
}
BENCHMARK(BM_Simbody_MassMatrix);

void BM_Simbody_InverseDynamics(benchmark::State& st) {
  auto& s = simbody();
  const auto& gravity = s.robot.system().getRigidBodyForces(s.state, SimTK::Stage::Dynamics);
  const SimTK::Vector mobility(model::kNv, 0.0), udot(model::kNv, 0.1);
  SimTK::Vector residual;
  for (auto _ : st) {
    s.robot.matter().calcResidualForceIgnoringConstraints(s.state, mobility, gravity, udot, residual);
    benchmark::DoNotOptimize(residual[7]);
  }
}
BENCHMARK(BM_Simbody_InverseDynamics);

void BM_Simbody_CentralMomentum(benchmark::State& st) {
  auto& s = simbody();
  for (auto _ : st) {
    benchmark::DoNotOptimize(s.robot.matter().calcSystemCentralMomentum(s.state));
  }
}
BENCHMARK(BM_Simbody_CentralMomentum);

// Simbody has no centroidal momentum *matrix*; the equivalent is one momentum per unit speed.
void BM_Simbody_CentroidalMatrixByColumns(benchmark::State& st) {
  auto& s = simbody();
  SimTK::State probe = s.state;
  for (auto _ : st) {
    for (int k = 0; k < model::kNv; ++k) {
      probe.updU() = 0;
      probe.updU()[k] = 1;
      s.robot.system().realize(probe, SimTK::Stage::Velocity);
      benchmark::DoNotOptimize(s.robot.matter().calcSystemCentralMomentum(probe));
    }
  }
}
BENCHMARK(BM_Simbody_CentroidalMatrixByColumns);

void BM_Simbody_PositionKinematics(benchmark::State& st) {
  auto& s = simbody();
  SimTK::State probe = s.state;
  int i = 0;
  for (auto _ : st) {
    probe.updQ()[7] = 0.01 * (i++ & 7);  // invalidate the position stage
    s.robot.system().realize(probe, SimTK::Stage::Position);
    benchmark::DoNotOptimize(s.robot.body(6).getBodyTransform(probe).p()[2]);
  }
}
BENCHMARK(BM_Simbody_PositionKinematics);

}  // namespace

BENCHMARK_MAIN();
