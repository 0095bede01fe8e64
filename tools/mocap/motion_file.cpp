#include "tools/mocap/motion_file.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>

namespace kuavo::mocap {
namespace {

constexpr std::size_t kCrcFieldOffset = 40;
constexpr std::size_t kPayloadCrcOffset = 36;
constexpr int kNq = model::kNq;

void put_u16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
void put_u32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void put_f64(std::uint8_t* p, double v) {
  std::uint64_t bits;
  std::memcpy(&bits, &v, 8);
  for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(bits >> (8 * i));
}
std::uint16_t get_u16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
std::uint32_t get_u32(const std::uint8_t* p) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
double get_f64(const std::uint8_t* p) {
  std::uint64_t bits = 0;
  for (int i = 7; i >= 0; --i) bits = (bits << 8) | p[i];
  double v;
  std::memcpy(&v, &bits, 8);
  return v;
}

std::uint32_t header_crc(const std::uint8_t* data) {
  std::uint32_t crc = crc32(data, kCrcFieldOffset);
  const std::uint8_t zero[4] = {0, 0, 0, 0};
  crc = crc32(zero, 4, crc);
  return crc32(data + kCrcFieldOffset + 4, kMotionHeaderBytes - kCrcFieldOffset - 4, crc);
}

}  // namespace

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
      return "frame rate is not a positive finite number";
    case MotionError::kBadLabel:
      return "contact label out of range";
    case MotionError::kIo:
      return "file could not be read or written";
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
  if (get_u32(data + 8) != kMotionVersion) return MotionError::kBadVersion;
  if (get_u32(data + 12) != kMotionHeaderBytes) return MotionError::kLayoutMismatch;
  if (size < kMotionHeaderBytes) return MotionError::kTooShort;
  if (get_u32(data + kCrcFieldOffset) != header_crc(data)) return MotionError::kBadHeaderChecksum;
  if (data[16] != static_cast<std::uint8_t>(robot.variant)) return MotionError::kWrongVariant;
  if (get_u16(data + 18) != kNq || get_u16(data + 20) != model::kNumJoints || get_u16(data + 22) != kMotionRecordBytes)
    return MotionError::kLayoutMismatch;
  for (int j = 0; j < model::kNumJoints; ++j) {
    const char* stored = reinterpret_cast<const char*>(data + kMotionFixedHeaderBytes + kMotionNameBytes * j);
    if (std::strncmp(stored, model::joint_name(robot, j), kMotionNameBytes) != 0) return MotionError::kLayoutMismatch;
  }
  const double rate = get_f64(data + 24);
  if (!std::isfinite(rate) || !(rate > 0.0)) return MotionError::kBadRate;
  const std::uint32_t frames = get_u32(data + 32);
  const std::size_t payload = static_cast<std::size_t>(frames) * kMotionRecordBytes;
  if (size - kMotionHeaderBytes < payload) return MotionError::kTruncated;
  if (crc32(data + kMotionHeaderBytes, payload) != get_u32(data + kPayloadCrcOffset))
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
  for (int i = 0; i < kNq; ++i) q[i] = get_f64(p + 8 * i);
  if (p[280] > 3) return MotionError::kBadLabel;
  label = static_cast<ContactLabel>(p[280]);
  return MotionError::kOk;
}

std::vector<std::uint8_t> encode_motion(const model::Model& robot, double rate_hz,
                                        const std::vector<dynamics::ConfigVector>& q,
                                        const std::vector<ContactLabel>& labels) {
  std::vector<std::uint8_t> b(kMotionHeaderBytes + q.size() * kMotionRecordBytes, 0);
  std::memcpy(b.data(), kMotionMagic, 8);
  put_u32(b.data() + 8, kMotionVersion);
  put_u32(b.data() + 12, static_cast<std::uint32_t>(kMotionHeaderBytes));
  b[16] = static_cast<std::uint8_t>(robot.variant);
  put_u16(b.data() + 18, kNq);
  put_u16(b.data() + 20, model::kNumJoints);
  put_u16(b.data() + 22, kMotionRecordBytes);
  put_f64(b.data() + 24, rate_hz);
  put_u32(b.data() + 32, static_cast<std::uint32_t>(q.size()));
  for (int j = 0; j < model::kNumJoints; ++j) {
    const char* name = model::joint_name(robot, j);
    std::memcpy(b.data() + kMotionFixedHeaderBytes + kMotionNameBytes * j, name,
                std::min(std::strlen(name), kMotionNameBytes - 1));
  }
  for (std::size_t f = 0; f < q.size(); ++f) {
    std::uint8_t* p = b.data() + kMotionHeaderBytes + f * kMotionRecordBytes;
    for (int i = 0; i < kNq; ++i) put_f64(p + 8 * i, q[f][i]);
    p[280] = static_cast<std::uint8_t>(f < labels.size() ? labels[f] : ContactLabel::kFlight);
  }
  put_u32(b.data() + kPayloadCrcOffset, crc32(b.data() + kMotionHeaderBytes, q.size() * kMotionRecordBytes));
  put_u32(b.data() + kCrcFieldOffset, header_crc(b.data()));
  return b;
}

bool write_motion_file(const std::string& path, const std::vector<std::uint8_t>& bytes, std::string& error) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (out) out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!out) {
    error = path + ": cannot write";
    return false;
  }
  return true;
}

bool load_motion_file(const std::string& path, const model::Model& robot, MotionHeader& header,
                      std::vector<dynamics::ConfigVector>& q, std::vector<ContactLabel>& labels, std::string& error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error = path + ": cannot open";
    return false;
  }
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  MotionError e = read_motion_header(bytes.data(), bytes.size(), robot, header);
  if (e == MotionError::kWrongVariant) {
    error = path + ": " + to_string(e) + " (file: " + model::to_string(static_cast<model::Variant>(bytes[16])) +
            ", expected: " + model::to_string(robot.variant) + ")";
    return false;
  }
  if (e != MotionError::kOk) {
    error = path + ": " + to_string(e);
    return false;
  }
  q.resize(header.frame_count);
  labels.resize(header.frame_count);
  for (std::uint32_t i = 0; i < header.frame_count; ++i) {
    if ((e = read_motion_frame(bytes.data(), bytes.size(), i, q[i], labels[i])) != MotionError::kOk) {
      error = path + ": frame " + std::to_string(i) + ": " + to_string(e);
      return false;
    }
  }
  return true;
}

std::string motion_csv(const model::Model& robot, double rate_hz, const std::vector<dynamics::ConfigVector>& q,
                       const std::vector<ContactLabel>& labels) {
  std::string s = "t_s,base_x_m,base_y_m,base_z_m,base_qx,base_qy,base_qz,base_qw";
  for (int j = 0; j < model::kNumJoints; ++j) s += std::string(",") + model::joint_name(robot, j) + "_rad";
  s += ",contact\n";
  char buf[48];
  for (std::size_t f = 0; f < q.size(); ++f) {
    std::snprintf(buf, sizeof buf, "%.4f", static_cast<double>(f) / rate_hz);
    s += buf;
    for (int i = 0; i < kNq; ++i) {
      std::snprintf(buf, sizeof buf, ",%.9g", q[f][i]);
      s += buf;
    }
    s += std::string(",") + to_string(f < labels.size() ? labels[f] : ContactLabel::kFlight) + "\n";
  }
  return s;
}

}  // namespace kuavo::mocap
