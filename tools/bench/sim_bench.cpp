// The simulator's cost: one plant state derivative (ours beside Simbody's), and
// the standing closed loop per 2 ms control tick on each ground, with CVODE's
// counters. Run pinned: taskset -c 1 build/bench/sim_bench
#include <benchmark/benchmark.h>

#include <memory>
#include <vector>

#include "controllers/standing/standing_controller.h"
#include "sim/plant.h"
#include "sim/plant_dynamics.h"
#include "sim/sensor_model.h"
#include "sim/simbody_model.h"

namespace {

using namespace kuavo;

const model::Model& robot() {
  static model::Model m = [] {
    model::Model out;
    model::build_model(model::Variant::kS45, 55.0, out);
    return out;
  }();
  return m;
}

// The standing loop of sim/closed_loop.cpp without its log: controller, sensors, plant.
struct Loop {
  std::unique_ptr<control::StandingState> controller = std::make_unique<control::StandingState>();
  std::unique_ptr<sim::Plant> plant;
  sim::SensorModel sensors{1};
  hal::SensorFrame frame;
  hal::CommandFrame command;
  long tick = 0;

  explicit Loop(const sim::PlantConfig& cfg) {
    control::standing_init(robot(), control::StandingConfig{}, *controller);
    plant = std::make_unique<sim::Plant>(robot(), cfg);
    dynamics::ConfigVector q = dynamics::neutral_configuration(robot());
    q.tail<model::kNumJoints>() = controller->pose_rad;
    control::place_on_ground(robot(), controller->data, q);
    plant->reset(q, dynamics::VelocityVector::Zero());
  }
  bool step() {
    sensors.sample(plant->truth(), static_cast<hal::TimeNs>(tick) * 2'000'000, frame);
    control::standing_step_rt(robot(), *controller, frame, command);
    plant->set_command(command);
    ++tick;
    return plant->advance(0.002) == sim::PlantError::kOk;
  }
};

// One CVODE right-hand side: ours (plant_dynamics.h) beside Simbody's realize(Acceleration)
// of the same robot with gravity only (the plant's custom force adds ~10 % to Simbody's figure).
void derivative(benchmark::State& state, bool simbody) {
  sim::SimbodyRobot r(robot(), true);
  SimTK::State s = r.system().getDefaultState();
  dynamics::ConfigVector q = dynamics::neutral_configuration(robot());
  dynamics::VelocityVector v = dynamics::VelocityVector::Constant(0.1);
  q[2] -= 0.002;  // every corner touching
  r.set_state(s, q, v);
  sim::PlantDynamics dyn(robot(), sim::simbody_layout(r, s));
  sim::PlantForceInputs in;
  for (auto& j : in.command.joints) j = {hal::JointMode::kPdTorque, 0.0, 0.0, 0.0, 200.0, 5.0};
  std::vector<double> y(s.getNY()), ydot(s.getNY());
  for (int i = 0; i < s.getNY(); ++i) y[i] = s.getY()[i];
  Eigen::Matrix<double, 6, 1> wrench;
  for (auto _ : state) {
    if (simbody) {
      s.updY()[0] += 0.0;  // invalidates the cache as CVODE's new y does
      r.system().realize(s, SimTK::Stage::Acceleration);
      benchmark::DoNotOptimize(s.getYDot()[0]);
    } else {
      dyn.derivative(0.0, y.data(), in, ydot.data(), wrench);
      benchmark::DoNotOptimize(ydot[0]);
    }
  }
}
BENCHMARK_CAPTURE(derivative, ours, false);
BENCHMARK_CAPTURE(derivative, simbody_gravity_only, true);

void closed_loop(benchmark::State& state, const sim::GroundParams& ground, sim::DerivativeEngine engine) {
  sim::PlantConfig cfg;
  cfg.ground = ground;
  cfg.derivatives = engine;
  cfg.absolute_tolerance = 0.1 * cfg.relative_tolerance;  // as closed_loop.cpp sets it
  Loop loop(cfg);
  for (int k = 0; k < 500; ++k) loop.step();  // settle for 1 s first
  const auto e0 = loop.plant->derivative_evaluations();
  const auto s0 = loop.plant->integrator_stats();
  long ticks = 0;
  for (auto _ : state) {
    if (!loop.step()) state.SkipWithError(loop.plant->last_error());
    ++ticks;
  }
  const auto s1 = loop.plant->integrator_stats();
  const double n = static_cast<double>(ticks);
  state.counters["evals/tick"] = static_cast<double>(loop.plant->derivative_evaluations() - e0) / n;
  state.counters["steps/tick"] = static_cast<double>(s1.steps - s0.steps) / n;
  state.counters["jacs/tick"] = static_cast<double>(s1.jacobian_evaluations - s0.jacobian_evaluations) / n;
  state.counters["setups/tick"] = static_cast<double>(s1.linear_setups - s0.linear_setups) / n;
  state.counters["nl_iters/tick"] = static_cast<double>(s1.nonlinear_iterations - s0.nonlinear_iterations) / n;
  state.counters["nl_fails/tick"] = static_cast<double>(s1.nonlinear_failures - s0.nonlinear_failures) / n;
  state.counters["err_fails/tick"] = static_cast<double>(s1.error_test_failures - s0.error_test_failures) / n;
  state.counters["RTF"] = benchmark::Counter(0.002 * n, benchmark::Counter::kIsRate);
}

BENCHMARK_CAPTURE(closed_loop, floor, sim::kFloor, sim::DerivativeEngine::kRigidBody)->Iterations(2500)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(closed_loop, carpet, sim::kCarpet, sim::DerivativeEngine::kRigidBody)->Iterations(2500)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(closed_loop, floor_simbody_derivative, sim::kFloor, sim::DerivativeEngine::kSimbody)->Iterations(1000)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(closed_loop, carpet_simbody_derivative, sim::kCarpet, sim::DerivativeEngine::kSimbody)->Iterations(1000)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
