// Floating-base conventions, in one place. Every algorithm, the simulator
// binding, the estimator and the logs follow these.
//
// Configuration q (kNq = 35):
//   q[0:3]  base_link origin in the world frame [m]
//   q[3:7]  base_link orientation, unit quaternion base->world, stored (x, y, z, w)
//           (Eigen's coeffs() order; Pinocchio's order too)
//   q[7:35] the 28 joint angles in controller order [rad]
//
// Velocity v (kNv = 34):
//   v[0:3]  linear velocity of the base origin, in BASE axes [m/s]
//   v[3:6]  angular velocity of the base, in BASE axes [rad/s]
//   v[6:34] joint rates [rad/s]
//   (Pinocchio's "local" free-flyer twist.) The base part of a generalized
//   force has the same split: force then moment, both in base axes.
//   Holding v constant moves the base along a screw: integrate() uses the
//   SE(3) exponential, so d/dt J(q) v with v constant is exactly J̇·v here.
//
// World frame: z up, gravity (0, 0, -kGravity_m_s2).
//
// Spatial vectors: linear part first. A motion is [v; ω], a force [f; n].
// Inside the algorithms they are expressed in world axes at one point fixed in
// space that coincides with the base origin at the current instant (this keeps
// magnitudes independent of how far the robot has walked).
//
// Frame Jacobians and frame accelerations are "local world aligned": rows
// [linear velocity of the frame origin; angular velocity], world axes.
// J̇·v is the classical acceleration of the frame origin (and angular
// acceleration) when v̇ = 0.
//
// Centroidal momentum h_G = A_G(q) v = [linear momentum; angular momentum about
// the CoM], world axes; Ȧ_G·v is ḣ_G when v̇ = 0.
#pragma once
