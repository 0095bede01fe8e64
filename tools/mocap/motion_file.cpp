#include "tools/mocap/motion_file.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

namespace kuavo::mocap {
namespace {

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

}  // namespace

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
  put_u32(b.data() + kMotionPayloadCrcOffset, crc32(b.data() + kMotionHeaderBytes, q.size() * kMotionRecordBytes));
  put_u32(b.data() + kMotionHeaderCrcOffset, motion_header_crc(b.data()));
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
  std::vector<std::uint8_t> bytes;
  if (!motion::read_motion_bytes(path, bytes, error) || !motion::check_motion_header(bytes, robot, path, header, error))
    return false;
  q.resize(header.frame_count);
  labels.resize(header.frame_count);
  for (std::uint32_t i = 0; i < header.frame_count; ++i) {
    if (!motion::read_checked_motion_frame(bytes, robot, i, path, q[i], labels[i], error)) return false;
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
