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

namespace {

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Depth below the terrain along its normal, and the force's parts in its frame.
struct TerrainPoint {
  Vec3 n;
  double depth_m;
  double normal_speed_m_s;  // v·n: positive moving out of the ground
};

TerrainPoint terrain_point(const Terrain& t, const Vec3& p, const Vec3& v) {
  TerrainPoint tp;
  tp.n = terrain_normal(t);
  tp.depth_m = (terrain_height_m(t, p.x(), p.y()) - p.z()) * tp.n.z();
  tp.normal_speed_m_s = v.dot(tp.n);
  return tp;
}

double terrain_normal_force(const GroundParams& g, const TerrainPoint& tp) {
  if (tp.depth_m <= 0.0) return 0.0;
  const double spring = g.normal_exponent == 1.0 ? g.normal_stiffness * tp.depth_m
                                                 : g.normal_stiffness * std::pow(tp.depth_m, g.normal_exponent);
  return std::max(0.0, spring * (1.0 - g.hunt_crossley_s_m * tp.normal_speed_m_s));
}

Vec3 tangential(const Vec3& x, const Vec3& n) { return x - x.dot(n) * n; }

Vec3 terrain_contact_force(const GroundParams& g, const Vec3& p, const Vec3& v, const ContactPointState& s) {
  const TerrainPoint tp = terrain_point(*g.terrain, p, v);
  const double fn = terrain_normal_force(g, tp);
  if (fn <= 0.0) return Vec3::Zero();
  Vec3 ft = -g.tangential_damping_Ns_m * tangential(v, tp.n);
  if (s.touching) ft -= g.tangential_stiffness_N_m * tangential(p - s.anchor_m, tp.n);
  const double limit = g.friction_coefficient * fn;
  const double norm = ft.norm();
  if (norm > limit) ft *= limit / norm;
  return fn * tp.n + ft;
}

void terrain_update_contact_point(const GroundParams& g, const Vec3& p, const Vec3& v, ContactPointState& s) {
  const TerrainPoint tp = terrain_point(*g.terrain, p, v);
  const double fn = terrain_normal_force(g, tp);
  if (fn <= 0.0) {
    s.touching = false;
    return;
  }
  if (!s.touching) {
    s.touching = true;
    s.anchor_m = p;
    return;
  }
  const Vec3 stretch = tangential(p - s.anchor_m, tp.n);
  const double limit = g.friction_coefficient * fn / g.tangential_stiffness_N_m;
  const double len = stretch.norm();
  if (len > limit) s.anchor_m = p - stretch * (limit / len);
}

}  // namespace

double terrain_height_m(const Terrain& t, double x_m, double y_m) {
  double h = t.slope_x * x_m + t.slope_y * y_m;
  if (t.step_hi_m > t.step_lo_m) {
    const auto ix = static_cast<std::int64_t>(std::floor((x_m - t.grid_origin_x_m) / t.tile_m));
    const auto iy = static_cast<std::int64_t>(std::floor((y_m - t.grid_origin_y_m) / t.tile_m));
    const std::uint64_t bits = splitmix64(t.seed ^ splitmix64(static_cast<std::uint64_t>(ix) * 0x100000001b3ULL ^
                                                              static_cast<std::uint64_t>(iy)));
    h += t.step_lo_m + (t.step_hi_m - t.step_lo_m) * static_cast<double>(bits >> 11) * 0x1.0p-53;
  } else {
    h += t.step_lo_m;
  }
  return h;
}

Vec3 terrain_normal(const Terrain& t) { return Vec3(-t.slope_x, -t.slope_y, 1.0).normalized(); }

static double normal_force(const GroundParams& g, const Vec3& p, const Vec3& v) {
  const double depth = -p.z();
  if (depth <= 0.0) return 0.0;
  // The ground pushes, never pulls: a fast lift-off leaves the damper no tension.
  const double spring = g.normal_exponent == 1.0 ? g.normal_stiffness * depth
                                                 : g.normal_stiffness * std::pow(depth, g.normal_exponent);
  return std::max(0.0, spring * (1.0 - g.hunt_crossley_s_m * v.z()));
}

Vec3 contact_force(const GroundParams& g, const Vec3& p, const Vec3& v, const ContactPointState& s) {
  if (g.terrain != nullptr) return terrain_contact_force(g, p, v, s);
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
  if (g.terrain != nullptr) return terrain_update_contact_point(g, p, v, s);
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
