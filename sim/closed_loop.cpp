#include "sim/closed_loop.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <type_traits>
#include <memory>
#include <vector>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/standing/standing_controller.h"
#include "drivers/config/drivers_config.h"
#include "rtos_shim/clock.h"
#include "rtos_shim/lockstep_scheduler.h"
#include "sim/mujoco_plant.h"
#include "sim/sensor_model.h"
#include "sim/run_log.h"

namespace kuavo::sim {
namespace {

using Log = RunLog;

void write_header(const model::Model& model, Log& log) {
  std::string h = "time_s,base_x_m,base_y_m,base_z_m,base_qx,base_qy,base_qz,base_qw";
  for (int j = 0; j < model::kNumJoints; ++j) h += std::string(",q_") + model::joint_name(model, j);
  for (int j = 0; j < model::kNumJoints; ++j) h += std::string(",tau_") + model::joint_name(model, j);
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    for (const char* a : {"x", "y", "z"}) h += std::string(",f_") + model::frame_name(model, c) + "_" + a;
  }
  h += "\n";
  log.write(h.data(), h.size());
}

void write_row(double t, const PlantTruth& truth, Log& log) {
  char buf[8192];
  int n = std::snprintf(buf, sizeof buf, "%.3f", t);
  for (int i = 0; i < 7; ++i) n += std::snprintf(buf + n, sizeof buf - n, ",%.9g", truth.q[i]);
  for (int j = 0; j < model::kNumJoints; ++j) n += std::snprintf(buf + n, sizeof buf - n, ",%.9g", truth.q[7 + j]);
  for (int j = 0; j < model::kNumJoints; ++j) n += std::snprintf(buf + n, sizeof buf - n, ",%.6g", truth.joint_torque_Nm[j]);
  for (const auto& f : truth.contact_force_N) n += std::snprintf(buf + n, sizeof buf - n, ",%.6g,%.6g,%.6g", f.x(), f.y(), f.z());
  buf[n++] = '\n';
  log.write(buf, static_cast<std::size_t>(n));
}

// The loop over either plant (Plant, MujocoPlant): same controller, sensors and log.
template <class PlantT>
RunSummary standing_loop(const model::Model& model, const RunConfig& config, PlantT& plant) {
  RunSummary out;
  out.engine = config.engine;
  // Controller state in one block allocated before the loop (static in the firmware).
  auto controller = std::make_unique<control::StandingState>();
  control::standing_init(model, control::StandingConfig{}, *controller);

  dynamics::ConfigVector q0 = dynamics::neutral_configuration(model);
  q0.tail<model::kNumJoints>() = controller->pose_rad;
  control::place_on_ground(model, controller->data, q0);
  if constexpr (std::is_same_v<PlantT, MujocoPlant>) {
    reset_on_floor(plant, q0);
  } else {
    plant.reset(q0, dynamics::VelocityVector::Zero());
  }
  plant.set_push(config.push);

  SensorModel sensors(config.seed);
  Log log(config.log_path);
  if (log.failed_to_open(config.log_path)) {
    out.ok = false;
    out.error = "cannot write log '" + config.log_path + "'";
    return out;
  }
  write_header(model, log);

  rtos::LockstepConfig sched_cfg;
  sched_cfg.control_period_ns = static_cast<rtos::TimeNs>(kControlPeriod_s * 1e9);
  sched_cfg.plan_period_ns = 0;
  sched_cfg.stop_ns = static_cast<rtos::TimeNs>(std::llround(config.duration_s * 1e9));
  rtos::LockstepScheduler sched;
  if (const auto err = sched.reset(sched_cfg); err != rtos::LockstepError::kOk) {
    out.ok = false;
    out.error = rtos::describe(err);
    return out;
  }

  // Commands in flight to the drives (latency model).
  std::vector<hal::CommandFrame> in_flight(static_cast<std::size_t>(std::max(0, config.command_latency_ticks)) + 1);
  hal::SensorFrame frame;
  hal::CommandFrame command;
  // Until the first tick the drives hold the pose passively.
  control::standing_step_rt(model, *controller, (sensors.sample(plant.truth(), 0, frame), frame), command);
  for (auto& c : in_flight) c = command;
  std::size_t slot = 0;

  out.min_base_height_m = plant.truth().q[2];
  const rtos::TimeNs wall_start = rtos::now_ns();
  rtos::SimEvent ev;
  while (sched.next(ev)) {
    if (ev.kind == rtos::SimEventKind::kControlTick) {
      sensors.sample(plant.truth(), ev.time_ns, frame);
      control::standing_step_rt(model, *controller, frame, command);
      in_flight[slot] = command;
      slot = (slot + 1) % in_flight.size();
      plant.set_command(in_flight[slot]);  // the oldest command reaches the drives now
      ++out.control_ticks;
    } else if (ev.kind == rtos::SimEventKind::kPlantStep) {
      const PlantError err = plant.advance(static_cast<double>(ev.dt_ns) * 1e-9);
      if (err != PlantError::kOk) {
        out.ok = false;
        out.error = plant.last_error();
        break;
      }
      const PlantTruth& t = plant.truth();
      write_row(static_cast<double>(ev.time_ns + ev.dt_ns) * 1e-9, t, log);
      record_plant_state(t, plant.time_s(), out);
      if (out.fell && plant.time_s() > out.fell_at_s + 0.5) break;  // nothing left to learn
    }
  }
  finish_run_summary(plant, static_cast<double>(rtos::now_ns() - wall_start) * 1e-9, log.digest(), out);
  return out;
}

}  // namespace

bool parse_engine(const char* text, Engine& out) {
  if (text == nullptr) return false;
  if (!std::strcmp(text, "simbody")) out = Engine::kSimbody;
  else if (!std::strcmp(text, "mujoco")) out = Engine::kMujoco;
  else return false;
  return true;
}

const char* to_string(Engine e) { return e == Engine::kMujoco ? "mujoco" : "simbody"; }

drivers::AnkleMotors run_ankle_motors(const model::Model& model, const RunConfig& config) {
  return config.ankle_motors ? drivers::ankle_motors_from_config(drivers::default_drivers_config(model))
                             : drivers::AnkleMotors{};
}

RunSummary run_standing(const model::Model& model, const RunConfig& config) {
  const drivers::AnkleMotors ankle_motors = run_ankle_motors(model, config);
  const drivers::AnkleMotors* plant_ankles = ankle_motors.active ? &ankle_motors : nullptr;
  if (config.engine == Engine::kMujoco) {
    MujocoPlantConfig plant_cfg;
    plant_cfg.ground = config.ground;
    plant_cfg.ankle_motors = plant_ankles;
    MujocoPlant plant(model, plant_cfg);
    if (!plant.ok()) {
      RunSummary out;
      out.engine = config.engine;
      out.ok = false;
      out.error = plant.last_error();
      return out;
    }
    return standing_loop(model, config, plant);
  }
  PlantConfig plant_cfg;
  plant_cfg.ground = config.ground;
  plant_cfg.integrator = config.integrator;
  plant_cfg.relative_tolerance = config.relative_tolerance;
  plant_cfg.absolute_tolerance = 0.1 * config.relative_tolerance;
  plant_cfg.ankle_motors = plant_ankles;
  Plant plant(model, plant_cfg);
  return standing_loop(model, config, plant);
}

void record_plant_state(const PlantTruth& t, double time_s, RunSummary& s) {
  const double tilt = tilt_deg(t.q);
  s.max_tilt_deg = std::max(s.max_tilt_deg, tilt);
  s.min_base_height_m = std::min(s.min_base_height_m, t.q[2]);
  for (const Vec3& p : t.contact_point_m) s.max_foot_sink_m = std::max(s.max_foot_sink_m, -p.z());
  if (!s.fell && (t.q[2] < kFallHeight_m || tilt > kFallTilt_deg)) {
    s.fell = true;
    s.fell_at_s = time_s;
  }
}

std::string summary_json(const RunSummary& s) {
  char buf[1024];
  std::snprintf(buf, sizeof buf,
                "{\n  \"ok\": %s,\n  \"error\": \"%s\",\n  \"engine\": \"%s\",\n  \"fell\": %s,\n  \"fell_at_s\": %.3f,\n"
                "  \"sim_time_s\": %.3f,\n  \"real_time_factor\": %.3f,\n  \"max_tilt_deg\": %.4f,\n"
                "  \"min_base_height_m\": %.4f,\n  \"max_foot_sink_m\": %.4f,\n  \"torque_saturations\": %llu,\n  \"control_ticks\": %llu,\n"
                "  \"plant_evaluations_per_tick\": %.2f,\n  \"plant_steps_per_tick\": %.2f,\n"
                "  \"log_sha256\": \"%s\"\n}\n",
                s.ok ? "true" : "false", s.error.c_str(), to_string(s.engine), s.fell ? "true" : "false", s.fell_at_s, s.sim_time_s,
                s.real_time_factor, s.max_tilt_deg, s.min_base_height_m, s.max_foot_sink_m,
                static_cast<unsigned long long>(s.torque_saturations),
                static_cast<unsigned long long>(s.control_ticks), s.plant_evaluations_per_tick, s.plant_steps_per_tick,
                s.log_sha256.c_str());
  return buf;
}

}  // namespace kuavo::sim
