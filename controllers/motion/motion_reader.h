// Robot motion file: the retargeted dance, for the controller and the firmware. This header
// is the format and its reader; load_motion.h turns a file into the controller's MotionPlan
// (the firmware and `kuavo simulate` both); tools/mocap/motion_file.h adds the offline
// writer and CSV.
//
// Binary layout, version 1 (all integers little-endian, doubles IEEE-754 little-endian):
//
//   offset size  field
//        0    8  magic "KUAVOMOT"
//        8    4  u32 format version (1)
//       12    4  u32 header size in bytes (= 64 + 24 × joint count = 736)
//       16    1  u8  robot variant (model::Variant: 0 = s45, 1 = s42)
//       17    1  u8  reserved (0)
//       18    2  u16 nq, configuration size (35, conventions.h)
//       20    2  u16 joint count (28)
//       22    2  u16 frame record size in bytes (288)
//       24    8  f64 frame rate [Hz] (100)
//       32    4  u32 frame count
//       36    4  u32 CRC-32 (IEEE 802.3, as zlib) of all frame records
//       40    4  u32 CRC-32 of the header bytes with this field set to 0
//       44   20  reserved (0)
//       64  24×J joint names in controller order, each NUL-padded to 24 bytes
//   then frame count records of 288 bytes:
//        0  280  35 × f64 q: base position [m] (world), base quaternion (x, y, z, w) base→world,
//                28 joint angles [rad] in controller order (conventions.h)
//      280    1  u8 contact label (ContactLabel: 0 flight, 1 left, 2 right, 3 double support)
//      281    7  reserved (0)
//
// The reader (read_motion_header / read_motion_frame) works on a byte buffer in place,
// allocates nothing and throws nothing.
#pragma once

#include <cstddef>
#include <cstdint>

#include "controllers/dynamics/data.h"
#include "controllers/model/model.h"
#include "controllers/planner/motion_plan.h"
#include "controllers/motion/contact_label.h"

namespace kuavo::motion {

inline constexpr char kMotionMagic[8] = {'K', 'U', 'A', 'V', 'O', 'M', 'O', 'T'};
inline constexpr std::uint32_t kMotionVersion = 1;
inline constexpr std::size_t kMotionNameBytes = 24;
inline constexpr std::size_t kMotionFixedHeaderBytes = 64;
inline constexpr std::size_t kMotionHeaderBytes = kMotionFixedHeaderBytes + kMotionNameBytes * model::kNumJoints;
inline constexpr std::size_t kMotionRecordBytes = 288;

// Stable numbers; never reuse one.
enum class MotionError : std::uint8_t {
  kOk = 0,
  kTooShort = 1,    // fewer bytes than a header
  kBadMagic = 2,    // not a motion file
  kBadVersion = 3,  // written by a newer or unknown format version
  kBadHeaderChecksum = 4,
  kWrongVariant = 5,    // recorded for the other arm variant
  kLayoutMismatch = 6,  // nq, joint count, record size or joint names differ from this build
  kTruncated = 7,       // fewer frame bytes than the header promises
  kBadPayloadChecksum = 8,
  kBadRate = 9,
  kBadLabel = 10,  // a contact label outside 0..3
  kIo = 11,        // the file could not be read or written
  kTrailingBytes = 12,     // more bytes than the header and its frames (appended or concatenated data)
  kNonFinite = 13,         // a NaN or infinite value in a frame
  kBaseImplausible = 14,   // base position outside the stage or its quaternion not unit
  kJointOutOfLimits = 15,  // a joint angle outside the model's position limits
  kTooManyFrames = 16,     // more frames than the controller's plan can hold
};
const char* to_string(MotionError e);

struct MotionHeader {
  model::Variant variant = model::Variant::kS45;
  double rate_hz = 100.0;
  std::uint32_t frame_count = 0;
};

std::uint32_t crc32(const std::uint8_t* data, std::size_t size, std::uint32_t crc = 0);
// CRC-32 of a motion header (kMotionHeaderBytes at data) with its own CRC field taken as 0.
std::uint32_t motion_header_crc(const std::uint8_t* data);
// Little-endian field access used by reader and writer.
std::uint16_t motion_get_u16(const std::uint8_t* p);
std::uint32_t motion_get_u32(const std::uint8_t* p);
double motion_get_f64(const std::uint8_t* p);
inline constexpr std::size_t kMotionPayloadCrcOffset = 36;
inline constexpr std::size_t kMotionHeaderCrcOffset = 40;

// Physical plausibility of a frame, the bounds the loader enforces (rules that hold for every
// motion `kuavo retarget` writes and that the controller relies on at run time).
// The retargeter clamps joints to the model's limits (tools/mocap/retarget.cpp counts samples
// more than 1e-9 rad outside); 1e-6 rad leaves room for an independent writer's rounding while
// being far below anything an encoder resolves (~1e-4 rad).
inline constexpr double kMotionJointLimitTolerance_rad = 1e-6;
// The writer stores the quaternion normalised in double precision; motion_plan_finish refuses
// a norm further than 1e-6 from 1, and the loader states the same rule.
inline constexpr double kMotionQuaternionNormTolerance = 1e-6;
// Base (pelvis) height in the world: the 1.66 m robot's pelvis stands at ~0.8 m. The deepest
// crouch `kuavo retarget` makes from the shared clips puts it at 0.19 m (cmu_05_20_mb, dynamic
// stage); below 0.1 m it would be on the floor. Above 2.0 m it would be more than a metre in the
// air (the clips' highest is 1.21 m). Values outside are a corrupt or foreign file.
inline constexpr double kMotionBaseHeightMin_m = 0.1;
inline constexpr double kMotionBaseHeightMax_m = 2.0;
// Horizontal base position: a 100 m square stage around the origin (the clips travel < 10 m).
inline constexpr double kMotionBaseHorizontalMax_m = 50.0;
// Frame rate: `kuavo retarget` writes 100 Hz. Slower than 4 Hz the beat of a 120 bpm dance is
// past the Nyquist rate (the BVH bound kBvhMaxFrameTime_s, same reason); faster than the 500 Hz
// control tick, frames fall between ticks that never read them. A rate of 1e308 Hz made a
// motion of zero duration that --check accepted.
inline constexpr double kMotionMinRate_hz = 4.0, kMotionMaxRate_hz = 500.0;
// Most frames a motion file may hold: the controller's capacity, checked on the header so a
// forged count cannot make a loader read or allocate more.
inline constexpr std::uint32_t kMotionMaxFrames = planner::kMaxMotionFrames;

// Validates the header and every checksum against the expected variant's joint names, and that
// the buffer is exactly the header and its frames (no trailing bytes).
MotionError read_motion_header(const std::uint8_t* data, std::size_t size, const model::Model& robot,
                               MotionHeader& header);
// Frame i of a buffer that passed read_motion_header.
MotionError read_motion_frame(const std::uint8_t* data, std::size_t size, std::uint32_t index,
                              dynamics::ConfigVector& q, ContactLabel& label);
// The plausibility rules above for one frame. On kJointOutOfLimits joint is the joint's index
// (controller order); on kNonFinite / kBaseImplausible it is -1.
MotionError check_motion_frame(const model::Model& robot, const dynamics::ConfigVector& q, int& joint);

}  // namespace kuavo::motion
