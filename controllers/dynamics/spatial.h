// Small fixed-size spatial-algebra helpers (linear part first, see conventions.h).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace kuavo::dynamics {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

inline Mat3 skew(const Vec3& a) {
  Mat3 s;
  s << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return s;
}

// Rotation by angle about a unit axis (Rodrigues).
inline Mat3 axis_rotation(const Vec3& axis, double angle_rad) {
  const double s = std::sin(angle_rad), c = std::cos(angle_rad);
  return c * Mat3::Identity() + s * skew(axis) + (1.0 - c) * axis * axis.transpose();
}

// m1 ×m m2 (motion cross motion).
inline Vec6 cross_motion(const Vec6& m1, const Vec6& m2) {
  Vec6 out;
  out.head<3>() = m1.tail<3>().cross(m2.head<3>()) + m1.head<3>().cross(m2.tail<3>());
  out.tail<3>() = m1.tail<3>().cross(m2.tail<3>());
  return out;
}

// m ×f f (motion cross force).
inline Vec6 cross_force(const Vec6& m, const Vec6& f) {
  Vec6 out;
  out.head<3>() = m.tail<3>().cross(f.head<3>());
  out.tail<3>() = m.tail<3>().cross(f.tail<3>()) + m.head<3>().cross(f.head<3>());
  return out;
}

// Rigid-body inertia about the reference point, world axes:
// mass, first moment h = m·c (c = CoM relative to the point), rotational inertia about the point.
struct SpatialInertia {
  double mass = 0.0;
  Vec3 first_moment = Vec3::Zero();
  Mat3 rotational = Mat3::Zero();

  Vec6 operator*(const Vec6& m) const {
    Vec6 f;
    f.head<3>() = mass * m.head<3>() - first_moment.cross(m.tail<3>());
    f.tail<3>() = first_moment.cross(m.head<3>()) + rotational * m.tail<3>();
    return f;
  }
  SpatialInertia& operator+=(const SpatialInertia& o) {
    mass += o.mass;
    first_moment += o.first_moment;
    rotational += o.rotational;
    return *this;
  }
  Mat6 matrix() const {
    Mat6 out;
    out.topLeftCorner<3, 3>() = mass * Mat3::Identity();
    out.topRightCorner<3, 3>() = -skew(first_moment);
    out.bottomLeftCorner<3, 3>() = skew(first_moment);
    out.bottomRightCorner<3, 3>() = rotational;
    return out;
  }
};

}  // namespace kuavo::dynamics
