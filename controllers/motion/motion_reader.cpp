#include "controllers/motion/motion_reader.h"

#include <cmath>
#include <cstring>

namespace kuavo::motion {
namespace {
constexpr int kNq = model::kNq;
}  // namespace

std::uint16_t motion_get_u16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}

std::uint32_t motion_get_u32(const std::uint8_t* p) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

double motion_get_f64(const std::uint8_t* p) {
  std::uint64_t bits = 0;
  for (int i = 7; i >= 0; --i) bits = (bits << 8) | p[i];
  double v;
  std::memcpy(&v, &bits, 8);
  return v;
}

std::uint32_t motion_header_crc(const std::uint8_t* data) {
  std::uint32_t crc = crc32(data, kMotionHeaderCrcOffset);
  const std::uint8_t zero[4] = {0, 0, 0, 0};
  crc = crc32(zero, 4, crc);
  return crc32(data + kMotionHeaderCrcOffset + 4, kMotionHeaderBytes - kMotionHeaderCrcOffset - 4, crc);
}

const char* to_string(MotionError e) {
  switch (e) {
    case MotionError::kOk:
      return "ok";
    case MotionError::kTooShort:
      return "file too short for a motion header";
    case MotionError::kBadMagic:
      return "not a Kuavo motion file (bad magic)";
    case MotionError::kBadVersion:
      return "unsupported motion format version";
    case MotionError::kBadHeaderChecksum:
      return "header checksum mismatch (corrupted header)";
    case MotionError::kWrongVariant:
      return "motion was made for the other robot variant";
    case MotionError::kLayoutMismatch:
      return "joint layout differs from this robot model";
    case MotionError::kTruncated:
      return "file truncated: fewer frames than the header says";
    case MotionError::kBadPayloadChecksum:
      return "frame data checksum mismatch (corrupted frames)";
    case MotionError::kBadRate:
      return "frame rate outside 4..500 Hz";
    case MotionError::kBadLabel:
      return "contact label out of range";
    case MotionError::kIo:
      return "file could not be read or written";
    case MotionError::kTrailingBytes:
      return "bytes after the last frame (appended or concatenated data)";
    case MotionError::kNonFinite:
      return "non-finite value (NaN or infinity)";
    case MotionError::kBaseImplausible:
      return "implausible base pose";
    case MotionError::kJointOutOfLimits:
      return "joint angle outside the robot's position limits";
    case MotionError::kTooManyFrames:
      return "more frames than the controller can hold";
  }
  return "unknown motion error";
}

std::uint32_t crc32(const std::uint8_t* data, std::size_t size, std::uint32_t crc) {
  // Bitwise reflected CRC-32 (poly 0xEDB88320): small, table-free, fast enough for files.
  crc = ~crc;
  for (std::size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

MotionError read_motion_header(const std::uint8_t* data, std::size_t size, const model::Model& robot,
                               MotionHeader& header) {
  if (data == nullptr || size < kMotionFixedHeaderBytes) return MotionError::kTooShort;
  if (std::memcmp(data, kMotionMagic, 8) != 0) return MotionError::kBadMagic;
  if (motion_get_u32(data + 8) != kMotionVersion) return MotionError::kBadVersion;
  if (motion_get_u32(data + 12) != kMotionHeaderBytes) return MotionError::kLayoutMismatch;
  if (size < kMotionHeaderBytes) return MotionError::kTooShort;
  if (motion_get_u32(data + kMotionHeaderCrcOffset) != motion_header_crc(data)) return MotionError::kBadHeaderChecksum;
  if (data[16] != static_cast<std::uint8_t>(robot.variant)) return MotionError::kWrongVariant;
  if (motion_get_u16(data + 18) != kNq || motion_get_u16(data + 20) != model::kNumJoints ||
      motion_get_u16(data + 22) != kMotionRecordBytes)
    return MotionError::kLayoutMismatch;
  for (int j = 0; j < model::kNumJoints; ++j) {
    const char* stored = reinterpret_cast<const char*>(data + kMotionFixedHeaderBytes + kMotionNameBytes * j);
    if (std::strncmp(stored, model::joint_name(robot, j), kMotionNameBytes) != 0) return MotionError::kLayoutMismatch;
  }
  const double rate = motion_get_f64(data + 24);
  if (!(rate >= kMotionMinRate_hz && rate <= kMotionMaxRate_hz)) return MotionError::kBadRate;
  const std::uint32_t frames = motion_get_u32(data + 32);
  if (frames > kMotionMaxFrames) return MotionError::kTooManyFrames;
  const std::size_t payload = static_cast<std::size_t>(frames) * kMotionRecordBytes;
  if (size - kMotionHeaderBytes < payload) return MotionError::kTruncated;
  if (size - kMotionHeaderBytes > payload) return MotionError::kTrailingBytes;
  if (crc32(data + kMotionHeaderBytes, payload) != motion_get_u32(data + kMotionPayloadCrcOffset))
    return MotionError::kBadPayloadChecksum;
  header.variant = robot.variant;
  header.rate_hz = rate;
  header.frame_count = frames;
  return MotionError::kOk;
}

MotionError read_motion_frame(const std::uint8_t* data, std::size_t size, std::uint32_t index,
                              dynamics::ConfigVector& q, ContactLabel& label) {
  const std::size_t at = kMotionHeaderBytes + static_cast<std::size_t>(index) * kMotionRecordBytes;
  if (data == nullptr || size < at + kMotionRecordBytes) return MotionError::kTruncated;
  const std::uint8_t* p = data + at;
  for (int i = 0; i < kNq; ++i) q[i] = motion_get_f64(p + 8 * i);
  if (p[280] > 3) return MotionError::kBadLabel;
  label = static_cast<ContactLabel>(p[280]);
  return MotionError::kOk;
}
MotionError check_motion_frame(const model::Model& robot, const dynamics::ConfigVector& q, int& joint) {
  joint = -1;
  if (!q.allFinite()) return MotionError::kNonFinite;
  if (!(q[2] >= kMotionBaseHeightMin_m && q[2] <= kMotionBaseHeightMax_m) ||
      !(std::abs(q[0]) <= kMotionBaseHorizontalMax_m && std::abs(q[1]) <= kMotionBaseHorizontalMax_m) ||
      !(std::abs(q.segment<4>(3).norm() - 1.0) <= kMotionQuaternionNormTolerance))
    return MotionError::kBaseImplausible;
  for (int j = 0; j < model::kNumJoints; ++j) {
    const double qj = q[7 + j];
    if (!(qj >= robot.limits.position_min_rad[j] - kMotionJointLimitTolerance_rad &&
          qj <= robot.limits.position_max_rad[j] + kMotionJointLimitTolerance_rad)) {
      joint = j;
      return MotionError::kJointOutOfLimits;
    }
  }
  return MotionError::kOk;
}

}  // namespace kuavo::motion
