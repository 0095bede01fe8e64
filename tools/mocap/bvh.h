// BVH (Biovision hierarchy) reading, posing and writing.
//
// The reader accepts the dialects met in practice (see ../shared/mocap/README.md):
//   - any rotation channel order per joint (ZYX, YXZ, ...), 0, 3 or 6 channels, position
//     channels on any joint;
//   - a UTF-8 byte-order mark; LF, CRLF, CR-only and mixed line endings; tabs or spaces;
//   - zero-length helper joints (they simply pose to the parent's position);
//   - position channels that are *added* to OFFSET (CMU, iClone CC_Base root) or that are
//     *absolute* and replace it (MotionBuilder-style non-root 6-channel joints): decided per
//     joint from the data (see position_absolute below).
// Units and the up axis are not stored in BVH; human_targets.h infers them.
//
// Bad input never aborts: parse_bvh() returns false with "line N: <problem>".
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace kuavo::mocap {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

enum class BvhChannel : std::uint8_t { kXposition, kYposition, kZposition, kXrotation, kYrotation, kZrotation };

struct BvhJoint {
  std::string name;            // End Sites are named "<parent name>_End"
  int parent = -1;             // index into Bvh::joints, -1 for the root
  Vec3 offset = Vec3::Zero();  // from the parent joint, parent axes, file units
  std::vector<BvhChannel> channels;
  int first_column = 0;  // column of channels[0] in a motion row
  bool end_site = false;
  bool position_absolute = false;  // position channels replace OFFSET instead of adding to it
  int line = 0;                    // line of the JOINT/ROOT/End Site keyword, for messages
};

struct Bvh {
  std::vector<BvhJoint> joints;  // depth-first: a parent always precedes its children
  int channel_count = 0;
  int frame_count = 0;
  double frame_time_s = 0.0;
  std::vector<double> motion;  // frame_count rows of channel_count values (degrees, file units)

  const double* row(int frame) const { return motion.data() + static_cast<std::size_t>(frame) * channel_count; }
  int find(std::string_view name) const;  // joint index or -1
};

// Parser limits: far above any real capture, they bound memory on hostile input.
inline constexpr int kBvhMaxJoints = 4096;
inline constexpr long kBvhMaxValues = 200'000'000;  // frames × channels (1.6 GB of doubles)

// Bounds no human motion capture exceeds. Each refuses, with the line and the rule, input that
// would otherwise become an absurd or non-finite motion further down (a root channel of 1e300
// made an all-NaN motion; Frame Time 1e-9 a one-frame one; Frame Time 10 s 1.3 million frames).
// 10 kHz: faster than any full-body capture records (optical systems reach 2 kHz at full
// resolution, IMU suits 1 kHz).
inline constexpr double kBvhMinFrameTime_s = 1e-4;
// 4 Hz: sampled any slower, the beat of a 120 bpm dance (2 Hz) is past the Nyquist rate and
// the dance itself is lost between frames.
inline constexpr double kBvhMaxFrameTime_s = 0.25;
// 30 min: longer than one dance piece, which is what one motion file plays (a show is a
// sequence of pieces). Bounds the work and memory of every later stage up front.
inline constexpr double kBvhMaxDuration_s = 1800.0;
// OFFSET components and position channels [file units]: 100 m in millimetres, the smallest
// unit in use. No capture volume is that large, and no bone comes near it in any unit.
inline constexpr double kBvhMaxLength = 1e5;
// Rotation channels [deg]: 2 778 turns. Unwrapped exports accumulate whole turns (the
// shared iClone clip reaches 750°); 30 min of pirouettes at 1.5 turns/s is 2 700 turns.
inline constexpr double kBvhMaxAngle_deg = 1e6;

// Parses a whole BVH text. On failure returns false and sets error to "line N: problem".
// Lines are counted as editors count them: LF, CRLF and a lone CR each end one line.
bool parse_bvh(std::string_view text, Bvh& out, std::string& error);
// Reads and parses a file; the error names the file too.
bool load_bvh_file(const std::string& path, Bvh& out, std::string& error);

// World pose of every joint at one frame (file axes and units): positions and rotations.
// Sizes of the outputs are set to joints.size() (allocates only if they were smaller).
void bvh_pose(const Bvh& bvh, int frame, std::vector<Vec3>& position, std::vector<Mat3>& rotation);
// The skeleton with every channel at zero (rest pose as written in the hierarchy).
void bvh_rest_pose(const Bvh& bvh, std::vector<Vec3>& position);

// Writes a BVH text (LF endings). Values are printed with enough digits to round-trip
// to better than 1e-9 of their magnitude.
std::string write_bvh(const Bvh& bvh);

const char* channel_name(BvhChannel c);

}  // namespace kuavo::mocap
