// Fixed-size, heap-free rigid-body algorithms for the Kuavo 4Pro model.
// Free functions over (const Model, Data workspace, inputs); conventions in
// conventions.h. Every function here is real-time safe: no allocation, no
// exceptions, no I/O, bounded time. Preconditions are stated per function and
// are the caller's job (they are cheap to meet: call forward_kinematics first).
#pragma once

#include "controllers/dynamics/conventions.h"
#include "controllers/dynamics/data.h"
#include "controllers/model/model.h"

namespace kuavo::dynamics {

using model::Model;

// q for the zero pose standing on the ground with straight legs (base at the
// height that puts the sole corners at z = 0), identity orientation.
ConfigVector neutral_configuration(const Model& model);

// q ⊕ v·dt: base moved along the screw of its local twist (SE(3) exponential),
// joints integrated linearly. Quaternion stays unit.
ConfigVector integrate(const ConfigVector& q, const VelocityVector& v, double dt_s);

// Body poses, joint motion subspaces and world-axis inertias.
void forward_kinematics(const Model& model, Data& data, const ConfigVector& q);
// forward_kinematics for the base and the bodies first_body … last_body only (a chain whose
// parents are the base or lie in it, e.g. one leg): their poses and joint motion subspaces by
// the same arithmetic, bit for bit; every other body's entries and every inertia are left as
// they were. Enough for frame_position and frame_jacobian on that chain's frames.
void forward_kinematics_chain(const Model& model, Data& data, const ConfigVector& q, int first_body, int last_body);
// Body spatial velocities. Requires forward_kinematics(q).
void forward_velocities(const Model& model, Data& data, const VelocityVector& v);

// Frame pose in the world.
Vec3 frame_position(const Model& model, const Data& data, int frame);
Mat3 frame_rotation(const Model& model, const Data& data, int frame);

// 6×kNv Jacobian of a point fixed on a body (world position given), rows
// [linear; angular], world axes. Requires forward_kinematics(q).
void point_jacobian(const Model& model, const Data& data, int body, const Vec3& point_world_m,
                    FrameJacobian& jacobian);
void frame_jacobian(const Model& model, const Data& data, int frame, FrameJacobian& jacobian);

// Fills data.acceleration with the body accelerations for v̇ = 0 and no gravity.
// Requires forward_velocities(v).
void bias_accelerations(const Model& model, Data& data);
// J̇·v of a frame: [classical linear acceleration of its origin; angular acceleration]
// for v̇ = 0. Requires bias_accelerations().
Vec6 frame_bias_acceleration(const Model& model, const Data& data, int frame);
// [linear velocity of the frame origin; angular velocity], world axes. Requires forward_velocities.
Vec6 frame_velocity(const Model& model, const Data& data, int frame);

// Joint-space mass matrix (composite rigid body algorithm) into data.mass_matrix,
// plus composite inertias, total mass, CoM and the momentum matrix at the
// reference point. Requires forward_kinematics(q).
void crba(const Model& model, Data& data);

// Inverse dynamics τ = M(q)v̇ + b(q, v) (gravity included when with_gravity)
// into data.tau. Requires forward_velocities(v).
void rnea(const Model& model, Data& data, const VelocityVector& a, bool with_gravity = true);

// Centroidal momentum matrix A_G, centroidal inertia, CoM, and Ȧ_G·v.
// Requires crba() and forward_velocities(v).
void centroidal_dynamics(const Model& model, Data& data);

// CoM Jacobian (3×kNv, world axes). Requires crba().
void com_jacobian(const Data& data, ComJacobian& jacobian);

// Everything the controllers need once per tick, sharing one kinematics pass:
// M, b = nonlinear effects (into data.tau), A_G, Ȧ_G·v, CoM, centroidal inertia.
void compute_all_terms(const Model& model, Data& data, const ConfigVector& q, const VelocityVector& v);

}  // namespace kuavo::dynamics
