// Leju's own MJCF of the 4Pro (shared/robot/<model>/xml/biped_sXX.xml), made loadable by
// Debian's MuJoCo 2.2.2 in a generated copy; the published file is never edited.
// The edits (shared/robot/README.md, "Known quirks"):
//   - the joint attribute actuatorfrcrange (newer MuJoCo) is dropped;
//   - <compiler> gains autolimits="true" (joints carry range without limited);
//   - a closing quote followed directly by the next attribute (s45 line 158) gets its space;
//   - meshdir becomes absolute, so the copy loads from any directory.
// And what the simulator adds: the base_link mass set so the robot weighs the model's total
// (Leju's update_mass.sh and our model::build_model rescale only the torso), the floor
// plane, the time step, gravity and the surface's friction coefficient. MuJoCo's contact
// law itself (solref, solimp, cone) stays at MuJoCo's defaults: it is the independent one.
#pragma once

#include <string>

#include "controllers/model/model.h"

namespace kuavo::sim {

struct MjcfOptions {
  double timestep_s = 5.0e-4;
  double friction_coefficient = 0.8;
  bool gravity = true;
  bool contact = true;
};

// The published MJCF of the model's variant (absolute path).
std::string published_mjcf_path(const model::Model& model);

// The generated copy's text; false with a message when the file cannot be read or an
// expected element is missing (the edits are checked, never applied blindly).
bool generate_mjcf(const model::Model& model, const MjcfOptions& options, std::string& xml, std::string& error);

}  // namespace kuavo::sim
