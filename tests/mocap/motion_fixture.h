// Shared set-up of the feasibility-repair, dynamics-oracle and dynamic-retargeting tests:
// the s45 model (built once), the standing configuration the repair itself starts from
// (centred_standing_pose at StandingConfig's height, placed on the ground, both soles then
// put exactly on the floor), and synthetic motions whose feet are placed by the offline leg
// IK (leg_ik_lm: within the joint limits, so a motion that reports no IK error is one the
// robot's legs can take). The foot quantities are computed here from
// the sole corners alone (centre = mean of the four corners, heading = toe-minus-heel
// direction), independently of how the code under test reads them.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <functional>
#include <memory>
#include <vector>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/standing/standing_controller.h"
#include "tools/mocap/contact_label.h"
#include "tools/mocap/leg_ik_lm.h"

namespace kuavo::mocap::test {

using dynamics::ConfigVector;
using dynamics::Mat3;
using dynamics::Vec3;

inline constexpr int kCorners = model::kNumContactPoints;  // 0..3 left sole, 4..7 right sole
inline constexpr double kRate_hz = 100.0;

inline const model::Model& robot() {
  static const auto m = [] {
    auto r = std::make_unique<model::Model>();
    model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, *r);
    return r;
  }();
  return *m;
}

inline dynamics::Data& scratch() {
  static const auto d = std::make_unique<dynamics::Data>();
  return *d;
}

// A measured figure for RecordProperty (3 significant digits).
inline std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

inline double weight_N() { return robot().total_mass_kg * model::kGravity_m_s2; }

inline Mat3 rot_z(double yaw) { return Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix(); }

inline void set_base_rotation(ConfigVector& q, const Mat3& r) {
  const Eigen::Quaterniond o(r);
  q[3] = o.x(), q[4] = o.y(), q[5] = o.z(), q[6] = o.w();
}

inline std::array<Vec3, kCorners> corners_of(const ConfigVector& q) {
  dynamics::forward_kinematics(robot(), scratch(), q);
  std::array<Vec3, kCorners> c;
  for (int k = 0; k < kCorners; ++k) c[k] = dynamics::frame_position(robot(), scratch(), k);
  return c;
}

struct Foot {
  Vec3 centre = Vec3::Zero();  // mean of the four sole corners; z: height above the floor
  double yaw = 0.0;
};

// Both feet of q: corners 0/1 are the toes, 2/3 the heels (model tables).
inline std::array<Foot, 2> feet_of(const ConfigVector& q) {
  const auto c = corners_of(q);
  std::array<Foot, 2> out;
  for (int f = 0; f < 2; ++f) {
    const int o = 4 * f;
    out[f].centre = 0.25 * (c[o] + c[o + 1] + c[o + 2] + c[o + 3]);
    const Vec3 along = (c[o] + c[o + 1]) - (c[o + 2] + c[o + 3]);
    out[f].yaw = std::atan2(along.y(), along.x());
  }
  return out;
}

inline Vec3 com_of(const ConfigVector& q) {
  dynamics::forward_kinematics(robot(), scratch(), q);
  dynamics::crba(robot(), scratch());
  return scratch().com_m;
}

struct Standing {
  ConfigVector q;
  std::array<Vec3, kCorners> corner_offset;  // flat sole corner − its foot centre, foot heading frame
  std::array<Foot, 2> feet;
  Vec3 base_from_mid;  // base origin − feet midpoint
};

inline const Standing& standing() {
  static const Standing s = [] {
    Standing out;
    out.q = dynamics::neutral_configuration(robot());
    out.q.tail<model::kNumJoints>() =
        control::centred_standing_pose(robot(), scratch(), control::StandingConfig{}.base_height_m);
    control::place_on_ground(robot(), scratch(), out.q);
    out.feet = feet_of(out.q);
    const auto c = corners_of(out.q);
    for (int k = 0; k < kCorners; ++k) {
      out.corner_offset[k] = c[k] - out.feet[k / 4].centre;
      out.corner_offset[k].z() = 0.0;
    }
    // The two legs of the model differ by a fraction of a millimetre: placed on the ground
    // by its lowest corner, the left sole floats 0.2 mm. Both soles exactly on the floor.
    for (auto& f : out.feet) f.centre.z() = 0.0;
    std::array<Vec3, kCorners> targets;
    for (int k = 0; k < kCorners; ++k) targets[k] = out.feet[k / 4].centre + out.corner_offset[k];
    leg_ik_lm(robot(), scratch(), targets, out.q);
    out.base_from_mid = out.q.head<3>() - 0.5 * (out.feet[0].centre + out.feet[1].centre);
    return out;
  }();
  return s;
}

// One synthetic frame: both feet (flat, sole centre and heading), which feet are down, the
// base (the standing offset over the feet midpoint, turned by base_yaw, plus base_shift) and
// the arms (offsets from the standing arms).
struct Keyframe {
  Foot left, right;
  bool left_down = true, right_down = true;
  Vec3 base_shift = Vec3::Zero();  // added to the default base position
  double base_yaw = 0.0;
  Eigen::Matrix<double, 2 * model::kArmJoints, 1> arms = Eigen::Matrix<double, 2 * model::kArmJoints, 1>::Zero();
  Vec3 base_lean = Vec3::Zero();  // rotation vector [rad] applied in the world frame after the yaw
};

// The frame by leg IK from guess; ik_error: the largest corner miss [m] (within joint limits).
inline ConfigVector frame_of(const Keyframe& k, const ConfigVector& guess, double* ik_error = nullptr) {
  const Standing& st = standing();
  ConfigVector q = guess;
  const Vec3 mid = 0.5 * (k.left.centre + k.right.centre);
  q.head<3>() = Vec3(mid.x(), mid.y(), 0.0) + rot_z(k.base_yaw) * st.base_from_mid + k.base_shift;
  const double lean = k.base_lean.norm();
  const Mat3 tilt = lean > 0.0 ? Eigen::AngleAxisd(lean, k.base_lean / lean).toRotationMatrix() : Mat3::Identity();
  set_base_rotation(q, tilt * rot_z(k.base_yaw));
  q.segment<2 * model::kArmJoints>(7 + 2 * model::kLegJoints) =
      st.q.segment<2 * model::kArmJoints>(7 + 2 * model::kLegJoints) + k.arms;
  std::array<Vec3, kCorners> targets;
  for (int c = 0; c < kCorners; ++c) {
    const Foot& f = c < 4 ? k.left : k.right;
    targets[c] = f.centre + rot_z(f.yaw) * st.corner_offset[c];
  }
  const double e = leg_ik_lm(robot(), scratch(), targets, q);
  if (ik_error) *ik_error = e;
  return q;
}

struct Motion {
  std::vector<ConfigVector> q;
  std::vector<ContactLabel> labels;
  double worst_ik_error_m = 0.0;
};

// frames frames of keyframe(i), each solved from the previous one.
inline Motion make_motion(int frames, const std::function<Keyframe(int)>& keyframe) {
  Motion m;
  ConfigVector guess = standing().q;
  for (int i = 0; i < frames; ++i) {
    const Keyframe k = keyframe(i);
    double e = 0.0;
    guess = frame_of(k, guess, &e);
    m.q.push_back(guess);
    m.labels.push_back(make_label(k.left_down, k.right_down));
    m.worst_ik_error_m = std::max(m.worst_ik_error_m, e);
  }
  return m;
}

// The standing keyframe (both feet where standing() has them).
inline Keyframe stand_key() {
  Keyframe k;
  k.left = standing().feet[0];
  k.right = standing().feet[1];
  return k;
}

// Foot swing between two footholds over frames [a, b): s = (i − a + 1)/(b − a + 1) ∈ (0, 1),
// horizontal by a smooth step, height h·sin(πs) (> 0 on every swing frame).
inline Foot swing(const Foot& from, const Foot& to, int i, int a, int b, double height_m) {
  const double s = static_cast<double>(i - a + 1) / (b - a + 1);
  const double w = s * s * (3.0 - 2.0 * s);
  Foot f;
  f.centre = from.centre + w * (to.centre - from.centre);
  f.centre.z() = height_m * std::sin(M_PI * s);
  f.yaw = from.yaw + w * (to.yaw - from.yaw);
  return f;
}

// A hop: standing, both feet and the pelvis 3 cm up (a sine arc) over frames [a, b), those
// frames labelled flight.
inline Motion hop_motion(int frames, int a, int b) {
  return make_motion(frames, [=](int i) {
    Keyframe k = stand_key();
    if (i >= a && i < b) {
      const double z = 0.03 * std::sin(M_PI * (i - a + 1) / (b - a + 1));
      k.left.centre.z() = k.right.centre.z() = z;
      k.base_shift.z() = z;
      k.left_down = k.right_down = false;
    }
    return k;
  });
}

// f moved by (dx, dy) and turned by yaw.
inline Foot moved(const Foot& f, double dx, double dy = 0.0, double yaw = 0.0) {
  Foot o = f;
  o.centre += Vec3(dx, dy, 0.0);
  o.yaw += yaw;
  return o;
}

}  // namespace kuavo::mocap::test
