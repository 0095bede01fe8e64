// Xsens MTi binary protocol (Xsens "MT Low-Level Communication Protocol"):
//   0xFA preamble | BID 0xFF | MID | LEN (0xFF -> 2-byte big-endian extended
//   length) | data | checksum, where BID + MID + LEN bytes + data + checksum
//   sum to 0 (mod 256). MID 0x36 = MTData2: items of XDI (u16 BE), size (u8),
//   big-endian values.
// A streaming parser: bytes in any chunking, garbage skipped, and after a bad
// checksum or an impossible length it resyncs on the next 0xFA *inside* the
// rejected bytes, so a real packet that began there is not lost.
// Real-time safe: fixed buffer, no heap.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "controllers/hal/types.h"
#include "drivers/driver_error.h"

namespace kuavo::drivers::mti {

inline constexpr std::uint8_t kPreamble = 0xFA;
inline constexpr std::uint8_t kBusId = 0xFF;
inline constexpr std::uint8_t kMidMtData2 = 0x36;
// Our output configuration (quaternion, rate of turn, acceleration, counter,
// time) is ~70 bytes; 512 leaves room and bounds the buffer.
inline constexpr int kMaxPayload_bytes = 512;

// XDI data identifiers (format bits 0-3 masked off).
inline constexpr std::uint16_t kXdiPacketCounter = 0x1020;
inline constexpr std::uint16_t kXdiSampleTimeFine = 0x1060;
inline constexpr std::uint16_t kXdiQuaternion = 0x2010;
inline constexpr std::uint16_t kXdiAcceleration = 0x4020;
inline constexpr std::uint16_t kXdiRateOfTurn = 0x8020;
// Precision bits (XDI & 0x3): only float32 and float64 are accepted.
inline constexpr std::uint16_t kPrecisionFloat32 = 0x0;
inline constexpr std::uint16_t kPrecisionFloat64 = 0x3;
// Coordinate bits (XDI & 0xC) of the orientation: the sensor must be set to ENU.
inline constexpr std::uint8_t kFrameEnu = 0x0;

struct MtData2 {
  std::array<double, 4> quaternion_wxyz{1.0, 0.0, 0.0, 0.0};
  std::array<double, 3> rate_of_turn_rad_s{};
  std::array<double, 3> acceleration_m_s2{};
  std::uint16_t packet_counter = 0;
  std::uint32_t sample_time_fine = 0;  // 10 kHz ticks
  std::uint8_t orientation_frame_bits = 0;  // XDI bits 2-3: 0 ENU, 4 NED, 8 NWU
  bool has_quaternion = false, has_rate_of_turn = false, has_acceleration = false;
  bool has_packet_counter = false, has_sample_time_fine = false;
};

struct ParserStats {
  std::uint32_t packets = 0;          // MTData2 packets decoded
  std::uint32_t other_messages = 0;   // valid packets of another MID
  std::uint32_t checksum_errors = 0;
  std::uint32_t length_errors = 0;
  std::uint32_t bad_items = 0;
  std::uint32_t skipped_bytes = 0;    // garbage and the heads of rejected packets
};

struct Parser {
  std::array<std::uint8_t, 6 + kMaxPayload_bytes + 1> buf{};
  int len = 0;
  ParserStats stats{};
};

// Feeds bytes until one MTData2 packet completes. Returns kOk with `out`
// filled and `consumed` = bytes used (call again with the rest), or kRxEmpty
// with consumed == n when no packet completed. Errors are only counted.
DriverError parse_rt(Parser& p, const std::uint8_t* bytes, std::size_t n, std::size_t& consumed,
                     MtData2& out);

// Decodes the payload of one MTData2 message (tests and fuzzing use it directly).
DriverError decode_mtdata2_rt(const std::uint8_t* payload, int length, MtData2& out);

// MTData2 -> HAL sample: valid only with all three quantities present and finite;
// the quaternion is normalised (rejected if its norm is far from 1). kBadConfig
// if the orientation is not in ENU (the MTi's default; set in MT Manager).
DriverError to_imu_sample(const MtData2& d, hal::TimeNs stamp_ns, hal::ImuSample& out);

}  // namespace kuavo::drivers::mti
