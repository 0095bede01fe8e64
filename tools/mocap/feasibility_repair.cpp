#include "tools/mocap/feasibility_repair.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <limits>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

#include "tools/mocap/leg_ik_lm.h"
#include "controllers/standing/standing_controller.h"

namespace kuavo::mocap {
namespace {

using dynamics::ConfigVector;
using dynamics::Mat3;
using dynamics::Vec3;

constexpr double kPi = 3.14159265358979323846;
constexpr int kFeet = 2;
constexpr int kCorners = model::kNumContactPoints / kFeet;
// A stance foot the legs miss by more than this is lowered toward (base lowered 1 cm a try).
constexpr double kStanceIkTolerance_m = 2e-3;
constexpr double kBaseLowerStep_m = 0.01;
constexpr int kMaxBaseLowerSteps = 20;
// The knee-bend lowering of the pelvis is spread over this either side [s], and reported
// where it exceeds kPelvisReport_m.
constexpr double kPelvisBlend_s = 0.25;
// How far the pelvis moves towards standing over its stance feet where a stance foot is out
// of reach (fractions of the way, tried in order; the least that reaches is kept).
constexpr double kReachSteps[] = {0.25, 0.5, 0.75, 1.0};
constexpr double kPelvisReport_m = 0.005;
// The pelvis stays within this of the feet midpoint's human offset [m] (a weight shift; a
// pelvis that flew ahead in a leap is brought back over the feet).
constexpr double kMaxPelvisOffset_m = 0.20;
// Swing-foot gesture ramps in and out over this, so a foot leaves and lands on the arc [s].
constexpr double kGestureRamp_s = 0.15;
// A touchdown moved by less than this is not reported (placement noise) [m, rad].
constexpr double kReportMove_m = 0.01;
constexpr double kReportTurn_rad = 0.05;
// Repairs of one kind closer than this are listed as one [s].
constexpr double kMergeGap_s = 0.05;

double wrap(double a) { return std::remainder(a, 2.0 * kPi); }
double smooth_step(double s) {
  s = std::clamp(s, 0.0, 1.0);
  return s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
}
Mat3 rot_z(double yaw) { return Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix(); }

struct FootPose {
  Vec3 centre = Vec3::Zero();  // sole centre, world (z: its height above the floor)
  double yaw = 0.0;
};

// Sole centre and heading of both feet at q.
std::array<FootPose, kFeet> foot_poses(const model::Model& robot, dynamics::Data& data, const ConfigVector& q) {
  dynamics::forward_kinematics(robot, data, q);
  std::array<FootPose, kFeet> out;
  for (int f = 0; f < kFeet; ++f) {
    Vec3 c = Vec3::Zero();
    for (int k = 0; k < kCorners; ++k) c += dynamics::frame_position(robot, data, f * kCorners + k);
    out[f].centre = c / kCorners;
    const Mat3 r = data.rotation[robot.frames[f * kCorners].body];
    out[f].yaw = std::atan2(r(1, 0), r(0, 0));
  }
  return out;
}

struct Interval {
  int a = 0, b = 0;  // frames [a, b)
  FootPose pose;
  bool placed = false;
};

class RepairLog {
 public:
  explicit RepairLog(double rate_hz) : rate_hz_(rate_hz) {}
  void add(RepairKind kind, int frame_a, int frame_b, const std::string& reason) {
    const double a = frame_a / rate_hz_, b = frame_b / rate_hz_;
    for (auto it = list_.rbegin(); it != list_.rend(); ++it) {
      if (it->kind == kind && a <= it->end_s + kMergeGap_s && it->reason == reason) {
        it->end_s = std::max(it->end_s, b);
        return;
      }
    }
    list_.push_back({a, b, kind, reason});
  }
  std::vector<Repair> take() {
    std::stable_sort(list_.begin(), list_.end(), [](const Repair& x, const Repair& y) { return x.start_s < y.start_s; });
    return std::move(list_);
  }

 private:
  double rate_hz_;
  std::vector<Repair> list_;
};

std::string fmt(const char* f, double a, double b = 0.0, double c = 0.0, double d = 0.0) {
  char buf[320];
  std::snprintf(buf, sizeof buf, f, a, b, c, d);
  return buf;
}

// Limits joint j's second differences to a_max: frames where |q̈| exceeds it (and 3 frames
// around) are smoothed by [¼ ½ ¼] passes until none does (at most 200 passes; a
// straight-line fill is what remains of a jump). Marks the frames it changed; false if none.
template <class V>
bool limit_acceleration(std::vector<V>& x, int j, double a_max, double rate_hz, std::vector<bool>& changed) {
  const int n = static_cast<int>(x.size());
  const double limit = a_max / (rate_hz * rate_hz);
  bool any = false;
  std::vector<double> y(n);
  std::vector<bool> mark(n);
  for (int pass = 0; pass < 200; ++pass) {
    std::fill(mark.begin(), mark.end(), false);
    bool over = false;
    for (int i = 1; i + 1 < n; ++i) {
      if (std::abs(x[i + 1][j] - 2.0 * x[i][j] + x[i - 1][j]) > limit * (1.0 + 1e-9)) {
        over = true;
        for (int k = std::max(1, i - 3); k <= std::min(n - 2, i + 3); ++k) mark[k] = true;
      }
    }
    if (!over) break;
    any = true;
    for (int i = 0; i < n; ++i) y[i] = x[i][j];
    for (int i = 1; i + 1 < n; ++i) {
      if (!mark[i]) continue;
      x[i][j] = 0.25 * y[i - 1] + 0.5 * y[i] + 0.25 * y[i + 1];
      changed[i] = true;
    }
  }
  return any;
}

// An override with `flag` set (force_double, calm_steps, square_stance) covers dance time t [s].
bool covers(const std::vector<RepairOverride>& overrides, bool RepairOverride::*flag, double t) {
  for (const RepairOverride& o : overrides) {
    if (o.*flag && t >= o.start_s && t < o.end_s) return true;
  }
  return false;
}

// An override forbids `kind` at dance time t [s].
bool forbids(const std::vector<RepairOverride>& overrides, RepairKind kind, double t) {
  for (const RepairOverride& o : overrides) {
    if (t >= o.start_s && t < o.end_s && !o.force_double && !o.calm_steps && (o.forbid_all || o.forbid == kind)) {
      return true;
    }
  }
  return false;
}

// need spread over ±w frames: a running maximum, then its moving average (never below what a
// frame needs, no step between frames).
std::vector<double> spread_over(const std::vector<double>& need, int w) {
  const int n = static_cast<int>(need.size());
  std::vector<double> peak(n, 0.0), out(n, 0.0);
  for (int i = 0; i < n; ++i) {
    for (int j = std::max(0, i - w); j <= std::min(n - 1, i + w); ++j) peak[i] = std::max(peak[i], need[j]);
  }
  for (int i = 0; i < n; ++i) {
    double sum = 0.0;
    for (int j = i - w; j <= i + w; ++j) sum += peak[std::clamp(j, 0, n - 1)];
    out[i] = sum / (2 * w + 1);
  }
  return out;
}

}  // namespace

const char* to_string(RepairKind k) {
  switch (k) {
    case RepairKind::kLeadIn: return "lead_in";
    case RepairKind::kFlight: return "flight_to_support";
    case RepairKind::kRetime: return "retime";
    case RepairKind::kStepSkipped: return "step_skipped";
    case RepairKind::kStride: return "stride";
    case RepairKind::kTurn: return "turn";
    case RepairKind::kTilt: return "tilt";
    case RepairKind::kTail: return "tail";
    case RepairKind::kForcedDouble: return "forced_double_support";
    case RepairKind::kUpperBodySpeed: return "upper_body_speed";
    case RepairKind::kPelvisHeight: return "pelvis_height";
    case RepairKind::kTravel: return "travel_speed";
    case RepairKind::kAttenuate: return "attenuate";
    case RepairKind::kBounce: return "bounce";
    case RepairKind::kStanceReach: return "stance_reach";
    case RepairKind::kStanceLean: return "stance_lean";
  }
  return "unknown";
}

bool parse_repair_overrides(const std::string& text, std::vector<RepairOverride>& out, std::string& error) {
  std::istringstream in(text);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    std::string a, b, verb, what, extra;
    if (!(ls >> a)) continue;
    RepairOverride o;
    char* end = nullptr;
    o.start_s = std::strtod(a.c_str(), &end);
    bool ok = end && *end == '\0' && (ls >> b);
    if (ok) {
      o.end_s = std::strtod(b.c_str(), &end);
      ok = end && *end == '\0';
    }
    ok = ok && (ls >> verb >> what) && !(ls >> extra) && std::isfinite(o.start_s) && std::isfinite(o.end_s) &&
         o.start_s >= 0.0 && o.end_s > o.start_s;
    if (ok && verb == "force") {
      ok = what == "double" || what == "square";
      o.force_double = true;
      o.square_stance = what == "square";
    } else if (ok && verb == "calm") {
      ok = what == "steps";
      o.calm_steps = true;
    } else if (ok && verb == "forbid") {
      if (what == "all") o.forbid_all = true;
      else if (what == "flight") o.forbid = RepairKind::kFlight;
      else if (what == "retime") o.forbid = RepairKind::kRetime;
      else if (what == "stride") o.forbid = RepairKind::kStride;
      else if (what == "turn") o.forbid = RepairKind::kTurn;
      else if (what == "upper") o.forbid = RepairKind::kUpperBodySpeed;
      else if (what == "pelvis") o.forbid = RepairKind::kPelvisHeight;
      else if (what == "travel") o.forbid = RepairKind::kTravel;
      else if (what == "attenuate") o.forbid = RepairKind::kAttenuate;
      else if (what == "bounce") o.forbid = RepairKind::kBounce;
      else if (what == "reach") o.forbid = RepairKind::kStanceReach;
      else if (what == "lean") o.forbid = RepairKind::kStanceLean;
      else ok = false;
    } else {
      ok = false;
    }
    if (!ok) {
      error = "line " + std::to_string(n) +
              ": expected 'START_S END_S forbid flight|retime|stride|turn|upper|pelvis|bounce|travel|attenuate|reach|lean|all', 'START_S END_S force double|square' "
              "or 'START_S END_S calm steps' (0 <= START_S < END_S)";
      return false;
    }
    out.push_back(o);
  }
  return true;
}

int count_steps(const std::vector<ContactLabel>& labels) {
  int steps = 0;
  for (std::size_t i = 1; i < labels.size(); ++i) {
    steps += (left_in_contact(labels[i - 1]) && !left_in_contact(labels[i])) ? 1 : 0;
    steps += (right_in_contact(labels[i - 1]) && !right_in_contact(labels[i])) ? 1 : 0;
  }
  return steps;
}

bool repair_motion(const model::Model& robot, const std::vector<ConfigVector>& geometric,
                   const std::vector<ContactLabel>& labels, double rate_hz, const RepairConfig& cfg,
                   const std::vector<RepairOverride>& overrides, RepairedMotion& out, std::string& error) {
  const int n_dance = static_cast<int>(geometric.size());
  if (n_dance < 2 || labels.size() != geometric.size()) {
    error = "repair: the geometric motion needs at least 2 frames and one contact label per frame";
    return false;
  }
  if (!(rate_hz >= 10.0 && rate_hz <= 1000.0)) {
    error = "repair: frame rate must be in [10, 1000] Hz";
    return false;
  }
  for (int i = 0; i < n_dance; ++i) {
    if (!geometric[i].allFinite()) {
      error = "repair: geometric frame " + std::to_string(i) + " is not finite";
      return false;
    }
  }
  const auto frames_of = [&](double s) { return static_cast<int>(std::lround(s * rate_hz)); };
  const int lead = frames_of(cfg.lead_in_s + cfg.blend_in_s);
  const int blend_start = frames_of(cfg.lead_in_s);
  const int tail = frames_of(cfg.tail_s);
  const int n = lead + n_dance + tail;
  const int min_swing = std::max(1, frames_of(cfg.min_swing_s));
  const int min_ds = std::max(1, frames_of(cfg.min_double_support_s));
  const auto dance_frame = [&](int i) { return std::clamp(i - lead, 0, n_dance - 1); };
  const auto in_dance = [&](int i) { return i >= lead && i < lead + n_dance; };
  const auto dance_time = [&](int i) { return (i - lead) / rate_hz; };
  const auto forbidden = [&](RepairKind kind, int i) { return in_dance(i) && forbids(overrides, kind, dance_time(i)); };
  const auto forced_double = [&](int i) {
    return in_dance(i) && covers(overrides, &RepairOverride::force_double, dance_time(i));
  };

  // A touchdown in the lead-in or the tail counts as the dance's first or last frame (the tail
  // takes the human's last step: cmu_05_07's landed 0.40 m ahead, 0.45 m beside the other foot).
  const auto calm = [&](int i) {
    return covers(overrides, &RepairOverride::calm_steps, dance_time(std::clamp(i, lead, lead + n_dance - 1)));
  };
  const auto square = [&](int i) {
    return in_dance(i) && covers(overrides, &RepairOverride::square_stance, dance_time(i));
  };
  const auto square_over = [&](const Interval& s) {  // a square hold meets [s.a, s.b)
    for (int i = s.a; i < s.b; ++i) {
      if (square(i)) return true;
    }
    return false;
  };

  RepairLog log(rate_hz);
  auto data = std::make_unique<dynamics::Data>();

  // Human (geometric) feet and the schedule it asks for.
  std::vector<std::array<FootPose, kFeet>> human(n_dance);
  for (int d = 0; d < n_dance; ++d) human[d] = foot_poses(robot, *data, geometric[d]);
  std::vector<std::array<bool, kFeet>> want(n);
  for (int i = 0; i < n; ++i) {
    if (!in_dance(i) || forced_double(i)) {
      want[i] = {true, true};
    } else {
      const ContactLabel c = labels[dance_frame(i)];
      want[i] = {left_in_contact(c), right_in_contact(c)};
    }
  }
  log.add(RepairKind::kLeadIn, 0, lead,
          fmt("the motion starts standing in double support (%.1f s) and blends into the dance's first pose (%.1f s)",
              cfg.lead_in_s, cfg.blend_in_s));
  for (int i = 0; i < n; ++i) {
    if (forced_double(i)) log.add(RepairKind::kForcedDouble, i, i + 1, "override: both feet down");
  }

  // 1. The schedule: a state machine that follows the human's wish frame by frame within
  // the robot's minimum swing and double-support times, never in flight.
  std::vector<std::array<bool, kFeet>> on(n);
  std::array<bool, kFeet> state{true, true};
  int in_state = min_ds;  // frames since the last change
  for (int i = 0; i < n; ++i) {
    const auto w = want[i];
    const bool both = state[0] && state[1];
    ++in_state;
    auto change = [&](std::array<bool, kFeet> s) {
      state = s;
      in_state = 0;
    };
    if (!w[0] && !w[1]) {
      if (forbidden(RepairKind::kFlight, i)) {
        change({false, false});
      } else {
        // A leap keeps its last foot down; its lifted foot comes down after the robot's
        // shortest swing (a flight longer than that is no leap the robot can stand through on
        // one leg: cmu_05_07's 1.7 s "flight" at 7.3 s, a fall on one leg at 8.0 s).
        const bool land = !both && (state[0] || state[1]) && in_state >= min_swing;
        log.add(RepairKind::kFlight, i, i + 1,
                both ? "both feet in the air (hop): kept in double support, the pelvis keeps its bounce"
                : land ? "both feet in the air (long leap): the lifted foot comes down after the robot's shortest swing"
                       : "both feet in the air (leap): the last foot stays down until the other lands");
        if ((!state[0] && !state[1]) || land) change({true, true});
      }
    } else if (!state[0] && !state[1]) {
      change(w);  // an allowed flight ends wherever the human lands
    } else if (both) {
      if (w[0] != w[1]) {
        if (in_state >= min_ds || forbidden(RepairKind::kRetime, i)) {
          change(w);
        } else {
          log.add(RepairKind::kRetime, i, i + 1, "double support lengthened to the robot's weight transfer time");
        }
      }
    } else {
      const int swing = state[0] ? 1 : 0;
      if (w[swing]) {  // the human's swing foot is down (touchdown, or a switch of feet)
        if (in_state >= min_swing || forbidden(RepairKind::kRetime, i)) {
          change({true, true});
        } else {
          log.add(RepairKind::kRetime, i, i + 1, "swing lengthened to the robot's shortest step");
        }
      }
    }
    on[i] = state;
  }
  // The human's own steps that the robot never took.
  for (int f = 0; f < kFeet; ++f) {
    for (int i = lead + 1; i < lead + n_dance; ++i) {
      if (want[i - 1][f] && !want[i][f]) {
        int j = i;
        while (j < lead + n_dance && !want[j][f]) ++j;
        bool lifted = false;
        for (int k = std::max(0, i - min_swing); k < std::min(n, j + min_swing); ++k) lifted |= !on[k][f];
        if (!lifted) log.add(RepairKind::kStepSkipped, i, j, "a human step too short to fit the robot's timing");
        i = j;
      }
    }
  }

  // 2. Stance intervals per foot and their footholds.
  std::array<std::vector<Interval>, kFeet> stance;
  for (int f = 0; f < kFeet; ++f) {
    for (int i = 0; i < n;) {
      if (!on[i][f]) {
        ++i;
        continue;
      }
      Interval iv;
      iv.a = i;
      while (i < n && on[i][f]) ++i;
      iv.b = i;
      // Where the human had this foot down during the interval (inside the dance).
      Vec3 sum = Vec3::Zero();
      double sc = 0.0, ss = 0.0;
      int count = 0;
      for (int k = std::max(iv.a, lead); k < std::min(iv.b, lead + n_dance); ++k) {
        if (!want[k][f]) continue;
        const FootPose& p = human[dance_frame(k)][f];
        sum += p.centre;
        sc += std::cos(p.yaw);
        ss += std::sin(p.yaw);
        ++count;
      }
      if (count > 0) {
        iv.pose.centre = sum / count;
        iv.pose.yaw = std::atan2(ss, sc);
        iv.placed = true;
      } else if (iv.a >= lead) {
        iv.pose = human[dance_frame(iv.a)][f];
        iv.placed = true;
      }
      iv.pose.centre.z() = 0.0;
      stance[f].push_back(iv);
    }
  }
  // Pivots: the human stance foot turning while the robot's stays planted.
  for (int f = 0; f < kFeet; ++f) {
    for (const Interval& iv : stance[f]) {
      double lo = 0.0, hi = 0.0;
      const int a = std::max(iv.a, lead), b = std::min(iv.b, lead + n_dance);
      for (int k = a; k < b; ++k) {
        const double d = wrap(human[dance_frame(k)][f].yaw - iv.pose.yaw);
        lo = std::min(lo, d);
        hi = std::max(hi, d);
      }
      if (hi - lo > cfg.pivot_yaw_rad) {
        log.add(RepairKind::kTurn, a, b,
                std::string(f == 0 ? "left" : "right") +
                    fmt(" foot pivots %.0f deg: it stays at its touchdown heading, the following steps turn",
                        (hi - lo) * 180.0 / kPi));
      }
    }
  }

  // Reachability of each touchdown from the other foot's foothold, in time order.
  dynamics::ConfigVector q_stand = dynamics::neutral_configuration(robot);
  q_stand.tail<model::kNumJoints>() =
      control::centred_standing_pose(robot, *data, control::StandingConfig{}.base_height_m);
  control::place_on_ground(robot, *data, q_stand);
  const auto stand_feet = foot_poses(robot, *data, q_stand);
  const double stand_width = stand_feet[0].centre.y() - stand_feet[1].centre.y();
  const Vec3 stand_base_from_mid = q_stand.head<3>() - 0.5 * (stand_feet[0].centre + stand_feet[1].centre);

  const auto stance_at = [&](int f, int i) -> Interval* {
    for (Interval& iv : stance[f]) {
      if (i >= iv.a && i < iv.b) return &iv;
    }
    return nullptr;
  };
  // Sets a foot down square beside the other (the standing width and heading); returns, for
  // the log, how far that moved it from its foothold.
  const auto set_square = [&](Interval& iv, const Interval& other, double side) {
    const FootPose before = iv.pose;
    iv.pose.yaw = other.pose.yaw;
    iv.pose.centre = other.pose.centre + rot_z(other.pose.yaw) * Vec3(0.0, side * stand_width, 0.0);
    return fmt(", %.2f m and %.0f deg from the human's foothold", (before.centre - iv.pose.centre).norm(),
               std::abs(wrap(before.yaw - iv.pose.yaw)) * 180.0 / kPi);
  };
  // The first footholds: a foot without a human foothold stands beside the other.
  for (int f = 0; f < kFeet; ++f) {
    Interval& iv = stance[f].front();
    if (iv.placed) continue;
    set_square(iv, stance[1 - f].front(), f == 0 ? 1.0 : -1.0);
    iv.placed = true;
  }
  struct Touchdown {
    int frame, foot;
    std::size_t index;
  };
  std::vector<Touchdown> touchdowns;
  for (int f = 0; f < kFeet; ++f) {
    for (std::size_t k = 0; k < stance[f].size(); ++k) touchdowns.push_back({stance[f][k].a, f, k});
  }
  std::stable_sort(touchdowns.begin(), touchdowns.end(),
                   [](const Touchdown& x, const Touchdown& y) { return x.frame < y.frame; });
  for (const Touchdown& td : touchdowns) {
    if (td.frame == 0 && td.foot == 0) continue;  // the first foothold of the left foot is the anchor
    Interval& iv = stance[td.foot][td.index];
    const Interval* other = stance_at(1 - td.foot, td.frame);
    if (other == nullptr) continue;  // an allowed flight: nothing to place against
    const double side = td.foot == 0 ? 1.0 : -1.0;
    // A square hold: the later of the two feet standing into it is set down beside the earlier
    // (the travel and stride limits below still apply to the step that brings it there).
    if (square_over(iv) && square_over(*other)) {
      const std::string moved = set_square(iv, *other, side);
      log.add(RepairKind::kForcedDouble, td.frame, iv.b,
              std::string("square hold: the ") +
                  (td.foot == 0 ? "left foot aimed beside the right" : "right foot aimed beside the left") + moved);
    }
    // The motion ends standing: a step landing in the tail is set down square (the travel and
    // stride limits below apply as to any step). cmu_05_07's last step, 0.30 m ahead, 0.35 m
    // beside and 46 deg turned from the other foot (after the limits), left the robot to stand
    // its last second in that stance, the pelvis 16 cm down: with the check on the sinking
    // stage (stop 80, motion a7d2ff1a) 4 of its 8 show-campaign falls came there, 12.9-13.5 s,
    // the motion ending at 12.71 s; squared, none after 8.3 s (d0046b7a: 2/100).
    if (cfg.square_tail_step && td.frame >= lead + n_dance) {
      const std::string moved = set_square(iv, *other, side);
      log.add(RepairKind::kTail, td.frame, iv.b,
              std::string("the step landing after the dance ends square: the ") +
                  (td.foot == 0 ? "left foot beside the right" : "right foot beside the left") + moved);
    }
    // Travel speed: from this foot's previous foothold, no farther than the speed limit over
    // the time since that touchdown (the stride check below may move it again).
    const bool calm_here = calm(td.frame);
    const double travel_speed = calm_here && cfg.max_travel_speed_m_s > 0.0
                                    ? std::min(cfg.max_travel_speed_m_s, cfg.calm_travel_speed_m_s)
                                    : cfg.max_travel_speed_m_s;
    const char* calm_note = calm_here ? ", calm steps" : "";
    if (travel_speed > 0.0 && td.index > 0 && !forbidden(RepairKind::kTravel, td.frame)) {
      const Interval& prev = stance[td.foot][td.index - 1];
      Vec3 step = iv.pose.centre - prev.pose.centre;
      step.z() = 0.0;
      const double most = travel_speed * (iv.a - prev.a) / rate_hz;
      if (step.norm() > most + kReportMove_m) {
        iv.pose.centre.head<2>() = prev.pose.centre.head<2>() + (most / step.norm()) * step.head<2>();
        log.add(RepairKind::kTravel, td.frame, iv.b,
                fmt("step of %.2f m in %.2f s shortened to %.2f m (travel at most %.2f m/s", step.norm(),
                    (iv.a - prev.a) / rate_hz, most, travel_speed) + calm_note + ")");
      }
    }
    const Mat3 r = rot_z(other->pose.yaw);
    Vec3 d = r.transpose() * (iv.pose.centre - other->pose.centre);
    const Vec3 d0 = d;
    const double forward = calm_here ? std::min(cfg.max_step_forward_m, cfg.calm_step_forward_m) : cfg.max_step_forward_m;
    const double backward = calm_here ? std::min(cfg.max_step_backward_m, cfg.calm_step_backward_m) : cfg.max_step_backward_m;
    const double widest = calm_here ? std::min(cfg.max_step_width_m, cfg.calm_step_width_m) : cfg.max_step_width_m;
    d.x() = std::clamp(d.x(), -backward, forward);
    d.y() = side * std::clamp(side * d.y(), cfg.min_step_width_m, widest);
    d.z() = 0.0;
    double rel = wrap(iv.pose.yaw - other->pose.yaw);
    const double rel0 = rel;
    rel = std::clamp(rel, -cfg.max_relative_yaw_rad, cfg.max_relative_yaw_rad);
    const bool moved = (d - Vec3(d0.x(), d0.y(), 0.0)).norm() > kReportMove_m;
    const bool turned = std::abs(rel - rel0) > kReportTurn_rad;
    if (moved && !forbidden(RepairKind::kStride, td.frame)) {
      iv.pose.centre = other->pose.centre + r * d;
      log.add(RepairKind::kStride, td.frame, iv.b,
              fmt("touchdown %.2f m from the human's, to a spot the legs reach (%.2f m ahead, %.2f m beside the "
                  "stance foot",
                  (d - Vec3(d0.x(), d0.y(), 0.0)).norm(), d.x(), side * d.y()) + calm_note + ")");
    }
    if (turned && !forbidden(RepairKind::kTurn, td.frame)) {
      iv.pose.yaw = other->pose.yaw + rel;
      log.add(RepairKind::kTurn, td.frame, iv.b,
              fmt("feet %.0f deg apart in heading, limited to %.0f deg (hip yaw range): the turn goes on in the "
                  "next steps",
                  std::abs(rel0) * 180.0 / kPi, cfg.max_relative_yaw_rad * 180.0 / kPi));
    }
  }

  // 3. Feet, frame by frame: stance at the foothold, swing from foothold to foothold, raised
  // to the arc and following the human's gesture in between.
  const int ramp = std::max(1, frames_of(kGestureRamp_s));
  std::vector<std::array<FootPose, kFeet>> feet(n);
  for (int f = 0; f < kFeet; ++f) {
    const auto& list = stance[f];
    for (std::size_t k = 0; k < list.size(); ++k) {
      for (int i = list[k].a; i < list[k].b; ++i) feet[i][f] = list[k].pose;
      if (k + 1 == list.size()) {
        for (int i = list[k].b; i < n; ++i) feet[i][f] = list[k].pose;  // an allowed flight to the end
        continue;
      }
      const Interval& p = list[k];
      const Interval& nx = list[k + 1];
      const int b0 = p.b - 1, a1 = nx.a;  // last stance frame, first stance frame
      const FootPose& h0 = human[dance_frame(b0)][f];
      const FootPose& h1 = human[dance_frame(a1)][f];
      for (int i = p.b; i < nx.a; ++i) {
        const double s = static_cast<double>(i - b0) / (a1 - b0);
        const double w = smooth_step(s);
        FootPose fp;
        fp.centre = p.pose.centre + w * (nx.pose.centre - p.pose.centre);
        fp.yaw = p.pose.yaw + w * wrap(nx.pose.yaw - p.pose.yaw);
        // The human's gesture: its foot's departure from its own line between lift and land.
        const double g = smooth_step(static_cast<double>(std::min(i - b0, a1 - i)) / ramp);
        const FootPose& h = human[dance_frame(i)][f];
        Vec3 gesture = h.centre - (h0.centre + s * (h1.centre - h0.centre));
        gesture.z() = 0.0;
        fp.centre += g * gesture;
        const double arc = cfg.swing_lift_m * std::sin(kPi * s);
        fp.centre.z() = std::max(arc, g * std::clamp(h.centre.z(), 0.0, cfg.max_foot_height_m));
        feet[i][f] = fp;
      }
    }
    for (int i = 0; i < stance[f].front().a; ++i) feet[i][f] = stance[f].front().pose;
  }

  // 4. Base and legs. The pelvis keeps the human's offset from its feet midpoint (bounded),
  // height, tilt (bounded) and yaw within the hip-yaw range of the stance feet; arms and
  // head as geometric; legs by IK to the feet.
  // The mean heading of frame i's feet on the floor; false with none down.
  const auto stance_yaw = [&](int i, double& yaw) {
    double sc = 0.0, ss = 0.0;
    for (int f = 0; f < kFeet; ++f) {
      if (!on[i][f]) continue;
      sc += std::cos(feet[i][f].yaw);
      ss += std::sin(feet[i][f].yaw);
    }
    yaw = std::atan2(ss, sc);
    return sc != 0.0 || ss != 0.0;
  };
  // The mean heading of frame i's two feet, down or not (the standing pose over them).
  const auto feet_yaw = [&](int i) {
    return std::atan2(std::sin(feet[i][0].yaw) + std::sin(feet[i][1].yaw),
                      std::cos(feet[i][0].yaw) + std::cos(feet[i][1].yaw));
  };
  std::vector<Vec3> base_pos(n);
  std::vector<Mat3> base_rot(n);
  std::vector<double> tilt_over(n, 0.0);  // the human's tilt where it was limited [rad]
  // A square hold's pelvis: over its feet as in standing over the whole range, eased in over
  // the 2·kPelvisBlend_s before it and out over the 2·kPelvisBlend_s after it (spread_over),
  // so through the swing that brings the later foot in and the first lift-off after it. Eased
  // inside the range instead (both feet down, the single supports around it left the human's
  // weight shift), the show campaign fell more, at the hold's end: cmu_05_07 9/60 and
  // cmu_05_20 5/60 against 8/60 and 3/60 (seeds 1–60, 3 + 2 falls at the hold's end).
  std::vector<double> centred(n, 0.0);
  for (int i = 0; i < n; ++i) centred[i] = square(i) ? 1.0 : 0.0;
  centred = spread_over(centred, std::max(1, frames_of(kPelvisBlend_s)));
  for (int i = 0; i < n; ++i) {
    const int d = dance_frame(i);
    const ConfigVector& g = geometric[d];
    const Vec3 human_mid = 0.5 * (human[d][0].centre + human[d][1].centre);
    const Vec3 robot_mid = 0.5 * (feet[i][0].centre + feet[i][1].centre);
    Vec3 offset = g.head<3>() - human_mid;
    offset.z() = 0.0;
    if (offset.norm() > kMaxPelvisOffset_m) offset *= kMaxPelvisOffset_m / offset.norm();
    if (centred[i] > 0.0) {
      Vec3 standing = rot_z(feet_yaw(i)) * stand_base_from_mid;
      standing.z() = 0.0;
      offset += centred[i] * (standing - offset);
    }
    Vec3 pos = robot_mid + offset;
    pos.z() = g[2];
    Eigen::Quaterniond qb(g[6], g[3], g[4], g[5]);
    Mat3 rot = qb.normalized().toRotationMatrix();
    // Tilt: the angle between the base z axis and the world z.
    const double tilt = std::acos(std::clamp(rot(2, 2), -1.0, 1.0));
    if (tilt > cfg.max_base_tilt_rad && in_dance(i)) {
      const Vec3 axis = rot.col(2).cross(Vec3::UnitZ());
      if (axis.norm() > 1e-9) {
        rot = Eigen::AngleAxisd(tilt - cfg.max_base_tilt_rad, axis.normalized()).toRotationMatrix() * rot;
      }
      tilt_over[i] = tilt;
    }
    // Yaw within the stance feet's hip-yaw range (mean of the feet on the floor).
    double feet_yaw = 0.0;
    if (stance_yaw(i, feet_yaw)) {
      const double yaw = std::atan2(rot(1, 0), rot(0, 0));
      const double rel = wrap(yaw - feet_yaw);
      const double limit = 0.5 * cfg.max_relative_yaw_rad + 0.1;
      const double rel_c = std::clamp(rel, -limit, limit);
      if (rel_c != rel) rot = rot_z(rel_c - rel) * rot;
    }
    base_pos[i] = pos;
    base_rot[i] = rot;
  }
  // One entry per run of tilted frames, with its largest tilt.
  for (int a = 0; a < n;) {
    if (tilt_over[a] <= 0.0) {
      ++a;
      continue;
    }
    int b = a;
    double worst = 0.0;
    while (b < n && tilt_over[b] > 0.0) worst = std::max(worst, tilt_over[b++]);
    log.add(RepairKind::kTilt, a, b,
            fmt("pelvis tilted up to %.0f deg, limited to %.0f deg", worst * 180.0 / kPi, cfg.max_base_tilt_rad * 180.0 / kPi));
    a = b;
  }
  // Stance knees within [min_stance_knee_rad, max_stance_knee_rad]: the pelvis comes down
  // where a stance leg (hip pitch to ankle pitch) would stretch beyond the length its least
  // knee bend gives, and up where it would fold below the length its deepest bend gives. Each
  // spread over ±kPelvisBlend_s (a running maximum, then its moving average: never below what
  // a frame needs, no step in the base height); a frame that needs both (a lunge) gets their
  // sum.
  std::vector<double> knee_lower(n, 0.0);  // how far the knee bend lowered each frame's pelvis
  if (cfg.min_stance_knee_rad > 0.0 || cfg.max_stance_knee_rad > 0.0) {
    dynamics::forward_kinematics(robot, *data, q_stand);
    std::array<Vec3, kFeet> hip_in_base, ankle_from_sole;
    double thigh = 0.0, shank = 0.0;
    const Mat3 r0 = Eigen::Quaterniond(q_stand[6], q_stand[3], q_stand[4], q_stand[5]).normalized().toRotationMatrix();
    for (int f = 0; f < kFeet; ++f) {
      const int hip = 1 + f * model::kLegJoints + 2, knee = hip + 1, ankle = hip + 2;  // bodies of joints 3, 4, 5
      hip_in_base[f] = r0.transpose() * (data->position_m[hip] - q_stand.head<3>());
      ankle_from_sole[f] = rot_z(-stand_feet[f].yaw) * (data->position_m[ankle] - stand_feet[f].centre);
      thigh = (data->position_m[knee] - data->position_m[hip]).norm();
      shank = (data->position_m[ankle] - data->position_m[knee]).norm();
    }
    const auto leg_length = [&](double knee) {
      return std::sqrt(thigh * thigh + shank * shank + 2.0 * thigh * shank * std::cos(knee));
    };
    const double longest = cfg.min_stance_knee_rad > 0.0 ? leg_length(cfg.min_stance_knee_rad) : thigh + shank;
    const double shortest = cfg.max_stance_knee_rad > 0.0 ? leg_length(cfg.max_stance_knee_rad) : 0.0;
    std::vector<double> need_down(n, 0.0), need_up(n, 0.0);
    for (int i = 0; i < n; ++i) {
      // The lead-in and tail frames too: they blend from standing into the first (out of the
      // last) dance pose, which must be the corrected one (or not, as that pose's override says).
      if (forbidden(RepairKind::kPelvisHeight, std::clamp(i, lead, lead + n_dance - 1))) continue;
      for (int f = 0; f < kFeet; ++f) {
        if (!on[i][f]) continue;
        const Vec3 d = base_pos[i] + base_rot[i] * hip_in_base[f] - (feet[i][f].centre + rot_z(feet[i][f].yaw) * ankle_from_sole[f]);
        const double h = d.head<2>().norm();
        // A stride beyond reach is the stride repair's and the IK's business.
        if (h < longest) need_down[i] = std::max(need_down[i], d.z() - std::sqrt(longest * longest - h * h));
        if (h < shortest) need_up[i] = std::max(need_up[i], std::sqrt(shortest * shortest - h * h) - d.z());
      }
    }
    const int w = std::max(1, frames_of(kPelvisBlend_s));
    const std::vector<double> lower = spread_over(need_down, w), raise = spread_over(need_up, w);
    for (int i = 0; i < n; ++i) {
      base_pos[i].z() += raise[i] - lower[i];
      knee_lower[i] = std::max(0.0, lower[i] - raise[i]);
    }
    for (int a = 0; a < n;) {
      if (!(lower[a] > kPelvisReport_m || raise[a] > kPelvisReport_m)) {
        ++a;
        continue;
      }
      int b = a;
      double down = 0.0, up = 0.0;
      while (b < n && (lower[b] > kPelvisReport_m || raise[b] > kPelvisReport_m)) {
        down = std::max(down, lower[b]);
        up = std::max(up, raise[b++]);
      }
      log.add(RepairKind::kPelvisHeight, a, b,
              fmt("pelvis lowered up to %.1f cm, raised up to %.1f cm: the stance knees stay within %.0f..%.0f deg",
                  100.0 * down, 100.0 * up, cfg.min_stance_knee_rad * 180.0 / kPi, cfg.max_stance_knee_rad * 180.0 / kPi));
      a = b;
    }
  }
  // Pelvis height with its vertical acceleration within ±max_vertical_acceleration_m_s2 (a
  // hop kept as a bounce, a drop into a crouch): smoothed where it is beyond, as the upper
  // body's (limit_acceleration). Reported where the height moved by more than kPelvisReport_m.
  if (cfg.max_vertical_acceleration_m_s2 > 0.0) {
    std::vector<Vec3> limited = base_pos;
    std::vector<bool> changed(n, false);
    if (limit_acceleration(limited, 2, cfg.max_vertical_acceleration_m_s2, rate_hz, changed)) {
      std::vector<double> moved(n, 0.0);
      for (int i = 0; i < n; ++i) {
        if (!changed[i] || forbidden(RepairKind::kBounce, std::clamp(i, lead, lead + n_dance - 1))) continue;
        moved[i] = limited[i].z() - base_pos[i].z();
        base_pos[i].z() = limited[i].z();
      }
      for (int a = 0; a < n;) {
        if (!(std::abs(moved[a]) > kPelvisReport_m)) {
          ++a;
          continue;
        }
        // The whole smoothed stretch around it, with its largest change.
        int b = a;
        while (a > 0 && changed[a - 1]) --a;
        double most = 0.0;
        while (b < n && changed[b]) most = std::max(most, std::abs(moved[b++]));
        log.add(RepairKind::kBounce, a, b,
                fmt("the pelvis rises or drops faster than the feet can carry (vertical acceleration beyond %.1f m/s^2): "
                    "smoothed, height changed up to %.1f cm",
                    cfg.max_vertical_acceleration_m_s2, 100.0 * most));
        a = b;
      }
    }
  }
  // Lead-in and tail: standing on the footholds, blended into / out of the dance.
  const auto standing_base = [&](int i, Vec3& pos, Mat3& rot) {
    rot = rot_z(feet_yaw(i));
    pos = 0.5 * (feet[i][0].centre + feet[i][1].centre) + rot * stand_base_from_mid;
    pos.z() = q_stand[2];
  };
  const auto blend_base = [&](int i, double w) {
    Vec3 sp;
    Mat3 sr;
    standing_base(i, sp, sr);
    base_pos[i] = sp + w * (base_pos[i] - sp);
    base_rot[i] = Eigen::Quaterniond(sr).slerp(w, Eigen::Quaterniond(base_rot[i])).toRotationMatrix();
  };
  for (int i = 0; i < lead; ++i) blend_base(i, i < blend_start ? 0.0 : smooth_step(double(i - blend_start) / (lead - blend_start)));
  for (int i = lead + n_dance; i < n; ++i) blend_base(i, 1.0 - smooth_step(double(i - lead - n_dance + 1) / std::max(1, tail)));
  if (tail > 0) log.add(RepairKind::kTail, lead + n_dance, n, "both feet down after the dance, blending to standing");

  // Corner offsets of a flat foot from its sole centre, in the foot's heading frame.
  std::array<Vec3, model::kNumContactPoints> corner_offset;
  {
    dynamics::forward_kinematics(robot, *data, q_stand);
    for (int c = 0; c < model::kNumContactPoints; ++c) {
      const int f = c / kCorners;
      corner_offset[c] = rot_z(-stand_feet[f].yaw) * (dynamics::frame_position(robot, *data, c) - stand_feet[f].centre);
      corner_offset[c].z() = 0.0;
    }
  }

  out = RepairedMotion{};
  out.rate_hz = rate_hz;
  out.lead_frames = lead;
  out.dance_frames = n_dance;
  out.q.resize(n);
  out.contacts.resize(n);
  // 5. Arms and head: standing in the lead-in and tail, blended, the dance in between; then
  // their accelerations limited to what the joints' torques can give (see limit_upper_body).
  constexpr int kUpper = 7 + 2 * model::kLegJoints;
  constexpr int kUpperJoints = model::kNq - kUpper;
  std::vector<Eigen::Matrix<double, kUpperJoints, 1>> upper(n);
  for (int i = 0; i < n; ++i) {
    const int d = dance_frame(i);
    double w = 1.0;
    if (i < lead) w = i < blend_start ? 0.0 : smooth_step(double(i - blend_start) / (lead - blend_start));
    if (i >= lead + n_dance) w = 1.0 - smooth_step(double(i - lead - n_dance + 1) / std::max(1, tail));
    upper[i] = q_stand.tail<kUpperJoints>() + w * (geometric[d].tail<kUpperJoints>() - q_stand.tail<kUpperJoints>());
  }
  if (cfg.upper_torque_share > 0.0) {
    dynamics::forward_kinematics(robot, *data, q_stand);
    dynamics::crba(robot, *data);
    for (int j = 0; j < kUpperJoints; ++j) {
      const int joint = kUpper - 7 + j;
      const double inertia = data->mass_matrix(6 + joint, 6 + joint);
      const double a_max = cfg.upper_torque_share * robot.limits.torque_Nm[joint] / inertia;
      std::vector<bool> changed(n, false);
      std::vector<double> original(n);
      for (int i = 0; i < n; ++i) original[i] = upper[i][j];
      if (!limit_acceleration(upper, j, a_max, rate_hz, changed)) continue;
      for (int i = 0; i < n; ++i) {
        if (changed[i] && forbidden(RepairKind::kUpperBodySpeed, i)) {  // the override keeps the human's
          upper[i][j] = original[i];
          changed[i] = false;
        }
      }
      for (int a = 0; a < n;) {
        if (!changed[a]) {
          ++a;
          continue;
        }
        int b = a;
        while (b < n && changed[b]) ++b;
        char why[160];
        std::snprintf(why, sizeof why,
                      "an arm or head joint accelerates beyond %.0f %% of its torque limit over its inertia: smoothed",
                      100.0 * cfg.upper_torque_share);
        log.add(RepairKind::kUpperBodySpeed, a, b, why);
        a = b;
      }
    }
  }
  // 6. Legs by IK to the feet, frame by frame: stance feet flat on their footholds. Where the
  // legs cannot lay a stance foot flat at the pelvis pose kept from the human (a torso
  // twisted or leaning beyond what the hip yaw, hip roll and ankle roll ranges reach from the
  // foothold, or a pelvis far off its feet), the pelvis moves towards standing over its stance
  // feet (level, their heading, the standing pose's place) by the least of the steps
  // kReachSteps that reaches, spread in time as the pelvis height is. Left as it was, the
  // stance foot stays tilted in the motion (cmu_05_07 at 7.5–12.7 s: the left foot 11–16°
  // with its ankle roll at the limit), and the online stack, whose contact keeps the foot
  // flat, tracks legs 0.2 rad off the reference there and fell in 8 of 20 carpet runs with
  // model errors.
  struct BasePose {
    Mat3 rot;
    Vec3 pos;
  };
  const auto standing_over_feet = [&](int i) {
    double yaw = 0.0;
    stance_yaw(i, yaw);  // a frame with a stance foot: the solve only moves the pelvis for one
    BasePose p{rot_z(yaw), Vec3::Zero()};
    if (on[i][0] && on[i][1]) {
      p.pos = 0.5 * (feet[i][0].centre + feet[i][1].centre) + rot_z(yaw) * stand_base_from_mid;
    } else {
      const int f = on[i][0] ? 0 : 1;
      p.pos = feet[i][f].centre + rot_z(feet[i][f].yaw - stand_feet[f].yaw) * (q_stand.head<3>() - stand_feet[f].centre);
    }
    return p;
  };
  const auto moved = [&](int i, double r) {
    BasePose p{base_rot[i], base_pos[i]};
    if (r <= 0.0) return p;
    const BasePose to = standing_over_feet(i);
    p.rot = Eigen::Quaterniond(base_rot[i]).slerp(r, Eigen::Quaterniond(to.rot)).toRotationMatrix();
    p.pos.head<2>() += r * (to.pos.head<2>() - base_pos[i].head<2>());
    return p;
  };
  ConfigVector q = q_stand;
  // The legs of frame i with the base at `base`: the best of the pelvis heights tried, its
  // largest stance-corner error returned.
  const auto solve_legs = [&](int i, const BasePose& base, ConfigVector& out_q) {
    q.tail<kUpperJoints>() = upper[i];
    const Eigen::Quaterniond qb(base.rot);
    q[3] = qb.x(), q[4] = qb.y(), q[5] = qb.z(), q[6] = qb.w();
    std::array<Vec3, model::kNumContactPoints> targets;
    for (int c = 0; c < model::kNumContactPoints; ++c) {
      const FootPose& fp = feet[i][c / kCorners];
      targets[c] = fp.centre + rot_z(fp.yaw) * corner_offset[c];
    }
    // Lowering helps a leg too short for its foothold and hurts one at a joint limit: the
    // best attempt is kept, not the last.
    ConfigVector best = q;
    double best_error = std::numeric_limits<double>::infinity();
    // Past the lowering steps: back up towards the height before the knee bend lowered it (a
    // long stride's rear ankle runs out of dorsiflexion in the deeper crouch).
    const int raise_steps = static_cast<int>(std::ceil(knee_lower[i] / kBaseLowerStep_m - 1e-9));
    for (int tries = 0; tries <= kMaxBaseLowerSteps + raise_steps; ++tries) {
      const double dz = tries <= kMaxBaseLowerSteps ? -tries * kBaseLowerStep_m
                                                    : std::min(knee_lower[i], (tries - kMaxBaseLowerSteps) * kBaseLowerStep_m);
      q.head<3>() = base.pos + Vec3(0.0, 0.0, dz);
      leg_ik_lm(robot, *data, targets, q);  // leaves the legs' kinematics at q in data
      double stance_error = 0.0;
      for (int c = 0; c < model::kNumContactPoints; ++c) {
        if (!on[i][c / kCorners]) continue;
        stance_error = std::max(stance_error, (dynamics::frame_position(robot, *data, c) - targets[c]).norm());
      }
      if (stance_error < best_error) {
        best_error = stance_error;
        best = q;
      }
      if (stance_error <= kStanceIkTolerance_m) break;
    }
    q = best;
    out_q = best;
    return best_error;
  };
  std::vector<double> stance_error(n, 0.0), need_turn(n, 0.0);
  for (int i = 0; i < n; ++i) {
    stance_error[i] = solve_legs(i, moved(i, 0.0), out.q[i]);
    if (stance_error[i] <= kStanceIkTolerance_m || !in_dance(i) || forbidden(RepairKind::kStanceReach, i)) continue;
    double best = stance_error[i];
    ConfigVector scratch;
    for (const double r : kReachSteps) {
      const double e = solve_legs(i, moved(i, r), scratch);
      if (e < best - kStanceIkTolerance_m) best = e, need_turn[i] = r;
      if (e <= kStanceIkTolerance_m) break;
    }
  }
  const std::vector<double> turn = spread_over(need_turn, frames_of(kPelvisBlend_s));
  for (int a = 0; a < n;) {
    if (!(turn[a] > 0.0)) {
      ++a;
      continue;
    }
    int b = a;
    double most = 0.0, reach_before = 0.0, reach_after = 0.0;
    for (; b < n && turn[b] > 0.0; ++b) {
      most = std::max(most, turn[b]);
      reach_before = std::max(reach_before, stance_error[b]);
      stance_error[b] = solve_legs(b, moved(b, turn[b]), out.q[b]);
      reach_after = std::max(reach_after, stance_error[b]);
    }
    log.add(RepairKind::kStanceReach, a, b,
            fmt("a stance foot cannot lie flat on its foothold within the leg joints' ranges at the human's pelvis "
                "pose (a corner %.1f cm off): the pelvis moved up to %.0f %% of the way to standing over its feet "
                "(%.1f cm off after)",
                100.0 * reach_before, 100.0 * most, 100.0 * reach_after));
    a = b;
  }
  // 7. Stance lean: where the CoM stands, on average over a while, ahead of or behind where
  // it stands over the ankles in the robot's standing pose, the pelvis moves back (or ahead)
  // by what exceeds the band, so the stance ankles hold the weight with their reserve (see
  // RepairConfig::max_stance_lean_m). The dance's own sway (faster than the window) stays.
  if (cfg.max_stance_lean_m > 0.0) {
    const auto com_of = [&](const ConfigVector& qi) {
      dynamics::forward_kinematics(robot, *data, qi);
      Vec3 sum = Vec3::Zero();
      double mass = 0.0;
      for (int b = 0; b < model::kNumBodies; ++b) {
        sum += robot.bodies[b].mass_kg * (data->position_m[b] + data->rotation[b] * robot.bodies[b].com_m);
        mass += robot.bodies[b].mass_kg;
      }
      return Vec3(sum / mass);
    };
    const auto ankle_of = [&](int f) { return data->position_m[1 + f * model::kLegJoints + model::kAnklePitchInLeg]; };
    // The standing pose's CoM ahead of its ankles' midpoint, and how far the CoM moves when
    // the pelvis does with the feet held (the legs' own mass moves less): 1 cm forward, the
    // legs re-solved to the standing soles.
    const Vec3 c_stand = com_of(q_stand);
    const Vec3 forward_stand = rot_z(stand_feet[0].yaw) * Vec3::UnitX();
    const double lean_stand = forward_stand.dot(c_stand - 0.5 * (ankle_of(0) + ankle_of(1)));
    double gain = 1.0;
    {
      std::array<Vec3, model::kNumContactPoints> soles;
      for (int c = 0; c < model::kNumContactPoints; ++c) {
        const FootPose& fp = stand_feet[c / kCorners];
        soles[c] = fp.centre + rot_z(fp.yaw) * corner_offset[c];
      }
      ConfigVector q_ahead = q_stand;
      q_ahead.head<3>() += 0.01 * forward_stand;
      leg_ik_lm(robot, *data, soles, q_ahead);
      gain = std::clamp(forward_stand.dot(com_of(q_ahead) - c_stand) / 0.01, 0.5, 1.0);
    }
    // How far each double-support frame's CoM stands ahead of (behind: < 0) the segment
    // between the two points where each foot's centre of pressure sits in the standing pose
    // (lean_stand ahead of its ankle), along the feet's heading: the CoM anywhere on that
    // segment is a weight shift the two ankles hold as they hold standing. Single supports
    // are left out: a step's CoM passes its stance ankle by design.
    std::vector<double> lean(n, 0.0), weight(n, 0.0);
    std::vector<Vec3> forward(n, Vec3::UnitX());
    for (int i = 0; i < n; ++i) {
      double yaw = 0.0;
      stance_yaw(i, yaw);
      forward[i] = rot_z(yaw) * Vec3::UnitX();
      if (!(on[i][0] && on[i][1])) continue;
      Vec3 c = com_of(out.q[i]);
      Vec3 p[kFeet];
      for (int f = 0; f < kFeet; ++f) p[f] = ankle_of(f) + lean_stand * (rot_z(feet[i][f].yaw) * Vec3::UnitX());
      c.z() = p[0].z() = p[1].z() = 0.0;
      const Vec3 d = p[1] - p[0];
      const double t = d.squaredNorm() > 0.0 ? std::clamp((c - p[0]).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
      lean[i] = forward[i].dot(c - (p[0] + t * d));
      weight[i] = 1.0;
    }
    const int w = std::max(1, frames_of(cfg.stance_lean_window_s / 2));
    std::vector<double> shift(n, 0.0), mean(n, 0.0);
    for (int i = 0; i < n; ++i) {
      double sum = 0.0, sw = 0.0;
      for (int j = std::max(0, i - w); j <= std::min(n - 1, i + w); ++j) sum += weight[j] * lean[j], sw += weight[j];
      if (sw < w) continue;  // less than half the window in double support
      mean[i] = sum / sw;
      const double over = std::max(0.0, std::abs(mean[i]) - cfg.stance_lean_band_m);
      if (forbidden(RepairKind::kStanceLean, i)) continue;
      shift[i] = -std::copysign(std::min(over / gain, cfg.max_stance_lean_m), mean[i]);
    }
    // Smoothed like the pelvis height, so the pelvis does not step.
    {
      const int b = std::max(1, frames_of(kPelvisBlend_s));
      std::vector<double> s(n, 0.0);
      for (int i = 0; i < n; ++i) {
        double sum = 0.0;
        int c = 0;
        for (int j = std::max(0, i - b); j <= std::min(n - 1, i + b); ++j) sum += shift[j], ++c;
        s[i] = sum / c;
      }
      shift = s;
    }
    for (int a = 0; a < n;) {
      if (!(std::abs(shift[a]) > kPelvisReport_m)) {
        ++a;
        continue;
      }
      int b = a;
      double most = 0.0, before = 0.0;
      int unreached = 0;
      for (; b < n && std::abs(shift[b]) > kPelvisReport_m; ++b) {
        BasePose p = moved(b, turn[b]);
        p.pos += shift[b] * forward[b];
        ConfigVector q_lean;
        const double e = solve_legs(b, p, q_lean);
        if (e > std::max(kStanceIkTolerance_m, stance_error[b])) {  // the legs do not reach: as it was
          ++unreached;
          continue;
        }
        stance_error[b] = e;
        out.q[b] = q_lean;
        if (std::abs(shift[b]) > std::abs(most)) most = shift[b];
        if (std::abs(mean[b]) > std::abs(before)) before = mean[b];
      }
      char why[320];
      std::snprintf(why, sizeof why,
                    "in double support the CoM stood up to %.1f cm %s where it stands over the ankles in the "
                    "standing pose (%.1f s average): the pelvis moved up to %.1f cm %s, so the ankles keep their "
                    "reserve",
                    100.0 * std::abs(before), before > 0.0 ? "ahead of" : "behind", cfg.stance_lean_window_s,
                    100.0 * std::abs(most), most < 0.0 ? "back" : "forward");
      std::string reason = why;
      if (unreached > 0) reason += " (" + std::to_string(unreached) + " frames kept as they were: the legs do not reach)";
      log.add(RepairKind::kStanceLean, a, b, reason);
      a = b;
    }
  }
  for (int i = 0; i < n; ++i) {
    out.max_leg_ik_error_m = std::max(out.max_leg_ik_error_m, stance_error[i]);
    out.contacts[i] = make_label(on[i][0], on[i][1]);
  }
  out.repairs = log.take();
  out.human_steps = count_steps(labels);
  out.robot_steps = count_steps(out.contacts);
  return true;
}

bool attenuate_gestures(std::vector<ConfigVector>& geometric, double rate_hz, const std::vector<AttenuationRange>& ranges,
                        double gain, double window_s, double lead_s, const std::vector<RepairOverride>& overrides,
                        std::vector<Repair>& log) {
  const int n = static_cast<int>(geometric.size());
  const int w = std::max(1, static_cast<int>(std::lround(window_s * rate_hz)));
  constexpr int kJoints = model::kNumJoints;
  const auto forbidden = [&](int i) { return forbids(overrides, RepairKind::kAttenuate, i / rate_hz); };
  // Weight of the scaling per frame: 1 inside a range, ramping to 0 over w frames outside.
  std::vector<double> weight(n, 0.0);
  for (const AttenuationRange& r : ranges) {
    for (int i = std::max(0, r.a - w); i < std::min(n, r.b + w); ++i) {
      const double s = i < r.a ? 1.0 - static_cast<double>(r.a - i) / w : (i >= r.b ? 1.0 - static_cast<double>(i - r.b + 1) / w : 1.0);
      weight[i] = std::max(weight[i], smooth_step(std::clamp(s, 0.0, 1.0)));
    }
  }
  std::vector<ConfigVector> out = geometric;
  bool changed = false;
  for (int i = 0; i < n; ++i) {
    if (weight[i] <= 0.0 || forbidden(i)) continue;
    Eigen::Matrix<double, kJoints, 1> mean = Eigen::Matrix<double, kJoints, 1>::Zero();
    double z = 0.0;
    for (int j = i - w; j <= i + w; ++j) {
      const ConfigVector& q = geometric[std::clamp(j, 0, n - 1)];
      mean += q.tail<kJoints>();
      z += q[2];
    }
    mean /= 2 * w + 1;
    z /= 2 * w + 1;
    const double k = 1.0 - weight[i] * (1.0 - gain);
    out[i].tail<kJoints>() = mean + k * (geometric[i].tail<kJoints>() - mean);
    out[i][2] = z + k * (geometric[i][2] - z);
    changed = true;
  }
  geometric = out;
  for (const AttenuationRange& r : ranges) {
    if (forbidden(r.a)) continue;
    Repair x;
    x.start_s = r.a / rate_hz + lead_s;
    x.end_s = r.b / rate_hz + lead_s;
    x.kind = RepairKind::kAttenuate;
    const std::string why = r.why.empty() ? fmt("the dynamic stage's result asked %.1fx a leg joint's torque limit here",
                                                r.torque_ratio)
                                          : r.why;
    x.reason = why + fmt(": the gestures are scaled to %.0f %% about their %.1f s average and the motion optimized again",
                         100.0 * gain, 2.0 * window_s);
    log.push_back(x);
  }
  return changed;
}

}  // namespace kuavo::mocap
