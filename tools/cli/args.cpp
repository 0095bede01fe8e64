#include "tools/cli/args.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>

namespace kuavo::cli {
namespace {

// strtod/strtoll skip leading space and accept a sign; the token must start with a digit, a
// sign or a point so "  5" and "" are refused.
bool starts_like_a_number(const char* text) {
  return text != nullptr && (std::isdigit(static_cast<unsigned char>(text[0])) || text[0] == '-' ||
                             text[0] == '+' || text[0] == '.');
}

}  // namespace

bool parse_number(const char* text, double lo, double hi, double& out) {
  if (!starts_like_a_number(text)) return false;
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0' || errno == ERANGE || !std::isfinite(v) || !(v >= lo && v <= hi)) return false;
  out = v;
  return true;
}

bool parse_integer(const char* text, long long lo, long long hi, long long& out) {
  if (!starts_like_a_number(text) || text[0] == '.') return false;
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text, &end, 10);
  if (end == text || *end != '\0' || errno == ERANGE || v < lo || v > hi) return false;
  out = v;
  return true;
}

bool parse_uint64(const char* text, std::uint64_t& out) {
  if (text == nullptr || !std::isdigit(static_cast<unsigned char>(text[0]))) return false;
  char* end = nullptr;
  errno = 0;
  const unsigned long long v = std::strtoull(text, &end, 10);
  if (*end != '\0' || errno == ERANGE) return false;
  static_assert(std::numeric_limits<unsigned long long>::max() == std::numeric_limits<std::uint64_t>::max());
  out = v;
  return true;
}

bool check_input_file(const std::string& path, std::string& error) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) {
    error = path + ": cannot open (no such file)";
    return false;
  }
  if (!std::filesystem::is_regular_file(status)) {
    error = path + ": not a regular file";
    return false;
  }
  return true;
}

bool check_output_file(const std::string& path, std::string& error) {
  std::error_code ec;
  const bool existed = std::filesystem::exists(path, ec);
  if (existed && std::filesystem::is_directory(path, ec)) {
    error = path + ": is a directory";
    return false;
  }
  std::FILE* f = std::fopen(path.c_str(), "ab");  // append: an existing file is not truncated
  if (f == nullptr) {
    error = path + ": cannot write (" + std::strerror(errno) + ")";
    return false;
  }
  std::fclose(f);
  if (!existed) std::filesystem::remove(path, ec);
  return true;
}

}  // namespace kuavo::cli
