// CANopen (CiA 301) frames the drive supervisor needs: NMT, SYNC, heartbeat,
// EMCY and expedited SDO download. Pre-defined connection set COB-IDs (node
// IDs 1..127). All functions are real-time safe.
#pragma once

#include <cstdint>
#include <linux/can.h>

#include "drivers/driver_error.h"

namespace kuavo::drivers::canopen {

inline constexpr std::uint32_t kCobNmt = 0x000;
inline constexpr std::uint32_t kCobSync = 0x080;
inline constexpr std::uint32_t kCobEmcy = 0x080;   // + node
inline constexpr std::uint32_t kCobTpdo1 = 0x180;  // + node
inline constexpr std::uint32_t kCobRpdo1 = 0x200;
inline constexpr std::uint32_t kCobTpdo2 = 0x280;
inline constexpr std::uint32_t kCobRpdo2 = 0x300;
inline constexpr std::uint32_t kCobSdoServerToClient = 0x580;
inline constexpr std::uint32_t kCobSdoClientToServer = 0x600;
inline constexpr std::uint32_t kCobHeartbeat = 0x700;

enum class NmtCommand : std::uint8_t {
  kStart = 0x01,
  kStop = 0x02,
  kEnterPreOperational = 0x80,
  kResetNode = 0x81,
  kResetCommunication = 0x82,
};

enum class NmtState : std::uint8_t {
  kBootUp = 0x00,
  kStopped = 0x04,
  kOperational = 0x05,
  kPreOperational = 0x7F,
  kUnknown = 0xFF,  // never seen / not a valid state byte
};

struct SdoWrite {
  std::uint16_t index = 0;
  std::uint8_t subindex = 0;
  std::uint8_t size_bytes = 4;  // 1, 2 or 4 (expedited)
  std::uint32_t value = 0;
};

struct Emergency {
  std::uint8_t node = 0;
  std::uint16_t error_code = 0;
  std::uint8_t error_register = 0;
};

void encode_nmt_rt(NmtCommand cmd, std::uint8_t node /* 0 = all */, can_frame& out);
void encode_sync_rt(can_frame& out);
void encode_sdo_download_rt(std::uint8_t node, const SdoWrite& w, can_frame& out);

// Heartbeat / boot-up (0x700 + node, 1 byte). kWrongCanId if not a heartbeat.
DriverError decode_heartbeat_rt(const can_frame& f, std::uint8_t& node, NmtState& state);
// SDO answer for (node, index, subindex): kOk for a download acknowledge,
// kSdoAbort (abort_code filled), kWrongCanId for another node/object,
// kUnknownCommand for other SDO commands, kWrongLength.
DriverError decode_sdo_reply_rt(const can_frame& f, std::uint8_t node, const SdoWrite& expected,
                                std::uint32_t& abort_code);
// EMCY (0x081..0x0FF, 8 bytes; an empty 0x080 frame is SYNC).
DriverError decode_emergency_rt(const can_frame& f, Emergency& out);

// Little-endian helpers (CANopen is little-endian).
inline void put_u16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
inline void put_u32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
inline std::uint16_t get_u16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
inline std::uint32_t get_u32(const std::uint8_t* p) {
  return std::uint32_t{p[0]} | (std::uint32_t{p[1]} << 8) | (std::uint32_t{p[2]} << 16) |
         (std::uint32_t{p[3]} << 24);
}

}  // namespace kuavo::drivers::canopen
