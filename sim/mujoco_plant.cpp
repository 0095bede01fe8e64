#include "sim/mujoco_plant.h"

#include <mujoco/mujoco.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "sim/motor_model.h"

namespace kuavo::sim {
namespace {

static_assert(mjVERSION_HEADER >= 222, "the MuJoCo plant is written against MuJoCo 2.2.2");

// MuJoCo's default warning handler prints to stdout and appends to MUJOCO_LOG.TXT in the
// working directory; the plant reads the warning counters in mjData instead.
void ignore_warning(const char*) {}

// Positions of a sphere and a corner in the foot's frame agree within this [m]; the
// published files give both to 0.01 mm.
constexpr double kSameSpot_m = 1e-4;

// A collision sphere of a sole and where its force goes among our corners.
struct SoleSphere {
  int geom = -1;
  int corner[2] = {-1, -1};
  double weight[2] = {0.0, 0.0};
};

// The warnings that mean the step went wrong (MuJoCo resets the state on a bad qacc).
constexpr int kFatalWarnings[] = {mjWARN_BADQACC, mjWARN_BADQPOS, mjWARN_BADQVEL, mjWARN_CONTACTFULL, mjWARN_CNSTRFULL};

}  // namespace

const char* mujoco_ground_refusal(const GroundParams& ground) {
  if (ground.terrain != nullptr) return "the MuJoCo engine models the flat floor only (no terrain)";
  if (std::strcmp(ground.name, kFloor.name) != 0) return "the MuJoCo engine models the floor only (no carpet)";
  return nullptr;
}

struct MujocoPlant::Impl {
  const model::Model& model;
  MujocoPlantConfig config;
  mjModel* m = nullptr;
  mjData* d = nullptr;
  char error[512] = "";
  int base_body = -1, base_q = 0, base_v = 0, accelerometer = 0;
  std::array<int, model::kNumJoints> joint_q{}, joint_v{};
  std::array<int, model::kNumContactPoints> corner_sphere{};
  std::vector<SoleSphere> spheres;
  std::vector<int> sphere_of_geom;  // index into spheres, or -1
  hal::CommandFrame command{};
  Push push{};
  PlantTruth truth;
  double time_s = 0.0;
  std::uint64_t saturations = 0, steps = 0;
  int warnings_seen[mjNWARNING] = {};

  Impl(const model::Model& mdl, const MujocoPlantConfig& c) : model(mdl), config(c) {
    mju_user_warning = ignore_warning;
    if (const char* why = mujoco_ground_refusal(c.ground)) {
      fail(why);
      return;
    }
    if (!(c.timestep_s > 0.0 && c.timestep_s <= 0.002)) {
      fail("MuJoCo time step outside (0, 2 ms]");
      return;
    }
    if (load() && map_names()) return;
    free_model();
  }
  ~Impl() { free_model(); }

  void free_model() {
    if (d != nullptr) mj_deleteData(d);
    if (m != nullptr) mj_deleteModel(m);
    d = nullptr;
    m = nullptr;
  }

  bool fail(const std::string& what) {
    std::snprintf(error, sizeof error, "%s", what.c_str());
    for (char& ch : error) ch = ch == '\n' ? ' ' : ch;  // one line, for logs and JSON
    return false;
  }

  bool load() {
    MjcfOptions options;
    options.timestep_s = config.timestep_s;
    options.friction_coefficient = config.ground.friction_coefficient;
    options.gravity = config.gravity;
    options.contact = config.contact;
    std::string xml, why;
    if (!generate_mjcf(model, options, xml, why)) return fail(why);
    // MuJoCo 2.2.2 loads MJCF from a file: the generated copy lives in the temp directory
    // while it loads (its meshdir is absolute), one name per process and plant.
    static std::atomic<unsigned> serial{0};
    std::error_code ec;
    const auto path = std::filesystem::temp_directory_path(ec) /
                      ("kuavo_mjcf_" + std::to_string(::getpid()) + "_" + std::to_string(serial++) + ".xml");
    {
      std::ofstream out(path, std::ios::binary);
      out << xml;
      if (!out) return fail("cannot write the generated MJCF '" + path.string() + "'");
    }
    char load_error[1000] = "";
    m = mj_loadXML(path.c_str(), nullptr, load_error, sizeof load_error);
    std::filesystem::remove(path, ec);
    if (m == nullptr) return fail(std::string("MuJoCo cannot load the generated MJCF: ") + load_error);
    d = mj_makeData(m);
    if (d == nullptr) return fail("mj_makeData failed");
    return true;
  }

  bool map_names() {
    base_body = mj_name2id(m, mjOBJ_BODY, model.tables->bodies[0].link_name);
    if (base_body < 0 || m->body_jntnum[base_body] != 1 || m->jnt_type[m->body_jntadr[base_body]] != mjJNT_FREE) {
      return fail("MJCF: base_link has no free joint");
    }
    base_q = m->jnt_qposadr[m->body_jntadr[base_body]];
    base_v = m->jnt_dofadr[m->body_jntadr[base_body]];
    for (int j = 0; j < model::kNumJoints; ++j) {
      const int id = mj_name2id(m, mjOBJ_JOINT, model::joint_name(model, j));
      if (id < 0 || m->jnt_type[id] != mjJNT_HINGE) return fail(std::string("MJCF: no hinge ") + model::joint_name(model, j));
      joint_q[j] = m->jnt_qposadr[id];
      joint_v[j] = m->jnt_dofadr[id];
    }
    const int acc = mj_name2id(m, mjOBJ_SENSOR, "BodyAcc");
    const int imu = mj_name2id(m, mjOBJ_SITE, "imu");
    if (acc < 0 || m->sensor_type[acc] != mjSENS_ACCELEROMETER || imu < 0 || m->site_bodyid[imu] != base_body) {
      return fail("MJCF: no accelerometer BodyAcc at the imu site of base_link");
    }
    for (int k = 0; k < 3; ++k) {  // the imu site must be the base origin in base axes (our IMU)
      if (std::abs(m->site_pos[3 * imu + k]) > 1e-12) return fail("MJCF: the imu site is not at the base origin");
    }
    if (std::abs(m->site_quat[4 * imu] - 1.0) > 1e-12) return fail("MJCF: the imu site is rotated");
    accelerometer = m->sensor_adr[acc];
    return map_soles();
  }

  // Each collision sphere of a sole goes to the corners at its x (our corners are the
  // soles' outer spheres; a middle sphere shares its force between the two it lies between).
  bool map_soles() {
    sphere_of_geom.assign(static_cast<std::size_t>(m->ngeom), -1);
    corner_sphere.fill(-1);
    for (int g = 0; g < m->ngeom; ++g) {
      if (m->geom_contype[g] == 0 && m->geom_conaffinity[g] == 0) continue;
      // Only the soles: the floor, and the spheres Leju puts at the hands (they touch the
      // floor in MuJoCo, not in Simbody, and only once the robot has fallen).
      bool on_sole = false;
      for (int c = 0; c < model::kNumContactPoints; ++c) {
        on_sole = on_sole || mj_name2id(m, mjOBJ_BODY, model.tables->bodies[model.frames[c].body].link_name) == m->geom_bodyid[g];
      }
      if (!on_sole) continue;
      if (m->geom_type[g] != mjGEOM_SPHERE) return fail("MJCF: a colliding geom of a sole is not a sphere");
      const Vec3 p(m->geom_pos[3 * g], m->geom_pos[3 * g + 1], m->geom_pos[3 * g + 2]);
      SoleSphere s;
      s.geom = g;
      std::vector<int> at_x;
      for (int c = 0; c < model::kNumContactPoints; ++c) {
        const model::Frame& f = model.frames[c];
        if (mj_name2id(m, mjOBJ_BODY, model.tables->bodies[f.body].link_name) != m->geom_bodyid[g]) continue;
        if (std::abs(f.position_m.x() - p.x()) > kSameSpot_m || std::abs(f.position_m.z() - p.z()) > kSameSpot_m) continue;
        if (std::abs(f.position_m.y() - p.y()) <= kSameSpot_m) {
          s.corner[0] = c, s.weight[0] = 1.0;
          corner_sphere[c] = g;
        }
        at_x.push_back(c);
      }
      if (s.corner[0] < 0 && at_x.size() == 2) {
        const double y0 = model.frames[at_x[0]].position_m.y(), y1 = model.frames[at_x[1]].position_m.y();
        const double w1 = (p.y() - y0) / (y1 - y0);
        if (w1 > 0.0 && w1 < 1.0) {
          s.corner[0] = at_x[0], s.weight[0] = 1.0 - w1;
          s.corner[1] = at_x[1], s.weight[1] = w1;
        }
      }
      if (s.corner[0] < 0) return fail("MJCF: a sole sphere lies at none of our sole corners");
      sphere_of_geom[static_cast<std::size_t>(g)] = static_cast<int>(spheres.size());
      spheres.push_back(s);
    }
    for (int c = 0; c < model::kNumContactPoints; ++c) {
      if (corner_sphere[c] < 0) return fail(std::string("MJCF: no sole sphere at ") + model::frame_name(model, c));
    }
    return true;
  }

  Eigen::Matrix3d base_rotation() const {
    Eigen::Matrix3d r;
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < 3; ++k) r(i, k) = d->xmat[9 * base_body + 3 * i + k];
    }
    return r;
  }

  void joint_state(JointValues& q, JointValues& v) const {
    for (int j = 0; j < model::kNumJoints; ++j) {
      q[j] = d->qpos[joint_q[j]];
      v[j] = d->qvel[joint_v[j]];
    }
  }

  void apply_drives() {
    JointValues q{}, v{}, tau{};
    joint_state(q, v);
    drive_torques(command, model, q, v, config.ankle_motors, tau);
    for (int j = 0; j < model::kNumJoints; ++j) d->qfrc_applied[joint_v[j]] = tau[j];
    // MuJoCo applies xfrc_applied at the body's centre of mass, as Plant applies the push.
    const double t = d->time;
    const bool pushing = push.duration_s > 0.0 && t >= push.start_s && t < push.start_s + push.duration_s;
    for (int k = 0; k < 3; ++k) d->xfrc_applied[6 * base_body + k] = pushing ? push.force_N[k] : 0.0;
  }

  // Derived quantities at the current state, then the truth in our conventions.
  void update_truth(bool count_saturations) {
    mj_forward(m, d);
    mj_subtreeVel(m, d);
    PlantTruth& t = truth;
    const Eigen::Matrix3d r = base_rotation();
    for (int k = 0; k < 3; ++k) t.q[k] = d->qpos[base_q + k];
    t.q[3] = d->qpos[base_q + 4], t.q[4] = d->qpos[base_q + 5], t.q[5] = d->qpos[base_q + 6], t.q[6] = d->qpos[base_q + 3];
    const Vec3 v_world(d->qvel[base_v], d->qvel[base_v + 1], d->qvel[base_v + 2]);
    t.v.head<3>() = r.transpose() * v_world;
    for (int k = 0; k < 3; ++k) t.v[3 + k] = d->qvel[base_v + 3 + k];
    JointValues q{}, v{}, tau{};
    joint_state(q, v);
    const int clipped = drive_torques(command, model, q, v, config.ankle_motors, tau);
    if (count_saturations) saturations += clipped;
    for (int j = 0; j < model::kNumJoints; ++j) {
      t.q[7 + j] = q[j];
      t.v[6 + j] = v[j];
      t.joint_torque_Nm[j] = tau[j];
    }
    for (int c = 0; c < model::kNumContactPoints; ++c) {
      const int g = corner_sphere[c];
      t.contact_point_m[c] = Vec3(d->geom_xpos[3 * g], d->geom_xpos[3 * g + 1], d->geom_xpos[3 * g + 2] - m->geom_size[3 * g]);
      t.contact_force_N[c].setZero();
    }
    for (int i = 0; i < d->ncon; ++i) {
      const mjContact& con = d->contact[i];
      int s = sphere_of_geom[static_cast<std::size_t>(con.geom2)];
      double sign = 1.0;  // the force of the contact on geom2, along the normal from geom1 to geom2
      if (s < 0) s = sphere_of_geom[static_cast<std::size_t>(con.geom1)], sign = -1.0;
      if (s < 0) continue;
      mjtNum f[6];
      mj_contactForce(m, d, i, f);
      Vec3 world = Vec3::Zero();
      for (int a = 0; a < 3; ++a) world += f[a] * Vec3(con.frame[3 * a], con.frame[3 * a + 1], con.frame[3 * a + 2]);
      const SoleSphere& sp = spheres[static_cast<std::size_t>(s)];
      for (int k = 0; k < 2; ++k) {
        if (sp.corner[k] >= 0) t.contact_force_N[sp.corner[k]] += sign * sp.weight[k] * world;
      }
    }
    for (int k = 0; k < 3; ++k) t.base_specific_force_m_s2[k] = d->sensordata[accelerometer + k];
    t.com_m = Vec3(d->subtree_com[3 * base_body], d->subtree_com[3 * base_body + 1], d->subtree_com[3 * base_body + 2]);
    const double mass = m->body_subtreemass[base_body];
    for (int k = 0; k < 3; ++k) {
      t.momentum[k] = mass * d->subtree_linvel[3 * base_body + k];
      t.momentum[3 + k] = d->subtree_angmom[3 * base_body + k];
    }
  }

  PlantError advance(double dt_s) {
    if (m == nullptr) return fail("the MuJoCo model did not load"), PlantError::kIntegratorFailed;
    const double n_real = dt_s / m->opt.timestep;
    const long long n = std::llround(n_real);
    if (n < 1 || std::abs(static_cast<double>(n) - n_real) > 1e-6) {
      fail("MuJoCo plant: the interval is not a whole number of time steps");
      return PlantError::kIntegratorFailed;
    }
    for (long long k = 0; k < n; ++k) {
      apply_drives();
      mj_step(m, d);
      ++steps;
    }
    time_s += dt_s;
    for (const int w : kFatalWarnings) {
      if (d->warning[w].number != warnings_seen[w]) {
        warnings_seen[w] = d->warning[w].number;
        std::snprintf(error, sizeof error, "MuJoCo warning %d at t = %.4f s (bad acceleration, state or a full contact buffer)", w, time_s);
        return PlantError::kIntegratorFailed;
      }
    }
    for (int i = 0; i < m->nq; ++i) {
      if (!std::isfinite(d->qpos[i])) return fail("non-finite plant state"), PlantError::kNonFiniteState;
    }
    for (int i = 0; i < m->nv; ++i) {
      if (!std::isfinite(d->qvel[i])) return fail("non-finite plant state"), PlantError::kNonFiniteState;
    }
    update_truth(true);
    return PlantError::kOk;
  }
};

MujocoPlant::MujocoPlant(const model::Model& model, const MujocoPlantConfig& config)
    : impl_(std::make_unique<Impl>(model, config)) {}
MujocoPlant::~MujocoPlant() = default;
bool MujocoPlant::ok() const { return impl_->m != nullptr; }

void MujocoPlant::reset(const dynamics::ConfigVector& q, const dynamics::VelocityVector& v, double time_s) {
  Impl& p = *impl_;
  if (p.m == nullptr) return;
  mj_resetData(p.m, p.d);
  for (int w = 0; w < mjNWARNING; ++w) p.warnings_seen[w] = p.d->warning[w].number;
  const Eigen::Quaterniond o(q[6], q[3], q[4], q[5]);
  const Vec3 v_world = o.normalized() * v.head<3>();
  for (int k = 0; k < 3; ++k) {
    p.d->qpos[p.base_q + k] = q[k];
    p.d->qvel[p.base_v + k] = v_world[k];
    p.d->qvel[p.base_v + 3 + k] = v[3 + k];
  }
  p.d->qpos[p.base_q + 3] = q[6], p.d->qpos[p.base_q + 4] = q[3], p.d->qpos[p.base_q + 5] = q[4], p.d->qpos[p.base_q + 6] = q[5];
  for (int j = 0; j < model::kNumJoints; ++j) {
    p.d->qpos[p.joint_q[j]] = q[7 + j];
    p.d->qvel[p.joint_v[j]] = v[6 + j];
  }
  p.d->time = time_s;
  p.time_s = time_s;
  p.update_truth(false);
}

void MujocoPlant::set_command(const hal::CommandFrame& command) { impl_->command = command; }
void MujocoPlant::set_push(const Push& push) { impl_->push = push; }
PlantError MujocoPlant::advance(double dt_s) { return impl_->advance(dt_s); }
double MujocoPlant::time_s() const { return impl_->time_s; }
const PlantTruth& MujocoPlant::truth() const { return impl_->truth; }
std::uint64_t MujocoPlant::torque_saturations() const { return impl_->saturations; }
std::uint64_t MujocoPlant::derivative_evaluations() const { return impl_->steps; }
Plant::IntegratorStats MujocoPlant::integrator_stats() const {
  Plant::IntegratorStats s;
  s.steps = static_cast<long>(impl_->steps);
  return s;
}
const char* MujocoPlant::last_error() const { return impl_->error; }
double MujocoPlant::sole_sphere_radius_m() const {
  return ok() ? impl_->m->geom_size[3 * impl_->corner_sphere[0]] : 0.0;
}
double MujocoPlant::total_mass_kg() const { return ok() ? mj_getTotalmass(impl_->m) : 0.0; }

void reset_on_floor(MujocoPlant& plant, dynamics::ConfigVector& q) {
  plant.reset(q, dynamics::VelocityVector::Zero());
  double lowest_m = 1e9;
  for (const Vec3& c : plant.truth().contact_point_m) lowest_m = std::min(lowest_m, c.z());
  q[2] -= lowest_m;
  plant.reset(q, dynamics::VelocityVector::Zero());
}

}  // namespace kuavo::sim
