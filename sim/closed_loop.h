// The deterministic closed loop on the desktop: a plant (Simbody, or MuJoCo on Leju's
// MJCF: RunConfig::engine), sensor model and a controller, stepped in lockstep virtual time (rtos_shim's scheduler). Writes
// a CSV log (one row per control tick) and returns a summary. Same inputs, same
// binary: byte-identical log. Only the real-time factor reads a clock (rtos_shim).
#pragma once

#include <cstdint>
#include <string>

#include "controllers/model/model.h"
#include "drivers/transmission/ankle_motors.h"
#include "sim/plant.h"

namespace kuavo::sim {

// Which simulator runs the robot: our Simbody plant (sim/plant.h: our tables, our contact
// model) or MuJoCo (sim/mujoco_plant.h: Leju's MJCF, MuJoCo's contact). The controller,
// the HAL, the drive law and the sensor model are the same for both.
enum class Engine : std::uint8_t { kSimbody = 0, kMujoco = 1 };
bool parse_engine(const char* text, Engine& out);  // "simbody" | "mujoco"
const char* to_string(Engine e);

// The longest run the command lines accept (kuavo simulate, kuavo_fw_sim, campaign specs): the
// longest motion the controller holds is 310 s (planner::kMaxMotionFrames at 100 Hz) plus
// settling; 600 s bounds a run's per-tick statistics (~300 k WBC ticks, a few MB) and its log.
inline constexpr double kMaxRunDuration_s = 600.0;

struct RunConfig {
  double duration_s = 10.0;
  GroundParams ground = kFloor;
  Push push{};                 // duration 0: no push
  std::uint64_t seed = 1;
  std::string log_path;        // empty: no CSV file (the hash is still computed)
  int command_latency_ticks = 0;  // commands reach the drives this many control ticks late
  Engine engine = Engine::kSimbody;
  Integrator integrator = Integrator::kCvodeBdf;  // the Simbody engine's
  double relative_tolerance = PlantConfig{}.relative_tolerance;
  // The plant's ankle pairs clip per motor through the linkage, and the online stack bounds
  // the motors (sim/motor_model.h, drivers/transmission/ankle_motors.h); false: each ankle
  // joint clips at its own peak and the stack bounds joint torques only.
  bool ankle_motors = true;
};

struct RunSummary {
  bool ok = true;              // false: the simulation itself failed (see error)
  std::string error;
  Engine engine = Engine::kSimbody;
  bool fell = false;           // torso below 0.5 m or tilted beyond 45°
  double fell_at_s = -1.0;
  double sim_time_s = 0.0;
  double real_time_factor = 0.0;
  double max_tilt_deg = 0.0;
  double min_base_height_m = 0.0;
  double max_foot_sink_m = 0.0;  // deepest sole-corner penetration
  std::uint64_t torque_saturations = 0;
  std::uint64_t control_ticks = 0;
  double plant_evaluations_per_tick = 0.0;  // forward-dynamics calls per 2 ms (Simbody's or MuJoCo's)
  double plant_steps_per_tick = 0.0;        // integrator steps per 2 ms (CVODE's or MuJoCo's)
  std::string log_sha256;
};

// Fall criteria of the issue: torso below 0.5 m or tilted beyond 45°.
inline constexpr double kFallHeight_m = 0.5;
inline constexpr double kFallTilt_deg = 45.0;
inline constexpr double kControlPeriod_s = 0.002;  // 500 Hz

// Shared by the closed loops. After each plant step: tilt, height, sink, fall.
void record_plant_state(const PlantTruth& truth, double time_s, RunSummary& s);
// After the loop: time, real-time factor (wall_s from rtos_shim), plant counters, log hash.
// PlantT: Plant or MujocoPlant.
template <class PlantT>
void finish_run_summary(const PlantT& plant, double wall_s, const std::string& log_sha256, RunSummary& s) {
  s.sim_time_s = plant.time_s();
  s.real_time_factor = wall_s > 0.0 ? s.sim_time_s / wall_s : 0.0;
  s.torque_saturations = plant.torque_saturations();
  if (s.control_ticks > 0) {
    s.plant_evaluations_per_tick = static_cast<double>(plant.derivative_evaluations()) / s.control_ticks;
    s.plant_steps_per_tick = static_cast<double>(plant.integrator_stats().steps) / s.control_ticks;
  }
  s.log_sha256 = log_sha256;
}

// RunConfig::ankle_motors: the default drivers configuration's ankle motors (their clamps and
// the leg transmissions), or inactive.
drivers::AnkleMotors run_ankle_motors(const model::Model& model, const RunConfig& config);

// Stands the robot in the standing pose under the standing controller.
RunSummary run_standing(const model::Model& model, const RunConfig& config);

// Summary as the JSON the CLI writes.
std::string summary_json(const RunSummary& s);

}  // namespace kuavo::sim
