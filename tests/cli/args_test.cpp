// The shared strict parser of command-line values (tools/cli/args.h).
#include "tools/cli/args.h"

#include <gtest/gtest.h>

#include <filesystem>

namespace kuavo::cli {
namespace {

TEST(CliArgs, NumbersAreWholeTokensInRange) {
  double x = -7.0;
  EXPECT_TRUE(parse_number("0.25", 0.0, 1.0, x));
  EXPECT_EQ(x, 0.25);
  EXPECT_TRUE(parse_number("-1e-3", -1.0, 1.0, x));
  for (const char* bad : {"", " 1", "1 ", "5x", "nan", "inf", "-inf", "1e400", "2", "0x1p-2junk"})
    EXPECT_FALSE(parse_number(bad, -1.0, 1.0, x)) << bad;
  EXPECT_EQ(x, -1e-3);  // untouched by a refused value
}

TEST(CliArgs, IntegersDoNotWrapOrTruncate) {
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

TEST(CliArgs, PathsAreCheckedForTheirUse) {
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

}  // namespace
}  // namespace kuavo::cli
