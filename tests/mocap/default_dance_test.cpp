// The built-in dance at other lengths (default_dance.h): whole 30 s cycles repeated, each one
// the first cycle's motion but for the arms where two cycles meet. Oracles: the BVH poser's
// joint positions (forward kinematics of the channels, independent of how the generator
// composes them); the dance's own gentlest change of arm phase (the intro's swing fading
// into the side steps' raises at 2 s: the hands' second difference peaks at 1.8 cm; its other
// changes peak at 2.8–7.8 cm) bounds each seam. Without the seams' cross-fade the settle's
// arms jump to the intro's (0.05 rad shoulder, 0.1 rad elbow: ~4 cm at the hands).
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "tools/mocap/default_dance.h"

namespace kuavo::mocap {
namespace {

std::vector<Vec3> joints_at(const Bvh& b, int frame) {
  std::vector<Vec3> p;
  std::vector<Mat3> r;
  bvh_pose(b, frame, p, r);
  return p;
}

double largest_move(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double m = 0.0;
  for (std::size_t j = 0; j < a.size(); ++j) m = std::max(m, (a[j] - b[j]).norm());
  return m;
}

// The largest |p(f+1) − 2 p(f) + p(f−1)| over the joints [BVH units: cm].
double second_difference(const Bvh& b, int f) {
  const auto a = joints_at(b, f - 1), m = joints_at(b, f), c = joints_at(b, f + 1);
  double out = 0.0;
  for (std::size_t j = 0; j < m.size(); ++j) out = std::max(out, (c[j] - 2.0 * m[j] + a[j]).norm());
  return out;
}

TEST(DefaultDance, DurationIsWholeCycles) {
  EXPECT_EQ(default_dance_cycles(30.0), 1);
  EXPECT_EQ(default_dance_cycles(240.0), 8);
  EXPECT_EQ(default_dance_cycles(300.0), 10);
  for (double bad : {0.0, 15.0, 45.0, 239.0, 330.0, -30.0}) EXPECT_EQ(default_dance_cycles(bad), 0) << bad;
}

TEST(DefaultDance, FourMinutesRepeatTheCycleAndMeetWithoutAJump) {
  const Bvh one = default_dance_bvh(), eight = default_dance_bvh(8);
  const int cycle = static_cast<int>(kDefaultDanceDuration_s * kDefaultDanceRate_hz);
  ASSERT_EQ(one.frame_count, cycle + 1);
  ASSERT_EQ(eight.frame_count, 8 * cycle + 1);
  EXPECT_NEAR((eight.frame_count - 1) * eight.frame_time_s, 240.0, 1e-9);
  const int seam_margin = static_cast<int>(0.6 * kDefaultDanceRate_hz);  // the arms' cross-fade: ±0.4 s ramps
  const int intro_end = static_cast<int>(2.0 * kDefaultDanceRate_hz), window = static_cast<int>(0.3 * kDefaultDanceRate_hz);
  double calm = 0.0;
  for (int f = intro_end - window; f <= intro_end + window; ++f) calm = std::max(calm, second_difference(one, f));
  RecordProperty("intro_end_second_difference_cm", std::to_string(calm));
  double worst_seam = 0.0;
  for (int c = 1; c < 8; ++c) {
    double seam = 0.0;
    for (int f = c * cycle - seam_margin; f <= c * cycle + seam_margin; ++f) seam = std::max(seam, second_difference(eight, f));
    EXPECT_LE(seam, calm) << "seam " << c;
    worst_seam = std::max(worst_seam, seam);
    // Away from the seams, cycle c is the first cycle (the turn's whole revolution differs in
    // the last bits of its sines).
    for (int k = seam_margin; k <= cycle - seam_margin; k += 37) {
      ASSERT_LT(largest_move(joints_at(eight, c * cycle + k), joints_at(one, k)), 1e-9) << "cycle " << c << " frame " << k;
    }
  }
  RecordProperty("seam_second_difference_cm", std::to_string(worst_seam));
  // The last cycle ends as the single dance does (the settle).
  EXPECT_LT(largest_move(joints_at(eight, 8 * cycle), joints_at(one, cycle)), 1e-9);
}

}  // namespace
}  // namespace kuavo::mocap
