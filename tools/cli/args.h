// Strict command-line values shared by the `kuavo` commands: a value is the whole token (no
// trailing junk, no leading space), finite, and inside the option's range; integers do not
// wrap. Paths are checked before any long run: inputs must be regular files, outputs writable.
#pragma once

#include <cstdint>
#include <string>

namespace kuavo::cli {

// A finite number in [lo, hi] ("5x", "nan", "inf", "" and " 5" are refused).
bool parse_number(const char* text, double lo, double hi, double& out);
// A decimal integer in [lo, hi] (no sign for lo >= 0, no overflow, no fraction).
bool parse_integer(const char* text, long long lo, long long hi, long long& out);
// An unsigned 64-bit decimal integer: digits only ("-1" and values above 2^64 - 1 are refused,
// not wrapped as strtoull does).
bool parse_uint64(const char* text, std::uint64_t& out);

// An input file: exists and is a regular file (a directory, device or pipe is refused).
// false with "PATH: why" in error.
bool check_input_file(const std::string& path, std::string& error);
// An output file can be opened for writing, checked without truncating an existing file
// (one created by the check is removed again). false with "PATH: why" in error.
bool check_output_file(const std::string& path, std::string& error);

}  // namespace kuavo::cli
