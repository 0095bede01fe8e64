#include "drivers/emulator/cia402_emulator.h"

#include "drivers/canopen/pdo_layout.h"

namespace kuavo::drivers::emulator {

using namespace canopen;

namespace {

EmulatedDrive* find(Cia402Emulator& emu, std::uint8_t node) {
  for (int i = 0; i < emu.count; ++i)
    if (emu.drives[i].config.node_id == node) return &emu.drives[i];
  return nullptr;
}

// True when the frame went out.
bool send(Cia402Emulator& emu, CanPort& port, const EmulatedDrive& d, const can_frame& f) {
  if (d.silent || roll(emu.faults, emu.faults.drop_probability)) {
    ++emu.frames_dropped;
    return false;
  }
  if (send_rt(port, f) != DriverError::kOk) return false;
  ++emu.frames_out;
  return true;
}

void send_heartbeat(Cia402Emulator& emu, CanPort& port, const EmulatedDrive& d) {
  can_frame f{};
  f.can_id = kCobHeartbeat + d.config.node_id;
  f.len = 1;
  f.data[0] = static_cast<std::uint8_t>(d.nmt);
  send(emu, port, d, f);
}

std::uint16_t statusword(Cia402State s) {
  switch (s) {
    case Cia402State::kNotReadyToSwitchOn: return 0x0000;
    case Cia402State::kSwitchOnDisabled: return 0x0250;
    case Cia402State::kReadyToSwitchOn: return 0x0231;
    case Cia402State::kSwitchedOn: return 0x0233;
    case Cia402State::kOperationEnabled: return 0x0237;
    case Cia402State::kQuickStopActive: return 0x0217;
    case Cia402State::kFaultReactionActive: return 0x021F;
    case Cia402State::kFault: return 0x0218;
  }
  return 0;
}

// CiA 402 device transitions for the controlword commands the master uses.
void apply_controlword(EmulatedDrive& d, std::uint16_t cw) {
  const bool reset_edge = (cw & 0x80) && !d.last_reset_bit;
  d.last_reset_bit = (cw & 0x80) != 0;
  if (d.power == Cia402State::kFault) {
    if (reset_edge) {
      d.power = Cia402State::kSwitchOnDisabled;
      d.error_code = 0;
    }
    return;
  }
  if ((cw & 0x02) == 0) {  // disable voltage
    d.power = Cia402State::kSwitchOnDisabled;
    return;
  }
  if ((cw & 0x04) == 0) {  // quick stop
    if (d.power == Cia402State::kOperationEnabled) d.power = Cia402State::kQuickStopActive;
    else d.power = Cia402State::kSwitchOnDisabled;
    return;
  }
  switch (cw & 0x0F) {
    case 0x06: d.power = Cia402State::kReadyToSwitchOn; break;
    case 0x07:
      if (d.power == Cia402State::kReadyToSwitchOn || d.power == Cia402State::kOperationEnabled)
        d.power = Cia402State::kSwitchedOn;
      break;
    case 0x0F:
      if (d.power == Cia402State::kSwitchedOn || d.power == Cia402State::kOperationEnabled)
        d.power = Cia402State::kOperationEnabled;
      break;
    default: break;
  }
}

void handle_sdo(Cia402Emulator& emu, CanPort& port, EmulatedDrive& d, const can_frame& f) {
  const std::uint16_t index = get_u16(&f.data[1]);
  const std::uint8_t sub = f.data[3];
  const std::uint32_t value = get_u32(&f.data[4]);
  can_frame r{};
  r.can_id = kCobSdoServerToClient + d.config.node_id;
  r.len = 8;
  put_u16(&r.data[1], index);
  r.data[3] = sub;
  const bool download = (f.data[0] & 0xE0) == 0x20;
  const bool known = (index >= 0x1400 && index <= 0x1403) || (index >= 0x1600 && index <= 0x1603) ||
                     (index >= 0x1800 && index <= 0x1803) || (index >= 0x1A00 && index <= 0x1A03) ||
                     index == 0x6060 || index == 0x1017 || index == 0x1006 ||
                     (index == kObjPositionLoopGains && (sub == 1 || sub == 2));
  if (!download || !known || d.nmt != NmtState::kPreOperational) {
    r.data[0] = 0x80;
    put_u32(&r.data[4], download && known ? 0x08000022u   // not in this device state
                                          : 0x06020000u);  // object does not exist
    send(emu, port, d, r);
    return;
  }
  ++d.sdo_writes;
  // A PDO counts as mapped once its COB-ID is written valid after remapping.
  const bool valid_cob = sub == 1 && (value & 0x80000000u) == 0;
  if (index == 0x1400) d.rpdo1_mapped = valid_cob;
  if (index == 0x1800) d.tpdo1_mapped = valid_cob;
  if (index == 0x1801) d.tpdo2_mapped = valid_cob;
  if (index == 0x1017) d.heartbeat_period_ms = static_cast<std::uint16_t>(value);
  if (index == 0x6060) d.mode = static_cast<std::int8_t>(value);
  if (index == 0x1600 && sub == 2) d.rpdo1_torque_object = static_cast<std::uint16_t>(value >> 16);
  if (index == kObjPositionLoopGains) (sub == 1 ? d.kp_register : d.kd_register) = value;
  r.data[0] = 0x60;
  send(emu, port, d, r);
}

void send_tpdos(Cia402Emulator& emu, CanPort& port, EmulatedDrive& d) {
  if (d.nmt != NmtState::kOperational) return;
  const DriveConfig& c = d.config;
  if (d.tpdo1_mapped) {
    can_frame f{};
    f.can_id = kCobTpdo1 + c.node_id;
    f.len = 8;
    put_u16(&f.data[0], statusword(d.power));
    bool clamped = false;
    DriveConfig unlimited = c;
    unlimited.torque_limit_Nm = 1e9;
    put_u16(&f.data[2], static_cast<std::uint16_t>(torque_to_permille(unlimited, drive_torque_Nm(d), clamped)));
    put_u32(&f.data[4], static_cast<std::uint32_t>(rad_to_counts(c, d.position_rad)));
    if (send(emu, port, d, f)) {
      d.reported_position_rad = {counts_to_rad(c, rad_to_counts(c, d.position_rad)), d.reported_position_rad[0]};
    }
  }
  if (d.tpdo2_mapped) {
    can_frame f{};
    f.can_id = kCobTpdo2 + c.node_id;
    f.len = 7;
    put_u32(&f.data[0], static_cast<std::uint32_t>(rad_to_counts(c, d.velocity_rad_s)));
    put_u16(&f.data[4], d.error_code);
    f.data[6] = static_cast<std::uint8_t>(d.mode);
    if (send(emu, port, d, f)) {
      d.reported_velocity_rad_s = {counts_to_rad(c, rad_to_counts(c, d.velocity_rad_s)), d.reported_velocity_rad_s[0]};
    }
  }
}

void boot(Cia402Emulator& emu, CanPort& port, EmulatedDrive& d, hal::TimeNs now_ns) {
  // Reset communication: PDO mapping back to (our) defaults = unmapped.
  d.rpdo1_mapped = d.tpdo1_mapped = d.tpdo2_mapped = false;
  d.heartbeat_period_ms = 0;
  d.target_torque_permille = 0;
  d.target_position_counts = 0;
  d.rpdo1_torque_object = 0;
  d.kp_register = d.kd_register = 0;
  d.power = d.power == Cia402State::kFault ? Cia402State::kFault : Cia402State::kSwitchOnDisabled;
  d.nmt = NmtState::kBootUp;
  send_heartbeat(emu, port, d);  // boot-up message
  d.nmt = NmtState::kPreOperational;
  d.next_heartbeat_ns = now_ns;
}

}  // namespace

void add_drive(Cia402Emulator& emu, const DriveConfig& config) {
  if (emu.count >= kMaxEmulatedDrives) return;
  EmulatedDrive d;
  d.config = config;
  emu.drives[emu.count++] = d;
}

double drive_torque_at_Nm(const EmulatedDrive& d, double position_rad, double velocity_rad_s, bool* saturated) {
  if (saturated != nullptr) *saturated = false;
  if (d.power != Cia402State::kOperationEnabled || d.nmt != NmtState::kOperational) return 0.0;
  const double field_Nm = d.target_torque_permille * d.config.rated_torque_Nm / 1000.0;
  if (d.mode == kModeCyclicSyncTorque) return d.rpdo1_torque_object == kObjTargetTorque ? field_Nm : 0.0;
  if (d.mode != kModeCyclicSyncPosition) return 0.0;
  const double offset_Nm = d.rpdo1_torque_object == kObjTorqueOffset ? field_Nm : 0.0;
  const double target_rad = counts_to_rad(d.config, d.target_position_counts);
  const double tau = register_to_gain(d.kp_register) * (target_rad - position_rad) -
                     register_to_gain(d.kd_register) * velocity_rad_s + offset_Nm;
  const double lim = d.config.torque_limit_Nm;
  if (tau > lim || tau < -lim) {
    if (saturated != nullptr) *saturated = true;
    return tau > lim ? lim : -lim;
  }
  return tau;
}

double drive_torque_Nm(const EmulatedDrive& d) { return drive_torque_at_Nm(d, d.position_rad, d.velocity_rad_s); }

bool set_drive_silent(Cia402Emulator& emu, std::uint8_t node, bool silent) {
  EmulatedDrive* d = find(emu, node);
  if (!emu.faults.armed || d == nullptr) return false;
  d->silent = silent;
  return true;
}

bool inject_drive_fault(Cia402Emulator& emu, std::uint8_t node, std::uint16_t error_code) {
  EmulatedDrive* d = find(emu, node);
  if (!emu.faults.armed || d == nullptr) return false;
  d->power = Cia402State::kFault;
  d->error_code = error_code;
  return true;
}

int serve_rt(Cia402Emulator& emu, CanPort& port, hal::TimeNs now_ns) {
  int handled = 0;
  RxFrame rx;
  can_frame f;
  while (receive_rt(port, rx) == DriverError::kOk) {
    ++handled;
    ++emu.frames_in;
    if (!as_classic(rx, f) || (f.can_id & ~CAN_SFF_MASK) != 0) continue;
    const std::uint32_t id = f.can_id & CAN_SFF_MASK;
    if (id == kCobNmt && f.len == 2) {
      for (int i = 0; i < emu.count; ++i) {
        EmulatedDrive& d = emu.drives[i];
        if (f.data[1] != 0 && f.data[1] != d.config.node_id) continue;
        switch (static_cast<NmtCommand>(f.data[0])) {
          case NmtCommand::kResetNode:
          case NmtCommand::kResetCommunication: boot(emu, port, d, now_ns); break;
          case NmtCommand::kStart: d.nmt = NmtState::kOperational; break;
          case NmtCommand::kStop: d.nmt = NmtState::kStopped; break;
          case NmtCommand::kEnterPreOperational: d.nmt = NmtState::kPreOperational; break;
        }
      }
    } else if (id == kCobSync && f.len == 0) {
      ++emu.syncs;
      for (int i = 0; i < emu.count; ++i) send_tpdos(emu, port, emu.drives[i]);
    } else if (id > kCobSdoClientToServer && id <= kCobSdoClientToServer + 0x7F && f.len == 8) {
      if (EmulatedDrive* d = find(emu, static_cast<std::uint8_t>(id - kCobSdoClientToServer))) handle_sdo(emu, port, *d, f);
    } else if (id > kCobRpdo1 && id <= kCobRpdo1 + 0x7F && f.len == 8) {
      EmulatedDrive* d = find(emu, static_cast<std::uint8_t>(id - kCobRpdo1));
      RxPdo1 pdo;
      if (d != nullptr && d->rpdo1_mapped && d->nmt == NmtState::kOperational &&
          decode_rpdo1_rt(f, d->config.node_id, pdo) == DriverError::kOk) {
        apply_controlword(*d, pdo.controlword);
        d->target_torque_permille = pdo.target_torque_permille;
        d->target_position_counts = pdo.target_position_counts;
      }
    }
  }
  for (int i = 0; i < emu.count; ++i) {
    EmulatedDrive& d = emu.drives[i];
    if (d.heartbeat_period_ms == 0 || d.nmt == NmtState::kUnknown) continue;
    if (now_ns >= d.next_heartbeat_ns) {
      send_heartbeat(emu, port, d);
      d.next_heartbeat_ns = now_ns + static_cast<hal::TimeNs>(d.heartbeat_period_ms) * 1'000'000;
    }
  }
  return handled;
}

}  // namespace kuavo::drivers::emulator
