#include "controllers/model/model.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>

#include "controllers/model/generated/biped_s42_tables.h"
#include "controllers/model/generated/biped_s45_tables.h"

namespace kuavo::model {
namespace {

Vec3 to_vec(const Vec3Table& v) { return {v.x, v.y, v.z}; }

Mat3 rpy_to_matrix(const Vec3Table& rpy) {
  return (Eigen::AngleAxisd(rpy.z, Vec3::UnitZ()) * Eigen::AngleAxisd(rpy.y, Vec3::UnitY()) *
          Eigen::AngleAxisd(rpy.x, Vec3::UnitX()))
      .toRotationMatrix();
}

}  // namespace

const char* to_string(ModelError e) {
  switch (e) {
    case ModelError::kOk: return "ok";
    case ModelError::kUnknownVariant: return "unknown robot variant (expected s45 or s42)";
    case ModelError::kMassTooSmall: return "total mass must exceed the non-torso mass of the model";
    case ModelError::kMassNotFinite: return "total mass is not a finite number";
  }
  return "unknown model error";
}

const char* to_string(Variant v) { return v == Variant::kS42 ? "s42" : "s45"; }

bool parse_variant(const char* text, Variant& out) {
  if (text != nullptr && std::strcmp(text, "s45") == 0) {
    out = Variant::kS45;
    return true;
  }
  if (text != nullptr && std::strcmp(text, "s42") == 0) {
    out = Variant::kS42;
    return true;
  }
  return false;
}

const ModelTables& tables_for(Variant v) { return v == Variant::kS42 ? kBipedS42 : kBipedS45; }

ModelError build_model(Variant v, double total_mass_kg, Model& out) {
  if (v != Variant::kS45 && v != Variant::kS42) return ModelError::kUnknownVariant;
  if (!std::isfinite(total_mass_kg)) return ModelError::kMassNotFinite;
  const ModelTables& t = tables_for(v);
  out.variant = v;
  out.tables = &t;
  double non_torso_kg = 0.0;
  for (int b = 0; b < kNumBodies; ++b) {
    const BodyTable& bt = t.bodies[b];
    Body& body = out.bodies[b];
    body.parent = bt.parent;
    body.joint_rotation = rpy_to_matrix(bt.joint_rpy_rad);
    body.joint_position_m = to_vec(bt.joint_xyz_m);
    body.axis = to_vec(bt.axis);
    body.mass_kg = bt.mass_kg;
    body.com_m = to_vec(bt.com_m);
    const double* i = bt.inertia_kgm2;
    body.inertia_com_kgm2 << i[0], i[3], i[4], i[3], i[1], i[5], i[4], i[5], i[2];
    if (b > 0) non_torso_kg += bt.mass_kg;
  }
  // A torso lighter than a tenth of the robot is a typo, not a robot.
  if (!(total_mass_kg - non_torso_kg > 0.1 * total_mass_kg)) return ModelError::kMassTooSmall;
  out.bodies[0].mass_kg = total_mass_kg - non_torso_kg;
  out.total_mass_kg = total_mass_kg;
  for (int f = 0; f < kNumFrames; ++f) {
    out.frames[f].body = t.frames[f].body;
    out.frames[f].position_m = to_vec(t.frames[f].xyz_m);
    out.frames[f].rotation = rpy_to_matrix(t.frames[f].rpy_rad);
  }
  for (int j = 0; j < kNumJoints; ++j) {
    const JointLimitTable& l = t.limits[j];
    out.limits.position_min_rad[j] = l.position_min_rad;
    out.limits.position_max_rad[j] = l.position_max_rad;
    out.limits.velocity_rad_s[j] = l.velocity_rad_s;
    out.limits.torque_Nm[j] = l.torque_Nm;
    out.limits.peak_velocity_rad_s[j] = l.peak_velocity_rad_s;
    out.limits.peak_torque_Nm[j] = l.peak_torque_Nm;
  }
  return ModelError::kOk;
}

void inset_sole_corners(Model& m, double inset_m) {
  static_assert(kNumContactPoints == 8, "four sole corners per foot");
  for (int foot = 0; foot < 2; ++foot) {
    Vec3 centre = Vec3::Zero();
    for (int k = 0; k < 4; ++k) centre += 0.25 * m.frames[4 * foot + k].position_m;
    for (int k = 0; k < 4; ++k) {
      Vec3& p = m.frames[4 * foot + k].position_m;
      for (int axis = 0; axis < 2; ++axis) {
        const double half = std::abs(p[axis] - centre[axis]);
        p[axis] = centre[axis] + std::copysign(std::max(half - inset_m, 0.0), p[axis] - centre[axis]);
      }
    }
  }
}

}  // namespace kuavo::model
