// Tool side of the robot motion file: encode, write, load into vectors, CSV export. The
// format, its reader and its checks are the online code's (controllers/motion/motion_reader.h,
// load_motion.h), named here in the offline namespace; these helpers allocate.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tools/mocap/contacts.h"
#include "controllers/motion/load_motion.h"
#include "controllers/motion/motion_reader.h"

namespace kuavo::mocap {

using motion::check_motion_frame;
using motion::crc32;
using motion::kMotionBaseHeightMax_m;
using motion::kMotionBaseHeightMin_m;
using motion::kMotionBaseHorizontalMax_m;
using motion::kMotionFixedHeaderBytes;
using motion::kMotionHeaderBytes;
using motion::kMotionHeaderCrcOffset;
using motion::kMotionJointLimitTolerance_rad;
using motion::kMotionMagic;
using motion::kMotionMaxFrames;
using motion::kMotionMaxRate_hz;
using motion::kMotionMinRate_hz;
using motion::kMotionNameBytes;
using motion::kMotionPayloadCrcOffset;
using motion::kMotionQuaternionNormTolerance;
using motion::kMotionRecordBytes;
using motion::kMotionVersion;
using motion::motion_get_f64;
using motion::motion_get_u16;
using motion::motion_get_u32;
using motion::motion_header_crc;
using motion::MotionError;
using motion::MotionHeader;
using motion::read_motion_frame;
using motion::read_motion_header;
using motion::to_string;

std::vector<std::uint8_t> encode_motion(const model::Model& robot, double rate_hz,
                                        const std::vector<dynamics::ConfigVector>& q,
                                        const std::vector<ContactLabel>& labels);
bool write_motion_file(const std::string& path, const std::vector<std::uint8_t>& bytes, std::string& error);
// Reads and fully validates a file as the online loader does (motion::load_motion without the
// plan: the same bytes, header and frame checks and messages); the message names the file.
bool load_motion_file(const std::string& path, const model::Model& robot, MotionHeader& header,
                      std::vector<dynamics::ConfigVector>& q, std::vector<ContactLabel>& labels, std::string& error);
// CSV: header row "t_s,base_x,...,qw,<28 joint names>,contact", one row per frame.
std::string motion_csv(const model::Model& robot, double rate_hz, const std::vector<dynamics::ConfigVector>& q,
                       const std::vector<ContactLabel>& labels);

}  // namespace kuavo::mocap
