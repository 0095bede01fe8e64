// The deterministic closed loop on the desktop: Simbody plant, sensor model and
// a controller, stepped in lockstep virtual time (rtos_shim's scheduler). Writes
// a CSV log (one row per control tick) and returns a summary. Same inputs, same
// binary: byte-identical log. Only the real-time factor reads a clock (rtos_shim).
#pragma once

#include <cstdint>
#include <string>

#include "controllers/model/model.h"
#include "sim/plant.h"

namespace kuavo::sim {

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
  Integrator integrator = Integrator::kCvodeBdf;
  double relative_tolerance = PlantConfig{}.relative_tolerance;
};

struct RunSummary {
  bool ok = true;              // false: the simulation itself failed (see error)
  std::string error;
  bool fell = false;           // torso below 0.5 m or tilted beyond 45°
  double fell_at_s = -1.0;
  double sim_time_s = 0.0;
  double real_time_factor = 0.0;
  double max_tilt_deg = 0.0;
  double min_base_height_m = 0.0;
  double max_foot_sink_m = 0.0;  // deepest sole-corner penetration
  std::uint64_t torque_saturations = 0;
  std::uint64_t control_ticks = 0;
  double plant_evaluations_per_tick = 0.0;  // Simbody forward-dynamics calls per 2 ms
  double plant_steps_per_tick = 0.0;        // CVODE steps per 2 ms
  std::string log_sha256;
};

// Fall criteria of the issue: torso below 0.5 m or tilted beyond 45°.
inline constexpr double kFallHeight_m = 0.5;
inline constexpr double kFallTilt_deg = 45.0;
inline constexpr double kControlPeriod_s = 0.002;  // 500 Hz

// Shared by the closed loops. After each plant step: tilt, height, sink, fall.
void record_plant_state(const PlantTruth& truth, double time_s, RunSummary& s);
// After the loop: time, real-time factor (wall_s from rtos_shim), plant counters, log hash.
void finish_run_summary(const Plant& plant, double wall_s, const std::string& log_sha256, RunSummary& s);

// Stands the robot in the standing pose under the standing controller.
RunSummary run_standing(const model::Model& model, const RunConfig& config);

// Summary as the JSON the CLI writes.
std::string summary_json(const RunSummary& s);

}  // namespace kuavo::sim
