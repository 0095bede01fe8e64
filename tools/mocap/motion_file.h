// Tool-side side of the robot motion file (format and reader: motion_reader.h): encode,
// write, load-and-validate with messages, CSV export. These allocate; the reader does not.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tools/mocap/contacts.h"
#include "tools/mocap/motion_reader.h"

namespace kuavo::mocap {

// Tool-side helpers (they allocate).
std::vector<std::uint8_t> encode_motion(const model::Model& robot, double rate_hz,
                                        const std::vector<dynamics::ConfigVector>& q,
                                        const std::vector<ContactLabel>& labels);
bool write_motion_file(const std::string& path, const std::vector<std::uint8_t>& bytes, std::string& error);
// Reads and fully validates a file; on error the message names the file and the problem.
bool load_motion_file(const std::string& path, const model::Model& robot, MotionHeader& header,
                      std::vector<dynamics::ConfigVector>& q, std::vector<ContactLabel>& labels, std::string& error);
// CSV: header row "t_s,base_x,...,qw,<28 joint names>,contact", one row per frame.
std::string motion_csv(const model::Model& robot, double rate_hz, const std::vector<dynamics::ConfigVector>& q,
                       const std::vector<ContactLabel>& labels);

}  // namespace kuavo::mocap
