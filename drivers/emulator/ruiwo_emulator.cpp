#include "drivers/emulator/ruiwo_emulator.h"

namespace kuavo::drivers::emulator {

void init_ruiwo_emulator(RuiwoEmulator& emu, const std::uint8_t* ids, int count) {
  emu = RuiwoEmulator{};
  emu.index_of_id.fill(-1);
  for (int i = 0; i < count && i < kMaxEmulatedRuiwo; ++i) {
    emu.motors[i].id = ids[i];
    emu.index_of_id[ids[i]] = static_cast<std::int8_t>(i);
    emu.count = i + 1;
  }
}

double motor_torque_Nm(const EmulatedRuiwoMotor& m) {
  if (!m.enabled) return 0.0;
  const ruiwo::PtmCommand& c = m.command;
  const double p = m.position_rad - m.zero_rad;
  return c.kp_Nm_per_rad * (c.position_rad - p) + c.kd_Nm_s_per_rad * (c.velocity_rad_s - m.velocity_rad_s) +
         c.torque_Nm;
}

bool set_silent(RuiwoEmulator& emu, std::uint8_t id, bool silent) {
  if (!emu.faults.armed || emu.index_of_id[id] < 0) return false;
  emu.motors[emu.index_of_id[id]].silent = silent;
  return true;
}

namespace {

bool is_special(const can_frame& f) {
  for (int i = 0; i < 7; ++i)
    if (f.data[i] != 0xFF) return false;
  return f.data[7] >= 0xFC && f.data[7] <= 0xFE;
}

void reply(RuiwoEmulator& emu, CanPort& port, EmulatedRuiwoMotor& m) {
  if (m.silent || roll(emu.faults, emu.faults.drop_probability)) {
    ++emu.replies_dropped;
    return;
  }
  ruiwo::Status s;
  s.motor_id = m.id;
  s.position_rad = m.position_rad - m.zero_rad;
  s.velocity_rad_s = m.velocity_rad_s;
  s.torque_Nm = motor_torque_Nm(m);
  s.temperature_raw = m.temperature_raw;
  s.fault_code = m.fault_code;
  can_frame f;
  ruiwo::encode_status_rt(s, f);
  if (roll(emu.faults, emu.faults.corrupt_probability)) {
    const unsigned bit = emu.faults.rng() % 64;
    f.data[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
  }
  if (send_rt(port, f) == DriverError::kOk) ++emu.replies_out;
}

}  // namespace

int serve_rt(RuiwoEmulator& emu, CanPort& port) {
  int handled = 0;
  RxFrame rx;
  can_frame f;
  while (receive_rt(port, rx) == DriverError::kOk) {
    ++handled;
    ++emu.frames_in;
    if (!as_classic(rx, f) || f.len != 8 || (f.can_id & ~CAN_SFF_MASK) != 0) {
      ++emu.unknown_frames;
      continue;
    }
    const std::uint32_t id = f.can_id & CAN_SFF_MASK;
    if (id > 0xFF || emu.index_of_id[id] < 0) {
      ++emu.unknown_frames;
      continue;
    }
    EmulatedRuiwoMotor& m = emu.motors[emu.index_of_id[id]];
    if (is_special(f)) {
      switch (static_cast<ruiwo::SpecialCommand>(f.data[7])) {
        case ruiwo::SpecialCommand::kEnable: m.enabled = true; break;
        case ruiwo::SpecialCommand::kDisable: m.enabled = false; break;
        case ruiwo::SpecialCommand::kSetZero: m.zero_rad = m.position_rad; break;
      }
    } else {
      (void)ruiwo::decode_ptm_rt(f, m.command);
    }
    reply(emu, port, m);
  }
  return handled;
}

}  // namespace kuavo::drivers::emulator
