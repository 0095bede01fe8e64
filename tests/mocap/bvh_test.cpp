// BVH reader: the three shared clips (every dialect quirk they carry), malformed input with
// clear messages, and a seeded mutation/truncation fuzz loop (no crash, always a message).
#include "tools/mocap/bvh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <random>
#include <sstream>

#include "tools/mocap/default_dance.h"

namespace kuavo::mocap {
namespace {

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

const std::string kMocap = std::string(KUAVO_SHARED_DIR) + "/mocap/";

constexpr const char* kSmall =
    "HIERARCHY\n"
    "ROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
    "  JOINT Leg\n  {\n    OFFSET 0 -10 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n"
    "    End Site\n    {\n      OFFSET 0 -10 0\n    }\n  }\n}\n"
    "MOTION\nFrames: 2\nFrame Time: 0.01\n"
    "0 100 0 0 0 0 90 0 0\n"
    "1 100 0 0 0 0 0 0 0\n";

TEST(mocap_bvh, ParsesTheSharedClips) {
  struct Clip {
    const char* file;
    int joints, channels, frames;
    double frame_time;
  };
  // Counts from ../shared/mocap/README.md (joints there exclude End Sites).
  for (const Clip& c :
       {Clip{"perfume_C_test.bvh", 23, 72, 1300, 0.025}, Clip{"cmu_05_20_mb.bvh", 31, 96, 1096, 0.0083333},
        Clip{"cmu_05_07_iclone_ccrig.bvh", 100, 303, 596, 0.016667}}) {
    Bvh b;
    std::string error;
    ASSERT_TRUE(load_bvh_file(kMocap + c.file, b, error)) << error;
    int joints = 0;
    for (const BvhJoint& j : b.joints) joints += !j.end_site;
    EXPECT_EQ(joints, c.joints) << c.file;
    EXPECT_EQ(b.channel_count, c.channels) << c.file;
    EXPECT_EQ(b.frame_count, c.frames) << c.file;
    EXPECT_NEAR(b.frame_time_s, c.frame_time, 1e-9) << c.file;
    EXPECT_EQ(b.motion.size(), static_cast<std::size_t>(c.frames) * c.channels);
  }
}

TEST(mocap_bvh, ChannelOrderAndOffsets) {
  Bvh b;
  std::string error;
  ASSERT_TRUE(parse_bvh(kSmall, b, error)) << error;
  ASSERT_EQ(b.joints.size(), 3u);
  EXPECT_EQ(b.joints[2].name, "Leg_End");
  std::vector<Vec3> p;
  std::vector<Mat3> r;
  bvh_pose(b, 0, p, r);
  // Root at (0, 100, 0); the leg turned 90° about Z swings its end site from -Y to +X.
  EXPECT_NEAR(p[1].y(), 90.0, 1e-9);
  EXPECT_NEAR(p[2].x(), 10.0, 1e-9);
  EXPECT_NEAR(p[2].y(), 90.0, 1e-9);
  bvh_pose(b, 1, p, r);
  EXPECT_NEAR(p[0].x(), 1.0, 1e-12);
}

TEST(mocap_bvh, PerfumeYxzOrderMatchesComposedRotations) {
  Bvh b;
  std::string error;
  ASSERT_TRUE(load_bvh_file(kMocap + "perfume_C_test.bvh", b, error)) << error;
  EXPECT_EQ(b.joints[0].channels[3], BvhChannel::kYrotation);
  EXPECT_EQ(b.joints[0].channels[4], BvhChannel::kXrotation);
  EXPECT_EQ(b.joints[0].channels[5], BvhChannel::kZrotation);
}

TEST(mocap_bvh, CcBaseRootPositionIsAddedToOffset) {
  Bvh b;
  std::string error;
  ASSERT_TRUE(load_bvh_file(kMocap + "cmu_05_07_iclone_ccrig.bvh", b, error)) << error;
  EXPECT_FALSE(b.joints[0].position_absolute);
  std::vector<Vec3> p;
  std::vector<Mat3> r;
  bvh_pose(b, 1, p, r);
  EXPECT_NEAR(p[0].y(), 105.214226 + b.row(1)[1], 1e-6);  // OFFSET + channel
}

// MotionBuilder-style 6-channel child joints carry absolute local positions (around their
// OFFSET); CMU/CC-style root positions are added to OFFSET. Both read right.
TEST(mocap_bvh, AbsoluteAndAdditivePositionChannels) {
  const std::string text =
      "HIERARCHY\nROOT Hips\n{\nOFFSET 0 90 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation "
      "Yrotation\nJOINT Leg\n{\nOFFSET 0 -40 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation "
      "Yrotation\nEnd Site\n{\nOFFSET 0 -40 0\n}\n}\n}\nMOTION\nFrames: 2\nFrame Time: 0.01\n"
      "1 2 0 0 0 0 0 -40 0 0 0 0\n"
      "1 3 0 0 0 0 1 -41 0 0 0 0\n";
  Bvh b;
  std::string error;
  ASSERT_TRUE(parse_bvh(text, b, error)) << error;
  EXPECT_FALSE(b.joints[0].position_absolute);  // values near 0, OFFSET 90: added
  EXPECT_TRUE(b.joints[1].position_absolute);   // values near OFFSET: replace it
  std::vector<Vec3> p;
  std::vector<Mat3> r;
  bvh_pose(b, 1, p, r);
  EXPECT_NEAR(p[0].y(), 93.0, 1e-12);
  EXPECT_NEAR(p[1].x(), 2.0, 1e-12);
  EXPECT_NEAR(p[1].y(), 52.0, 1e-12);
}

TEST(mocap_bvh, MixedLineEndingsReadTheSame) {
  std::string crlf;
  for (char c : std::string(kSmall)) {
    if (c == '\n' && crlf.size() % 3 == 0) crlf += '\r';
    crlf += c;
  }
  Bvh a, b;
  std::string error;
  ASSERT_TRUE(parse_bvh(kSmall, a, error));
  ASSERT_TRUE(parse_bvh(crlf, b, error)) << error;
  EXPECT_EQ(a.motion, b.motion);
}

TEST(mocap_bvh, WriteReadRoundTrip) {
  const Bvh dance = default_dance_bvh();
  Bvh back;
  std::string error;
  ASSERT_TRUE(parse_bvh(write_bvh(dance), back, error)) << error;
  ASSERT_EQ(back.joints.size(), dance.joints.size());
  ASSERT_EQ(back.motion.size(), dance.motion.size());
  for (std::size_t i = 0; i < dance.motion.size(); ++i) ASSERT_NEAR(back.motion[i], dance.motion[i], 1e-6);
}

TEST(mocap_bvh, MalformedFilesNameTheLineAndProblem) {
  struct Case {
    std::string text;
    std::string expect;
  };
  const std::string head = "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n}\n";
  const Case cases[] = {
      {"", "line 1: empty file"},
      {"HIERARCHY\nROOT A\n{\nOFFSET 0 zero 0\n", "line 4: OFFSET of 'A' needs 3 finite numbers"},
      {"HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Wrotation Zrotation\n",
       "line 5: unknown channel 'Wrotation'"},
      {"HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n", "missing '}'"},
      {head + "MOTION\nFrames: 2\nFrame Time: 0.1\n1 2 3\n4 5\n", "line 11: motion row 1 has 2 values, expected 3"},
      {head + "MOTION\nFrames: 3\nFrame Time: 0.1\n1 2 3\n4 5 6\n", "file ends after 2 of 3 motion rows"},
      {head + "MOTION\nFrames: 1\nFrame Time: 0.1\n1 2 nan\n", "line 10: motion value 'nan' is not a finite number"},
      {head + "MOTION\nFrames: 1\nFrame Time: -1\n1 2 3\n", "line 9: Frame Time: needs a positive number"},
      {head + "MOTION\nFrames: 1\nFrame Time: 0.1\n1 2 3\n4 5 6\n", "line 11: more motion rows than 'Frames: 1'"},
      {head + "MOTION\nFrames: 1\nFrame Time: 0.1\n1 2 3 4\n", "line 10: motion row 0 has more than 3 values"},
      {"HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 9 Xrotation\n", "line 5: CHANNELS of 'A' needs a count 0..6"},
  };
  for (const Case& c : cases) {
    Bvh b;
    std::string error;
    EXPECT_FALSE(parse_bvh(c.text, b, error)) << c.text;
    EXPECT_NE(error.find(c.expect), std::string::npos) << "got: " << error << "\nexpected: " << c.expect;
  }
}

std::string with_line_endings(const std::string& lf_text, const std::string& eol) {
  std::string out;
  for (char c : lf_text) {
    if (c == '\n')
      out += eol;
    else
      out += c;
  }
  return out;
}

// Issue 22: a UTF-8 byte-order mark read as "expected HIERARCHY, found '???HIERARCHY'", and
// CR-only line endings put the whole file on one line ("motion row 0 has more than 96 values").
TEST(mocap_bvh, ByteOrderMarkAndEveryLineEndingReadTheSame) {
  std::string lf = read_file(kMocap + "cmu_05_20_mb.bvh");
  lf.erase(std::remove(lf.begin(), lf.end(), '\r'), lf.end());  // the clip mixes CRLF and LF
  Bvh reference;
  std::string error;
  ASSERT_TRUE(parse_bvh(lf, reference, error)) << error;
  std::string mixed;  // every third line ends CRLF, every third CR alone
  int line = 0;
  for (char c : lf) {
    if (c != '\n') {
      mixed += c;
      continue;
    }
    mixed += line % 3 == 0 ? "\r\n" : line % 3 == 1 ? "\r" : "\n";
    ++line;
  }
  const std::string variants[] = {"\xEF\xBB\xBF" + lf, with_line_endings(lf, "\r\n"), with_line_endings(lf, "\r"),
                                  "\xEF\xBB\xBF" + with_line_endings(lf, "\r"), mixed};
  for (const std::string& text : variants) {
    Bvh b;
    ASSERT_TRUE(parse_bvh(text, b, error)) << error;
    EXPECT_EQ(b.motion, reference.motion);
    ASSERT_EQ(b.joints.size(), reference.joints.size());
    for (std::size_t i = 0; i < b.joints.size(); ++i) {
      EXPECT_EQ(b.joints[i].name, reference.joints[i].name);
      EXPECT_EQ(b.joints[i].line, reference.joints[i].line);  // lines counted the same way
    }
  }
}

// Errors name the same line whatever the line endings.
TEST(mocap_bvh, ErrorLinesAreTheSameInEveryLineEnding) {
  const std::string text =
      "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n}\n"
      "MOTION\nFrames: 3\nFrame Time: 0.1\n1 2 3\n4 5\n7 8 9\n";
  for (const char* eol : {"\n", "\r\n", "\r"}) {
    Bvh b;
    std::string error;
    EXPECT_FALSE(parse_bvh(with_line_endings(text, eol), b, error));
    EXPECT_NE(error.find("line 11: motion row 1 has 2 values, expected 3"), std::string::npos) << error;
    EXPECT_FALSE(parse_bvh("\xEF\xBB\xBF" + with_line_endings(text, eol), b, error));
    EXPECT_NE(error.find("line 11: motion row 1 has 2 values, expected 3"), std::string::npos) << error;
  }
  Bvh b;
  std::string error;
  EXPECT_FALSE(parse_bvh(std::string("\xFF\xFEH\0I\0", 6), b, error));
  EXPECT_NE(error.find("line 1: the file is UTF-16"), std::string::npos) << error;
}

// Issue 22: Frame Time 1e-9 and 10 s were accepted, and a root channel scaled by 1e300 made
// an all-NaN motion. Every bound names the line and the rule; values at a bound still pass.
TEST(mocap_bvh, ValuesBeyondHumanMotionNameTheLineAndTheRule) {
  const auto file = [](const std::string& offset, const std::string& frames, const std::string& dt,
                       const std::string& row) {
    return "HIERARCHY\nROOT Hips\n{\nOFFSET " + offset +
           "\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
           "End Site\n{\nOFFSET 0 -10 0\n}\n}\nMOTION\nFrames: " +
           frames + "\nFrame Time: " + dt + "\n" + row + "\n";
  };
  const std::string ok_row = "0 90 0 0 0 0";
  struct Case {
    std::string text;
    std::string expect;  // empty: accepted
  };
  const Case cases[] = {
      {file("0 0 0", "1", "1e-9", ok_row), "line 13: Frame Time: '1e-9' s is below 0.0001 s"},
      {file("0 0 0", "1", "10", ok_row), "line 13: Frame Time: '10' s is above 0.25 s"},
      {file("0 0 0", "1", "0.0001", ok_row), ""},
      {file("0 0 0", "1", "0.25", ok_row), ""},
      {file("0 0 0", "7202", "0.25", ok_row), "line 12: Frames: 7202 at Frame Time 0.25 s last 1800.25 s"},
      {file("0 0 0", "0", "0.01", ""), "line 12: Frames: needs a positive integer"},
      {file("0 1e300 0", "1", "0.01", ok_row), "line 4: OFFSET of 'Hips' '1e300' exceeds 100000 file units"},
      {file("0 -100000 0", "1", "0.01", ok_row), ""},
      {file("0 0 0", "1", "0.01", "0 9e301 0 0 0 0"),
       "line 14: motion row 0, 'Hips' Yposition '9e301' exceeds 100000 file units"},
      {file("0 0 0", "1", "0.01", "0 90 0 0 -1000001 0"),
       "line 14: motion row 0, 'Hips' Xrotation '-1000001' exceeds 1e+06 degrees"},
      {file("0 0 0", "1", "0.01", "0 90 0 0 -1000000 0"), ""},
  };
  for (const Case& c : cases) {
    Bvh b;
    std::string error;
    const bool ok = parse_bvh(c.text, b, error);
    if (c.expect.empty()) {
      EXPECT_TRUE(ok) << error << "\n" << c.text;
      continue;
    }
    EXPECT_FALSE(ok) << c.text;
    EXPECT_NE(error.find(c.expect), std::string::npos) << "got: " << error << "\nexpected: " << c.expect;
  }
  // The shared clip with its root position channels scaled by 1e300, as the fuzzer did it.
  Bvh clip;
  std::string error;
  ASSERT_TRUE(load_bvh_file(kMocap + "cmu_05_20_mb.bvh", clip, error)) << error;
  for (int f = 0; f < clip.frame_count; ++f) clip.motion[static_cast<std::size_t>(f) * clip.channel_count] *= 1e300;
  Bvh b;
  EXPECT_FALSE(parse_bvh(write_bvh(clip), b, error));
  EXPECT_NE(error.find("'Hips' Xposition"), std::string::npos) << error;
  EXPECT_NE(error.find("exceeds 100000 file units"), std::string::npos) << error;
}

// Seeded mutation + truncation fuzz: every input either parses or fails with "line N: ...".
TEST(mocap_bvh, FuzzedInputNeverCrashesAndAlwaysExplains) {
  const std::string seed_text = read_file(kMocap + "cmu_05_20_mb.bvh").substr(0, 9000);
  const std::string seeds[] = {std::string(kSmall), seed_text};
  std::mt19937 rng(20251121u);
  const char alphabet[] = "{}\n\r\t -.0123456789eE+ROOTJOINTEndSiteOFFSETCHANNELSXYZrotationpositionMOTIONFrames:Time";
  int failures = 0;
  for (int iter = 0; iter < 3000; ++iter) {
    std::string s = seeds[iter % 2];
    const int edits = 1 + static_cast<int>(rng() % 8);
    for (int e = 0; e < edits && !s.empty(); ++e) {
      const std::size_t at = rng() % s.size();
      switch (rng() % 5) {
        case 0:
          s[at] = alphabet[rng() % (sizeof alphabet - 1)];
          break;
        case 1:
          s.erase(at, 1 + rng() % 16);
          break;
        case 2:
          s.insert(at, 1, alphabet[rng() % (sizeof alphabet - 1)]);
          break;
        case 3:
          s.resize(at);
          break;  // truncation
        case 4:
          s.insert(at, s.substr(rng() % s.size(), rng() % 64));
          break;
      }
    }
    Bvh b;
    std::string error;
    if (!parse_bvh(s, b, error)) {
      ++failures;
      ASSERT_EQ(error.rfind("line ", 0), 0u) << error;
    } else {
      ASSERT_EQ(b.motion.size(), static_cast<std::size_t>(b.frame_count) * b.channel_count);
      std::vector<Vec3> p;
      std::vector<Mat3> r;
      for (int f = 0; f < std::min(b.frame_count, 3); ++f) bvh_pose(b, f, p, r);
    }
  }
  EXPECT_GT(failures, 1000);  // the loop really exercises the error paths
}

}  // namespace
}  // namespace kuavo::mocap
