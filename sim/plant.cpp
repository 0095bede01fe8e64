#include "sim/plant.h"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Simbody.h>
#include <cstdio>
#include <cstring>
#include <exception>

#include "sim/joint_stop.h"
#include "sim/motor_model.h"
#include "sim/newton_system.h"
#include "sim/plant_dynamics.h"
#include "sim/simbody_model.h"

namespace kuavo::sim {
namespace {

SimTK::Vec3 to_simtk(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
Vec3 from_simtk(const SimTK::Vec3& v) { return {v[0], v[1], v[2]}; }

// Where a sole corner is and how fast it moves, in the world (state at least at Velocity).
void contact_point_motion(const model::Model& m, const SimbodyRobot& r, const SimTK::State& s, int c, Vec3& p,
                          Vec3& v) {
  const model::Frame& f = m.frames[c];
  const SimTK::MobilizedBody& b = r.body(f.body);
  const SimTK::Vec3 station = to_simtk(f.position_m);
  p = from_simtk(b.findStationLocationInGround(s, station));
  v = from_simtk(b.findStationVelocityInGround(s, station));
}

// Everything the custom force reads; owned by Plant::Impl, updated between intervals.
struct ForceInputs {
  const model::Model* model = nullptr;
  const SimbodyRobot* robot = nullptr;
  PlantForceInputs forces;  // shared with PlantDynamics; forces.push points at push below
  Push push{};
  mutable std::uint64_t saturations = 0;
  // Contact wrench of the last force evaluation: [force; moment about the world origin].
  mutable Eigen::Matrix<double, 6, 1> contact_wrench = Eigen::Matrix<double, 6, 1>::Zero();
  mutable bool count_saturations = false;
};

class RobotForces : public SimTK::Force::Custom::Implementation {
 public:
  explicit RobotForces(const ForceInputs* in) : in_(in) {}

  void calcForce(const SimTK::State& s, SimTK::Vector_<SimTK::SpatialVec>& body_forces,
                 SimTK::Vector_<SimTK::Vec3>&, SimTK::Vector& mobility_forces) const override {
    const model::Model& m = *in_->model;
    const SimbodyRobot& r = *in_->robot;
    JointValues q{}, v{}, tau{};
    for (int j = 0; j < model::kNumJoints; ++j) {
      q[j] = r.body(j + 1).getOneQ(s, 0);
      v[j] = r.body(j + 1).getOneU(s, 0);
    }
    const int clipped = drive_torques(in_->forces.command, m, q, v, in_->forces.ankle_motors, tau);
    if (in_->count_saturations) in_->saturations += clipped;
    for (int j = 0; j < model::kNumJoints; ++j) {
      if (in_->forces.actuation != nullptr) tau[j] = actuated_torque(*in_->forces.actuation, j, tau[j], v[j]);
      tau[j] += joint_stop_torque(q[j], v[j], m.limits.position_min_rad[j], m.limits.position_max_rad[j]);
      r.body(j + 1).applyOneMobilityForce(s, 0, tau[j], mobility_forces);
    }
    if (in_->forces.torque_source != nullptr) {
      JointValues extra{};
      in_->forces.torque_source->add_joint_torques(q, v, extra);
      for (int j = 0; j < model::kNumJoints; ++j) r.body(j + 1).applyOneMobilityForce(s, 0, extra[j], mobility_forces);
    }
    in_->contact_wrench.setZero();
    if (in_->forces.contact) {
      for (int c = 0; c < model::kNumContactPoints; ++c) {
        Vec3 p, v;
        contact_point_motion(m, r, s, c, p, v);
        const Vec3 force = contact_force(in_->forces.ground, p, v, in_->forces.points[c]);
        if (force.z() > 0.0) {
          r.body(m.frames[c].body).applyForceToBodyPoint(s, to_simtk(m.frames[c].position_m), to_simtk(force), body_forces);
          in_->contact_wrench.head<3>() += force;
          in_->contact_wrench.tail<3>() += p.cross(force);
        }
      }
    }
    const Push& push = in_->push;
    const double t = s.getTime();
    if (push.duration_s > 0.0 && t >= push.start_s && t < push.start_s + push.duration_s) {
      const SimTK::MobilizedBody& torso = r.body(0);
      torso.applyForceToBodyPoint(s, torso.getBodyMassCenterStation(s), to_simtk(push.force_N), body_forces);
    }
  }
  SimTK::Real calcPotentialEnergy(const SimTK::State&) const override { return 0; }

 private:
  const ForceInputs* in_;
};

}  // namespace

bool parse_integrator(const char* text, Integrator& out) {
  if (text == nullptr) return false;
  if (!std::strcmp(text, "cvode")) out = Integrator::kCvodeBdf;
  else if (!std::strcmp(text, "rkm")) out = Integrator::kSimbodyRungeKuttaMerson;
  else if (!std::strcmp(text, "euler")) out = Integrator::kSemiImplicitEuler;
  else return false;
  return true;
}

const char* to_string(Integrator i) {
  switch (i) {
    case Integrator::kCvodeBdf: return "cvode";
    case Integrator::kSimbodyRungeKuttaMerson: return "rkm";
    case Integrator::kSemiImplicitEuler: return "euler";
  }
  return "unknown";
}

struct Plant::Impl {
  const model::Model& model;
  PlantConfig config;
  SimbodyRobot robot;
  ForceInputs inputs;
  SimTK::State state;
  PlantTruth truth;
  std::uint64_t evaluations = 0;
  Eigen::Matrix<double, 6, 1> contact_impulse = Eigen::Matrix<double, 6, 1>::Zero();
  char error[200] = "";

  // CVODE over y = Simbody's [q; u].
  SUNContext sun = nullptr;
  void* cvode = nullptr;
  N_Vector y = nullptr;
  SUNMatrix jac = nullptr;  // unused: CVODE's matrix-based interface wants one; NewtonSystem holds J
  SUNLinearSolver solver = nullptr;
  NewtonSystem newton;
  bool cvode_ready = false;
  bool needs_restart = true;
  std::unique_ptr<PlantDynamics> dynamics;  // CVODE's ẏ and the truth (see plant_dynamics.h)
  std::array<double, NewtonSystem::kN> y_end{};
  static constexpr long kCrossCheckIntervals = 50;  // 0.1 s at the 2 ms control period
  long intervals = 0;
  double max_mismatch = 0.0;
  IntegratorStats stats_before_restart;  // summed over earlier CVODE runs (restarts after projection)
  std::unique_ptr<SimTK::Integrator> simbody_integrator;
  std::unique_ptr<SimTK::TimeStepper> stepper;

  Impl(const model::Model& m, const PlantConfig& c) : model(m), config(c), robot(m, c.gravity) {
    inputs.model = &model;
    inputs.robot = &robot;
    inputs.forces.ground = c.ground;
    inputs.forces.contact = c.contact;
    inputs.forces.gravity = c.gravity;
    inputs.forces.push = &inputs.push;
    inputs.forces.actuation = c.actuation;
    inputs.forces.ankle_motors = c.ankle_motors;
    SimTK::Force::Custom(robot.forces(), new RobotForces(&inputs));
    robot.system().realizeTopology();
    state = robot.system().getDefaultState();
    dynamics = std::make_unique<PlantDynamics>(m, simbody_layout(robot, state));
  }

  ~Impl() {
    if (cvode != nullptr) CVodeFree(&cvode);
    if (solver != nullptr) SUNLinSolFree(solver);
    if (jac != nullptr) SUNMatDestroy(jac);
    if (y != nullptr) N_VDestroy(y);
    if (sun != nullptr) SUNContext_Free(&sun);
  }

  static int rhs(sunrealtype t, N_Vector yv, N_Vector ydot, void* user) {
    auto* self = static_cast<Impl*>(user);
    ++self->evaluations;
    if (self->config.derivatives == DerivativeEngine::kRigidBody) {
      Eigen::Matrix<double, 6, 1> wrench;
      sunrealtype* out = N_VGetArrayPointer(ydot);
      const int ny = self->state.getNY();
      if (!self->dynamics->derivative(t, N_VGetArrayPointer(yv), self->inputs.forces, out, wrench)) return 1;
      for (int i = 0; i < 6; ++i) out[ny + i] = wrench[i];
      return 0;
    }
    SimTK::State& s = self->state;
    s.setTime(t);
    SimTK::Vector& ys = s.updY();
    const sunrealtype* in = N_VGetArrayPointer(yv);
    for (int i = 0; i < ys.size(); ++i) ys[i] = in[i];
    self->robot.system().realize(s, SimTK::Stage::Acceleration);
    const SimTK::Vector& d = s.getYDot();
    sunrealtype* out = N_VGetArrayPointer(ydot);
    for (int i = 0; i < d.size(); ++i) {
      if (!std::isfinite(d[i])) return 1;  // recoverable: CVODE retries with a smaller step
      out[i] = d[i];
    }
    // Quadrature states: the contact impulse, integrated to the same tolerance as the motion.
    for (int i = 0; i < 6; ++i) out[d.size() + i] = self->inputs.contact_wrench[i];
    return 0;
  }

  static int linear_system(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix, sunbooleantype jok,
                           sunbooleantype* jcur, sunrealtype gamma, void* user, N_Vector tmp1, N_Vector tmp2, N_Vector) {
    auto* self = static_cast<Impl*>(user);
    bool current = false;
    const int rc = self->newton.update(self->cvode, rhs, self, t, y, fy, jok, &current, gamma, tmp1, tmp2);
    *jcur = current ? SUNTRUE : SUNFALSE;
    return rc;
  }

  // CVODE's own counters since the last (re)start.
  IntegratorStats cvode_stats() const {
    IntegratorStats st;
    long v = 0;
    CVodeGetNumSteps(cvode, &v);
    st.steps = v;
    CVodeGetNumLinSolvSetups(cvode, &v);
    st.linear_setups = v;
    CVodeGetNumErrTestFails(cvode, &v);
    st.error_test_failures = v;
    CVodeGetNumNonlinSolvIters(cvode, &v);
    st.nonlinear_iterations = v;
    CVodeGetNumNonlinSolvConvFails(cvode, &v);
    st.nonlinear_failures = v;
    return st;
  }

  bool start_cvode() {
    const int n = state.getNY() + 6;  // + contact impulse quadrature
    if (n != NewtonSystem::kN || state.getNQ() != NewtonSystem::kNq) return fail("state layout is not [q; u] of the model");
    if (sun == nullptr && SUNContext_Create(nullptr, &sun) != 0) return fail("SUNContext_Create failed");
    if (y == nullptr) {
      y = N_VNew_Serial(n, sun);
      jac = SUNDenseMatrix(1, 1, sun);
      solver = newton.make_linear_solver(sun);
      cvode = CVodeCreate(CV_BDF, sun);
      if (y == nullptr || jac == nullptr || solver == nullptr || cvode == nullptr) return fail("CVODE set-up failed");
    }
    sunrealtype* data = N_VGetArrayPointer(y);
    for (int i = 0; i < state.getNY(); ++i) data[i] = state.getY()[i];
    for (int i = 0; i < 6; ++i) data[state.getNY() + i] = contact_impulse[i];
    if (cvode_ready) {  // CVodeReInit zeroes CVODE's counters: keep what they held
      const IntegratorStats now = cvode_stats();
      stats_before_restart.steps += now.steps;
      stats_before_restart.linear_setups += now.linear_setups;
      stats_before_restart.error_test_failures += now.error_test_failures;
      stats_before_restart.nonlinear_iterations += now.nonlinear_iterations;
      stats_before_restart.nonlinear_failures += now.nonlinear_failures;
    }
    int rc = cvode_ready ? CVodeReInit(cvode, state.getTime(), y) : CVodeInit(cvode, rhs, state.getTime(), y);
    if (rc != CV_SUCCESS) return fail("CVodeInit failed");
    if (!cvode_ready) {
      CVodeSetUserData(cvode, this);
      CVodeSStolerances(cvode, config.relative_tolerance, config.absolute_tolerance);
      CVodeSetLinearSolver(cvode, solver, jac);
      CVodeSetLinSysFn(cvode, linear_system);
      CVodeSetMaxNumSteps(cvode, 100000);
      // Command changes at every tick move the step size and with it gamma; the
      // default (re-factor on a 30 % change) then factors almost every step, which
      // cost 40 % of the run. A stale factorisation only slows Newton a little.
      CVodeSetDeltaGammaMaxLSetup(cvode, 0.9);
      // The contact Jacobian changes slowly while standing or dancing; a finite-
      // difference Jacobian costs 75 Simbody evaluations, so keep one longer.
      CVodeSetJacEvalFrequency(cvode, 200);
      cvode_ready = true;
    }
    return true;
  }

  bool fail(const char* what) {
    std::snprintf(error, sizeof error, "%s", what);
    for (char& c : error) c = c == '\n' ? ' ' : c;  // one line, for logs and JSON
    return false;
  }

  void update_truth() {
    SimTK::State& s = state;
    robot.system().realize(s, SimTK::Stage::Acceleration);
    robot.get_state(s, truth.q, truth.v);
    for (int c = 0; c < model::kNumContactPoints; ++c) {
      Vec3 v;
      contact_point_motion(model, robot, s, c, truth.contact_point_m[c], v);
      truth.contact_force_N[c] =
          inputs.forces.contact ? contact_force(inputs.forces.ground, truth.contact_point_m[c], v, inputs.forces.points[c])
                                : Vec3::Zero();
    }
    JointValues q{}, v{}, tau{};
    for (int j = 0; j < model::kNumJoints; ++j) {
      q[j] = robot.body(j + 1).getOneQ(s, 0);
      v[j] = robot.body(j + 1).getOneU(s, 0);
    }
    drive_torques(inputs.forces.command, model, q, v, inputs.forces.ankle_motors, tau);
    for (int j = 0; j < model::kNumJoints; ++j) {
      truth.joint_torque_Nm[j] = tau[j];
      if (inputs.forces.actuation != nullptr) {
        truth.joint_torque_Nm[j] = actuated_torque(*inputs.forces.actuation, j, truth.joint_torque_Nm[j], v[j]);
      }
    }
    if (inputs.forces.torque_source != nullptr) {
      JointValues extra{};
      inputs.forces.torque_source->add_joint_torques(q, v, extra);
      for (int j = 0; j < model::kNumJoints; ++j) truth.joint_torque_Nm[j] += extra[j];
    }
    const SimTK::MobilizedBody& base = robot.body(0);
    const SimTK::Vec3 a = base.getBodyOriginAcceleration(s);
    const SimTK::Vec3 g(0, 0, config.gravity ? -model::kGravity_m_s2 : 0.0);
    truth.base_specific_force_m_s2 = from_simtk(~base.getBodyRotation(s) * (a - g));
    truth.com_m = from_simtk(robot.matter().calcSystemMassCenterLocationInGround(s));
    const SimTK::SpatialVec h = robot.matter().calcSystemCentralMomentum(s);
    truth.momentum << h[1][0], h[1][1], h[1][2], h[0][0], h[0][1], h[0][2];
  }

  // Simbody's truth path is kept for the Simbody integrators and the kSimbody derivative.
  bool truth_from_plant_dynamics() const {
    return config.integrator == Integrator::kCvodeBdf && config.derivatives == DerivativeEngine::kRigidBody;
  }

  // At the end of an interval (or a reset): drives that clip are counted, the contact
  // anchors move, the truth is filled. Returns false when the state is not finite.
  bool finish_interval(bool count_saturations) {
    if (!truth_from_plant_dynamics()) {
      if (count_saturations) {
        inputs.count_saturations = true;
        robot.system().realize(state, SimTK::Stage::Dynamics);
        inputs.count_saturations = false;
      }
      update_contacts();
      update_truth();
      return true;
    }
    const SimTK::Vector& ys = state.getY();
    for (int i = 0; i < ys.size(); ++i) y_end[i] = ys[i];
    std::uint64_t clipped = 0;
    std::array<Vec3, model::kNumContactPoints> corner_velocity;
    if (!dynamics->truth(state.getTime(), y_end.data(), inputs.forces, truth, corner_velocity, clipped)) return false;
    if (count_saturations) inputs.saturations += clipped;
    // The anchors move first, the reported forces use the moved anchors (as update_truth does).
    for (int c = 0; c < model::kNumContactPoints; ++c) {
      update_contact_point(inputs.forces.ground, truth.contact_point_m[c], corner_velocity[c], inputs.forces.points[c]);
      truth.contact_force_N[c] = inputs.forces.contact ? contact_force(inputs.forces.ground, truth.contact_point_m[c],
                                                                       corner_velocity[c], inputs.forces.points[c])
                                                       : Vec3::Zero();
    }
    // Simbody keeps watching: every kCrossCheckIntervals its derivative is compared with ours.
    if (++intervals % kCrossCheckIntervals == 0) {
      max_mismatch = std::max(max_mismatch, derivative_mismatch());
    }
    return true;
  }

  double derivative_mismatch() {
    const int ny = state.getNY();
    std::array<double, NewtonSystem::kN> ours{}, theirs{};
    for (int i = 0; i < ny; ++i) y_end[i] = state.getY()[i];
    Eigen::Matrix<double, 6, 1> wrench;
    // Simbody's Pin has no rotor inertia: compare the two without it.
    PlantForceInputs forces = inputs.forces;
    JointActuation no_armature;
    if (forces.actuation != nullptr) {
      no_armature = *forces.actuation;
      no_armature.armature_kgm2.fill(0.0);
      forces.actuation = &no_armature;
    }
    dynamics->derivative(state.getTime(), y_end.data(), forces, ours.data(), wrench);
    for (int i = 0; i < 6; ++i) ours[ny + i] = wrench[i];
    state.invalidateAllCacheAtOrAbove(SimTK::Stage::Dynamics);  // re-run the forces for their wrench
    robot.system().realize(state, SimTK::Stage::Acceleration);
    for (int i = 0; i < ny; ++i) theirs[i] = state.getYDot()[i];
    for (int i = 0; i < 6; ++i) theirs[ny + i] = inputs.contact_wrench[i];
    double worst = 0.0;
    for (int i = 0; i < ny + 6; ++i) worst = std::max(worst, std::abs(ours[i] - theirs[i]) / (1.0 + std::abs(theirs[i])));
    return worst;
  }

  void update_contacts() {
    const SimTK::State& s = state;
    for (int c = 0; c < model::kNumContactPoints; ++c) {
      Vec3 p, v;
      contact_point_motion(model, robot, s, c, p, v);
      update_contact_point(inputs.forces.ground, p, v, inputs.forces.points[c]);
    }
  }
};

Plant::Plant(const model::Model& model, const PlantConfig& config) : impl_(std::make_unique<Impl>(model, config)) {}
Plant::~Plant() = default;

void Plant::reset(const dynamics::ConfigVector& q, const dynamics::VelocityVector& v, double time_s) {
  Impl& p = *impl_;
  p.state.setTime(time_s);
  p.robot.set_state(p.state, q, v);
  for (auto& c : p.inputs.forces.points) c = ContactPointState{};
  p.contact_impulse.setZero();
  p.robot.system().realize(p.state, SimTK::Stage::Velocity);
  p.update_contacts();
  if (p.config.integrator == Integrator::kCvodeBdf) {
    p.needs_restart = true;
  } else if (p.config.integrator == Integrator::kSemiImplicitEuler) {
    // nothing to set up
  } else {
    p.simbody_integrator = std::make_unique<SimTK::RungeKuttaMersonIntegrator>(p.robot.system());
    p.simbody_integrator->setAccuracy(p.config.relative_tolerance);
    p.stepper = std::make_unique<SimTK::TimeStepper>(p.robot.system(), *p.simbody_integrator);
    p.stepper->initialize(p.state);
  }
  p.finish_interval(false);
}

void Plant::set_command(const hal::CommandFrame& command) { impl_->inputs.forces.command = command; }
void Plant::set_torque_source(const JointTorqueSource* source) { impl_->inputs.forces.torque_source = source; }
void Plant::set_push(const Push& push) { impl_->inputs.push = push; }

PlantError Plant::advance(double dt_s) {
  // Simbody reports a state gone bad (a diverging explicit integrator's NaNs) by
  // throwing; the caller gets an error value instead of an abort.
  try {
    return advance_interval(dt_s);
  } catch (const std::exception& e) {
    impl_->fail(e.what());
    return PlantError::kIntegratorFailed;
  }
}

PlantError Plant::advance_interval(double dt_s) {
  Impl& p = *impl_;
  const double t_end = p.state.getTime() + dt_s;
  p.inputs.count_saturations = false;
  if (p.config.actuation != nullptr && !p.truth_from_plant_dynamics()) {
    for (const double a : p.config.actuation->armature_kgm2) {
      if (a != 0.0) {
        p.fail("rotor inertia (armature) needs the cvode integrator with the rigid-body derivative");
        return PlantError::kIntegratorFailed;
      }
    }
  }
  if (p.config.integrator == Integrator::kCvodeBdf) {
    // The command and the contact anchors change between intervals; CVODE's error
    // control takes those steps in stride, so the multistep history (and its
    // Jacobian) carries on unless the state was edited from outside.
    if (p.needs_restart && !p.start_cvode()) return PlantError::kIntegratorFailed;
    p.needs_restart = false;
    CVodeSetStopTime(p.cvode, t_end);
    sunrealtype t = p.state.getTime();
    const int rc = CVode(p.cvode, t_end, p.y, &t, CV_NORMAL);
    if (rc < 0) {
      std::snprintf(p.error, sizeof p.error, "CVODE failed at t = %.6f s (flag %d)", static_cast<double>(t), rc);
      return PlantError::kIntegratorFailed;
    }
    SimTK::Vector& ys = p.state.updY();
    const sunrealtype* data = N_VGetArrayPointer(p.y);
    for (int i = 0; i < ys.size(); ++i) ys[i] = data[i];
    for (int i = 0; i < 6; ++i) p.contact_impulse[i] = data[ys.size() + i];
    p.state.setTime(t_end);
  } else if (p.config.integrator == Integrator::kSemiImplicitEuler) {
    const int n = std::max(1, static_cast<int>(std::lround(dt_s / p.config.euler_substep_s)));
    const double h = dt_s / n;
    SimTK::Vector qdot;
    const double t0 = p.state.getTime();
    for (int k = 0; k < n; ++k) {
      p.state.setTime(t0 + k * h);
      p.robot.system().realize(p.state, SimTK::Stage::Acceleration);
      ++p.evaluations;
      p.contact_impulse += h * p.inputs.contact_wrench;
      const SimTK::Vector udot = p.state.getUDot();
      p.state.updU() += h * udot;
      p.robot.matter().multiplyByN(p.state, false, p.state.getU(), qdot);
      p.state.updQ() += h * qdot;
    }
    p.state.setTime(t_end);
  } else {
    p.stepper->initialize(p.state);
    p.stepper->stepTo(t_end);
    p.state = p.stepper->getState();
  }
  // Keep the base quaternion on the unit sphere (CVODE does not know it must be);
  // it drifts slowly, so project rarely and restart CVODE from the edited state.
  const SimTK::MobilizedBody& base = p.robot.body(0);
  double quat_norm2 = 0.0;
  for (int i = 0; i < 4; ++i) quat_norm2 += base.getOneQ(p.state, i) * base.getOneQ(p.state, i);
  if (std::abs(quat_norm2 - 1.0) > 1e-7 || p.config.integrator == Integrator::kSimbodyRungeKuttaMerson) {
    p.robot.system().realize(p.state, SimTK::Stage::Position);
    p.robot.system().project(p.state, 1e-10);
    p.needs_restart = true;
  }
  for (int i = 0; i < p.state.getNY(); ++i) {
    if (!std::isfinite(p.state.getY()[i])) {
      p.fail("non-finite plant state");
      return PlantError::kNonFiniteState;
    }
  }
  // Count saturation once per interval at its end state (what the drive does now).
  if (!p.finish_interval(true)) {
    p.fail("non-finite plant derivative");
    return PlantError::kNonFiniteState;
  }
  return PlantError::kOk;
}

Plant::IntegratorStats Plant::integrator_stats() const {
  const Impl& p = *impl_;
  IntegratorStats st;
  if (p.cvode == nullptr) return st;
  const IntegratorStats now = p.cvode_stats();
  const IntegratorStats& before = p.stats_before_restart;
  st.steps = before.steps + now.steps;
  st.linear_setups = before.linear_setups + now.linear_setups;
  st.error_test_failures = before.error_test_failures + now.error_test_failures;
  st.nonlinear_iterations = before.nonlinear_iterations + now.nonlinear_iterations;
  st.nonlinear_failures = before.nonlinear_failures + now.nonlinear_failures;
  st.jacobian_evaluations = p.newton.jacobian_evaluations();
  return st;
}

double Plant::time_s() const { return impl_->state.getTime(); }
const PlantTruth& Plant::truth() const { return impl_->truth; }
std::uint64_t Plant::torque_saturations() const { return impl_->inputs.saturations; }
std::uint64_t Plant::derivative_evaluations() const { return impl_->evaluations; }
const char* Plant::last_error() const { return impl_->error; }

double Plant::derivative_mismatch() { return impl_->derivative_mismatch(); }
double Plant::max_derivative_mismatch() const { return impl_->max_mismatch; }
Eigen::Matrix<double, 6, 1> Plant::contact_impulse() const { return impl_->contact_impulse; }

}  // namespace kuavo::sim
