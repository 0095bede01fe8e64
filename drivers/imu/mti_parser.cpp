#include "drivers/imu/mti_parser.h"

#include <bit>
#include <cmath>
#include <cstring>

namespace kuavo::drivers::mti {

namespace {

std::uint32_t be32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}
std::uint64_t be64(const std::uint8_t* p) { return (std::uint64_t{be32(p)} << 32) | be32(p + 4); }

// Reads `count` floats of the item's precision into out.
bool read_floats(std::uint16_t xdi, const std::uint8_t* data, int size, int count, double* out) {
  const std::uint16_t precision = xdi & 0x3;
  if (precision == kPrecisionFloat32 && size == 4 * count) {
    for (int i = 0; i < count; ++i) out[i] = std::bit_cast<float>(be32(data + 4 * i));
    return true;
  }
  if (precision == kPrecisionFloat64 && size == 8 * count) {
    for (int i = 0; i < count; ++i) out[i] = std::bit_cast<double>(be64(data + 8 * i));
    return true;
  }
  return false;
}

// Drops the first byte and everything up to the next preamble.
void resync(Parser& p) {
  int next = 1;
  while (next < p.len && p.buf[next] != kPreamble) ++next;
  p.stats.skipped_bytes += static_cast<std::uint32_t>(next);
  std::memmove(p.buf.data(), p.buf.data() + next, static_cast<std::size_t>(p.len - next));
  p.len -= next;
}

enum class Step { kNeedMore, kRejected, kOther, kPacket };

// Examines the buffer head: is a whole packet there, and is it good?
Step examine(Parser& p, MtData2& out) {
  if (p.len == 0) return Step::kNeedMore;
  if (p.buf[0] != kPreamble) return Step::kRejected;
  if (p.len < 2) return Step::kNeedMore;
  if (p.buf[1] != kBusId) return Step::kRejected;
  if (p.len < 4) return Step::kNeedMore;
  int header = 4;
  int length = p.buf[3];
  if (length == 0xFF) {
    if (p.len < 6) return Step::kNeedMore;
    header = 6;
    length = (p.buf[4] << 8) | p.buf[5];
  }
  if (length > kMaxPayload_bytes) {
    ++p.stats.length_errors;
    return Step::kRejected;
  }
  const int total = header + length + 1;
  if (p.len < total) return Step::kNeedMore;
  std::uint8_t sum = 0;
  for (int i = 1; i < total; ++i) sum = static_cast<std::uint8_t>(sum + p.buf[i]);
  if (sum != 0) {
    ++p.stats.checksum_errors;
    return Step::kRejected;
  }
  Step step = Step::kOther;
  if (p.buf[2] != kMidMtData2) {
    ++p.stats.other_messages;
  } else if (decode_mtdata2_rt(p.buf.data() + header, length, out) == DriverError::kOk) {
    ++p.stats.packets;
    step = Step::kPacket;
  } else {
    ++p.stats.bad_items;
  }
  std::memmove(p.buf.data(), p.buf.data() + total, static_cast<std::size_t>(p.len - total));
  p.len -= total;
  return step;
}

}  // namespace

DriverError decode_mtdata2_rt(const std::uint8_t* payload, int length, MtData2& out) {
  MtData2 d;
  int pos = 0;
  while (pos < length) {
    if (length - pos < 3) return DriverError::kMtiBadItem;
    const std::uint16_t xdi = static_cast<std::uint16_t>((payload[pos] << 8) | payload[pos + 1]);
    const int size = payload[pos + 2];
    const std::uint8_t* data = payload + pos + 3;
    if (size > length - pos - 3) return DriverError::kMtiBadItem;
    switch (xdi & 0xFFF0) {
      case kXdiQuaternion:
        if (!read_floats(xdi, data, size, 4, d.quaternion_wxyz.data())) return DriverError::kMtiBadItem;
        d.has_quaternion = true;
        d.orientation_frame_bits = static_cast<std::uint8_t>(xdi & 0xC);
        break;
      case kXdiRateOfTurn:
        if (!read_floats(xdi, data, size, 3, d.rate_of_turn_rad_s.data())) return DriverError::kMtiBadItem;
        d.has_rate_of_turn = true;
        break;
      case kXdiAcceleration:
        if (!read_floats(xdi, data, size, 3, d.acceleration_m_s2.data())) return DriverError::kMtiBadItem;
        d.has_acceleration = true;
        break;
      case kXdiPacketCounter:
        if (size != 2) return DriverError::kMtiBadItem;
        d.packet_counter = static_cast<std::uint16_t>((data[0] << 8) | data[1]);
        d.has_packet_counter = true;
        break;
      case kXdiSampleTimeFine:
        if (size != 4) return DriverError::kMtiBadItem;
        d.sample_time_fine = be32(data);
        d.has_sample_time_fine = true;
        break;
      default:
        break;  // other outputs are allowed and skipped
    }
    pos += 3 + size;
  }
  out = d;
  return DriverError::kOk;
}

DriverError parse_rt(Parser& p, const std::uint8_t* bytes, std::size_t n, std::size_t& consumed,
                     MtData2& out) {
  consumed = 0;
  while (true) {
    // Drain what is already buffered (several packets may follow a resync).
    for (;;) {
      const Step s = examine(p, out);
      if (s == Step::kPacket) return DriverError::kOk;
      if (s == Step::kRejected) {
        resync(p);
        continue;
      }
      if (s == Step::kNeedMore) break;
    }
    if (consumed == n) return DriverError::kRxEmpty;
    p.buf[p.len++] = bytes[consumed++];
  }
}

DriverError to_imu_sample(const MtData2& d, hal::TimeNs stamp_ns, hal::ImuSample& out) {
  out.valid = false;
  out.stamp_ns = stamp_ns;
  if (!d.has_quaternion || !d.has_rate_of_turn || !d.has_acceleration) return DriverError::kMtiIncomplete;
  // The estimator assumes a z-up world; NED output would flip gravity.
  if (d.orientation_frame_bits != kFrameEnu) return DriverError::kBadConfig;
  const auto& q = d.quaternion_wxyz;
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  bool finite = std::isfinite(norm);
  for (double v : d.rate_of_turn_rad_s) finite = finite && std::isfinite(v);
  for (double v : d.acceleration_m_s2) finite = finite && std::isfinite(v);
  // float32 quaternions are normalised to ~1e-7; 1e-3 only rejects garbage.
  if (!finite || std::abs(norm - 1.0) > 1e-3) return DriverError::kMtiBadItem;
  out.orientation_xyzw = {q[1] / norm, q[2] / norm, q[3] / norm, q[0] / norm};
  out.angular_rate_rad_s = d.rate_of_turn_rad_s;
  out.acceleration_m_s2 = d.acceleration_m_s2;
  out.valid = true;
  return DriverError::kOk;
}

}  // namespace kuavo::drivers::mti
