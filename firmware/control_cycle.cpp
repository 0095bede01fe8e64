#include "firmware/control_cycle.h"

#include <algorithm>

namespace kuavo::firmware {

namespace {

// Status records every second at 500 Hz: enough to follow a run, few enough
// that the ring never fills.
constexpr std::uint64_t kStatusEveryCycles = 500;

void log_fault(Firmware& fw, Fault f, int joint, hal::TimeNs now_ns) {
  if (fw.log != nullptr) log_rt(*fw.log, LogRecord{now_ns, LogKind::kFault, fw.mode.mode, f, static_cast<std::int16_t>(joint), 0.0});
}

void log_mode(Firmware& fw, hal::TimeNs now_ns) {
  if (fw.log != nullptr) log_rt(*fw.log, LogRecord{now_ns, LogKind::kModeChange, fw.mode.mode, fw.mode.latched, -1, 0.0});
}

// Fraction of the controller's gains applied in ramped modes.
double ramp(const Firmware& fw, hal::TimeNs now_ns) {
  const double in_mode = static_cast<double>(now_ns - fw.mode.since_ns);
  switch (fw.mode.mode) {
    case Mode::kStandUp: return std::clamp(in_mode / static_cast<double>(fw.config.stand_up_duration_ns), 0.0, 1.0);
    case Mode::kFinish: return std::clamp(1.0 - in_mode / static_cast<double>(fw.config.finish_duration_ns), 0.0, 1.0);
    default: return 1.0;
  }
}

// A refused command: latch, log, and send damping in its place.
void refuse(Firmware& fw, hal::TimeNs now_ns, hal::CommandFrame& out) {
  const Fault latched_before = fw.mode.latched;
  latch_fault_rt(fw.mode, fw.last_filter.fault, now_ns);
  if (latched_before == Fault::kNone) log_fault(fw, fw.last_filter.fault, fw.last_filter.joint, now_ns);
  log_mode(fw, now_ns);
  damping_command_rt(fw.config, now_ns, out);
}

}  // namespace

void firmware_init(Firmware& fw, const model::Model& model, const FirmwareConfig& config, LogSink* log) {
  fw.model = &model;
  fw.config = config;
  fw.mode = ModeState{};
  fw.log = log;
  control::StandingConfig standing{};
  standing.dt_s = static_cast<double>(config.control_period_ns) * 1e-9;
  control::standing_init(model, standing, fw.standing);
}

bool cycle_begin_rt(Firmware& fw, const hal::SensorFrame& sensors, const CycleInputs& in, hal::TimeNs now_ns) noexcept {
  ++fw.cycles;
  fw.now_ns = now_ns;
  ModeInputs mi;
  mi.estop = in.estop;
  mi.request = in.request;
  mi.dance_done = in.dance_done;
  // Watchdogs guard damping too: a fault seen there latches and blocks stand-up.
  const Mode before = fw.mode.mode;
  if (before != Mode::kBoot && before != Mode::kSelfCheck) {
    fw.last_watchdog = check_watchdogs_rt(fw.config, sensors, in.watch, now_ns);
    if (fw.last_watchdog.fault == Fault::kNone) fw.last_watchdog = check_samples_plausible_rt(*fw.model, sensors);
    mi.fault = fw.last_watchdog.fault;
    fw.max_tilt_rad = std::max(fw.max_tilt_rad, tilt_rad(sensors.imu));
  }
  if (before == Mode::kSelfCheck) mi.self_check_passed = self_check_passed_rt(fw.config, sensors, in.watch.bus, now_ns);
  const Fault latched_before = fw.mode.latched;
  const bool changed = step_mode_rt(fw.mode, mi, now_ns, fw.config.self_check_timeout_ns,
                                    fw.config.stand_up_duration_ns, fw.config.finish_duration_ns);
  if (latched_before == Fault::kNone && fw.mode.latched != Fault::kNone) {
    log_fault(fw, fw.mode.latched, fw.mode.latched == mi.fault ? fw.last_watchdog.joint : -1, now_ns);
  }
  if (changed) {
    log_mode(fw, now_ns);
    if (fw.mode.mode == Mode::kStandUp) {
      // From where the joints are, inside their stops: a joint resting on a stop may read a
      // little past it (encoder quantum, the stop's give), and the ramp's reference must not.
      for (int j = 0; j < model::kNumJoints; ++j) {
        fw.ramp_from_rad[j] = std::clamp(sensors.joints[j].position_rad, fw.model->limits.position_min_rad[j],
                                         fw.model->limits.position_max_rad[j]);
      }
      fw.standing.filter_started = false;  // no velocity history across a damping phase
    }
  }
  if (fw.cycles % kStatusEveryCycles == 0 && fw.log != nullptr) {
    log_rt(*fw.log, LogRecord{now_ns, LogKind::kStatus, fw.mode.mode, fw.mode.latched, -1, fw.max_tilt_rad});
    fw.max_tilt_rad = 0.0;
  }
  return is_active(fw.mode.mode);
}

void cycle_end_rt(Firmware& fw, const hal::SensorFrame& sensors, bool controller_ran, hal::TimeNs now_ns,
                  hal::CommandFrame& out) noexcept {
  (void)sensors;
  if (!controller_ran) {
    if (fw.mode.mode == Mode::kBoot || fw.mode.mode == Mode::kSelfCheck) {
      disabled_command_rt(now_ns, out);
    } else {
      damping_command_rt(fw.config, now_ns, out);
    }
    return;
  }
  // The controller's own output is checked before the ramp: scaling by a
  // small ramp factor must not turn a bad command (kp < 0) into a passing one.
  fw.last_filter = check_command_rt(*fw.model, fw.config, fw.controller_command);
  if (fw.last_filter.fault != Fault::kNone) {
    refuse(fw, now_ns, out);
    return;
  }
  const double a = ramp(fw, now_ns);
  const bool standing_up = fw.mode.mode == Mode::kStandUp;
  const double kd_floor = fw.config.damping_kd_Nm_s_per_rad;
  for (int j = 0; j < model::kNumJoints; ++j) {
    hal::JointCommand c = fw.controller_command.joints[j];
    if (a < 1.0 && c.mode == hal::JointMode::kPdTorque) {
      // Standing up, the reference moves from where the joints were to the
      // controller's; finishing, it stays and only the gains fade. The damping
      // gain stays as a floor so the ramp ends in (not below) damping.
      if (standing_up) c.position_ref_rad = fw.ramp_from_rad[j] + a * (c.position_ref_rad - fw.ramp_from_rad[j]);
      c.kp_Nm_per_rad *= a;
      c.kd_Nm_s_per_rad = c.kd_Nm_s_per_rad > kd_floor ? kd_floor + a * (c.kd_Nm_s_per_rad - kd_floor) : c.kd_Nm_s_per_rad;
      c.torque_ff_Nm *= a;
      c.velocity_ref_rad_s *= a;
    }
    out.joints[j] = c;
  }
  out.stamp_ns = now_ns;
  fw.last_filter = check_command_rt(*fw.model, fw.config, out);
  if (fw.last_filter.fault != Fault::kNone) refuse(fw, now_ns, out);
}

}  // namespace kuavo::firmware
