#include "tools/mocap/motion_file.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

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
  // A directory, device or pipe is refused before reading (a directory makes the stream
  // throw; /dev/zero never ends); so is a file larger than the largest valid motion.
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) {
    error = path + ": cannot open";
    return false;
  }
  if (!std::filesystem::is_regular_file(status)) {
    error = path + ": not a regular file";
    return false;
  }
  constexpr std::uintmax_t kMaxBytes = kMotionHeaderBytes + std::uintmax_t{kMotionMaxFrames} * kMotionRecordBytes;
  const std::uintmax_t file_bytes = std::filesystem::file_size(path, ec);
  if (ec) {
    error = path + ": cannot open";
    return false;
  }
  if (file_bytes > kMaxBytes) {
    error = path + ": " + std::to_string(file_bytes) + " bytes, more than the largest motion (" +
            std::to_string(kMaxBytes) + " bytes, " + std::to_string(kMotionMaxFrames) + " frames)";
    return false;
  }
  std::ifstream in(path, std::ios::binary);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(file_bytes));
  if (in) in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!in || in.gcount() != static_cast<std::streamsize>(bytes.size())) {
    error = path + ": cannot read";
    return false;
  }
  MotionError e = read_motion_header(bytes.data(), bytes.size(), robot, header);
  if (e == MotionError::kWrongVariant) {
    const bool known = bytes[16] == static_cast<std::uint8_t>(model::Variant::kS45) ||
                       bytes[16] == static_cast<std::uint8_t>(model::Variant::kS42);
    const auto file_variant = static_cast<model::Variant>(bytes[16]);
    error = path + ": " +
            (known ? to_string(e) + std::string(" (file: ") + model::to_string(file_variant) + ", expected: " +
                         model::to_string(robot.variant) + ")"
                   : "unknown robot variant byte " + std::to_string(bytes[16]) + " at offset 16 (expected " +
                         std::to_string(static_cast<int>(robot.variant)) + " = " + model::to_string(robot.variant) + ")");
    return false;
  }
  if (e == MotionError::kTrailingBytes) {
    const std::uint32_t frames = motion_get_u32(bytes.data() + 32);
    error = path + ": " + to_string(e) + ": " + std::to_string(bytes.size()) + " bytes, the header and its " +
            std::to_string(frames) + " frames make " +
            std::to_string(kMotionHeaderBytes + std::size_t{frames} * kMotionRecordBytes);
    return false;
  }
  if (e != MotionError::kOk) {
    error = path + ": " + to_string(e);
    return false;
  }
  q.resize(header.frame_count);
  labels.resize(header.frame_count);
  char buf[160];
  for (std::uint32_t i = 0; i < header.frame_count; ++i) {
    if ((e = read_motion_frame(bytes.data(), bytes.size(), i, q[i], labels[i])) != MotionError::kOk) {
      error = path + ": frame " + std::to_string(i) + ": " + to_string(e);
      return false;
    }
    int joint = -1;
    if ((e = check_motion_frame(robot, q[i], joint)) != MotionError::kOk) {
      error = path + ": frame " + std::to_string(i) + ": " + to_string(e);
      if (e == MotionError::kJointOutOfLimits) {
        std::snprintf(buf, sizeof buf, ": %s = %.9g rad, limits [%.4f, %.4f] rad", model::joint_name(robot, joint),
                      q[i][7 + joint], robot.limits.position_min_rad[joint], robot.limits.position_max_rad[joint]);
        error += buf;
      } else if (e == MotionError::kBaseImplausible) {
        std::snprintf(buf, sizeof buf,
                      ": position (%.9g, %.9g, %.9g) m (|x|, |y| <= %.0f m, height %.1f..%.1f m), quaternion norm %.9g",
                      q[i][0], q[i][1], q[i][2], kMotionBaseHorizontalMax_m, kMotionBaseHeightMin_m,
                      kMotionBaseHeightMax_m, q[i].segment<4>(3).norm());
        error += buf;
      }
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
