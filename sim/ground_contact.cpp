#include "sim/ground_contact.h"

#include <cmath>
#include <cstring>

namespace kuavo::sim {

bool parse_ground(const char* text, GroundParams& out) {
  if (text == nullptr) return false;
  if (std::strcmp(text, "floor") == 0) {
    out = kFloor;
    return true;
  }
  if (std::strcmp(text, "carpet") == 0) {
    out = kCarpet;
    return true;
  }
  return false;
}

static double normal_force(const GroundParams& g, const Vec3& p, const Vec3& v) {
  const double depth = -p.z();
  if (depth <= 0.0) return 0.0;
  // The ground pushes, never pulls: a fast lift-off leaves the damper no tension.
  const double spring = g.normal_exponent == 1.0 ? g.normal_stiffness * depth
                                                 : g.normal_stiffness * std::pow(depth, g.normal_exponent);
  return std::max(0.0, spring * (1.0 - g.hunt_crossley_s_m * v.z()));
}

Vec3 contact_force(const GroundParams& g, const Vec3& p, const Vec3& v, const ContactPointState& s) {
  const double fn = normal_force(g, p, v);
  Vec3 f(0.0, 0.0, fn);
  if (fn <= 0.0) return f;
  Eigen::Vector2d ft = Eigen::Vector2d::Zero();
  if (s.touching) {
    ft = -g.tangential_stiffness_N_m * (p.head<2>() - s.anchor_m.head<2>()) - g.tangential_damping_Ns_m * v.head<2>();
  } else {
    ft = -g.tangential_damping_Ns_m * v.head<2>();
  }
  const double limit = g.friction_coefficient * fn;
  const double norm = ft.norm();
  if (norm > limit) ft *= limit / norm;
  f.head<2>() = ft;
  return f;
}

void update_contact_point(const GroundParams& g, const Vec3& p, const Vec3& v, ContactPointState& s) {
  const double fn = normal_force(g, p, v);
  if (fn <= 0.0) {
    s.touching = false;
    return;
  }
  if (!s.touching) {
    s.touching = true;
    s.anchor_m = p;
    return;
  }
  // Slipping: move the anchor so the spring alone sits on the friction limit.
  const Eigen::Vector2d stretch = p.head<2>() - s.anchor_m.head<2>();
  const double limit = g.friction_coefficient * fn / g.tangential_stiffness_N_m;
  const double len = stretch.norm();
  if (len > limit) s.anchor_m.head<2>() = p.head<2>() - stretch * (limit / len);
}

}  // namespace kuavo::sim
