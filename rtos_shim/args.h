// The command line of every program -- kuavo's commands, kuavo_fw and kuavo_fw_sim -- read by
// one small strict parser. Start-up only (it allocates); never called from a real-time task.
//
// It lives in rtos_shim because that is where a process meets its operating system (clock,
// scheduler, memory locking; here argv and the file system) and because rtos_shim sits below
// everything: the robot image links it without linking anything from tools/.
//
// Rules every program gets from it:
//  - a value is the whole next token: "5x", " 5", "nan", "inf" and out-of-range numbers are
//    refused, integers never wrap ("-1" is not 2^64 - 1);
//  - every number has a range and a unit, both named in the message that refuses it;
//  - a missing value is named ("--log needs a value (CSV)"), also when the next token is another
//    option; an option given twice is refused (no silent "last one wins");
//  - options carry the modes they apply to; refuse_inapplicable() names one given outside them;
//  - input files must be regular files, outputs writable -- checked at parse time, before any
//    long run starts.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <string>
#include <vector>

namespace kuavo::args {

// --- Single values (also used on their own, e.g. for list items and configuration text) ---

// A finite number in [lo, hi] ("5x", "nan", "inf", "" and " 5" are refused).
bool parse_number(const char* text, double lo, double hi, double& out);
// A decimal integer in [lo, hi] (no overflow, no fraction, no exponent).
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

// --- The option table ---

// Modes are bits a program defines (e.g. kStand = 1, kMotion = 2); 0 = every mode.
using ModeMask = unsigned;
inline constexpr ModeMask kAllModes = 0;

struct Option {
  enum class Kind { kFlag, kNumber, kInteger, kUint64, kChoice, kText, kInputFile, kOutputFile, kCustom };
  std::string name;         // "--stand"
  std::string alias;        // "-o", or empty
  Kind kind = Kind::kFlag;
  std::string value_name;   // "SECONDS", "FILE": for messages and usage
  double lo = 0.0, hi = 0.0;  // kNumber / kInteger range
  bool lo_open = false;     // (lo, hi] instead of [lo, hi]
  std::string unit;         // "s", "kg", "steps": named in the range message
  std::vector<std::string> choices;  // kChoice
  ModeMask modes = kAllModes;
  // Destinations (one, by kind).
  bool* flag = nullptr;
  double* number = nullptr;
  long long* integer = nullptr;
  std::uint64_t* uint64 = nullptr;
  std::string* text = nullptr;  // kChoice, kText, kInputFile, kOutputFile
  std::function<bool(const char*)> custom;  // kCustom: false = refused, `value_name` says what it takes
  bool given = false;
};

class Parser {
 public:
  explicit Parser(std::string program) : program_(std::move(program)) {}

  // Each returns the option, so `.modes` can be set: p.number(...).modes = kMotion.
  Option& flag(const std::string& name, bool* out);
  Option& number(const std::string& name, const std::string& value_name, double lo, double hi, const std::string& unit,
                 double* out, bool lo_open = false);
  Option& integer(const std::string& name, const std::string& value_name, long long lo, long long hi,
                  const std::string& unit, long long* out);
  Option& uint64(const std::string& name, const std::string& value_name, std::uint64_t* out);
  Option& choice(const std::string& name, std::vector<std::string> choices, std::string* out);
  Option& text(const std::string& name, const std::string& value_name, std::string* out);
  Option& input_file(const std::string& name, const std::string& value_name, std::string* out);
  Option& output_file(const std::string& name, const std::string& value_name, std::string* out);
  Option& custom(const std::string& name, const std::string& value_name, std::function<bool(const char*)> parse);
  // Positional arguments (tokens not starting with '-'): at most `max` of them, in order.
  void positionals(const std::string& value_name, std::vector<std::string>* out, int max);

  enum class Result { kOk, kHelp, kError };
  // argv[0] is the program or command name and is skipped. kHelp: --help or -h was given
  // (print the usage to stdout, exit 0). kError: error() says why (exit 2).
  Result parse(int argc, char** argv);
  // After parse: refuses (false, error() set) any given option outside `mode`;
  // `mode_name` says which mode in the message ("a --stand run").
  bool refuse_inapplicable(ModeMask mode, const std::string& mode_name);
  bool given(const std::string& name) const;
  // "kuavo simulate: --stand needs SECONDS in (0, 600] s, got '5x'".
  const std::string& error() const { return error_; }

 private:
  Option& add(Option o);
  bool fail(const std::string& why);
  bool take(Option& o, const char* value);

  std::string program_;
  std::deque<Option> options_;  // a deque: the references add() returns stay valid
  std::string positional_name_;
  std::vector<std::string>* positionals_ = nullptr;
  int max_positionals_ = 0;
  std::string error_;
};

}  // namespace kuavo::args
