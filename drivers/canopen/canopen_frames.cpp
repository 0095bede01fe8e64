#include "drivers/canopen/canopen_frames.h"

namespace kuavo::drivers::canopen {

namespace {

// Rejects error, extended and remote frames: none of ours use them.
DriverError check_plain(const can_frame& f) {
  if (f.can_id & (CAN_ERR_FLAG | CAN_EFF_FLAG)) return DriverError::kWrongCanId;
  if (f.can_id & CAN_RTR_FLAG) return DriverError::kRemoteFrame;
  return DriverError::kOk;
}

}  // namespace

void encode_nmt_rt(NmtCommand cmd, std::uint8_t node, can_frame& out) {
  out = can_frame{};
  out.can_id = kCobNmt;
  out.len = 2;
  out.data[0] = static_cast<std::uint8_t>(cmd);
  out.data[1] = node;
}

void encode_sync_rt(can_frame& out) {
  out = can_frame{};
  out.can_id = kCobSync;
  out.len = 0;  // no counter (0x1019 = 0)
}

void encode_sdo_download_rt(std::uint8_t node, const SdoWrite& w, can_frame& out) {
  out = can_frame{};
  out.can_id = kCobSdoClientToServer + node;
  out.len = 8;
  // ccs = 1 (download), e = 1 (expedited), s = 1 (size given), n = 4 - size.
  const std::uint8_t n = static_cast<std::uint8_t>(4 - w.size_bytes);
  out.data[0] = static_cast<std::uint8_t>(0x20 | (n << 2) | 0x03);
  put_u16(&out.data[1], w.index);
  out.data[3] = w.subindex;
  put_u32(&out.data[4], w.value);
  // Bytes beyond the size carry no data; zero them (the drive ignores them).
  for (int i = 4 + w.size_bytes; i < 8; ++i) out.data[i] = 0;
}

DriverError decode_heartbeat_rt(const can_frame& f, std::uint8_t& node, NmtState& state) {
  if (const DriverError e = check_plain(f); e != DriverError::kOk) return e;
  const std::uint32_t id = f.can_id & CAN_SFF_MASK;
  if (id <= kCobHeartbeat || id > kCobHeartbeat + 0x7F) return DriverError::kWrongCanId;
  if (f.len != 1) return DriverError::kWrongLength;
  node = static_cast<std::uint8_t>(id - kCobHeartbeat);
  switch (f.data[0] & 0x7F) {  // bit 7 is the node-guarding toggle bit
    case 0x00: state = NmtState::kBootUp; break;
    case 0x04: state = NmtState::kStopped; break;
    case 0x05: state = NmtState::kOperational; break;
    case 0x7F: state = NmtState::kPreOperational; break;
    default: state = NmtState::kUnknown; return DriverError::kUnknownCommand;
  }
  return DriverError::kOk;
}

DriverError decode_sdo_reply_rt(const can_frame& f, std::uint8_t node, const SdoWrite& expected,
                                std::uint32_t& abort_code) {
  if (const DriverError e = check_plain(f); e != DriverError::kOk) return e;
  if ((f.can_id & CAN_SFF_MASK) != kCobSdoServerToClient + node) return DriverError::kWrongCanId;
  if (f.len != 8) return DriverError::kWrongLength;
  if (get_u16(&f.data[1]) != expected.index || f.data[3] != expected.subindex) {
    return DriverError::kWrongCanId;
  }
  if (f.data[0] == 0x60) return DriverError::kOk;
  if (f.data[0] == 0x80) {
    abort_code = get_u32(&f.data[4]);
    return DriverError::kSdoAbort;
  }
  return DriverError::kUnknownCommand;
}

DriverError decode_emergency_rt(const can_frame& f, Emergency& out) {
  if (const DriverError e = check_plain(f); e != DriverError::kOk) return e;
  const std::uint32_t id = f.can_id & CAN_SFF_MASK;
  if (id <= kCobEmcy || id > kCobEmcy + 0x7F) return DriverError::kWrongCanId;
  if (f.len != 8) return DriverError::kWrongLength;
  out.node = static_cast<std::uint8_t>(id - kCobEmcy);
  out.error_code = get_u16(&f.data[0]);
  out.error_register = f.data[2];
  return DriverError::kOk;
}

}  // namespace kuavo::drivers::canopen
