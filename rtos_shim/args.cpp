#include "rtos_shim/args.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>

namespace kuavo::args {
namespace {

// strtod/strtoll skip leading space and accept a sign; the token must start with a digit, a
// sign or a point so "  5" and "" are refused.
bool starts_like_a_number(const char* text) {
  return text != nullptr && (std::isdigit(static_cast<unsigned char>(text[0])) || text[0] == '-' ||
                             text[0] == '+' || text[0] == '.');
}

// "%g" without the noise: 600, 0.2, 1e+04.
std::string short_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
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
  if (path.empty()) {
    error = "an empty output path";
    return false;
  }
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

Option& Parser::add(Option o) {
  options_.push_back(std::move(o));
  return options_.back();
}

Option& Parser::flag(const std::string& name, bool* out) {
  Option o;
  o.name = name;
  o.kind = Option::Kind::kFlag;
  o.flag = out;
  return add(std::move(o));
}

Option& Parser::number(const std::string& name, const std::string& value_name, double lo, double hi,
                       const std::string& unit, double* out, bool lo_open) {
  Option o;
  o.name = name;
  o.kind = Option::Kind::kNumber;
  o.value_name = value_name;
  o.lo = lo;
  o.hi = hi;
  o.lo_open = lo_open;
  o.unit = unit;
  o.number = out;
  return add(std::move(o));
}

Option& Parser::integer(const std::string& name, const std::string& value_name, long long lo, long long hi,
                        const std::string& unit, long long* out) {
  Option o;
  o.name = name;
  o.kind = Option::Kind::kInteger;
  o.value_name = value_name;
  o.lo = static_cast<double>(lo);
  o.hi = static_cast<double>(hi);
  o.unit = unit;
  o.integer = out;
  return add(std::move(o));
}

Option& Parser::uint64(const std::string& name, const std::string& value_name, std::uint64_t* out) {
  Option o;
  o.name = name;
  o.kind = Option::Kind::kUint64;
  o.value_name = value_name;
  o.uint64 = out;
  return add(std::move(o));
}

Option& Parser::choice(const std::string& name, std::vector<std::string> choices, std::string* out) {
  Option o;
  o.name = name;
  o.kind = Option::Kind::kChoice;
  for (const std::string& c : choices) o.value_name += (o.value_name.empty() ? "" : "|") + c;
  o.choices = std::move(choices);
  o.text = out;
  return add(std::move(o));
}

Option& Parser::text(const std::string& name, const std::string& value_name, std::string* out) {
  Option o;
  o.name = name;
  o.kind = Option::Kind::kText;
  o.value_name = value_name;
  o.text = out;
  return add(std::move(o));
}

Option& Parser::input_file(const std::string& name, const std::string& value_name, std::string* out) {
  Option& o = text(name, value_name, out);
  o.kind = Option::Kind::kInputFile;
  return o;
}

Option& Parser::output_file(const std::string& name, const std::string& value_name, std::string* out) {
  Option& o = text(name, value_name, out);
  o.kind = Option::Kind::kOutputFile;
  return o;
}

Option& Parser::custom(const std::string& name, const std::string& value_name, std::function<bool(const char*)> parse) {
  Option o;
  o.name = name;
  o.kind = Option::Kind::kCustom;
  o.value_name = value_name;
  o.custom = std::move(parse);
  return add(std::move(o));
}

void Parser::positionals(const std::string& value_name, std::vector<std::string>* out, int max) {
  positional_name_ = value_name;
  positionals_ = out;
  max_positionals_ = max;
}

bool Parser::fail(const std::string& why) {
  error_ = program_ + ": " + why;
  return false;
}

bool Parser::take(Option& o, const char* v) {
  using K = Option::Kind;
  const std::string got = std::string(", got '") + v + "'";
  switch (o.kind) {
    case K::kNumber: {
      double x = 0.0;
      if (!parse_number(v, o.lo, o.hi, x) || (o.lo_open && !(x > o.lo))) {
        return fail(o.name + " needs " + o.value_name + " in " + (o.lo_open ? "(" : "[") + short_number(o.lo) + ", " +
                    short_number(o.hi) + "]" + (o.unit.empty() ? "" : " " + o.unit) + got);
      }
      *o.number = x;
      return true;
    }
    case K::kInteger: {
      long long n = 0;
      if (!parse_integer(v, static_cast<long long>(o.lo), static_cast<long long>(o.hi), n)) {
        return fail(o.name + " needs a whole number " + o.value_name + " in " + short_number(o.lo) + ".." +
                    short_number(o.hi) + (o.unit.empty() ? "" : " " + o.unit) + got);
      }
      *o.integer = n;
      return true;
    }
    case K::kUint64:
      if (!parse_uint64(v, *o.uint64)) return fail(o.name + " needs a whole number " + o.value_name + " in 0..2^64-1" + got);
      return true;
    case K::kChoice:
      for (const std::string& c : o.choices) {
        if (c == v) {
          *o.text = c;
          return true;
        }
      }
      return fail(o.name + " must be " + o.value_name + got);
    case K::kText:
      *o.text = v;
      return true;
    case K::kInputFile: {
      std::string why;
      if (!check_input_file(v, why)) return fail(o.name + " " + why);
      *o.text = v;
      return true;
    }
    case K::kOutputFile: {
      std::string why;
      if (!check_output_file(v, why)) return fail(o.name + " " + why);
      *o.text = v;
      return true;
    }
    case K::kCustom:
      if (!o.custom(v)) return fail(o.name + " must be " + o.value_name + got);
      return true;
    case K::kFlag:
      break;
  }
  return true;
}

Parser::Result Parser::parse(int argc, char** argv) {
  error_.clear();
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    if (!std::strcmp(a, "--help") || !std::strcmp(a, "-h")) return Result::kHelp;
    if (a[0] != '-' || a[1] == '\0') {  // a positional ("-" alone is one too: no option is named "-")
      if (positionals_ == nullptr || static_cast<int>(positionals_->size()) >= max_positionals_) {
        fail(positionals_ == nullptr ? std::string("unexpected argument '") + a + "'"
                                     : "more than " + std::to_string(max_positionals_) + " " + positional_name_ + " ('" + a + "')");
        return Result::kError;
      }
      positionals_->push_back(a);
      continue;
    }
    Option* o = nullptr;
    for (Option& x : options_)
      if (x.name == a || (!x.alias.empty() && x.alias == a)) o = &x;
    if (o == nullptr) {
      fail(std::string("unknown option '") + a + "'");
      return Result::kError;
    }
    if (o->given) {
      fail(o->name + " given twice");
      return Result::kError;
    }
    o->given = true;
    if (o->kind == Option::Kind::kFlag) {
      *o->flag = true;
      continue;
    }
    // The next token is the value; another option there means the value is missing (a
    // negative number is a value: "--push -1..." is not an option name).
    const char* v = i + 1 < argc ? argv[i + 1] : nullptr;
    if (v == nullptr || (v[0] == '-' && v[1] == '-')) {
      fail(o->name + " needs a value (" + o->value_name + ")" + (v ? std::string(", got option '") + v + "'" : ""));
      return Result::kError;
    }
    ++i;
    if (!take(*o, v)) return Result::kError;
  }
  return Result::kOk;
}

bool Parser::refuse_inapplicable(ModeMask mode, const std::string& mode_name) {
  for (const Option& o : options_) {
    if (o.given && o.modes != kAllModes && (o.modes & mode) == 0) return fail(o.name + " does not apply to " + mode_name);
  }
  return true;
}

bool Parser::given(const std::string& name) const {
  for (const Option& o : options_)
    if (o.name == name) return o.given;
  return false;
}

}  // namespace kuavo::args
