// The closed-loop check's repair ladder (tools/cli/verify_ladder.h), against its definition
// worked out by hand: at 100 Hz with a 50-frame lead-in, a fall at 5.00 s is dance frame 450,
// its range [450 − 200, 450 + 30) = [250, 480); a first fall there scales by the gain, a
// second (an overlapping range before) takes the gestures out with calm steps, a third holds
// both feet down. A pushed run is given up exactly where that third rung would come after its
// push, at most before_s (the range's lead) after it.
#include <gtest/gtest.h>

#include "tools/cli/verify_ladder.h"

namespace kuavo::cli {
namespace {

constexpr double kRate = 100.0;
constexpr int kLead = 50, kDance = 1000;

TEST(VerifyLadder, RangeAndRungs) {
  const VerifyLadder ladder{0.5, 2.0, 0.3};
  std::vector<std::pair<int, int>> scaled;
  VerifyRange r;
  ASSERT_TRUE(verification_range(5.0, kLead, kDance, kRate, ladder, scaled, r));
  EXPECT_EQ(r.a, 250);
  EXPECT_EQ(r.b, 480);
  EXPECT_EQ(r.gain, 0.5);
  EXPECT_FALSE(r.calm_steps);
  EXPECT_FALSE(r.hold);
  ASSERT_EQ(scaled.size(), 1u);

  ASSERT_TRUE(verification_range(5.5, kLead, kDance, kRate, ladder, scaled, r));  // [300, 530): overlaps
  EXPECT_EQ(r.gain, 0.0);
  EXPECT_TRUE(r.calm_steps);
  EXPECT_FALSE(r.hold);

  ASSERT_TRUE(verification_range(5.2, kLead, kDance, kRate, ladder, scaled, r));  // overlaps both
  EXPECT_TRUE(r.hold);
  EXPECT_EQ(r.gain, 0.0);
  EXPECT_TRUE(r.calm_steps);

  // Elsewhere the ladder starts again; at the dance's ends the range is cut; in the lead-in
  // there is nothing to repair.
  ASSERT_TRUE(verification_range(9.0, kLead, kDance, kRate, ladder, scaled, r));  // [650, 880)
  EXPECT_EQ(r.gain, 0.5);
  EXPECT_FALSE(r.hold);
  ASSERT_TRUE(verification_range(1.0, kLead, kDance, kRate, ladder, scaled, r));
  EXPECT_EQ(r.a, 0);
  EXPECT_EQ(r.b, 80);
  ASSERT_TRUE(verification_range(10.4, kLead, kDance, kRate, ladder, scaled, r));  // dance frame 990
  EXPECT_EQ(r.a, 790);
  EXPECT_EQ(r.b, 1000);
  EXPECT_FALSE(verification_range(0.1, kLead, kDance, kRate, ladder, scaled, r));
}

TEST(VerifyLadder, PushedRunGivenUpOnlyAtTheHoldAfterItsPush) {
  const VerifyLadder ladder{0.5, 2.0, 0.3};
  std::vector<std::pair<int, int>> scaled = {{250, 480}};
  // One repair there: the next is the second rung, not a hold.
  EXPECT_FALSE(gives_up_pushed_run(4.0, 5.0, kLead, kDance, kRate, ladder, scaled));
  scaled.emplace_back(300, 530);
  // Two: the next would hold both feet down.
  EXPECT_TRUE(gives_up_pushed_run(4.0, 5.0, kLead, kDance, kRate, ladder, scaled));
  EXPECT_TRUE(gives_up_pushed_run(3.0, 5.0, kLead, kDance, kRate, ladder, scaled));  // 2 s before: in range
  EXPECT_EQ(scaled, (std::vector<std::pair<int, int>>{{250, 480}, {300, 530}}));     // left as it was
  // The push still to come (or at the fall's instant): the model errors felled it, the ladder
  // goes on as for any fall. A push more than before_s earlier did not tip it over either.
  EXPECT_FALSE(gives_up_pushed_run(6.0, 5.0, kLead, kDance, kRate, ladder, scaled));
  EXPECT_FALSE(gives_up_pushed_run(5.0, 5.0, kLead, kDance, kRate, ladder, scaled));
  EXPECT_FALSE(gives_up_pushed_run(2.9, 5.0, kLead, kDance, kRate, ladder, scaled));
  // A fall away from both ranges (10 s: [750, 980)): the first rung.
  EXPECT_FALSE(gives_up_pushed_run(4.0, 10.0, kLead, kDance, kRate, ladder, scaled));
}

// A run with the show set's model errors is given up where a range that held both feet down
// lies under its fall's range: [250, 480), [300, 530), then [270, 500) held (two before it).
TEST(VerifyLadder, ModelErrorRunGivenUpWhereTheFeetWereAlreadyHeld) {
  const VerifyLadder ladder{0.5, 2.0, 0.3};
  std::vector<std::pair<int, int>> scaled = {{250, 480}, {300, 530}};
  // Two repairs there, neither a hold: the ladder still has its third rung.
  EXPECT_FALSE(gives_up_held_run(5.0, kLead, kDance, kRate, ladder, scaled));
  scaled.emplace_back(270, 500);
  EXPECT_TRUE(gives_up_held_run(5.0, kLead, kDance, kRate, ladder, scaled));
  // 7.0 s is dance frame 650: [450, 680) overlaps the held [270, 500) by 50 frames.
  EXPECT_TRUE(gives_up_held_run(7.0, kLead, kDance, kRate, ladder, scaled));
  // 7.5 s: [500, 730) starts where the held range ends (half-open): not over it, though it
  // overlaps [300, 530), which scaled without holding.
  EXPECT_FALSE(gives_up_held_run(7.5, kLead, kDance, kRate, ladder, scaled));
  EXPECT_FALSE(gives_up_held_run(10.0, kLead, kDance, kRate, ladder, scaled));  // [750, 980)
  EXPECT_FALSE(gives_up_held_run(0.1, kLead, kDance, kRate, ladder, scaled));   // in the lead-in
  EXPECT_EQ(scaled.size(), 3u);  // left as it was
  // Order matters: the same three ranges with the wide one first hold nowhere but the last.
  const std::vector<std::pair<int, int>> other = {{100, 900}, {250, 480}, {600, 700}};
  EXPECT_FALSE(gives_up_held_run(5.0, kLead, kDance, kRate, ladder, other));  // [250, 480): over 2nd, 1 before it
  std::vector<std::pair<int, int>> third = other;
  third.emplace_back(260, 490);  // two before it overlap: held
  EXPECT_TRUE(gives_up_held_run(5.0, kLead, kDance, kRate, ladder, third));
}

}  // namespace
}  // namespace kuavo::cli
