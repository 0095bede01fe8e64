#include "drivers/canopen/pdo_layout.h"

#include <cmath>

namespace kuavo::drivers::canopen {

namespace {

DriverError check_pdo(const can_frame& f, std::uint32_t cob, std::uint8_t min_len) {
  if (f.can_id & (CAN_ERR_FLAG | CAN_EFF_FLAG)) return DriverError::kWrongCanId;
  if (f.can_id & CAN_RTR_FLAG) return DriverError::kRemoteFrame;
  if ((f.can_id & CAN_SFF_MASK) != cob) return DriverError::kWrongCanId;
  if (f.len < min_len || f.len > CAN_MAX_DLEN) return DriverError::kWrongLength;
  return DriverError::kOk;
}

constexpr std::uint32_t map_entry(std::uint16_t index, std::uint8_t sub, std::uint8_t bits) {
  return (std::uint32_t{index} << 16) | (std::uint32_t{sub} << 8) | bits;
}

constexpr std::uint32_t kPdoInvalid = 0x80000000u;  // COB-ID bit 31: PDO does not exist

}  // namespace

void encode_rpdo1_rt(std::uint8_t node, const RxPdo1& pdo, can_frame& out) {
  out = can_frame{};
  out.can_id = kCobRpdo1 + node;
  out.len = 8;
  put_u16(&out.data[0], pdo.controlword);
  put_u16(&out.data[2], static_cast<std::uint16_t>(pdo.target_torque_permille));
  put_u32(&out.data[4], static_cast<std::uint32_t>(pdo.target_position_counts));
}

DriverError decode_rpdo1_rt(const can_frame& f, std::uint8_t node, RxPdo1& out) {
  if (const DriverError e = check_pdo(f, kCobRpdo1 + node, 8); e != DriverError::kOk) return e;
  if (f.len != 8) return DriverError::kWrongLength;
  out.controlword = get_u16(&f.data[0]);
  out.target_torque_permille = static_cast<std::int16_t>(get_u16(&f.data[2]));
  out.target_position_counts = static_cast<std::int32_t>(get_u32(&f.data[4]));
  return DriverError::kOk;
}

bool gain_to_register(double gain, std::uint32_t& reg) {
  if (!(gain >= 0.0) || !(gain <= 4.0e6 / kGainRegisterPerUnit)) return false;  // NaN fails both
  reg = static_cast<std::uint32_t>(std::lround(gain * kGainRegisterPerUnit));
  return true;
}

DriverError decode_tpdo1_rt(const can_frame& f, std::uint8_t node, TxPdo1& out) {
  if (const DriverError e = check_pdo(f, kCobTpdo1 + node, 8); e != DriverError::kOk) return e;
  out.statusword = get_u16(&f.data[0]);
  out.actual_torque_permille = static_cast<std::int16_t>(get_u16(&f.data[2]));
  out.actual_position_counts = static_cast<std::int32_t>(get_u32(&f.data[4]));
  return DriverError::kOk;
}

DriverError decode_tpdo2_rt(const can_frame& f, std::uint8_t node, TxPdo2& out) {
  if (const DriverError e = check_pdo(f, kCobTpdo2 + node, 7); e != DriverError::kOk) return e;
  out.actual_velocity_counts_s = static_cast<std::int32_t>(get_u32(&f.data[0]));
  out.error_code = get_u16(&f.data[4]);
  out.mode_display = static_cast<std::int8_t>(f.data[6]);
  return DriverError::kOk;
}

ConfigSequence pdo_config_sequence(std::uint8_t node, std::uint16_t heartbeat_period_ms,
                                   std::uint32_t cycle_period_us, const DriveLoop& loop) {
  const bool csp = loop.mode == kModeCyclicSyncPosition;
  ConfigSequence s;
  auto add = [&](std::uint16_t index, std::uint8_t sub, std::uint8_t size, std::uint32_t value) {
    s.writes[s.count++] = SdoWrite{index, sub, size, value};
  };
  auto map_pdo = [&](std::uint16_t comm, std::uint16_t mapping, std::uint32_t cob,
                     std::initializer_list<std::uint32_t> entries) {
    add(comm, 1, 4, kPdoInvalid | cob);
    add(comm, 2, 1, 1);  // synchronous, every SYNC
    add(mapping, 0, 1, 0);
    std::uint8_t sub = 1;
    for (std::uint32_t e : entries) add(mapping, sub++, 4, e);
    add(mapping, 0, 1, static_cast<std::uint32_t>(entries.size()));
    add(comm, 1, 4, cob);
  };
  map_pdo(0x1400, 0x1600, kCobRpdo1 + node,
          {map_entry(0x6040, 0, 16), map_entry(csp ? kObjTorqueOffset : kObjTargetTorque, 0, 16),
           map_entry(0x607A, 0, 32)});
  map_pdo(0x1800, 0x1A00, kCobTpdo1 + node,
          {map_entry(0x6041, 0, 16), map_entry(0x6077, 0, 16), map_entry(0x6064, 0, 32)});
  map_pdo(0x1801, 0x1A01, kCobTpdo2 + node,
          {map_entry(0x606C, 0, 32), map_entry(0x603F, 0, 16), map_entry(0x6061, 0, 8)});
  // Unused PDOs off, so they add no bus load.
  add(0x1401, 1, 4, kPdoInvalid | (kCobRpdo2 + node));
  add(0x1402, 1, 4, kPdoInvalid | (0x400u + node));
  add(0x1403, 1, 4, kPdoInvalid | (0x500u + node));
  add(0x1802, 1, 4, kPdoInvalid | (0x380u + node));
  add(0x1803, 1, 4, kPdoInvalid | (0x480u + node));
  if (csp) {  // the gains before the mode: the loop never runs on stale gains
    add(kObjPositionLoopGains, 1, 4, loop.kp_register);
    add(kObjPositionLoopGains, 2, 4, loop.kd_register);
  }
  add(0x6060, 0, 1, static_cast<std::uint8_t>(csp ? kModeCyclicSyncPosition : kModeCyclicSyncTorque));
  add(0x1017, 0, 2, heartbeat_period_ms);
  add(0x1006, 0, 4, cycle_period_us);
  return s;
}

}  // namespace kuavo::drivers::canopen
