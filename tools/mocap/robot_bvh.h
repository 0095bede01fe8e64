// A BVH whose skeleton *is* the robot's kinematic tree, driven by known configurations.
// It is the retargeting oracle (tests/mocap) and the benchmark input: every robot body is a
// BVH joint named after its link, written Y-up (BVH habit) in the given units, with End
// Sites at the toe, hand and face keypoints so every keypoint has a joint of its own.
#pragma once

#include <vector>

#include "controllers/dynamics/data.h"
#include "controllers/model/model.h"
#include "tools/mocap/bvh.h"

namespace kuavo::mocap {

// q: configurations per frame (conventions.h). units_per_m: 100 writes centimetres.
Bvh robot_bvh(const model::Model& robot, const std::vector<dynamics::ConfigVector>& q, double frame_time_s,
              double units_per_m);

// A smooth, limit-respecting test motion: every joint swings on its own sinusoid over the
// middle third of its range, the base sways, turns and floats (feet clear of the ground).
// Deterministic.
std::vector<dynamics::ConfigVector> robot_test_motion(const model::Model& robot, int frames, double rate_hz);

}  // namespace kuavo::mocap
