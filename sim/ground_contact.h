// Compliant ground contact at the 8 sole-corner points: a spring-damper normal
// force and a stick-slip tangential force (a tangential spring anchored where the
// point touched down, limited by Coulomb friction; the anchor slides when the
// spring would exceed μ·f_n). Pure functions of the point's state: no Simbody here.
#pragma once

#include <Eigen/Core>
#include <cstdint>

namespace kuavo::sim {

using Vec3 = Eigen::Vector3d;

// Uneven ground (sim/perturbation.h draws it): a plane tilted by the two slopes,
// carrying square tiles whose heights differ (steps). Tile heights come from a hash of
// (seed, tile index), so the terrain needs no storage and is the same at every query.
// Contact forces act along the plane's normal and friction in its tangent plane; the
// step edges themselves are not modelled (a corner sees only the height under it).
struct Terrain {
  double slope_x = 0.0;  // dz/dx
  double slope_y = 0.0;  // dz/dy
  double tile_m = 0.5;
  double grid_origin_x_m = 0.0, grid_origin_y_m = 0.0;
  double step_lo_m = 0.0, step_hi_m = 0.0;  // tile heights, uniform in [lo, hi]
  std::uint64_t seed = 0;
};
double terrain_height_m(const Terrain& t, double x_m, double y_m);
Vec3 terrain_normal(const Terrain& t);

struct GroundParams {
  const char* name;
  double normal_stiffness;          // per contact point, N/m^exponent
  double normal_exponent;           // f = k·d^n: 1 linear (floor), 2 stiffening (carpet foam)
  // Hunt–Crossley damping: f_n = k·d·(1 + c·ḋ) with d the depth and ḋ its rate, so the force
  // starts from zero at first touch (a plain damper would jump, and a stiff
  // integrator cannot step over the jump).
  double hunt_crossley_s_m;
  double tangential_stiffness_N_m;  // stiction spring
  double tangential_damping_Ns_m;
  double friction_coefficient;
  const Terrain* terrain = nullptr;  // nullptr: the flat z = 0 plane
};

// floor: hard floor, about 0.1 mm of compression under the standing robot.
// carpet: the paper's stage. Foam stiffens as it compresses (f = k·d²): standing
// (67 N a point) sinks the feet 1.5 cm, one foot (135 N a point) 2.1 cm. A linear
// spring soft enough to sink that far would let the robot tip over on it (its roll
// stiffness, Σk·y², is below m·g·h), which real carpet does not do.
// Hunt–Crossley damping chosen so that at the standing load the effective damper
// is near critical for the ~7 kg a point carries (floor 4000 N·s/m, carpet 400 N·s/m).
// μ is the real surface; the controllers plan with 0.5.
inline constexpr GroundParams kFloor{"floor", 6.0e5, 1.0, 60.0, 3.0e5, 2.0e3, 0.8};
inline constexpr GroundParams kCarpet{"carpet", 3.0e5, 2.0, 6.0, 1.5e4, 3.0e2, 0.6};

// "floor" / "carpet"; false for anything else.
bool parse_ground(const char* text, GroundParams& out);

struct ContactPointState {
  Vec3 anchor_m = Vec3::Zero();  // where the tangential spring is attached (z unused)
  bool touching = false;
};

// Force of the ground (z = 0 plane, or g.terrain) on a point at position p and velocity v.
Vec3 contact_force(const GroundParams& g, const Vec3& p, const Vec3& v, const ContactPointState& s);

// Between integration intervals: attach the anchor on touchdown, drop it on
// lift-off, and slide it while the point slips.
void update_contact_point(const GroundParams& g, const Vec3& p, const Vec3& v, ContactPointState& s);

}  // namespace kuavo::sim
