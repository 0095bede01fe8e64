#include "tools/mocap/contacts.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

namespace kuavo::mocap {
namespace {

// Runs of equal values shorter than min_frames flip to their neighbours' value, shortest
// first, until none is left (deterministic: ties resolve to the earliest run).
void merge_short_runs(std::vector<bool>& s, int min_frames) {
  const int n = static_cast<int>(s.size());
  for (int guard = 0; guard < n; ++guard) {
    int best_start = -1, best_len = min_frames;
    for (int i = 0; i < n;) {
      int j = i;
      while (j < n && s[j] == s[i]) ++j;
      const bool interior = i > 0 && j < n;  // a run touching the clip's ends has no two neighbours
      if (interior && j - i < best_len) {
        best_len = j - i;
        best_start = i;
      }
      i = j;
    }
    if (best_start < 0) return;
    for (int k = best_start; k < best_start + best_len; ++k) s[k] = !s[k];
  }
}

std::vector<bool> detect_foot(const HumanTargets& t, int ankle, int toe, double ankle_h, double toe_h,
                              const ContactThresholds& th) {
  const int n = static_cast<int>(t.frames.size());
  std::vector<bool> contact(n, false);
  bool on = false;
  for (int i = 0; i < n; ++i) {
    const Vec3& a = t.frames[i].position_m[ankle];
    double height = a.z() - ankle_h;
    if (t.present[toe]) height = std::min(height, t.frames[i].position_m[toe].z() - toe_h);
    const int i0 = std::max(0, i - 1), i1 = std::min(n - 1, i + 1);
    const double dt = (i1 - i0) / t.rate_hz;
    const auto horizontal_speed = [&](int kp) {
      const Vec3 d = t.frames[i1].position_m[kp] - t.frames[i0].position_m[kp];
      return dt > 0.0 ? std::hypot(d.x(), d.y()) / dt : 0.0;
    };
    // A foot pivoting on its heel or ball moves the other end: take the faster of the two.
    double speed = horizontal_speed(ankle);
    if (t.present[toe]) speed = std::max(speed, horizontal_speed(toe));
    if (!on && height < th.touchdown_height_m && speed < th.touchdown_speed_m_s)
      on = true;
    else if (on && (height > th.liftoff_height_m || speed > th.liftoff_speed_m_s))
      on = false;
    contact[i] = on;
  }
  merge_short_runs(contact, std::max(1, static_cast<int>(std::lround(th.min_phase_s * t.rate_hz))));
  return contact;
}

}  // namespace

const char* to_string(ContactLabel c) {
  switch (c) {
    case ContactLabel::kFlight:
      return "flight";
    case ContactLabel::kLeftSupport:
      return "left";
    case ContactLabel::kRightSupport:
      return "right";
    case ContactLabel::kDoubleSupport:
      return "double";
  }
  return "?";
}

bool parse_contact_label(const std::string& text, ContactLabel& out) {
  for (ContactLabel c :
       {ContactLabel::kFlight, ContactLabel::kLeftSupport, ContactLabel::kRightSupport, ContactLabel::kDoubleSupport}) {
    if (text == to_string(c)) {
      out = c;
      return true;
    }
  }
  return false;
}

std::vector<ContactLabel> detect_contacts(const HumanTargets& targets, const model::Model& robot,
                                          const ContactThresholds& thresholds) {
  const double ankle_h = robot_ankle_height_m(robot), toe_h = robot_toe_height_m(robot);
  const auto left = detect_foot(targets, kKpLeftAnkle, kKpLeftToe, ankle_h, toe_h, thresholds);
  const auto right = detect_foot(targets, kKpRightAnkle, kKpRightToe, ankle_h, toe_h, thresholds);
  std::vector<ContactLabel> labels(targets.frames.size());
  for (std::size_t i = 0; i < labels.size(); ++i) labels[i] = make_label(left[i], right[i]);
  return labels;
}

bool apply_contact_overrides(const std::string& text, double rate_hz, std::vector<ContactLabel>& labels,
                             std::string& error) {
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream fields(line);
    std::string a, b, label, extra;
    if (!(fields >> a)) continue;
    const std::string where = "contacts line " + std::to_string(line_no) + ": ";
    if (!(fields >> b >> label) || (fields >> extra)) {
      error = where + "expected 'start_s end_s label'";
      return false;
    }
    double t0 = 0.0, t1 = 0.0;
    const auto num = [](const std::string& s, double& v) {
      const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
      return r.ec == std::errc() && r.ptr == s.data() + s.size() && std::isfinite(v);
    };
    if (!num(a, t0) || !num(b, t1) || t0 < 0.0 || !(t1 > t0)) {
      error = where + "times must be numbers with 0 <= start_s < end_s, got '" + a + "' '" + b + "'";
      return false;
    }
    ContactLabel c{};
    if (!parse_contact_label(label, c)) {
      error = where + "unknown label '" + label + "' (expected flight, left, right or double)";
      return false;
    }
    for (std::size_t i = 0; i < labels.size(); ++i) {
      const double t = static_cast<double>(i) / rate_hz;
      if (t >= t0 - 1e-9 && t < t1 - 1e-9) labels[i] = c;
    }
  }
  return true;
}

int count_contact_phases(const std::vector<ContactLabel>& labels) {
  int phases = 0;
  for (std::size_t i = 0; i < labels.size(); ++i)
    if (i == 0 || labels[i] != labels[i - 1]) ++phases;
  return phases;
}

}  // namespace kuavo::mocap
