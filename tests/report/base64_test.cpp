// Base64 against RFC 4648's test vectors (section 10) and a binary round trip.
#include "tools/report/base64.h"

#include <gtest/gtest.h>

namespace kuavo::report {
namespace {

TEST(Base64, Rfc4648Vectors) {
  const char* vectors[][2] = {{"", ""},         {"f", "Zg=="},         {"fo", "Zm8="},        {"foo", "Zm9v"},
                              {"foob", "Zm9vYg=="}, {"fooba", "Zm9vYmE="}, {"foobar", "Zm9vYmFy"}};
  for (const auto& [plain, coded] : vectors) {
    EXPECT_EQ(base64_encode(std::string_view(plain)), coded);
    std::vector<unsigned char> back;
    ASSERT_TRUE(base64_decode(coded, back));
    EXPECT_EQ(std::string(back.begin(), back.end()), plain);
  }
}

TEST(Base64, EveryByteRoundTripsAndBadTextIsRefused) {
  std::string all;
  for (int i = 0; i < 256; ++i) all += static_cast<char>(i);
  const std::string coded = base64_encode(all);
  // 256 = 85·3 + 1: ... fc fd fe | ff → "/P3+" (63 15 55 62) "/w==" (63 48, padding).
  EXPECT_EQ(coded.substr(coded.size() - 8), "/P3+/w==");
  std::vector<unsigned char> back;
  ASSERT_TRUE(base64_decode(coded, back));
  EXPECT_EQ(std::string(back.begin(), back.end()), all);
  EXPECT_FALSE(base64_decode("Zm9", back));    // not a multiple of 4
  EXPECT_FALSE(base64_decode("Zm9v!A==", back));
}

}  // namespace
}  // namespace kuavo::report
