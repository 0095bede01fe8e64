// The paper's Fig. 4 and Fig. 5 for one run of the dynamic stage, as SVG plots with their
// numbers (issue 18), and the two motion measures Fig. 6 plots against the horizon.
//
// Geometric and dynamic motion share one time axis, the dance clock: geometric frame i is at
// i / rate, dynamic frame i at (i − lead_frames) / rate, so the dynamic motion's lead-in shows
// at negative times and the two curves line up over the dance. Velocities are the oracle's
// finite differences (mocap::frame_rates), torques, forces and the ZMP come from its
// DynamicsCheck (least-norm forces for the geometric motion, the TO's for the dynamic one).
// Offline; allocates.
#pragma once

#include <string>
#include <vector>

#include "controllers/dynamics/rigid_body.h"
#include "tools/mocap/contact_label.h"
#include "tools/mocap/dynamics_check.h"

namespace kuavo::cli {

// One motion as the figures see it (all three of the same length).
struct FigureMotion {
  const std::vector<dynamics::ConfigVector>& q;
  const std::vector<mocap::ContactLabel>& contacts;
  const mocap::DynamicsCheck& check;
};

// A number a figure shows, for both motions (its name says the unit).
struct FigureNumber {
  std::string name;
  double geometric = 0.0, dynamic = 0.0;
};

struct RetargetFigures {
  std::vector<std::string> files;  // names inside the directory, in writing order
  std::vector<FigureNumber> numbers;
};

// Writes into dir (which must exist):
//  - fig4_knee.svg: both knees (leg_l4, leg_r4): angle with its position limits, RNEA torque
//    with ±the torque limit; max |τ|/limit and the frames above the limit;
//  - fig5_dynamics.svg: left hip pitch velocity (the swing leg's largest joint; mean over the
//    frames the left foot swings), left shoulder pitch velocity, the left foot's lateral force
//    in its own sole frame while it is down, and the ZMP's distance outside the support polygon.
// false with a message on an I/O failure.
bool write_retarget_figures(const model::Model& robot, const FigureMotion& geometric, const FigureMotion& dynamic,
                            int lead_frames, double rate_hz, const std::string& dir, RetargetFigures& out,
                            std::string& error);

// Mean |q̇| of the swinging leg's six joints over the frames with exactly one foot down [rad/s]
// (0 without such frames): how fast the dance's steps are.
double swing_leg_speed_rad_s(const std::vector<dynamics::ConfigVector>& q,
                             const std::vector<mocap::ContactLabel>& contacts, double rate_hz);

// Mean CoM speed over frames [first, first + count) ∩ the motion [m/s]: the CoM path length
// over its duration (0 for fewer than two frames).
double com_speed_m_s(const model::Model& robot, const std::vector<dynamics::ConfigVector>& q, double rate_hz,
                     int first, int count);

}  // namespace kuavo::cli
