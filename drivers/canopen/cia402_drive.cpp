#include "drivers/canopen/cia402_drive.h"

#include <cmath>
#include <numbers>

namespace kuavo::drivers::canopen {

namespace {

void enter(DriveState& st, DrivePhase phase, hal::TimeNs now_ns) {
  st.phase = phase;
  st.phase_since_ns = now_ns;
}

void fail(DriveState& st, DriverError e, hal::TimeNs now_ns) {
  st.error = e;
  enter(st, DrivePhase::kFailed, now_ns);
}

}  // namespace

double counts_to_rad(const DriveConfig& cfg, double counts) {
  return counts * (2.0 * std::numbers::pi / cfg.counts_per_rev);
}

namespace {
double counts_of_rad(const DriveConfig& cfg, double rad) { return rad * cfg.counts_per_rev / (2.0 * std::numbers::pi); }
}  // namespace

std::int32_t rad_to_counts(const DriveConfig& cfg, double rad) {
  const double c = std::isfinite(rad) ? counts_of_rad(cfg, rad) : 0.0;
  const double lim = 2147483647.0;
  return static_cast<std::int32_t>(std::lround(c > lim ? lim : (c < -lim ? -lim : c)));
}

namespace {

// The i16 per-mille of the rated torque, saturated at its range (counted in `clamped`).
std::int16_t permille_field(const DriveConfig& cfg, double torque_Nm, bool& clamped) {
  double pm = std::round(torque_Nm / cfg.rated_torque_Nm * 1000.0);
  if (pm > 32767.0) pm = 32767.0, clamped = true;
  if (pm < -32767.0) pm = -32767.0, clamped = true;
  return static_cast<std::int16_t>(pm);
}

}  // namespace

std::int16_t torque_to_permille(const DriveConfig& cfg, double torque_Nm, bool& clamped) {
  clamped = false;
  double t = torque_Nm;
  if (!std::isfinite(t)) {
    t = 0.0;
    clamped = true;
  } else if (t > cfg.torque_limit_Nm) {
    t = cfg.torque_limit_Nm;
    clamped = true;
  } else if (t < -cfg.torque_limit_Nm) {
    t = -cfg.torque_limit_Nm;
    clamped = true;
  }
  return permille_field(cfg, t, clamped);
}

namespace {

// CSP: the torque offset (0x60B2) is not the motor's torque. The drive applies
// kp (target - position) - kd velocity + offset and clips that sum at its own limit; the
// firmware writes the offset so that the sum at the last sample is the torque it wants,
// so with the joint moving the offset exceeds the limit by kd velocity while the torque
// does not. What is clamped is therefore the drive's torque at that sample, at the limit,
// and the offset follows it. Without a sample yet, the offset itself is.
std::int16_t csp_offset_to_permille(const DriveConfig& cfg, const DriveState& st, const DriveCommand& cmd,
                                    bool& clamped) {
  if (!st.have_tpdo1 || !st.have_tpdo2) return torque_to_permille(cfg, cmd.torque_Nm, clamped);
  const double position = counts_to_rad(cfg, st.tpdo1.actual_position_counts);
  const double velocity = counts_to_rad(cfg, st.tpdo2.actual_velocity_counts_s);
  const double loop = cfg.csp_kp_Nm_per_rad * (cmd.position_rad - position) - cfg.csp_kd_Nm_s_per_rad * velocity;
  const double at_sample = cmd.torque_Nm + loop;
  const double lim = cfg.torque_limit_Nm;
  clamped = at_sample > lim || at_sample < -lim;
  const double offset = clamped ? (at_sample > lim ? lim : -lim) - loop : cmd.torque_Nm;
  return permille_field(cfg, offset, clamped);
}

}  // namespace

DriverError position_to_counts_rt(const DriveConfig& cfg, double rad, std::int32_t& counts) {
  const double c = counts_of_rad(cfg, rad);
  if (!(std::abs(c) <= 2147483647.0)) return DriverError::kCommandRefused;  // NaN fails too
  counts = static_cast<std::int32_t>(std::lround(c));
  return DriverError::kOk;
}

bool drive_loop(const DriveConfig& cfg, DriveLoop& out) {
  out = DriveLoop{};
  out.mode = cfg.mode;
  if (cfg.mode == kModeCyclicSyncTorque) return true;
  if (cfg.mode != kModeCyclicSyncPosition) return false;
  return gain_to_register(cfg.csp_kp_Nm_per_rad, out.kp_register) &&
         gain_to_register(cfg.csp_kd_Nm_s_per_rad, out.kd_register);
}

void start_drive(const DriveConfig& cfg, DriveState& st, hal::TimeNs now_ns, can_frame& out) {
  st = DriveState{};
  DriveLoop loop;
  if (!drive_loop(cfg, loop)) loop.kp_register = loop.kd_register = 0;  // refused at validation before
  st.config = pdo_config_sequence(cfg.node_id, cfg.heartbeat_period_ms, cfg.cycle_period_us, loop);
  enter(st, DrivePhase::kWaitBoot, now_ns);
  encode_nmt_rt(NmtCommand::kResetCommunication, cfg.node_id, out);
}

DriverError handle_frame_rt(const DriveConfig& cfg, DriveState& st, const can_frame& f,
                            hal::TimeNs stamp_ns) {
  const std::uint8_t node = cfg.node_id;
  if (decode_tpdo1_rt(f, node, st.tpdo1) == DriverError::kOk) {
    st.tpdo1_ns = stamp_ns;
    st.have_tpdo1 = true;
    st.power = decode_statusword(st.tpdo1.statusword);
    return DriverError::kOk;
  }
  if (decode_tpdo2_rt(f, node, st.tpdo2) == DriverError::kOk) {
    st.have_tpdo2 = true;
    return DriverError::kOk;
  }
  std::uint8_t hb_node = 0;
  NmtState nmt = NmtState::kUnknown;
  if (decode_heartbeat_rt(f, hb_node, nmt) == DriverError::kOk && hb_node == node) {
    st.nmt = nmt;
    st.heartbeat_ns = stamp_ns;
    if (nmt == NmtState::kBootUp && st.phase == DrivePhase::kWaitBoot) {
      enter(st, DrivePhase::kConfiguring, stamp_ns);
    } else if (nmt == NmtState::kBootUp && st.phase != DrivePhase::kIdle) {
      // An unexpected reboot loses the PDO mapping: never run on defaults.
      fail(st, DriverError::kUnexpectedNmtState, stamp_ns);
    }
    return DriverError::kOk;
  }
  Emergency em;
  if (decode_emergency_rt(f, em) == DriverError::kOk && em.node == node) {
    st.last_emergency = em;
    ++st.emergencies;
    return DriverError::kOk;
  }
  if (st.phase == DrivePhase::kConfiguring && st.sdo_pending) {
    std::uint32_t abort_code = 0;
    const DriverError e =
        decode_sdo_reply_rt(f, node, st.config.writes[st.config_step], abort_code);
    if (e == DriverError::kOk) {
      st.sdo_pending = false;
      st.sdo_attempts = 0;
      ++st.config_step;
      return DriverError::kOk;
    }
    if (e == DriverError::kSdoAbort) {
      st.last_abort_code = abort_code;
      st.sdo_pending = false;
      fail(st, DriverError::kSdoAbort, stamp_ns);
      return DriverError::kOk;
    }
  }
  return DriverError::kWrongCanId;
}

bool step_rt(const DriveConfig& cfg, DriveState& st, hal::TimeNs now_ns, const DriveCommand& cmd,
             can_frame& out) {
  switch (st.phase) {
    case DrivePhase::kIdle:
      return false;
    case DrivePhase::kFailed:
      if (!st.was_operational) return false;
      encode_rpdo1_rt(cfg.node_id, RxPdo1{controlword::kDisableVoltage, 0, 0}, out);
      return true;
    case DrivePhase::kWaitBoot:
      if (now_ns - st.phase_since_ns > kBootTimeout_ns) fail(st, DriverError::kBootTimeout, now_ns);
      return false;
    case DrivePhase::kConfiguring: {
      if (st.sdo_pending) {
        if (now_ns - st.sdo_sent_ns <= kSdoTimeout_ns) return false;
        if (st.sdo_attempts > kSdoRetries) {
          fail(st, DriverError::kSdoTimeout, now_ns);
          return false;
        }
      }
      if (st.config_step >= st.config.count) {
        enter(st, DrivePhase::kStarting, now_ns);
        encode_nmt_rt(NmtCommand::kStart, cfg.node_id, out);
        return true;
      }
      encode_sdo_download_rt(cfg.node_id, st.config.writes[st.config_step], out);
      st.sdo_pending = true;
      st.sdo_sent_ns = now_ns;
      ++st.sdo_attempts;
      return true;
    }
    case DrivePhase::kStarting:
      if (st.nmt == NmtState::kOperational) {
        enter(st, DrivePhase::kOperational, now_ns);
        st.was_operational = true;
        break;  // fall through to the cyclic frame below
      }
      if (now_ns - st.phase_since_ns > kStartTimeout_ns) {
        fail(st, DriverError::kUnexpectedNmtState, now_ns);
      }
      return false;
    case DrivePhase::kOperational:
      break;
  }

  // Operational: heartbeat consumer, then the cyclic RPDO1.
  if (now_ns - st.heartbeat_ns > cfg.heartbeat_timeout_ns) {
    fail(st, DriverError::kHeartbeatLost, now_ns);
    return step_rt(cfg, st, now_ns, cmd, out);  // the safe frame, this cycle
  }
  if (st.nmt != NmtState::kOperational) {
    fail(st, DriverError::kUnexpectedNmtState, now_ns);
    return step_rt(cfg, st, now_ns, cmd, out);
  }
  // Silent drive: the reference is the last TPDO1, or the entry to operational.
  const hal::TimeNs last_seen = st.have_tpdo1 && st.tpdo1_ns > st.phase_since_ns ? st.tpdo1_ns
                                                                                  : st.phase_since_ns;
  st.stale = now_ns - last_seen > cfg.tpdo_timeout_ns;
  if (st.stale) st.error = DriverError::kReplyTimeout;
  DriverError sm_error = DriverError::kOk;
  RxPdo1 pdo;
  pdo.controlword = next_controlword_rt(st.power, cmd.enable, st.control, sm_error);
  if (sm_error != DriverError::kOk) st.error = sm_error;
  if (cmd.enable) {
    if (st.enable_since_ns < 0) st.enable_since_ns = now_ns;
    if (st.power != Cia402State::kOperationEnabled &&
        now_ns - st.enable_since_ns > kEnableTimeout_ns) {
      st.error = DriverError::kEnableTimeout;
    }
  } else {
    st.enable_since_ns = -1;
  }
  if (st.power == Cia402State::kFault && st.error == DriverError::kOk) {
    st.error = DriverError::kDriveFault;
  }
  // Torque only once the drive is really enabled; otherwise 0.
  bool clamped = false;
  const bool torque_on = cmd.enable && st.power == Cia402State::kOperationEnabled;
  if (cfg.mode == kModeCyclicSyncPosition) {
    // Held (last reported position, no offset) unless torque is on and the target is good.
    pdo.target_position_counts = st.tpdo1.actual_position_counts;
    pdo.target_torque_permille = 0;
    if (torque_on) {
      std::int32_t counts = 0;
      if (position_to_counts_rt(cfg, cmd.position_rad, counts) != DriverError::kOk ||
          !std::isfinite(cmd.torque_Nm)) {
        ++st.refused_commands;
        st.error = DriverError::kCommandRefused;
      } else {
        pdo.target_position_counts = counts;
        pdo.target_torque_permille = csp_offset_to_permille(cfg, st, cmd, clamped);
        if (clamped) ++st.torque_clamps;
      }
    }
    encode_rpdo1_rt(cfg.node_id, pdo, out);
    return true;
  }
  pdo.target_torque_permille = torque_to_permille(cfg, torque_on ? cmd.torque_Nm : 0.0, clamped);
  if (clamped) ++st.torque_clamps;
  pdo.target_position_counts = rad_to_counts(cfg, cmd.position_rad);
  encode_rpdo1_rt(cfg.node_id, pdo, out);
  return true;
}

MotorSample motor_sample(const DriveConfig& cfg, const DriveState& st) {
  MotorSample s;
  s.position_rad = counts_to_rad(cfg, st.tpdo1.actual_position_counts);
  s.velocity_rad_s = counts_to_rad(cfg, st.tpdo2.actual_velocity_counts_s);
  s.torque_Nm = st.tpdo1.actual_torque_permille * cfg.rated_torque_Nm / 1000.0;
  s.stamp_ns = st.tpdo1_ns;
  s.valid = st.have_tpdo1 && st.have_tpdo2 && !st.stale && st.phase == DrivePhase::kOperational;
  return s;
}

}  // namespace kuavo::drivers::canopen
