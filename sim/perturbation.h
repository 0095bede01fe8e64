// Model mismatch between the simulated robot and the controller's model: the plant
// (and its sensors) get a robot that is not the tables the controller plans with.
// Off by default (PerturbationSet{} draws nothing and run_motion takes the unperturbed
// path byte for byte). Seeded: draw_perturbation(set, seed) is a pure function, so a
// campaign's run is fixed by its seed. The controller never sees any of this.
//
// Default ranges of the "show" set and where each comes from (kShowSet in perturbation.cpp):
// - link mass ±6 % per link: FACTS.md §3.2, the URDF total (51.7 kg) is 6 % under the
//   weighed 55 kg and Leju moves all of it into the torso; we spread the same size of
//   error over every link.
// - link CoM ±1 cm per axis, inertia ±10 % (the whole tensor scaled): engineering guess,
//   CAD without cables, bolts and electronics.
// - armature (reflected rotor inertia): ×[0.5, 1.5] of N²·I_rotor, N the gear ratio of
//   FACTS.md §5.1 (encoder constants 2¹⁷·18 / ·10 / ·36), I_rotor = 1.002e-4 kg·m² for
//   the EtherCAT PA100-class motors (FACTS.md §2.4, Leju's Drake transmission tag) and
//   1.0e-5 kg·m² for the smaller CK / Ruiwo motors (engineering guess from motor size).
// - joint Coulomb friction [0, 2 %] of the joint's peak torque: engineering guess for
//   geared actuators (Leju's kuavo.json carries static/dynamic friction gains of 1.0 with
//   no unit); viscous [0, 0.4] N·m·s/rad: Leju's MJCF damping="0.2" (xml/biped_s45.xml)
//   ±100 %.
// - torque constant ±5 %: engineering guess, the low end of data sheets' ±5-10 % Kt
//   tolerance because Leju sets current→torque per motor type (FACTS.md §5.1).
// - foot-ground μ 0.4-1.0 and uneven ground (tiles ±1 cm, tilt ±2° per axis): issue 20's
//   stage conditions; tile side 0.5 m (engineering guess: stage deck panels).
// - IMU gyro bias ±0.1 °/s, accelerometer bias ±0.05 m/s² (5 mg), scale ±0.5 % per axis:
//   engineering guess for the turn-on errors of a MEMS IMU of the MTi-600 class, on top
//   of the in-run bias stability sensor_model.h already draws (FACTS.md §5.3).
// - encoder offsets ±0.3° per joint: engineering guess for the absolute-encoder zeroing
//   (FACTS.md §5.1 multi-turn zeroing, the ankles' −15° motor offset calibration).
// - command latency jitter [0, 0.5 ms] per tick: FACTS.md §5.1, the EtherCAT distributed
//   clock cycle of 500 µs a command can wait for.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "controllers/model/model.h"
#include "sim/ground_contact.h"

namespace kuavo::sim {

// A uniform range [lo, hi]; lo == hi draws that value (0 = off for additive errors).
struct Range {
  double lo = 0.0;
  double hi = 0.0;
};

struct PerturbationSet {
  std::string name = "none";
  Range link_mass_rel;          // m ← m·(1 + e)
  Range link_com_m;             // each CoM axis ← + e
  Range link_inertia_rel;       // I ← I·(1 + e)
  Range armature_scale;         // × kNominalArmature_kgm2 (0: none)
  Range coulomb_rel_peak;       // τ_c = e·peak torque
  Range viscous_Nm_s_rad;
  Range torque_constant_rel;    // τ ← τ·(1 + e)
  Range foot_friction;          // μ; {0, 0}: the ground's own
  Range ground_step_m;          // per tile
  Range ground_tilt_deg;        // per axis (slope about x and y)
  Range gyro_bias_rad_s;        // per axis
  Range accel_bias_m_s2;        // per axis
  Range imu_scale_rel;          // per axis, gyro and accelerometer
  Range encoder_offset_rad;     // per joint
  Range command_jitter_s;       // extra delay of each tick's command, drawn every tick
};

// Each range's key (JSON files, the summary's echo) and member, in one fixed order.
struct NamedRange {
  const char* key;
  Range PerturbationSet::*member;
};
inline constexpr int kNumPerturbationRanges = 15;
const std::array<NamedRange, kNumPerturbationRanges>& perturbation_ranges();

// "none" (the default) and "show" (the ranges named at the top of this file).
bool perturbation_set_by_name(const std::string& name, PerturbationSet& out);
// Every range finite, lo ≤ hi, and inside what the plant can represent (masses and
// inertias stay positive, μ in (0, 2], jitter below one control period). nullptr: fine.
const char* validate_perturbation_set(const PerturbationSet& set);

// Reflected rotor inertia per joint before armature_scale (see the top of this file).
const std::array<double, model::kNumJoints>& nominal_armature_kgm2();

// The plant's actuators: what the drive's torque goes through on the way to the joint.
struct JointActuation {
  std::array<double, model::kNumJoints> armature_kgm2{};
  std::array<double, model::kNumJoints> coulomb_Nm{};
  std::array<double, model::kNumJoints> viscous_Nm_s_rad{};
  std::array<double, model::kNumJoints> torque_scale{};  // Kt_true / Kt_nominal
};

// Coulomb friction is smoothed as τ_c·tanh(v / kCoulombSmoothing_rad_s): a sign change
// inside one step would stall the stiff integrator. The joint creeps at
// v = kCoulombSmoothing·atanh(τ/τ_c) under a torque below τ_c (engineering choice:
// 1 mrad/s, a degree a quarter minute).
inline constexpr double kCoulombSmoothing_rad_s = 1e-3;

// Joint torque from the drive's output: torque-constant error, then friction.
double actuated_torque(const JointActuation& a, int joint, double drive_Nm, double v_rad_s);

struct SensorErrors {
  Eigen::Vector3d gyro_bias_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias_m_s2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_scale = Eigen::Vector3d::Ones();
  Eigen::Vector3d accel_scale = Eigen::Vector3d::Ones();
  std::array<double, model::kNumJoints> encoder_offset_rad{};
};

// One draw of a set: what the plant and the sensors of one run are.
struct PlantPerturbation {
  bool active = false;  // false: the plant is the controller's model exactly
  std::string set_name = "none";
  std::uint64_t seed = 0;
  PerturbationSet set;
  std::array<double, model::kNumBodies> mass_scale{};
  std::array<Eigen::Vector3d, model::kNumBodies> com_offset_m{};
  std::array<double, model::kNumBodies> inertia_scale{};
  JointActuation actuation;
  double foot_friction = 0.0;  // 0: the ground's own
  Terrain terrain;
  SensorErrors sensors;
  Range command_jitter_s;
};

// Draws every error of the set from its own generator seeded with seed (Coulomb friction
// scales with the nominal model's peak torques). A set whose ranges are all zero (the
// "none" set) gives active = false.
PlantPerturbation draw_perturbation(const model::Model& nominal, const PerturbationSet& set, std::uint64_t seed);

// The plant's model: the nominal one with the drawn link errors (total_mass_kg updated).
void perturbed_model(const model::Model& nominal, const PlantPerturbation& p, model::Model& out);

// The ground the plant stands on: μ and terrain applied (terrain points into p).
GroundParams perturbed_ground(const GroundParams& ground, const PlantPerturbation& p);

// A uniform draw in [lo, hi] from a 64-bit value (53 bits used): portable, unlike
// std::uniform_real_distribution, so a seed means the same run on any library.
inline double uniform_from_bits(std::uint64_t bits, const Range& r) {
  return r.lo + (r.hi - r.lo) * static_cast<double>(bits >> 11) * 0x1.0p-53;
}

// The set's ranges and the draw's figures (plant mass, μ, tilt, ...) as a JSON object.
std::string perturbation_json(const PlantPerturbation& p, const model::Model& plant_model);

}  // namespace kuavo::sim
