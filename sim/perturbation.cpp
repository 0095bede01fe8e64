#include "sim/perturbation.h"

#include <cmath>
#include <cstdio>
#include <random>

namespace kuavo::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// FACTS.md §2.4: Leju's Drake transmission tag for the PA100-class drives.
constexpr double kRotorPa100_kgm2 = 1.002e-4;
// Engineering guess for the CK (ankle) and Ruiwo (arm, head) motors: a smaller frame.
constexpr double kRotorSmall_kgm2 = 1.0e-5;

// Gear ratio and rotor per joint: FACTS.md §5.1 motor table (hip roll, knee PA100_18 18:1;
// hip yaw, hip pitch, shoulder pitch PA100 10:1; ankles CK 36:1; arm 2-7, head Ruiwo 36:1).
std::array<double, model::kNumJoints> make_nominal_armature() {
  std::array<double, model::kNumJoints> a{};
  auto reflected = [](double ratio, double rotor) { return ratio * ratio * rotor; };
  for (int side = 0; side < 2; ++side) {
    const int l = side * model::kLegJoints;
    a[l + 0] = reflected(18.0, kRotorPa100_kgm2);  // hip roll
    a[l + 1] = reflected(10.0, kRotorPa100_kgm2);  // hip yaw
    a[l + 2] = reflected(10.0, kRotorPa100_kgm2);  // hip pitch
    a[l + 3] = reflected(18.0, kRotorPa100_kgm2);  // knee
    a[l + 4] = reflected(36.0, kRotorSmall_kgm2);  // ankle pitch (CK, through the linkage)
    a[l + 5] = reflected(36.0, kRotorSmall_kgm2);  // ankle roll
    const int arm = model::kLeftArmFirst + side * model::kArmJoints;
    a[arm] = reflected(10.0, kRotorPa100_kgm2);  // shoulder pitch
    for (int k = 1; k < model::kArmJoints; ++k) a[arm + k] = reflected(36.0, kRotorSmall_kgm2);
  }
  a[model::kHeadFirst] = a[model::kHeadFirst + 1] = reflected(36.0, kRotorSmall_kgm2);
  return a;
}

PerturbationSet make_show_set() {
  PerturbationSet s;
  s.name = "show";
  s.link_mass_rel = {-0.06, 0.06};
  s.link_com_m = {-0.01, 0.01};
  s.link_inertia_rel = {-0.10, 0.10};
  s.armature_scale = {0.5, 1.5};
  s.coulomb_rel_peak = {0.0, 0.02};
  s.viscous_Nm_s_rad = {0.0, 0.4};
  s.torque_constant_rel = {-0.05, 0.05};
  s.foot_friction = {0.4, 1.0};
  s.ground_step_m = {-0.01, 0.01};
  s.ground_tilt_deg = {-2.0, 2.0};
  s.gyro_bias_rad_s = {-0.1 * kDeg, 0.1 * kDeg};
  s.accel_bias_m_s2 = {-0.05, 0.05};
  s.imu_scale_rel = {-0.005, 0.005};
  s.encoder_offset_rad = {-0.3 * kDeg, 0.3 * kDeg};
  s.command_jitter_s = {0.0, 0.0005};
  return s;
}

bool is_zero(const Range& r) { return r.lo == 0.0 && r.hi == 0.0; }

template <class F>
void for_each_range(const PerturbationSet& s, F&& f) {
  for (const NamedRange& r : perturbation_ranges()) f(r.key, s.*r.member);
}

// Control period the jitter must stay below (sim/closed_loop.h kControlPeriod_s, 500 Hz).
constexpr double kControlPeriodLimit_s = 0.002;

}  // namespace

const std::array<NamedRange, kNumPerturbationRanges>& perturbation_ranges() {
  using S = PerturbationSet;
  static constexpr std::array<NamedRange, kNumPerturbationRanges> kRanges{{
      {"link_mass_rel", &S::link_mass_rel},
      {"link_com_m", &S::link_com_m},
      {"link_inertia_rel", &S::link_inertia_rel},
      {"armature_scale", &S::armature_scale},
      {"coulomb_rel_peak", &S::coulomb_rel_peak},
      {"viscous_Nm_s_rad", &S::viscous_Nm_s_rad},
      {"torque_constant_rel", &S::torque_constant_rel},
      {"foot_friction", &S::foot_friction},
      {"ground_step_m", &S::ground_step_m},
      {"ground_tilt_deg", &S::ground_tilt_deg},
      {"gyro_bias_rad_s", &S::gyro_bias_rad_s},
      {"accel_bias_m_s2", &S::accel_bias_m_s2},
      {"imu_scale_rel", &S::imu_scale_rel},
      {"encoder_offset_rad", &S::encoder_offset_rad},
      {"command_jitter_s", &S::command_jitter_s},
  }};
  return kRanges;
}

const std::array<double, model::kNumJoints>& nominal_armature_kgm2() {
  static const std::array<double, model::kNumJoints> a = make_nominal_armature();
  return a;
}

bool perturbation_set_by_name(const std::string& name, PerturbationSet& out) {
  if (name == "none") {
    out = PerturbationSet{};
    return true;
  }
  if (name == "show") {
    out = make_show_set();
    return true;
  }
  return false;
}

const char* validate_perturbation_set(const PerturbationSet& s) {
  const char* bad = nullptr;
  for_each_range(s, [&](const char*, const Range& r) {
    if (bad == nullptr && !(std::isfinite(r.lo) && std::isfinite(r.hi) && r.lo <= r.hi)) bad = "a range is not finite or has lo > hi";
  });
  if (bad != nullptr) return bad;
  if (s.link_mass_rel.lo <= -1.0 || s.link_inertia_rel.lo <= -1.0) return "link_mass_rel and link_inertia_rel must stay above -1";
  if (s.armature_scale.lo < 0.0) return "armature_scale must be >= 0";
  if (s.coulomb_rel_peak.lo < 0.0 || s.viscous_Nm_s_rad.lo < 0.0) return "friction must be >= 0";
  if (s.torque_constant_rel.lo <= -1.0) return "torque_constant_rel must stay above -1";
  if (!is_zero(s.foot_friction) && !(s.foot_friction.lo > 0.0 && s.foot_friction.hi <= 2.0)) return "foot_friction must be in (0, 2]";
  if (std::abs(s.ground_tilt_deg.lo) > 30.0 || std::abs(s.ground_tilt_deg.hi) > 30.0) return "ground_tilt_deg must be within +-30";
  if (std::abs(s.ground_step_m.lo) > 0.1 || std::abs(s.ground_step_m.hi) > 0.1) return "ground_step_m must be within +-0.1";
  if (s.imu_scale_rel.lo <= -1.0) return "imu_scale_rel must stay above -1";
  if (s.command_jitter_s.lo < 0.0 || s.command_jitter_s.hi >= kControlPeriodLimit_s)
    return "command_jitter_s must be in [0, 0.002)";
  return nullptr;
}

double actuated_torque(const JointActuation& a, int j, double drive_Nm, double v_rad_s) {
  return a.torque_scale[j] * drive_Nm - a.coulomb_Nm[j] * std::tanh(v_rad_s / kCoulombSmoothing_rad_s) -
         a.viscous_Nm_s_rad[j] * v_rad_s;
}

PlantPerturbation draw_perturbation(const model::Model& nominal, const PerturbationSet& set, std::uint64_t seed) {
  PlantPerturbation p;
  p.set = set;
  p.set_name = set.name;
  p.seed = seed;
  bool any = false;
  for_each_range(set, [&](const char*, const Range& r) { any = any || !is_zero(r); });
  p.active = any;
  // Neutral values first, so an inactive draw is the nominal robot.
  p.mass_scale.fill(1.0);
  p.inertia_scale.fill(1.0);
  for (auto& c : p.com_offset_m) c.setZero();
  p.actuation.torque_scale.fill(1.0);
  if (!any) return p;

  // Every quantity is drawn in a fixed order from one generator, whatever its range, so
  // changing one range leaves the other draws of a seed unchanged.
  std::mt19937_64 rng(seed);
  auto draw = [&](const Range& r) { return uniform_from_bits(rng(), r); };
  for (int b = 0; b < model::kNumBodies; ++b) {
    p.mass_scale[b] = 1.0 + draw(set.link_mass_rel);
    for (int k = 0; k < 3; ++k) p.com_offset_m[b][k] = draw(set.link_com_m);
    p.inertia_scale[b] = 1.0 + draw(set.link_inertia_rel);
  }
  const auto& nominal_armature = nominal_armature_kgm2();
  for (int j = 0; j < model::kNumJoints; ++j) {
    p.actuation.armature_kgm2[j] = nominal_armature[j] * draw(set.armature_scale);
    p.actuation.coulomb_Nm[j] = draw(set.coulomb_rel_peak) * nominal.limits.peak_torque_Nm[j];
    p.actuation.viscous_Nm_s_rad[j] = draw(set.viscous_Nm_s_rad);
    p.actuation.torque_scale[j] = 1.0 + draw(set.torque_constant_rel);
    p.sensors.encoder_offset_rad[j] = draw(set.encoder_offset_rad);
  }
  p.foot_friction = draw(set.foot_friction);
  p.terrain.slope_x = std::tan(draw(set.ground_tilt_deg) * kDeg);
  p.terrain.slope_y = std::tan(draw(set.ground_tilt_deg) * kDeg);
  p.terrain.step_lo_m = set.ground_step_m.lo;
  p.terrain.step_hi_m = set.ground_step_m.hi;
  p.terrain.grid_origin_x_m = uniform_from_bits(rng(), {0.0, p.terrain.tile_m});
  p.terrain.grid_origin_y_m = uniform_from_bits(rng(), {0.0, p.terrain.tile_m});
  p.terrain.seed = rng();
  for (int k = 0; k < 3; ++k) {
    p.sensors.gyro_bias_rad_s[k] = draw(set.gyro_bias_rad_s);
    p.sensors.accel_bias_m_s2[k] = draw(set.accel_bias_m_s2);
    p.sensors.gyro_scale[k] = 1.0 + draw(set.imu_scale_rel);
    p.sensors.accel_scale[k] = 1.0 + draw(set.imu_scale_rel);
  }
  p.command_jitter_s = set.command_jitter_s;
  return p;
}

void perturbed_model(const model::Model& nominal, const PlantPerturbation& p, model::Model& out) {
  out = nominal;
  out.total_mass_kg = 0.0;
  for (int b = 0; b < model::kNumBodies; ++b) {
    model::Body& body = out.bodies[b];
    body.mass_kg *= p.mass_scale[b];
    body.com_m += p.com_offset_m[b];
    body.inertia_com_kgm2 *= p.inertia_scale[b];
    out.total_mass_kg += body.mass_kg;
  }
}

GroundParams perturbed_ground(const GroundParams& ground, const PlantPerturbation& p) {
  GroundParams g = ground;
  if (!p.active) return g;
  if (p.foot_friction > 0.0) g.friction_coefficient = p.foot_friction;
  const bool flat = p.terrain.slope_x == 0.0 && p.terrain.slope_y == 0.0 && p.terrain.step_lo_m == 0.0 &&
                    p.terrain.step_hi_m == 0.0;
  g.terrain = flat ? nullptr : &p.terrain;
  return g;
}

std::string perturbation_json(const PlantPerturbation& p, const model::Model& plant_model) {
  std::string s = "{\"set\": \"" + p.set_name + "\", \"seed\": " + std::to_string(p.seed) + ", \"ranges\": {";
  char buf[256];
  bool first = true;
  for_each_range(p.set, [&](const char* name, const Range& r) {
    std::snprintf(buf, sizeof buf, "%s\"%s\": [%.6g, %.6g]", first ? "" : ", ", name, r.lo, r.hi);
    s += buf;
    first = false;
  });
  double armature_max = 0.0, coulomb_max = 0.0, kt_min = 1.0, kt_max = 1.0, offset_max = 0.0;
  for (int j = 0; j < model::kNumJoints; ++j) {
    armature_max = std::max(armature_max, p.actuation.armature_kgm2[j]);
    coulomb_max = std::max(coulomb_max, p.actuation.coulomb_Nm[j]);
    kt_min = std::min(kt_min, p.actuation.torque_scale[j]);
    kt_max = std::max(kt_max, p.actuation.torque_scale[j]);
    offset_max = std::max(offset_max, std::abs(p.sensors.encoder_offset_rad[j]));
  }
  std::snprintf(buf, sizeof buf,
                "}, \"drawn\": {\"plant_mass_kg\": %.4f, \"foot_friction\": %.4f, \"tilt_deg\": [%.4f, %.4f], "
                "\"armature_kgm2_max\": %.5f, \"coulomb_Nm_max\": %.4f, \"torque_scale\": [%.4f, %.4f], ",
                plant_model.total_mass_kg, p.foot_friction, std::atan(p.terrain.slope_x) / kDeg,
                std::atan(p.terrain.slope_y) / kDeg, armature_max, coulomb_max, kt_min, kt_max);
  s += buf;
  const SensorErrors& e = p.sensors;
  std::snprintf(buf, sizeof buf,
                "\"gyro_bias_rad_s\": [%.3g, %.3g, %.3g], \"accel_bias_m_s2\": [%.3g, %.3g, %.3g], "
                "\"encoder_offset_rad_max\": %.3g}}",
                e.gyro_bias_rad_s.x(), e.gyro_bias_rad_s.y(), e.gyro_bias_rad_s.z(), e.accel_bias_m_s2.x(),
                e.accel_bias_m_s2.y(), e.accel_bias_m_s2.z(), offset_max);
  s += buf;
  return s;
}

}  // namespace kuavo::sim
