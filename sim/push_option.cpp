#include "sim/push_option.h"

#include <cstring>
#include <string>

#include "rtos_shim/args.h"

namespace kuavo::sim {

bool parse_push(const char* text, Push& out) {
  if (text == nullptr) return false;
  // Five fields; the separators are checked, so "5:1,2:3,4" and "5:1,2,3:4:5" are refused.
  const std::string s(text);
  const char separators[] = {':', ',', ',', ':'};
  std::string fields[5];
  std::size_t pos = 0;
  for (int k = 0; k < 5; ++k) {
    const std::size_t end = k < 4 ? s.find(separators[k], pos) : s.size();
    if (end == std::string::npos) return false;
    fields[k] = s.substr(pos, end - pos);
    pos = end + 1;
  }
  double t = 0.0, f[3] = {0.0, 0.0, 0.0}, d = 0.0;
  if (!args::parse_number(fields[0].c_str(), 0.0, kPushMaxStart_s, t) ||
      !args::parse_number(fields[4].c_str(), 0.0, kPushMaxDuration_s, d) || !(d > 0.0)) {
    return false;
  }
  for (int i = 0; i < 3; ++i)
    if (!args::parse_number(fields[1 + i].c_str(), -kPushMaxForce_N, kPushMaxForce_N, f[i])) return false;
  out.start_s = t;
  out.duration_s = d;
  out.force_N = Vec3(f[0], f[1], f[2]);
  return true;
}

}  // namespace kuavo::sim
