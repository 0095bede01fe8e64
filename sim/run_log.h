// Shared by the closed loops: a CSV writer that hashes exactly the bytes it writes
// (the determinism check compares these hashes) and the fall measure.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "sim/plant.h"
#include "sim/sha256.h"

namespace kuavo::sim {

class RunLog {
 public:
  explicit RunLog(const std::string& path) {
    if (!path.empty()) file_ = std::fopen(path.c_str(), "w");
  }
  ~RunLog() {
    if (file_ != nullptr) std::fclose(file_);
  }
  RunLog(const RunLog&) = delete;
  RunLog& operator=(const RunLog&) = delete;
  bool failed_to_open(const std::string& path) const { return !path.empty() && file_ == nullptr; }
  void write(const char* text, std::size_t n) {
    hash_.update(text, n);
    if (file_ != nullptr) std::fwrite(text, 1, n, file_);
  }
  void write(const std::string& s) { write(s.data(), s.size()); }
  std::string digest() { return hash_.hex_digest(); }

 private:
  std::FILE* file_ = nullptr;
  Sha256 hash_;
};

// Angle between the torso's z axis and the vertical [deg].
inline double tilt_deg(const dynamics::ConfigVector& q) {
  const Eigen::Quaterniond o(q[6], q[3], q[4], q[5]);
  const double cos_tilt = std::clamp((o.toRotationMatrix() * Eigen::Vector3d::UnitZ()).z(), -1.0, 1.0);
  return std::acos(cos_tilt) * 180.0 / 3.14159265358979323846;
}

}  // namespace kuavo::sim
