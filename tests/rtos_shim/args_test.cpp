// The shared strict command-line parser (rtos_shim/args.h).
#include "rtos_shim/args.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <initializer_list>
#include <string>
#include <vector>

namespace kuavo::args {
namespace {

TEST(Args, NumbersAreWholeTokensInRange) {
  double x = -7.0;
  EXPECT_TRUE(parse_number("0.25", 0.0, 1.0, x));
  EXPECT_EQ(x, 0.25);
  EXPECT_TRUE(parse_number("-1e-3", -1.0, 1.0, x));
  for (const char* bad : {"", " 1", "1 ", "5x", "nan", "inf", "-inf", "1e400", "2", "0x1p-2junk"})
    EXPECT_FALSE(parse_number(bad, -1.0, 1.0, x)) << bad;
  EXPECT_EQ(x, -1e-3);  // untouched by a refused value
}

TEST(Args, IntegersDoNotWrapOrTruncate) {
  long long n = 0;
  EXPECT_TRUE(parse_integer("50", 0, 50, n));
  EXPECT_EQ(n, 50);
  for (const char* bad : {"51", "-1", "5abc", "5.0", "1e1", "", "99999999999999999999999", "nan"})
    EXPECT_FALSE(parse_integer(bad, 0, 50, n)) << bad;
  std::uint64_t u = 0;
  EXPECT_TRUE(parse_uint64("18446744073709551615", u));
  EXPECT_EQ(u, 18446744073709551615ull);
  for (const char* bad : {"-1", "+1", "18446744073709551616", "99999999999999999999999", "1x", ""})
    EXPECT_FALSE(parse_uint64(bad, u)) << bad;
}

TEST(Args, PathsAreCheckedForTheirUse) {
  std::string error;
  EXPECT_FALSE(check_input_file(KUAVO_BINARY_DIR, error));
  EXPECT_NE(error.find("not a regular file"), std::string::npos) << error;
  EXPECT_FALSE(check_input_file(std::string(KUAVO_BINARY_DIR) + "/no_such_file", error));
  EXPECT_FALSE(check_output_file(KUAVO_BINARY_DIR, error));
  EXPECT_FALSE(check_output_file(std::string(KUAVO_BINARY_DIR) + "/no_such_dir/out.json", error));
  const std::string fresh = std::string(KUAVO_BINARY_DIR) + "/args_test_output.json";
  EXPECT_TRUE(check_output_file(fresh, error)) << error;
  EXPECT_FALSE(std::filesystem::exists(fresh));  // the check leaves nothing behind
}


// argv from a list (argv[0] is the program name, skipped by the parser).
struct Argv {
  std::vector<std::string> args;
  std::vector<char*> ptrs;
  explicit Argv(std::initializer_list<const char*> list) {
    args.emplace_back("prog");
    for (const char* a : list) args.emplace_back(a);
    for (std::string& a : args) ptrs.push_back(a.data());
    ptrs.push_back(nullptr);
  }
  int argc() const { return static_cast<int>(args.size()); }
  char** argv() { return ptrs.data(); }
};

constexpr ModeMask kStand = 1, kMotion = 2;

struct Fixture {
  double stand_s = 0.0, horizon_s = 1.2;
  long long steps = 0;
  std::uint64_t seed = 1;
  std::string ground = "floor", log, motion_text;
  bool check = false;
  std::vector<std::string> inputs;
  Parser p{"prog"};
  Fixture() {
    p.number("--stand", "SECONDS", 0.0, 600.0, "s", &stand_s, /*lo_open=*/true).modes = kStand;
    p.number("--horizon", "SECONDS", 0.2, 1.4, "s", &horizon_s).modes = kMotion;
    p.integer("--steps", "STEPS", 1, 200, "steps", &steps).modes = kMotion;
    p.uint64("--seed", "N", &seed);
    p.choice("--ground", {"floor", "carpet"}, &ground);
    p.output_file("--log", "CSV", &log);
    p.flag("--check", &check);
    p.text("--out", "DIR", &motion_text).alias = "-o";
    p.positionals("MOTION", &inputs, 1);
  }
  Parser::Result run(std::initializer_list<const char*> list) {
    Argv a(list);
    return p.parse(a.argc(), a.argv());
  }
};

TEST(ArgsParser, ReadsEveryKindOfValue) {
  Fixture f;
  ASSERT_EQ(f.run({"m.motion", "--horizon", "0.6", "--steps", "20", "--seed", "18446744073709551615", "--ground",
                   "carpet", "--check", "-o", "dir"}),
            Parser::Result::kOk)
      << f.p.error();
  EXPECT_EQ(f.horizon_s, 0.6);
  EXPECT_EQ(f.steps, 20);
  EXPECT_EQ(f.seed, 18446744073709551615ull);
  EXPECT_EQ(f.ground, "carpet");
  EXPECT_TRUE(f.check);
  EXPECT_EQ(f.motion_text, "dir");
  ASSERT_EQ(f.inputs.size(), 1u);
  EXPECT_EQ(f.inputs[0], "m.motion");
  EXPECT_TRUE(f.p.refuse_inapplicable(kMotion, "a motion run"));
  EXPECT_TRUE(f.p.given("--steps"));
  EXPECT_FALSE(f.p.given("--stand"));
}

// Each refusal names the option, what it takes (range and unit) and what it got.
TEST(ArgsParser, RefusalsNameOptionRangeUnitAndValue) {
  const struct {
    std::initializer_list<const char*> argv;
    const char* message;
  } cases[] = {
      {{"--stand", "5x"}, "prog: --stand needs SECONDS in (0, 600] s, got '5x'"},
      {{"--stand", "0"}, "prog: --stand needs SECONDS in (0, 600] s, got '0'"},
      {{"--stand", "1e9"}, "prog: --stand needs SECONDS in (0, 600] s, got '1e9'"},
      {{"--stand", "nan"}, "prog: --stand needs SECONDS in (0, 600] s, got 'nan'"},
      {{"--steps", "5.0"}, "prog: --steps needs a whole number STEPS in 1..200 steps, got '5.0'"},
      {{"--seed", "-1"}, "prog: --seed needs a whole number N in 0..2^64-1, got '-1'"},
      {{"--seed", "99999999999999999999999"}, "prog: --seed needs a whole number N in 0..2^64-1, got '99999999999999999999999'"},
      {{"--ground", "ice"}, "prog: --ground must be floor|carpet, got 'ice'"},
      {{"--horizon"}, "prog: --horizon needs a value (SECONDS)"},
      {{"--log", "--check"}, "prog: --log needs a value (CSV), got option '--check'"},
      {{"--bogus"}, "prog: unknown option '--bogus'"},
      {{"--check", "--check"}, "prog: --check given twice"},
      {{"a", "b"}, "prog: more than 1 MOTION ('b')"},
      {{"--log", KUAVO_BINARY_DIR}, "prog: --log " KUAVO_BINARY_DIR ": is a directory"},
  };
  for (const auto& c : cases) {
    Fixture f;
    EXPECT_EQ(f.run(c.argv), Parser::Result::kError) << c.message;
    EXPECT_EQ(f.p.error(), c.message);
  }
}

TEST(ArgsParser, OptionsOutsideTheModeAreRefused) {
  Fixture f;
  ASSERT_EQ(f.run({"--stand", "5", "--horizon", "0.6"}), Parser::Result::kOk);
  EXPECT_FALSE(f.p.refuse_inapplicable(kStand, "a --stand run"));
  EXPECT_EQ(f.p.error(), "prog: --horizon does not apply to a --stand run");
  Fixture g;
  ASSERT_EQ(g.run({"--stand", "5", "--seed", "3"}), Parser::Result::kOk);
  EXPECT_TRUE(g.p.refuse_inapplicable(kStand, "a --stand run"));  // --seed applies to every mode
}

TEST(ArgsParser, HelpAndNegativeNumbers) {
  Fixture f;
  EXPECT_EQ(f.run({"--stand", "5", "-h"}), Parser::Result::kHelp);
  Parser p("prog");
  double x = 0.0;
  p.number("--x", "X", -10.0, 10.0, "m", &x);
  std::vector<char*> argv;
  std::string a0 = "prog", a1 = "--x", a2 = "-2.5";
  argv = {a0.data(), a1.data(), a2.data(), nullptr};
  ASSERT_EQ(p.parse(3, argv.data()), Parser::Result::kOk) << p.error();  // "-2.5" is a value, not an option
  EXPECT_EQ(x, -2.5);
}

}  // namespace
}  // namespace kuavo::args
