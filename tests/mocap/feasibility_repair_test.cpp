// Feasibility repair (tools/mocap/feasibility_repair.h) on small synthetic motions built
// from the standing configuration with the leg IK: one case per repair kind, the override
// file, and motions that need nothing. Every result is also held to the invariants the
// dynamic stage relies on (never in flight unless an override kept it, stance feet flat and
// still on the floor, swings and double supports no shorter than the robot's minimums,
// standing at both ends).
#include "tools/mocap/feasibility_repair.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "tests/mocap/motion_fixture.h"
#include "tools/mocap/dynamics_check.h"

namespace kuavo::mocap {
namespace {

using namespace kuavo::mocap::test;

// A leg IK that reaches its targets stops below 1e-9 m; anything above this is a miss (the
// repair itself accepts a stance foot up to 2 mm off before it lowers the base). Every motion
// here is within the legs' reach, so feet are checked to this.
constexpr double kIkConverged_m = 1e-6;

int frames_of(double s) { return static_cast<int>(std::lround(s * kRate_hz)); }
int lead_frames(const RepairConfig& c = {}) { return frames_of(c.lead_in_s + c.blend_in_s); }

bool has(const RepairedMotion& r, RepairKind k) {
  return std::any_of(r.repairs.begin(), r.repairs.end(), [&](const Repair& x) { return x.kind == k; });
}
const Repair* first(const RepairedMotion& r, RepairKind k) {
  for (const Repair& x : r.repairs) {
    if (x.kind == k) return &x;
  }
  return nullptr;
}
std::string listing(const RepairedMotion& r) {
  std::string s;
  for (const Repair& x : r.repairs) {
    s += std::string(to_string(x.kind)) + " [" + std::to_string(x.start_s) + ", " + std::to_string(x.end_s) +
         ") " + x.reason + "\n";
  }
  return s;
}

RepairedMotion repair(const Motion& m, const std::vector<RepairOverride>& overrides = {},
                      const RepairConfig& cfg = {}) {
  EXPECT_LT(m.worst_ik_error_m, 1e-6) << "the synthetic motion's own feet are where they were put";
  RepairedMotion out;
  std::string error;
  EXPECT_TRUE(repair_motion(robot(), m.q, m.labels, kRate_hz, cfg, overrides, out, error)) << error;
  return out;
}

// Invariants of every repaired motion. allow_flight: an override kept a flight; foot_m: how
// far a stance corner may be off the floor or slide.
void expect_dancable(const RepairedMotion& r, int dance_frames, const RepairConfig& cfg = {},
                     bool allow_flight = false, double foot_m = kIkConverged_m) {
  SCOPED_TRACE(listing(r));
  const int lead = lead_frames(cfg), n = lead + dance_frames + frames_of(cfg.tail_s);
  ASSERT_EQ(r.lead_frames, lead);
  ASSERT_EQ(r.dance_frames, dance_frames);
  ASSERT_EQ(static_cast<int>(r.q.size()), n);
  ASSERT_EQ(static_cast<int>(r.contacts.size()), n);
  EXPECT_EQ(r.contacts.front(), ContactLabel::kDoubleSupport);
  EXPECT_EQ(r.contacts.back(), ContactLabel::kDoubleSupport);
  EXPECT_LT(r.max_leg_ik_error_m, foot_m);
  EXPECT_EQ(r.robot_steps, count_steps(r.contacts));
  for (int i = 0; i < n; ++i) {
    ASSERT_TRUE(r.q[i].allFinite()) << i;
    ASSERT_NEAR(r.q[i].segment<4>(3).norm(), 1.0, 1e-12) << i;
    if (!allow_flight) {
      ASSERT_NE(r.contacts[i], ContactLabel::kFlight) << "frame " << i;
    }
  }
  // Stance feet flat on the floor and still over each stance interval.
  std::vector<std::array<Vec3, kCorners>> corners(n);
  for (int i = 0; i < n; ++i) corners[i] = corners_of(r.q[i]);
  for (int f = 0; f < 2; ++f) {
    const auto down = [&](int i) { return f == 0 ? left_in_contact(r.contacts[i]) : right_in_contact(r.contacts[i]); };
    int since = -1;
    for (int i = 0; i < n; ++i) {
      if (!down(i)) {
        since = -1;
        continue;
      }
      if (since < 0) since = i;
      for (int c = 4 * f; c < 4 * f + 4; ++c) {
        ASSERT_LE(std::abs(corners[i][c].z()), foot_m) << "foot " << f << " frame " << i;
        ASSERT_LE((corners[i][c] - corners[since][c]).norm(), 2.0 * foot_m)
            << "foot " << f << " slides at frame " << i;
      }
    }
  }
  // Swings and weight transfers no shorter than the robot's minimums (between steps).
  const int min_swing = frames_of(cfg.min_swing_s), min_ds = frames_of(cfg.min_double_support_s);
  for (int f = 0; f < 2 && !allow_flight; ++f) {
    for (int i = 1; i < n; ++i) {
      const bool was = f == 0 ? left_in_contact(r.contacts[i - 1]) : right_in_contact(r.contacts[i - 1]);
      const bool now = f == 0 ? left_in_contact(r.contacts[i]) : right_in_contact(r.contacts[i]);
      if (!(was && !now)) continue;
      int j = i;
      while (j < n && !(f == 0 ? left_in_contact(r.contacts[j]) : right_in_contact(r.contacts[j]))) ++j;
      EXPECT_GE(j - i, min_swing) << "swing of foot " << f << " at frame " << i;
      int k = i - 1;  // the double support before the lift-off
      while (k >= 0 && r.contacts[k] == ContactLabel::kDoubleSupport) --k;
      if (k >= 0) {
        EXPECT_GE(i - 1 - k, min_ds) << "weight transfer before frame " << i;
      }
    }
  }
  for (std::size_t k = 0; k < r.repairs.size(); ++k) {
    const Repair& x = r.repairs[k];
    EXPECT_LE(x.start_s, x.end_s);
    EXPECT_GE(x.start_s, 0.0);
    EXPECT_LE(x.end_s, n / kRate_hz + 1e-9);
    EXPECT_FALSE(x.reason.empty());
    if (k > 0) {
      EXPECT_LE(r.repairs[k - 1].start_s, x.start_s) << "listed in time order";
    }
  }
  ASSERT_NE(first(r, RepairKind::kLeadIn), nullptr);
  EXPECT_EQ(first(r, RepairKind::kLeadIn)->start_s, 0.0);
  EXPECT_NEAR(first(r, RepairKind::kLeadIn)->end_s, lead / kRate_hz, 1e-12);
}

// Where the left sole centre is relative to the right's, in the right foot's heading frame:
// x ahead, y beside.
Eigen::Vector2d left_from_right(const ConfigVector& q) {
  const auto f = feet_of(q);
  const Vec3 d = rot_z(f[1].yaw).transpose() * (f[0].centre - f[1].centre);
  return d.head<2>();
}

// ---- overrides ----

TEST(mocap_feasibility_repair, ParsesTheDocumentedOverrideLines) {
  std::vector<RepairOverride> o;
  std::string error;
  ASSERT_TRUE(parse_repair_overrides("# a comment line\n"
                                     "0.5 1.25 forbid flight\n"
                                     "\n"
                                     "  2 3 forbid retime   # trailing comment\n"
                                     "3 4 forbid stride\n"
                                     "4 5.5 forbid turn\n"
                                     "6 7 forbid all\n"
                                     "0 0.1 force double\n"
                                     "8 9 calm steps\n"
                                     "9 10 force square\n",
                                     o, error))
      << error;
  ASSERT_EQ(o.size(), 8u);
  EXPECT_TRUE(o[7].force_double);
  EXPECT_TRUE(o[7].square_stance);
  EXPECT_FALSE(o[5].square_stance);
  EXPECT_TRUE(o[6].calm_steps);
  EXPECT_FALSE(o[6].force_double);
  EXPECT_FALSE(o[6].forbid_all);
  EXPECT_FALSE(o[0].calm_steps);
  EXPECT_EQ(o[0].start_s, 0.5);
  EXPECT_EQ(o[0].end_s, 1.25);
  EXPECT_FALSE(o[0].force_double);
  EXPECT_FALSE(o[0].forbid_all);
  EXPECT_EQ(o[0].forbid, RepairKind::kFlight);
  EXPECT_EQ(o[1].forbid, RepairKind::kRetime);
  EXPECT_EQ(o[2].forbid, RepairKind::kStride);
  EXPECT_EQ(o[3].forbid, RepairKind::kTurn);
  EXPECT_EQ(o[3].end_s, 5.5);
  EXPECT_TRUE(o[4].forbid_all);
  EXPECT_FALSE(o[4].force_double);
  EXPECT_TRUE(o[5].force_double);
  EXPECT_EQ(o[5].start_s, 0.0);
  EXPECT_EQ(o[5].end_s, 0.1);

  o.clear();
  EXPECT_TRUE(parse_repair_overrides("", o, error));
  EXPECT_TRUE(o.empty());
}

TEST(mocap_feasibility_repair, RejectsMalformedOverrideLinesNamingTheLine) {
  const char* bad[] = {
      "1 0.5 forbid flight",         // end before start
      "1 1 forbid flight",           // empty range
      "-0.5 1 forbid flight",        // negative start
      "a 1 forbid flight",           // not a number
      "0.5 1x forbid flight",        // trailing garbage in a number
      "nan 1 forbid flight",         // not finite
      "0 inf forbid flight",         // not finite
      "0.5 1 forbid jump",           // unknown kind
      "0.5 1 forbid tilt",           // not a kind the override knows
      "0.5 1 force single",          // only `force double` and `force square`
      "0.5 1 allow flight",          // unknown verb
      "0.5 1 forbid",                // missing kind
      "0.5 1",                       // missing verb
      "0.5",                         // missing end
      "0.5 1 forbid flight please",  // extra word
  };
  for (const char* line : bad) {
    SCOPED_TRACE(line);
    std::vector<RepairOverride> o;
    std::string error;
    // Blank, comment and good lines count: the bad one is line 4.
    EXPECT_FALSE(parse_repair_overrides(std::string("\n# overrides\n0 1 forbid all\n") + line + "\n2 3 force double\n",
                                        o, error));
    EXPECT_NE(error.find("line 4"), std::string::npos) << error;
  }
}

TEST(mocap_feasibility_repair, RefusesBadInput) {
  const ConfigVector q = standing().q;
  RepairedMotion out;
  std::string error;
  EXPECT_FALSE(repair_motion(robot(), {q}, {ContactLabel::kDoubleSupport}, kRate_hz, {}, {}, out, error));
  EXPECT_FALSE(error.empty());
  error.clear();
  EXPECT_FALSE(repair_motion(robot(), {q, q, q}, {ContactLabel::kDoubleSupport, ContactLabel::kDoubleSupport},
                             kRate_hz, {}, {}, out, error));
  EXPECT_FALSE(error.empty());
  std::vector<ConfigVector> frames(4, q);
  frames[2][7 + 3] = std::numeric_limits<double>::infinity();
  error.clear();
  EXPECT_FALSE(repair_motion(robot(), frames, std::vector<ContactLabel>(4, ContactLabel::kDoubleSupport), kRate_hz,
                             {}, {}, out, error));
  EXPECT_NE(error.find("not finite"), std::string::npos) << error;
  EXPECT_NE(error.find("2"), std::string::npos) << error;
  error.clear();
  EXPECT_FALSE(repair_motion(robot(), std::vector<ConfigVector>(4, q),
                             std::vector<ContactLabel>(4, ContactLabel::kDoubleSupport), 0.0, {}, {}, out, error));
  EXPECT_FALSE(error.empty());
}

TEST(mocap_feasibility_repair, CountsSwingPhases) {
  using L = ContactLabel;
  EXPECT_EQ(count_steps({}), 0);
  EXPECT_EQ(count_steps({L::kDoubleSupport, L::kDoubleSupport}), 0);
  EXPECT_EQ(count_steps({L::kDoubleSupport, L::kLeftSupport, L::kDoubleSupport, L::kRightSupport, L::kDoubleSupport}),
            2);
  EXPECT_EQ(count_steps({L::kDoubleSupport, L::kFlight, L::kDoubleSupport}), 2);  // a hop lifts both feet
  EXPECT_EQ(count_steps({L::kLeftSupport, L::kRightSupport, L::kLeftSupport}), 2);  // a switch lifts one each time
}

// ---- motions that need nothing ----

// Standing still while the arms wave: no repair but the lead-in and the tail, and the dance
// frames come out as they went in (legs re-solved onto the feet they already stand on).
TEST(mocap_feasibility_repair, StandingNeedsNoRepairAndKeepsItsFrames) {
  const int n = 150;
  const Motion m = make_motion(n, [](int i) {
    Keyframe k = stand_key();
    // From rest (a dance already moving when the lead-in hands over gets the join smoothed:
    // ArmSnapIsSmoothedWithinTheJointTorque).
    k.arms[0] = -0.3 * (1.0 - std::cos(2.0 * M_PI * i / n));  // left shoulder pitch
    k.arms[7 + 3] = -0.4 * (1.0 - std::cos(M_PI * i / n));    // right elbow
    return k;
  });
  const RepairedMotion r = repair(m);
  expect_dancable(r, n);
  SCOPED_TRACE(listing(r));
  for (const Repair& x : r.repairs) {
    EXPECT_TRUE(x.kind == RepairKind::kLeadIn || x.kind == RepairKind::kTail) << to_string(x.kind);
  }
  EXPECT_EQ(r.human_steps, 0);
  EXPECT_EQ(r.robot_steps, 0);
  double worst = 0.0;
  for (int d = 0; d < n; ++d) worst = std::max(worst, (r.q[r.lead_frames + d] - m.q[d]).cwiseAbs().maxCoeff());
  EXPECT_LT(worst, 1e-9);
  RecordProperty("max_frame_change", number(worst));
}

// The geometric motion's step forward of 0.2 m, 0.5 s swing, 0.6 s double supports: within
// every limit. No repair; the schedule is the human's; in double support the frames are
// unchanged (the leg IK stops below 1e-9 m, measured 9e-11 m: see the bounds); the stance foot
// stays and the swing lands on the human's foothold. The swing frames themselves differ by
// design (the repair's own arc, and the pelvis over the repaired feet).
TEST(mocap_feasibility_repair, SlowValidStepNeedsNoRepair) {
  const int n = 200, a = 60, b = 110;
  const Foot l0 = standing().feet[0], l1 = moved(l0, 0.20);
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    k.left = i < a ? l0 : (i >= b ? l1 : swing(l0, l1, i, a, b, 0.05));
    k.left_down = i < a || i >= b;
    return k;
  });
  const RepairedMotion r = repair(m);
  expect_dancable(r, n);
  SCOPED_TRACE(listing(r));
  for (const Repair& x : r.repairs) {
    EXPECT_TRUE(x.kind == RepairKind::kLeadIn || x.kind == RepairKind::kTail) << to_string(x.kind);
  }
  EXPECT_EQ(r.human_steps, 1);
  EXPECT_EQ(r.robot_steps, 1);
  const int lead = r.lead_frames;
  double whole = 0.0, base = 0.0, upper = 0.0, corner = 0.0, stance_corner = 0.0;
  for (int d = 0; d < n; ++d) {
    ASSERT_EQ(r.contacts[lead + d], m.labels[d]) << d;
    const ConfigVector& q = r.q[lead + d];
    const auto c_out = corners_of(q), c_in = corners_of(m.q[d]);
    if (m.labels[d] == ContactLabel::kDoubleSupport) {
      whole = std::max(whole, (q - m.q[d]).cwiseAbs().maxCoeff());
      base = std::max(base, (q.head<7>() - m.q[d].head<7>()).cwiseAbs().maxCoeff());
      upper = std::max(upper, (q.tail<16>() - m.q[d].tail<16>()).cwiseAbs().maxCoeff());
      for (int c = 0; c < kCorners; ++c) corner = std::max(corner, (c_out[c] - c_in[c]).norm());
    } else {
      for (int c = 4; c < kCorners; ++c) stance_corner = std::max(stance_corner, (c_out[c] - c_in[c]).norm());
    }
  }
  // Leg angles: the IK stops with corners within 1e-9 m, which over a lever ≥ 5 cm (ankle
  // roll to a sole corner) is ≤ 2e-8 rad (measured 4.8e-10); everything else within 1e-9.
  EXPECT_LT(whole, 2e-8);
  EXPECT_LT(base, 1e-9);
  EXPECT_LT(upper, 1e-12);
  EXPECT_LT(corner, 1e-9);
  EXPECT_LT(stance_corner, 1e-9);
  RecordProperty("double_support_frame_change", number(whole));
  RecordProperty("double_support_base_change", number(base));
  RecordProperty("double_support_corner_change_m", number(corner));
  const auto landed = feet_of(r.q[lead + b + 5]);
  EXPECT_LT((landed[0].centre - l1.centre).norm(), 1e-9);
}

// ---- one case per repair kind ----

// A hop (both feet 3 cm up for 0.2 s, the pelvis with them): both feet stay down, the
// pelvis keeps its bounce, the flight is listed over exactly its frames.
// The bounce keeps the human's pelvis height exactly with the vertical acceleration limit
// off (this hop's 6.7 m/s² is beyond the default; FastDipIsSmoothedToWhatTheFeetCarry).
TEST(mocap_feasibility_repair, HopBecomesADoubleSupportBounce) {
  const int n = 150, a = 50, b = 70;
  const Motion m = hop_motion(n, a, b);
  RepairConfig cfg;
  cfg.max_vertical_acceleration_m_s2 = 0.0;
  const RepairedMotion r = repair(m, {}, cfg);
  expect_dancable(r, n, cfg);
  SCOPED_TRACE(listing(r));
  const Repair* flight = first(r, RepairKind::kFlight);
  ASSERT_NE(flight, nullptr);
  EXPECT_NEAR(flight->start_s, (r.lead_frames + a) / kRate_hz, 1e-9);
  EXPECT_NEAR(flight->end_s, (r.lead_frames + b) / kRate_hz, 1e-9);
  for (int d = 0; d < n; ++d) {
    EXPECT_EQ(r.contacts[r.lead_frames + d], ContactLabel::kDoubleSupport) << d;
    EXPECT_NEAR(r.q[r.lead_frames + d][2], m.q[d][2], 1e-12) << "pelvis height at " << d;
  }
  EXPECT_EQ(r.human_steps, 2);
  EXPECT_EQ(r.robot_steps, 0);
}

// A leap (right steps, both feet off the floor for 0.1 s, right lands, left follows): the
// left foot stays down until the right lands.
TEST(mocap_feasibility_repair, LeapBecomesAStep) {
  const int n = 200;
  const Foot l0 = standing().feet[0], r0 = standing().feet[1];
  const Foot r1 = moved(r0, 0.25), l1 = moved(l0, 0.50);
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    k.right = i < 50 ? r0 : (i >= 90 ? r1 : swing(r0, r1, i, 50, 90, 0.05));
    k.right_down = i < 50 || i >= 90;
    k.left = i < 80 ? l0 : (i >= 120 ? l1 : swing(l0, l1, i, 80, 120, 0.05));
    k.left_down = i < 80 || i >= 120;
    return k;
  });
  ASSERT_EQ(m.labels[85], ContactLabel::kFlight);
  const RepairedMotion r = repair(m);
  expect_dancable(r, n);
  SCOPED_TRACE(listing(r));
  ASSERT_TRUE(has(r, RepairKind::kFlight));
  EXPECT_EQ(r.robot_steps, 2);
  const int lead = r.lead_frames;
  for (int d = 80; d < 90; ++d) EXPECT_TRUE(left_in_contact(r.contacts[lead + d])) << "the last foot stays down, " << d;
  // Both end where the human's feet did (within reach: 0.25 m ahead).
  const auto end = feet_of(r.q[lead + n - 1]);
  EXPECT_LT((end[0].centre - l1.centre).norm(), 1e-6);
  EXPECT_LT((end[1].centre - r1.centre).norm(), 1e-6);
}

// A 0.2 s swing (the robot's shortest is 0.3 s): the touchdown is delayed to 0.3 s.
TEST(mocap_feasibility_repair, ShortSwingIsRetimed) {
  const int n = 150, a = 60, b = 80;
  const Foot l0 = standing().feet[0], l1 = moved(l0, 0.10);
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    k.left = i < a ? l0 : (i >= b ? l1 : swing(l0, l1, i, a, b, 0.04));
    k.left_down = i < a || i >= b;
    return k;
  });
  const RepairedMotion r = repair(m);
  expect_dancable(r, n);
  SCOPED_TRACE(listing(r));
  const Repair* retime = first(r, RepairKind::kRetime);
  ASSERT_NE(retime, nullptr);
  EXPECT_NEAR(retime->start_s, (r.lead_frames + b) / kRate_hz, 1e-9);
  EXPECT_FALSE(has(r, RepairKind::kStepSkipped));
  EXPECT_EQ(r.robot_steps, 1);
  int lift = -1, land = -1;
  for (int i = 1; i < static_cast<int>(r.contacts.size()); ++i) {
    if (left_in_contact(r.contacts[i - 1]) && !left_in_contact(r.contacts[i])) lift = i;
    if (!left_in_contact(r.contacts[i - 1]) && left_in_contact(r.contacts[i])) land = i;
  }
  EXPECT_EQ(lift, r.lead_frames + a) << "lift-off as the human's";
  EXPECT_EQ(land - lift, frames_of(RepairConfig{}.min_swing_s)) << "the swing lengthened to the minimum, no more";
  EXPECT_LT((feet_of(r.q.back())[0].centre - l1.centre).norm(), 1e-6) << "landing on the human's foothold";
}

// A right step, 30 ms of double support, then a 50 ms tap of the left foot: the tap cannot
// fit after the weight transfer the robot needs, so it is skipped and reported.
TEST(mocap_feasibility_repair, StepThatCannotFitIsSkipped) {
  const int n = 160;
  const Foot r0 = standing().feet[1], r1 = moved(r0, 0.10), l0 = standing().feet[0];
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    k.right = i < 50 ? r0 : (i >= 90 ? r1 : swing(r0, r1, i, 50, 90, 0.04));
    k.right_down = i < 50 || i >= 90;
    k.left = (i >= 93 && i < 98) ? swing(l0, l0, i, 93, 98, 0.02) : l0;
    k.left_down = !(i >= 93 && i < 98);
    return k;
  });
  const RepairedMotion r = repair(m);
  expect_dancable(r, n);
  SCOPED_TRACE(listing(r));
  const Repair* skipped = first(r, RepairKind::kStepSkipped);
  ASSERT_NE(skipped, nullptr);
  EXPECT_NEAR(skipped->start_s, (r.lead_frames + 93) / kRate_hz, 1e-9);
  EXPECT_NEAR(skipped->end_s, (r.lead_frames + 98) / kRate_hz, 1e-9);
  EXPECT_EQ(r.human_steps, 2);
  EXPECT_EQ(r.robot_steps, 1);
  for (const ContactLabel c : r.contacts) EXPECT_TRUE(left_in_contact(c));
}

// A 0.6 m stride (the limit is 0.40 m ahead of the stance foot): the touchdown is placed at
// the limit, beside where the human put it.
TEST(mocap_feasibility_repair, LongStrideIsShortened) {
  const int n = 200, a = 60, b = 110;
  const Foot l0 = standing().feet[0], l1 = moved(l0, 0.60);
  const auto key = [&](int i) {
    Keyframe k = stand_key();
    k.left = i < a ? l0 : (i >= b ? l1 : swing(l0, l1, i, a, b, 0.05));
    k.left_down = i < a || i >= b;
    return k;
  };
  const Motion m = make_motion(n, key);
  ASSERT_GT(left_from_right(m.q.back()).x(), 0.55) << "the precondition: the human's stride is too long";
  const RepairConfig cfg;
  const RepairedMotion r = repair(m, {}, cfg);
  expect_dancable(r, n);
  SCOPED_TRACE(listing(r));
  const Repair* stride = first(r, RepairKind::kStride);
  ASSERT_NE(stride, nullptr);
  EXPECT_NEAR(stride->start_s, (r.lead_frames + b) / kRate_hz, 1e-9);
  const Eigen::Vector2d d = left_from_right(r.q.back());
  // At the limit, at the human's width.
  EXPECT_NEAR(d.x(), cfg.max_step_forward_m, kIkConverged_m);
  EXPECT_NEAR(d.y(), left_from_right(m.q.back()).y(), kIkConverged_m);
  for (int i = r.lead_frames + b; i < static_cast<int>(r.q.size()); ++i) {
    EXPECT_LE(left_from_right(r.q[i]).x(), cfg.max_step_forward_m + kIkConverged_m) << i;
  }

  // Forbidden, the stride stays as the human took it.
  std::vector<RepairOverride> o;
  std::string error;
  ASSERT_TRUE(parse_repair_overrides("0 10 forbid stride\n", o, error)) << error;
  // The 0.6 m stride kept puts the rear leg at the edge of its reach while the front foot
  // swings: the repair accepts a stance foot up to 2 mm off (measured 1.2 mm).
  const RepairedMotion kept = repair(m, o, cfg);
  expect_dancable(kept, n, cfg, false, 2e-3);
  EXPECT_FALSE(has(kept, RepairKind::kStride)) << listing(kept);
  EXPECT_NEAR(left_from_right(kept.q.back()).x(), left_from_right(m.q.back()).x(), 2e-3);
}

// The right foot pivots 0.5 rad in place while both feet are down (a planted foot cannot):
// listed as a turn, and the robot's right foot keeps one heading throughout, the human's
// mean heading over the stance.
TEST(mocap_feasibility_repair, PivotingStanceFootKeepsOneHeading) {
  const int n = 150;
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    const double s = std::clamp((i - 40) / 60.0, 0.0, 1.0);
    k.right.yaw = 0.5 * s * s * (3.0 - 2.0 * s);
    return k;
  });
  const RepairConfig cfg;
  ASSERT_GT(feet_of(m.q.back())[1].yaw, cfg.pivot_yaw_rad + 0.1);
  const RepairedMotion r = repair(m, {}, cfg);
  expect_dancable(r, n, cfg);
  SCOPED_TRACE(listing(r));
  const Repair* turn = first(r, RepairKind::kTurn);
  ASSERT_NE(turn, nullptr);
  EXPECT_NE(turn->reason.find("pivot"), std::string::npos);
  double sc = 0.0, ss = 0.0;
  for (const ConfigVector& q : m.q) {
    const double y = feet_of(q)[1].yaw;
    sc += std::cos(y), ss += std::sin(y);
  }
  const double mean = std::atan2(ss, sc);
  double worst = 0.0;
  for (const ConfigVector& q : r.q) worst = std::max(worst, std::abs(feet_of(q)[1].yaw - mean));
  // The heading from a toe–heel pair 0.24 m apart, each corner within the IK's convergence.
  EXPECT_LT(worst, 2.0 * kIkConverged_m / 0.24);
  RecordProperty("right_foot_heading_error_rad", number(worst));
}

// The left foot lands turned out 0.95 rad against the right (the repair allows 0.80): the
// touchdown heading is limited, listed as a turn.
TEST(mocap_feasibility_repair, TouchdownHeadingIsLimitedToTheHipYawRange) {
  const int n = 200, a = 60, b = 110;
  const Foot l0 = standing().feet[0], l1 = moved(l0, 0.05, 0.0, 0.95);
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    k.left = i < a ? l0 : (i >= b ? l1 : swing(l0, l1, i, a, b, 0.05));
    k.left_down = i < a || i >= b;
    // The pelvis turns half way with the foot, so each hip yaw stays within its range.
    k.base_yaw = 0.475 * std::clamp(double(i - a) / (b - a), 0.0, 1.0);
    return k;
  });
  const RepairConfig cfg;
  const RepairedMotion r = repair(m, {}, cfg);
  expect_dancable(r, n, cfg);
  SCOPED_TRACE(listing(r));
  const Repair* turn = first(r, RepairKind::kTurn);
  ASSERT_NE(turn, nullptr);
  EXPECT_NEAR(turn->start_s, (r.lead_frames + b) / kRate_hz, 1e-9);
  const auto f = feet_of(r.q[r.lead_frames + n - 1]);
  EXPECT_NEAR(f[0].yaw - f[1].yaw, cfg.max_relative_yaw_rad, 2.0 * kIkConverged_m / 0.24);
}

// A dance that starts with the left foot in the air and the arms raised: the robot first
// stands on both feet in its standing pose, then blends in; the dance frames' arms follow.
TEST(mocap_feasibility_repair, StartOffTheFloorGetsALeadIn) {
  const int n = 150, land = 40;
  const Foot l0 = standing().feet[0];
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    if (i < land) k.left.centre.z() = 0.05 * (1.0 - static_cast<double>(i) / land);
    k.left_down = i >= land;
    k.arms[0] = -1.2;  // left shoulder forward
    k.arms[7] = -1.0;
    return k;
  });
  ASSERT_EQ(m.labels.front(), ContactLabel::kRightSupport);
  const RepairConfig cfg;
  const RepairedMotion r = repair(m, {}, cfg);
  expect_dancable(r, n, cfg);
  SCOPED_TRACE(listing(r));
  ASSERT_GT(r.lead_frames, 0);
  EXPECT_EQ(r.lead_frames, frames_of(cfg.lead_in_s + cfg.blend_in_s));
  constexpr int kUpper = 7 + 2 * model::kLegJoints;
  const int still = frames_of(cfg.lead_in_s);
  for (int i = 0; i < still; ++i) {
    EXPECT_EQ(r.contacts[i], ContactLabel::kDoubleSupport);
    EXPECT_LT((r.q[i] - r.q[0]).cwiseAbs().maxCoeff(), 1e-12) << "standing still at " << i;
  }
  EXPECT_LT((r.q[0].tail<model::kNq - kUpper>() - standing().q.tail<model::kNq - kUpper>()).cwiseAbs().maxCoeff(),
            1e-12)
      << "the standing arms and head";
  const auto f0 = feet_of(r.q[0]);
  EXPECT_NEAR(f0[1].centre.x(), standing().feet[1].centre.x(), 1e-6);
  EXPECT_NEAR(f0[0].centre.y() - f0[1].centre.y(), standing().feet[0].centre.y() - standing().feet[1].centre.y(),
              1e-6)
      << "the left foot stands beside the right at the standing width";
  for (int d = 0; d < n; ++d) {
    EXPECT_LT((r.q[r.lead_frames + d].tail<model::kNq - kUpper>() - m.q[d].tail<model::kNq - kUpper>())
                  .cwiseAbs()
                  .maxCoeff(),
              1e-12)
        << "dance arms at " << d;
  }
  EXPECT_LT((feet_of(r.q[r.lead_frames + n - 1])[0].centre - l0.centre).norm(), 1e-6);
}

// A dance that ends with the right foot in the air: the tail brings it down and the robot
// ends standing in double support in its standing pose.
TEST(mocap_feasibility_repair, EndOffTheFloorGetsATail) {
  const int n = 200, lift = 150;
  const Foot r0 = standing().feet[1], r1 = moved(r0, 0.10);
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    if (i >= lift) k.right = swing(r0, r1, i, lift, n + 20, 0.08);  // still in the air at the end
    k.right_down = i < lift;
    return k;
  });
  ASSERT_EQ(m.labels.back(), ContactLabel::kLeftSupport);
  RepairConfig cfg;
  const RepairedMotion r = repair(m, {}, cfg);
  expect_dancable(r, n, cfg);
  SCOPED_TRACE(listing(r));
  const Repair* tail = nullptr;
  for (const Repair& x : r.repairs) {
    if (x.kind == RepairKind::kTail && x.reason.find("both feet down") == 0) tail = &x;
  }
  ASSERT_NE(tail, nullptr);
  const int end_of_dance = r.lead_frames + n;
  // The right foot, still in the air when the clip ends (aimed 0.10 m ahead, 0.08 m by the
  // clip's last frame), lands in the tail square beside the left, at the standing width, as the
  // robot stands; and the move is listed. Without it (square_tail_step off) it lands where the
  // human's would.
  RepairConfig human_cfg = cfg;
  human_cfg.square_tail_step = false;
  const RepairedMotion human = repair(m, {}, human_cfg);
  expect_dancable(human, n, human_cfg);
  const Eigen::Vector2d ends = left_from_right(r.q.back()), human_ends = left_from_right(human.q.back());
  const double stand_width = standing().feet[0].centre.y() - standing().feet[1].centre.y();
  EXPECT_NEAR(ends.x(), 0.0, 1e-6) << ends.transpose();
  EXPECT_NEAR(ends.y(), stand_width, 1e-6) << ends.transpose();
  const auto last = feet_of(r.q.back());
  EXPECT_NEAR(last[0].yaw, last[1].yaw, 1e-9);
  EXPECT_LT(human_ends.x(), -0.07) << "the human's last step lands ahead: " << human_ends.transpose();
  int squared = 0;
  for (const Repair& x : r.repairs) {
    if (x.kind != RepairKind::kTail || x.reason.find("ends square: the right foot beside the left") == std::string::npos) {
      continue;
    }
    ++squared;
    EXPECT_GE(x.start_s, end_of_dance / kRate_hz - 1e-9) << x.reason;
    char moved[32];
    std::snprintf(moved, sizeof moved, ", %.2f m", (human_ends - ends).norm());
    EXPECT_NE(x.reason.find(moved), std::string::npos) << x.reason << " (moved " << (human_ends - ends).norm() << " m)";
  }
  EXPECT_EQ(squared, 1);
  for (const Repair& x : human.repairs) EXPECT_EQ(x.reason.find("ends square"), std::string::npos) << x.reason;
  EXPECT_NEAR(tail->start_s, end_of_dance / kRate_hz, 1e-9);
  EXPECT_NEAR(tail->end_s, static_cast<double>(r.q.size()) / kRate_hz, 1e-9);
  for (int i = end_of_dance; i < static_cast<int>(r.q.size()); ++i) {
    EXPECT_EQ(r.contacts[i], ContactLabel::kDoubleSupport) << i;
  }
  constexpr int kUpper = 7 + 2 * model::kLegJoints;
  EXPECT_LT((r.q.back().tail<model::kNq - kUpper>() - standing().q.tail<model::kNq - kUpper>()).cwiseAbs().maxCoeff(),
            1e-12);
}

// A deep plié: the standing pose moved 15 cm down (the repair puts the soles back on the
// floor, the pelvis stays at 0.63 m). The legs cannot take it within their
// limits (knee and ankle pitch at their ends): the best leg solution at the asked height misses
// the floor by ~6 mm. Lowering the pelvis further only takes the feet further off, so the
// repair must not return anything worse than that first attempt.
// (The repair used to keep the last of its 21 lowering attempts, not the best: pelvis at
// 0.43 m, soles 5.9 cm above the floor.)
TEST(mocap_feasibility_repair, UnreachablePelvisHeightDoesNotGetWorse) {
  const int n = 50;
  const double drop = 0.15;
  std::vector<ConfigVector> q(n, standing().q);
  for (ConfigVector& f : q) f[2] -= drop;
  const std::vector<ContactLabel> labels(n, ContactLabel::kDoubleSupport);
  // The best the legs do at the asked height (both soles on the floor where they stand).
  ConfigVector best = standing().q;
  best[2] -= drop;
  std::array<Vec3, kCorners> targets;
  for (int c = 0; c < kCorners; ++c) targets[c] = standing().feet[c / 4].centre + standing().corner_offset[c];
  const double reachable = leg_ik_lm(robot(), scratch(), targets, best);
  ASSERT_GT(reachable, 2e-3) << "the precondition: the plié is out of the legs' reach";
  RepairedMotion r;
  std::string error;
  ASSERT_TRUE(repair_motion(robot(), q, labels, kRate_hz, {}, {}, r, error)) << error;
  // The repair's IK starts from the previous frame's legs (the lead-in blends down from
  // standing), so at the joint limits it may settle in another corner of the limit box than
  // the fresh solve above: measured 9.3 mm (corner-error norm) against 6.3 mm (largest
  // coordinate). Twice the fresh miss still tells the best attempt from the last one (60 mm).
  EXPECT_LE(r.max_leg_ik_error_m, 2.0 * reachable);
  const ConfigVector& mid = r.q[r.lead_frames + n / 2];
  EXPECT_GE(mid[2], q[0][2] - 1e-9) << "the pelvis lowered below the asked height, away from the floor";
  for (const Vec3& c : corners_of(mid)) EXPECT_LE(std::abs(c.z()), 2.0 * reachable);
}

// leg_ik_lm leaves the legs' kinematics of the pose it returns in data (the repair's leg solve
// reads the stance corners from there), whether its last trial step was taken or not: the right
// foot 5 cm forward and 2 cm up (reachable), 0.5 m forward (beyond reach; its iteration ends
// on a rejected trial), 0.3 m down (beyond reach), and the plié's targets; each against a
// fresh forward kinematics of the returned pose.
TEST(mocap_feasibility_repair, LegIkLeavesTheReturnedPosesKinematicsInData) {
  const std::array<Vec3, 3> right_moved = {Vec3(0.05, 0.0, 0.02), Vec3(0.5, 0.0, 0.0), Vec3(0.0, 0.0, -0.3)};
  const std::array<double, 3> drops = {0.0, 0.0, 0.15};
  for (int k = 0; k < 3; ++k) {
    SCOPED_TRACE(k);
    ConfigVector q = standing().q;
    q[2] -= drops[k];
    std::array<Vec3, kCorners> targets;
    for (int c = 0; c < kCorners; ++c) {
      targets[c] = standing().feet[c / 4].centre + standing().corner_offset[c] + (c >= 4 ? right_moved[k] : Vec3::Zero());
    }
    dynamics::Data& data = scratch();
    const double miss = leg_ik_lm(robot(), data, targets, q);
    dynamics::Data fresh;
    dynamics::forward_kinematics(robot(), fresh, q);
    double worst = 0.0;
    for (int c = 0; c < kCorners; ++c) {
      EXPECT_EQ(dynamics::frame_position(robot(), data, c), dynamics::frame_position(robot(), fresh, c)) << "corner " << c;
      worst = std::max(worst, (targets[c] - dynamics::frame_position(robot(), fresh, c)).cwiseAbs().maxCoeff());
    }
    EXPECT_EQ(miss, worst);
    if (k == 0) {
      EXPECT_LT(miss, 1e-6);
    } else {
      EXPECT_GT(miss, 0.01) << "the precondition: beyond reach";
    }
  }
}

// The leg solve's JᵀJ is Eigen's jac.transpose() * jac bit for bit (the motions were verified
// with that product), over random Jacobians with zeros, signed zeros and entries from 1e-5 to
// 1e4; and it is JᵀJ (each entry against the long-double sum, to 1e-15 of the entries' size).
TEST(mocap_feasibility_repair, LegJacobianGramIsEigensProductBitForBit) {
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  std::uniform_int_distribution<int> pick(0, 9);
  int differ = 0;
  for (int t = 0; t < 20000; ++t) {
    Eigen::Matrix<double, 9, 6> jac;
    for (int r = 0; r < 9; ++r) {
      for (int c = 0; c < 6; ++c) {
        const int p = pick(rng);
        jac(r, c) = p == 0 ? 0.0 : p == 1 ? -0.0 : normal(rng) * std::pow(10.0, pick(rng) - 5);
      }
    }
    const Eigen::Matrix<double, 6, 6> eigen = jac.transpose() * jac;
    const Eigen::Matrix<double, 6, 6> gram = leg_jacobian_gram(jac);
    for (int i = 0; i < 36; ++i) differ += std::memcmp(&eigen.data()[i], &gram.data()[i], sizeof(double)) != 0;
    for (int i = 0; i < 6; ++i) {
      for (int j = 0; j < 6; ++j) {
        long double exact = 0.0L, size = 0.0L;
        for (int r = 0; r < 9; ++r) {
          exact += static_cast<long double>(jac(r, i)) * jac(r, j);
          size += std::abs(static_cast<long double>(jac(r, i)) * jac(r, j));
        }
        ASSERT_LE(std::abs(gram(i, j) - exact), 1e-15L * size + 1e-300L) << t << " (" << i << ", " << j << ")";
      }
    }
  }
  EXPECT_EQ(differ, 0) << "entries that differ from Eigen's product in some bit, of " << 20000 * 36;
}

// A dancer on straight legs: the pelvis raised until the knees are nearly straight (the
// human's stance, scaled), then held. The repair lowers the pelvis (listed as pelvis_height)
// until every stance knee of the IK's output is bent at least min_stance_knee_rad, without a
// step in the base height; `forbid pelvis` keeps the straight legs.
TEST(mocap_feasibility_repair, StraightLegsGetTheirKneesBent) {
  const int knee_l = 7 + 3, knee_r = 7 + model::kLegJoints + 3;
  // The raise that leaves the knees at ~0.12 rad (bisection on the fixture's own IK).
  double lo = 0.0, hi = 0.2;
  for (int it = 0; it < 30; ++it) {
    const double mid = 0.5 * (lo + hi);
    Keyframe k = stand_key();
    k.base_shift.z() = mid;
    double e = 0.0;
    const ConfigVector q = frame_of(k, standing().q, &e);
    (e < 1e-6 && std::min(q[knee_l], q[knee_r]) > 0.12 ? lo : hi) = mid;
  }
  const int n = 200;
  const Motion m = make_motion(n, [&](int) {
    Keyframe k = stand_key();
    k.base_shift.z() = lo;
    return k;
  });
  const RepairConfig cfg;
  ASSERT_LT(std::min(m.q[0][knee_l], m.q[0][knee_r]), cfg.min_stance_knee_rad - 0.2) << "precondition: straight legs";
  const RepairedMotion r = repair(m);
  expect_dancable(r, n);
  SCOPED_TRACE(listing(r));
  ASSERT_TRUE(has(r, RepairKind::kPelvisHeight));
  double least_knee = 10.0, largest_dz = 0.0;
  for (int i = 0; i < static_cast<int>(r.q.size()); ++i) {
    least_knee = std::min({least_knee, r.q[i][knee_l], r.q[i][knee_r]});
    if (i > 0) largest_dz = std::max(largest_dz, std::abs(r.q[i][2] - r.q[i - 1][2]));
  }
  // The repair plans the lowering on the distance from the hip pitch to the ankle pitch joint
  // with the standing pose's hip roll; the IK's knee is the oracle: measured 0.457 rad for
  // 0.5 (the hip roll changes as the leg straightens).
  EXPECT_GE(least_knee, cfg.min_stance_knee_rad - 0.05);
  // No step: the lowering (~5 cm here) spread over ±0.25 s, the lead-in's blend included.
  EXPECT_LT(largest_dz, 3e-3);
  RecordProperty("least_knee_rad", number(least_knee));
  RecordProperty("largest_base_step_m", number(largest_dz));

  const RepairedMotion kept = repair(m, {{0.0, 100.0, false, false, RepairKind::kPelvisHeight}});
  EXPECT_FALSE(has(kept, RepairKind::kPelvisHeight));
  EXPECT_LT(std::min(kept.q[kept.lead_frames + n / 2][knee_l], kept.q[kept.lead_frames + n / 2][knee_r]), 0.2);
}

// A deep crouch: the pelvis lowered until the knees fold past max_stance_knee_rad (within the
// legs' reach). The repair raises the pelvis (pelvis_height) until the IK's stance knees are
// within the bound.
TEST(mocap_feasibility_repair, DeepCrouchIsRaisedToTheKneeBound) {
  const int knee_l = 7 + 3, knee_r = 7 + model::kLegJoints + 3;
  const RepairConfig cfg;
  double lo = 0.0, hi = 0.3;  // the drop that folds the knees to max + 0.3 rad
  for (int it = 0; it < 30; ++it) {
    const double mid = 0.5 * (lo + hi);
    Keyframe k = stand_key();
    k.base_shift.z() = -mid;
    double e = 0.0;
    const ConfigVector q = frame_of(k, standing().q, &e);
    (e < 1e-6 && std::max(q[knee_l], q[knee_r]) < cfg.max_stance_knee_rad + 0.3 ? lo : hi) = mid;
  }
  const int n = 200;
  const Motion m = make_motion(n, [&](int) {
    Keyframe k = stand_key();
    k.base_shift.z() = -lo;
    return k;
  });
  ASSERT_GT(std::max(m.q[0][knee_l], m.q[0][knee_r]), cfg.max_stance_knee_rad + 0.2) << "precondition: a deep crouch";
  const RepairedMotion r = repair(m);
  expect_dancable(r, n);
  SCOPED_TRACE(listing(r));
  ASSERT_TRUE(has(r, RepairKind::kPelvisHeight));
  double deepest = 0.0;
  for (const ConfigVector& q : r.q) deepest = std::max({deepest, q[knee_l], q[knee_r]});
  EXPECT_LE(deepest, cfg.max_stance_knee_rad + 0.05);
  RecordProperty("deepest_knee_rad", number(deepest));
}

// A lean of up to 0.55 rad (32°), forward and a little to the side, in double support:
// beyond the base tilt bound (RepairConfig::max_base_tilt_rad). Checked from the frames' own
// quaternions: no output frame tilts beyond the bound; where the human leaned beyond it the
// pelvis leans by exactly the bound in the human's direction (the body z axis keeps its
// horizontal direction: the least rotation back, not a different lean); frames within the
// bound keep their orientation; one tilt entry covers the frames beyond it. With the bound
// out of reach the lean is left as it is.
TEST(mocap_feasibility_repair, DeepLeanIsLimitedToTheTiltBound) {
  const int n = 200, a = 50, b = 150;
  const Vec3 axis = Vec3(0.3, 0.95, 0.0).normalized();  // about this horizontal axis: forward, a little left
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    k.base_shift.z() = -0.1;  // the hips lower, so the legs reach under the lean
    if (i > a && i < b) k.base_lean = 0.55 * std::sin(M_PI * (i - a) / (b - a)) * axis;
    return k;
  });
  const auto tilt_of = [](const ConfigVector& q) {
    const Eigen::Quaterniond qb(q[6], q[3], q[4], q[5]);
    return std::acos(std::clamp(qb.normalized().toRotationMatrix()(2, 2), -1.0, 1.0));
  };
  const auto z_heading = [](const ConfigVector& q) {  // the body z axis's horizontal direction
    const Vec3 z = Eigen::Quaterniond(q[6], q[3], q[4], q[5]).normalized().toRotationMatrix().col(2);
    return std::atan2(z.y(), z.x());
  };
  const RepairConfig cfg;
  double before = 0.0;
  for (const ConfigVector& q : m.q) before = std::max(before, tilt_of(q));
  ASSERT_GT(before, cfg.max_base_tilt_rad + 0.1) << "precondition: the lean is beyond the bound";
  const RepairedMotion r = repair(m);
  expect_dancable(r, n);
  SCOPED_TRACE(listing(r));
  const Repair* tilt = first(r, RepairKind::kTilt);
  ASSERT_NE(tilt, nullptr);
  int first_over = -1, last_over = -1, over = 0;
  double worst = 0.0, unchanged = 0.0;
  for (int d = 0; d < n; ++d) {
    const ConfigVector& in = m.q[d];
    const ConfigVector& out = r.q[r.lead_frames + d];
    const double t_in = tilt_of(in), t_out = tilt_of(out);
    worst = std::max(worst, t_out);
    ASSERT_LE(t_out, cfg.max_base_tilt_rad + 1e-9) << "frame " << d;
    if (t_in > cfg.max_base_tilt_rad) {
      if (first_over < 0) first_over = d;
      last_over = d, ++over;
      EXPECT_NEAR(t_out, cfg.max_base_tilt_rad, 1e-9) << "frame " << d;
      EXPECT_NEAR(std::remainder(z_heading(out) - z_heading(in), 2.0 * M_PI), 0.0, 1e-9) << "frame " << d;
    } else {
      const Eigen::Quaterniond qi(in[6], in[3], in[4], in[5]), qo(out[6], out[3], out[4], out[5]);
      unchanged = std::max(unchanged, qi.angularDistance(qo));
    }
  }
  ASSERT_GT(over, 20);
  EXPECT_LT(unchanged, 1e-9) << "frames within the bound keep their orientation";
  EXPECT_LE(tilt->start_s, (r.lead_frames + first_over) / kRate_hz + 1e-9);
  EXPECT_GE(tilt->end_s, (r.lead_frames + last_over + 1) / kRate_hz - 1e-9);
  EXPECT_EQ(std::count_if(r.repairs.begin(), r.repairs.end(), [](const Repair& x) { return x.kind == RepairKind::kTilt; }), 1);
  RecordProperty("lean_in_rad", number(before));
  RecordProperty("lean_out_rad", number(worst));

  RepairConfig off;
  off.max_base_tilt_rad = M_PI;
  const RepairedMotion unlimited = repair(m, {}, off);
  EXPECT_FALSE(has(unlimited, RepairKind::kTilt));
  double kept = 0.0;
  for (int d = 0; d < n; ++d) kept = std::max(kept, tilt_of(unlimited.q[unlimited.lead_frames + d]));
  EXPECT_NEAR(kept, before, 1e-9);
}

// A dip of 8 cm in 0.3 s in double support: 8.8 m/s² at its bottom, beyond the 0.5 g the
// feet carry (RepairConfig::max_vertical_acceleration_m_s2). The repair smooths it until no
// frame's second difference of the pelvis height is beyond the limit (checked here from the
// frames, not from the repair's own bookkeeping); the dip stays a dip; `forbid bounce` gives
// exactly what the repair gives with the limit off.
TEST(mocap_feasibility_repair, FastDipIsSmoothedToWhatTheFeetCarry) {
  const int n = 200, a = 80, b = 110;
  const double depth = 0.08;
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    if (i >= a && i <= b) k.base_shift.z() = -depth * std::sin(M_PI * (i - a) / (b - a));
    return k;
  });
  const RepairConfig cfg;
  const double limit = cfg.max_vertical_acceleration_m_s2 / (kRate_hz * kRate_hz);
  double before = 0.0;
  for (int i = 1; i + 1 < n; ++i) before = std::max(before, std::abs(m.q[i + 1][2] - 2.0 * m.q[i][2] + m.q[i - 1][2]));
  ASSERT_GT(before, 1.5 * limit) << "precondition: the dip is beyond the limit";
  const RepairedMotion r = repair(m);
  expect_dancable(r, n);
  SCOPED_TRACE(listing(r));
  const Repair* bounce = first(r, RepairKind::kBounce);
  ASSERT_NE(bounce, nullptr);
  EXPECT_LE(bounce->start_s, (r.lead_frames + a) / kRate_hz);
  EXPECT_GE(bounce->end_s, (r.lead_frames + b) / kRate_hz);
  const int total = static_cast<int>(r.q.size());
  double after = 0.0, lowest = r.q[0][2];
  for (int i = 1; i + 1 < total; ++i) {
    after = std::max(after, std::abs(r.q[i + 1][2] - 2.0 * r.q[i][2] + r.q[i - 1][2]));
    lowest = std::min(lowest, r.q[i][2]);
  }
  EXPECT_LE(after, limit * (1.0 + 1e-6));
  const double kept = r.q[0][2] - lowest;  // frame 0 stands
  EXPECT_GT(kept, 0.25 * depth) << "smoothed, not flattened";
  EXPECT_LT(kept, depth);
  RecordProperty("dip_kept_m", number(kept));

  std::vector<RepairOverride> overrides;
  std::string error;
  ASSERT_TRUE(parse_repair_overrides("0 2 forbid bounce\n", overrides, error)) << error;
  const RepairedMotion forbidden = repair(m, overrides);
  EXPECT_FALSE(has(forbidden, RepairKind::kBounce));
  RepairConfig off;
  off.max_vertical_acceleration_m_s2 = 0.0;
  const RepairedMotion unlimited = repair(m, {}, off);  // the other repairs (pelvis_height) as they are
  ASSERT_EQ(forbidden.q.size(), unlimited.q.size());
  for (std::size_t i = 0; i < unlimited.q.size(); ++i) ASSERT_EQ(forbidden.q[i], unlimited.q[i]) << i;
  double deepest = 0.0;
  for (const ConfigVector& q : unlimited.q) deepest = std::max(deepest, unlimited.q[0][2] - q[2]);
  EXPECT_GT(deepest, kept + 0.01) << "the forbidden smoothing would have taken more than 1 cm off the dip";
}

// Walking at 0.6 m/s: steps of 0.3 m, each foot 0.6 m per 1 s cycle (0.15 s double support,
// 0.35 s swings), within the legs' reach step by step but faster than the robot travels. The
// repair shortens the steps (listed as travel_speed): the dance travels no faster than
// max_travel_speed_m_s (the lag is made up by later steps, each within the limit; this walk
// ends 0.3 m short of the human's end); `forbid travel` keeps the pace.
TEST(mocap_feasibility_repair, FastTravelIsSlowedToTheRobotsPace) {
  const int ds = 15, sw = 35, steps = 6, a0 = 40;
  const int n = a0 + steps * (ds + sw) + 150;
  const Foot l0 = standing().feet[0], r0 = standing().feet[1];
  const auto foot_x = [&](int foot, int k) {  // after k steps
    int moves = foot == 0 ? (k + 1) / 2 : k / 2;
    return moves == 0 ? 0.0 : 0.3 + 0.6 * (moves - 1) + (foot == 1 ? 0.3 : 0.0);
  };
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    for (int foot = 0; foot < 2; ++foot) {
      const Foot base = foot == 0 ? l0 : r0;
      int taken = 0;
      for (int s = 0; s < steps; ++s) {
        const int a = a0 + s * (ds + sw) + ds, b = a + sw;  // swing frames of step s
        const bool mine = (s % 2 == 0) == (foot == 0);
        if (!mine) continue;
        if (i >= b) taken = s + 1;
        if (i >= a && i < b) {
          const Foot from = moved(base, foot_x(foot, s));
          const Foot to = moved(base, foot_x(foot, s + 1));
          (foot == 0 ? k.left : k.right) = swing(from, to, i, a, b, 0.05);
          (foot == 0 ? k.left_down : k.right_down) = false;
          taken = -1;
          break;
        }
      }
      if (taken >= 0) (foot == 0 ? k.left : k.right) = moved(base, foot_x(foot, taken));
    }
    return k;
  });
  const RepairConfig cfg;
  const RepairedMotion r = repair(m);
  expect_dancable(r, n);
  SCOPED_TRACE(listing(r));
  ASSERT_TRUE(has(r, RepairKind::kTravel));
  // The feet midpoint over the walk (first lift-off to the human's last touchdown, plus one
  // cycle to catch up): no faster than the limit on average, and at the end where the human is.
  const int lead = r.lead_frames;
  const int w0 = lead + a0 + ds, w1 = lead + a0 + steps * (ds + sw);
  const auto mid_x = [&](int i) {
    const auto f = feet_of(r.q[i]);
    return 0.5 * (f[0].centre.x() + f[1].centre.x());
  };
  // The window's ends do not fall on the feet's cycles: 0.03 m/s of slack (measured 0.474).
  const double speed = (mid_x(w1) - mid_x(w0)) / ((w1 - w0) / kRate_hz);
  EXPECT_LE(speed, cfg.max_travel_speed_m_s + 0.03);
  // Slowed, not stopped: it still walks at nearly the limit.
  EXPECT_GE(speed, cfg.max_travel_speed_m_s - 0.1);
  RecordProperty("walk_speed_m_s", number(speed));

  const RepairedMotion kept = repair(m, {{0.0, 100.0, false, false, RepairKind::kTravel}});
  EXPECT_FALSE(has(kept, RepairKind::kTravel));
  const auto mid_kept = [&](int i) {
    const auto f = feet_of(kept.q[i]);
    return 0.5 * (f[0].centre.x() + f[1].centre.x());
  };
  EXPECT_GT((mid_kept(w1) - mid_kept(w0)) / ((w1 - w0) / kRate_hz), 0.5);

  // Calm steps over the walk: the calm pace (0.35 m/s) instead, the same slack; and a calm
  // range is no forbid (the walk is still slowed where it asks for nothing else).
  RepairOverride calm;
  calm.start_s = 0.0, calm.end_s = 100.0, calm.calm_steps = true;
  const RepairedMotion slow = repair(m, {calm});
  ASSERT_TRUE(has(slow, RepairKind::kTravel));
  const auto mid_slow = [&](int i) {
    const auto f = feet_of(slow.q[i]);
    return 0.5 * (f[0].centre.x() + f[1].centre.x());
  };
  // The rule itself: each touchdown within the calm pace × the time since that foot's last one
  // from its last foothold (1 cm: what the repair does not report as a move), and a touchdown
  // at most calm_step_forward_m ahead of the other foot.
  for (int f = 0; f < 2; ++f) {
    const auto down = [&](int i) { return f == 0 ? left_in_contact(slow.contacts[i]) : right_in_contact(slow.contacts[i]); };
    int last = -1;
    for (int i = 1; i < static_cast<int>(slow.q.size()); ++i) {
      if (!down(i) || down(i - 1)) continue;
      if (last >= 0) {
        const double step = (feet_of(slow.q[i])[f].centre - feet_of(slow.q[last])[f].centre).head<2>().norm();
        EXPECT_LE(step, cfg.calm_travel_speed_m_s * (i - last) / kRate_hz + 0.01) << "foot " << f << " frame " << i;
      }
      EXPECT_LE(feet_of(slow.q[i])[f].centre.x() - feet_of(slow.q[i])[1 - f].centre.x(), cfg.calm_step_forward_m + 1e-3);  // the leg IK: 0.1 mm
      last = i;
    }
  }
  // Slower than the normal pace over the walk (the window's edges add the same slack).
  const double calm_speed = (mid_slow(w1) - mid_slow(w0)) / ((w1 - w0) / kRate_hz);
  EXPECT_LT(calm_speed, speed - 0.05);
  RecordProperty("calm_walk_speed_m_s", number(calm_speed));
}

// A shoulder snap (0.5 rad in 50 ms, ~1200 rad/s² peaks): the RNEA oracle prices it beyond
// the joint's torque limit; the repair smooths the frames around it (listed as
// upper_body_speed) until the oracle's torque at that shoulder is within the limit, and
// leaves the rest of the motion as it was. `forbid upper` over the snap keeps it.
TEST(mocap_feasibility_repair, ArmSnapIsSmoothedWithinTheJointTorque) {
  const int n = 150, at = 75, len = 5;
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    const double s = std::clamp(double(i - at) / len, 0.0, 1.0);
    k.arms[0] = -0.5 * s * s * (3.0 - 2.0 * s);  // left shoulder pitch
    return k;
  });
  const int joint = 2 * model::kLegJoints;  // zarm_l1
  ASSERT_EQ(std::string(model::joint_name(robot(), joint)), "zarm_l1_joint");
  const double limit = robot().limits.torque_Nm[joint];
  const auto worst_torque = [&](const std::vector<ConfigVector>& q, const std::vector<ContactLabel>& labels) {
    DynamicsCheck c;
    check_dynamics(robot(), q, labels, kRate_hz, nullptr, 0.5, c);
    double worst = 0.0;
    for (int i = 1; i + 1 < static_cast<int>(q.size()); ++i) worst = std::max(worst, std::abs(c.tau_Nm[i][joint]));
    return worst;
  };
  ASSERT_GT(worst_torque(m.q, m.labels), limit) << "the precondition: the snap is beyond the shoulder";
  const RepairedMotion r = repair(m);
  expect_dancable(r, n);
  SCOPED_TRACE(listing(r));
  ASSERT_TRUE(has(r, RepairKind::kUpperBodySpeed));
  for (const Repair& x : r.repairs) {
    if (x.kind != RepairKind::kUpperBodySpeed) continue;
    // Around the snap only (the output clock has the lead-in before the dance).
    EXPECT_GE(x.start_s, (r.lead_frames + at - 25) / kRate_hz);
    EXPECT_LE(x.end_s, (r.lead_frames + at + len + 25) / kRate_hz);
  }
  const double after = worst_torque(r.q, r.contacts);
  EXPECT_LE(after, limit);
  RecordProperty("shoulder_torque_Nm_before", number(worst_torque(m.q, m.labels)));
  RecordProperty("shoulder_torque_Nm_after", number(after));
  // Away from the snap the arm is the human's.
  for (int d = 0; d < at - 30; ++d) EXPECT_NEAR(r.q[r.lead_frames + d][7 + joint], m.q[d][7 + joint], 1e-12) << d;
  // Forbidden: the snap stays.
  std::vector<RepairOverride> o;
  std::string error;
  ASSERT_TRUE(parse_repair_overrides("0.0 1.5 forbid upper\n", o, error)) << error;
  const RepairedMotion kept = repair(m, o);
  EXPECT_FALSE(has(kept, RepairKind::kUpperBodySpeed));
  for (int d = 0; d < n; ++d) EXPECT_NEAR(kept.q[kept.lead_frames + d][7 + joint], m.q[d][7 + joint], 1e-12) << d;
}

// ---- overrides applied ----

TEST(mocap_feasibility_repair, ForbiddenFlightStaysInTheSchedule) {
  const int n = 150, a = 50, b = 70;
  const Motion m = hop_motion(n, a, b);
  std::vector<RepairOverride> o;
  std::string error;
  ASSERT_TRUE(parse_repair_overrides("0.45 0.75 forbid flight\n", o, error)) << error;
  const RepairedMotion r = repair(m, o);
  expect_dancable(r, n, {}, /*allow_flight=*/true);
  SCOPED_TRACE(listing(r));
  EXPECT_FALSE(has(r, RepairKind::kFlight));
  for (int d = 0; d < n; ++d) {
    EXPECT_EQ(r.contacts[r.lead_frames + d], (d >= a && d < b) ? ContactLabel::kFlight : ContactLabel::kDoubleSupport)
        << d;
  }
  // Another kind forbidden over the range leaves the flight repair alone.
  o.clear();
  ASSERT_TRUE(parse_repair_overrides("0.45 0.75 forbid stride\n", o, error)) << error;
  EXPECT_TRUE(has(repair(m, o), RepairKind::kFlight));
}

TEST(mocap_feasibility_repair, ForcedDoubleSupportHoldsBothFeetDown) {
  const int n = 200, a = 60, b = 110;
  const Foot l0 = standing().feet[0], l1 = moved(l0, 0.20);
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    k.left = i < a ? l0 : (i >= b ? l1 : swing(l0, l1, i, a, b, 0.05));
    k.left_down = i < a || i >= b;
    return k;
  });
  std::vector<RepairOverride> o;
  std::string error;
  ASSERT_TRUE(parse_repair_overrides("0.5 1.2 force double\n", o, error)) << error;
  const RepairedMotion r = repair(m, o);
  expect_dancable(r, n);
  SCOPED_TRACE(listing(r));
  const Repair* forced = first(r, RepairKind::kForcedDouble);
  ASSERT_NE(forced, nullptr);
  EXPECT_NEAR(forced->start_s, (r.lead_frames + 50) / kRate_hz, 1e-9);
  EXPECT_NEAR(forced->end_s, (r.lead_frames + 120) / kRate_hz, 1e-9);
  for (int d = 50; d < 120; ++d) EXPECT_EQ(r.contacts[r.lead_frames + d], ContactLabel::kDoubleSupport) << d;
  EXPECT_EQ(r.human_steps, 1);
  EXPECT_EQ(r.robot_steps, 0);
}

// A square hold: the human steps the left foot 0.20 m ahead, then the right foot 0.40 m (to
// 0.20 m ahead of the left), both turning 0.3 rad, leaning 0.08 m forward of its feet; the
// hold starts during the right foot's swing. With `force square` the right foot lands beside
// the left at the standing width and the left's heading, and the pelvis stands over the feet
// as in standing (the fixture's standing pose turned to the feet, independent of the repair);
// with `force double` the stagger and the lean stay. The left step, before the hold, is kept
// in both.
TEST(mocap_feasibility_repair, ForcedSquareHoldSetsTheFeetSideBySide) {
  const int n = 360;
  const Foot l0 = standing().feet[0], r0 = standing().feet[1];
  const Foot l1 = moved(l0, 0.20, 0.0, 0.3), r1 = moved(r0, 0.40, 0.0, 0.3);
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    k.left = i < 40 ? l0 : (i >= 80 ? l1 : swing(l0, l1, i, 40, 80, 0.05));
    k.right = i < 120 ? r0 : (i >= 160 ? r1 : swing(r0, r1, i, 120, 160, 0.05));
    k.left_down = i < 40 || i >= 80;
    k.right_down = i < 120 || i >= 160;
    if (i >= 160) k.base_shift = Vec3(0.08, 0.0, 0.0);
    return k;
  });
  const auto pelvis_from_mid = [](const ConfigVector& q) {
    const auto f = feet_of(q);
    return Eigen::Vector2d(q.head<2>() - 0.5 * (f[0].centre + f[1].centre).head<2>());
  };
  std::string error;
  for (const char* verb : {"square", "double"}) {
    SCOPED_TRACE(verb);
    std::vector<RepairOverride> o;
    ASSERT_TRUE(parse_repair_overrides(std::string("1.4 3.0 force ") + verb + "\n", o, error)) << error;
    const RepairedMotion r = repair(m, o);
    expect_dancable(r, n);
    SCOPED_TRACE(listing(r));
    const int held = r.lead_frames + 225;  // inside the hold (frames 140..300), both feet down from 150
    ASSERT_EQ(r.contacts[held], ContactLabel::kDoubleSupport);
    const bool square = verb == std::string("square");
    const Eigen::Vector2d feet = left_from_right(r.q[held]);
    const auto f = feet_of(r.q[held]);
    EXPECT_NEAR(feet_of(r.q[r.lead_frames + 100])[0].centre.x(), l1.centre.x(), 1e-6) << "the left step is kept";
    if (square) {
      EXPECT_NEAR(feet.x(), 0.0, 1e-6);
      EXPECT_NEAR(feet.y(), standing().feet[0].centre.y() - standing().feet[1].centre.y(), 1e-6);
      EXPECT_NEAR(f[0].yaw, f[1].yaw, 1e-6);
      const Eigen::Vector2d standing_offset = (rot_z(f[1].yaw) * standing().base_from_mid).head<2>();
      EXPECT_NEAR((pelvis_from_mid(r.q[held]) - standing_offset).norm(), 0.0, 1e-6);
      bool listed = false;
      for (const Repair& x : r.repairs) listed |= x.kind == RepairKind::kForcedDouble && x.reason.find("square hold") == 0;
      EXPECT_TRUE(listed);
      RecordProperty("pelvis_from_standing_m", number((pelvis_from_mid(r.q[held]) - standing_offset).norm()));
    } else {
      EXPECT_GT(-feet.x(), 0.1) << "the right foot lands ahead of the left (the human's 0.20 m, averaged)";
      EXPECT_GT((pelvis_from_mid(r.q[held]) - (rot_z(f[1].yaw) * standing().base_from_mid).head<2>()).norm(), 0.05)
          << "the lean stays";
    }
  }
}

}  // namespace
}  // namespace kuavo::mocap

namespace kuavo::mocap {
namespace {

using namespace kuavo::mocap::test;

// The oracle's second pass on its own: a shoulder swinging ±0.4 rad at 1 Hz; frames [200, 300)
// scaled to half about their 1-s moving average. Inside the range (away from its ramps) the
// swing's amplitude is half the original's (the moving average over one period is the
// swing's centre); beyond the ramps the frames are untouched; a range an override forbids is
// left alone and not listed.
TEST(mocap_feasibility_repair, AttenuationScalesGesturesInsideItsRangeOnly) {
  const int n = 500;
  const int joint = 7 + 2 * model::kLegJoints;  // left shoulder pitch in q
  std::vector<ConfigVector> q(n, standing().q);
  for (int i = 0; i < n; ++i) q[i][joint] += 0.4 * std::sin(2.0 * M_PI * i / kRate_hz);
  std::vector<ConfigVector> att = q;
  std::vector<Repair> log;
  ASSERT_TRUE(attenuate_gestures(att, kRate_hz, {{200, 300, 1.7, {}}}, 0.5, 0.5, 1.8, {}, log));
  ASSERT_EQ(log.size(), 1u);
  EXPECT_EQ(log[0].kind, RepairKind::kAttenuate);
  EXPECT_NEAR(log[0].start_s, 2.0 + 1.8, 1e-12);
  EXPECT_NEAR(log[0].end_s, 3.0 + 1.8, 1e-12);
  const double centre = standing().q[joint];
  double inside = 0.0, outside = 0.0;
  for (int i = 0; i < n; ++i) {
    if (i >= 200 && i < 300) inside = std::max(inside, std::abs(att[i][joint] - centre));
    if (i < 150 || i >= 350) outside = std::max(outside, (att[i] - q[i]).cwiseAbs().maxCoeff());
  }
  EXPECT_NEAR(inside, 0.2, 0.01);
  EXPECT_EQ(outside, 0.0);
  RecordProperty("inside_amplitude_rad", number(inside));

  std::vector<ConfigVector> kept = q;
  std::vector<Repair> none;
  RepairOverride o;
  o.start_s = 0.0, o.end_s = 10.0, o.forbid = RepairKind::kAttenuate;
  EXPECT_FALSE(attenuate_gestures(kept, kRate_hz, {{200, 300, 1.7, {}}}, 0.5, 0.5, 1.8, {o}, none));
  EXPECT_TRUE(none.empty());
  for (int i = 0; i < n; ++i) ASSERT_EQ(kept[i], q[i]);

  // The closed-loop check's range carries its own reason; gain 0 leaves the 1 s average.
  std::vector<ConfigVector> flat = q;
  std::vector<Repair> why_log;
  ASSERT_TRUE(attenuate_gestures(flat, kRate_hz, {{200, 300, 0.0, "it fell here"}}, 0.0, 0.5, 1.8, {}, why_log));
  ASSERT_EQ(why_log.size(), 1u);
  EXPECT_EQ(why_log[0].reason.rfind("it fell here: the gestures are scaled to 0 %", 0), 0u) << why_log[0].reason;
  double left = 0.0;
  for (int i = 200; i < 300; ++i) left = std::max(left, std::abs(flat[i][joint] - centre));
  // The 101-frame average of the 1 Hz sine at 100 Hz: a whole period (0) plus the one frame
  // half a period away, −sin/101: what is left is 0.4/101 at most.
  EXPECT_NEAR(left, 0.4 / 101.0, 1e-6);
}

// ---- stance lean (opt-in: RepairConfig::max_stance_lean_m) ----

// The CoM's fore-aft distance ahead of the segment between the two feet's standing centres of
// pressure (each foot's ankle plus the standing pose's own CoM-ahead-of-ankles), by the
// fixture's forward kinematics and CRBA: the test's own reading of what the repair measures.
double lean_of(const ConfigVector& q) {
  const auto ankles = [](const ConfigVector& x) {
    dynamics::forward_kinematics(robot(), scratch(), x);
    std::array<Vec3, 2> a;
    for (int f = 0; f < 2; ++f) a[f] = scratch().position_m[1 + f * model::kLegJoints + model::kAnklePitchInLeg];
    return a;
  };
  const auto st = ankles(standing().q);
  const double stand = com_of(standing().q).x() - 0.5 * (st[0].x() + st[1].x());  // standing faces +x
  const auto feet = feet_of(q);
  const auto a = ankles(q);
  Vec3 p[2];
  for (int f = 0; f < 2; ++f) p[f] = a[f] + stand * (rot_z(feet[f].yaw) * Vec3::UnitX()), p[f].z() = 0.0;
  Vec3 c = com_of(q);
  c.z() = 0.0;
  const Vec3 d = p[1] - p[0];
  const double t = std::clamp((c - p[0]).dot(d) / d.squaredNorm(), 0.0, 1.0);
  const double yaw = std::atan2(std::sin(feet[0].yaw) + std::sin(feet[1].yaw), std::cos(feet[0].yaw) + std::cos(feet[1].yaw));
  return (rot_z(yaw) * Vec3::UnitX()).dot(c - (p[0] + t * d));
}

// Standing side by side, the pelvis moves 4 cm ahead of its standing place (the CoM ~3.8 cm)
// for 2 s: with the lean on (max 5 cm, band 1 cm), the repair moves the pelvis back until the
// CoM stands the band ahead of the standing pose's (the pelvis-to-CoM ratio measured on the
// standing pose), checked by the fixture's CRBA and kinematics in the middle of the hold; off
// (the default) and with `forbid lean`, the frames keep the human's lean. Only the pelvis's
// place changes: its orientation and the arms are the human's, the feet stay on their
// footholds (expect_dancable).
TEST(mocap_feasibility_repair, HeldForwardLeanMovesThePelvisBackOverTheAnkles) {
  const int n = 300, a = 50, b = 250, ramp = 30;
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    const double s = std::min({1.0, std::max(0.0, double(i - a) / ramp), std::max(0.0, double(b - i) / ramp)});
    k.base_shift.x() = 0.04 * s * s * (3.0 - 2.0 * s);
    k.arms[3] = -0.5;  // left elbow bent: the arms must stay the human's
    return k;
  });
  RepairConfig on;
  on.max_stance_lean_m = 0.05;
  const RepairedMotion off = repair(m);
  const RepairedMotion r = repair(m, {}, on);
  std::vector<RepairOverride> forbid;
  std::string error;
  ASSERT_TRUE(parse_repair_overrides("0 3 forbid lean\n", forbid, error)) << error;
  const RepairedMotion kept = repair(m, forbid, on);
  expect_dancable(r, n, on);
  SCOPED_TRACE(listing(r));
  EXPECT_FALSE(has(off, RepairKind::kStanceLean));
  EXPECT_FALSE(has(kept, RepairKind::kStanceLean));
  const Repair* lean = first(r, RepairKind::kStanceLean);
  ASSERT_NE(lean, nullptr);
  const int lead = r.lead_frames, mid = lead + (a + b) / 2;
  EXPECT_LE(lean->start_s, (lead + a + ramp) / kRate_hz);
  EXPECT_GE(lean->end_s, (lead + b - ramp) / kRate_hz);
  const double before = lean_of(off.q[mid]), after = lean_of(r.q[mid]);
  EXPECT_GT(before, 0.035) << "precondition: the held lean";
  EXPECT_NEAR(lean_of(kept.q[mid]), before, 1e-9);
  EXPECT_NEAR(after, on.stance_lean_band_m, 1e-3);
  RecordProperty("lean_before_m", number(before));
  RecordProperty("lean_after_m", number(after));
  for (int i = 0; i < static_cast<int>(r.q.size()); ++i) {
    ASSERT_LT((r.q[i].segment<4>(3) - off.q[i].segment<4>(3)).cwiseAbs().maxCoeff(), 1e-12) << i;
    ASSERT_LT((r.q[i].tail<16>() - off.q[i].tail<16>()).cwiseAbs().maxCoeff(), 1e-12) << i;
    ASSERT_LT(std::abs(r.q[i][2] - off.q[i][2]), 1e-12) << i;  // the height too
  }
}

// What is not a lean: the pelvis swaying 4 cm ahead and back at 1 Hz (faster than the 1 s
// average), and a weight shift towards one foot along the line between the feet, before and
// after a 0.2 m step (on the staggered feet the CoM is then 5 cm ahead of the feet's midpoint,
// on the segment between the two standing centres of pressure). With the lean on, neither is repaired and
// the frames are those of the lean off, bit for bit.
TEST(mocap_feasibility_repair, SwayAndWeightShiftAreNotLeans) {
  RepairConfig on;
  on.max_stance_lean_m = 0.05;
  const int n = 300;
  const Motion sway = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    k.base_shift.x() = 0.04 * std::sin(2.0 * M_PI * i / kRate_hz);
    return k;
  });
  const Foot l0 = standing().feet[0], l1 = moved(l0, 0.20);
  const Motion step = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    k.left = i < 60 ? l0 : (i >= 110 ? l1 : swing(l0, l1, i, 60, 110, 0.05));
    k.left_down = i < 60 || i >= 110;
    // The weight a quarter of the way from the feet's midpoint to the left foot, along the line
    // between them (standing: 4.5 cm to the left; on the staggered feet: diagonally ahead).
    k.base_shift = 0.25 * (k.left.centre - k.right.centre);
    k.base_shift.z() = 0.0;
    return k;
  });
  for (const Motion* m : {&sway, &step}) {
    const RepairedMotion r = repair(*m, {}, on), off = repair(*m);
    SCOPED_TRACE(listing(r));
    expect_dancable(r, n, on);
    EXPECT_FALSE(has(r, RepairKind::kStanceLean));
    ASSERT_EQ(r.q.size(), off.q.size());
    for (std::size_t i = 0; i < r.q.size(); ++i) ASSERT_EQ(r.q[i], off.q[i]) << i;
  }
  // The staggered stance's CoM: near the segment, well ahead of the feet's midpoint (which a
  // lean read from the midpoint would move back).
  const RepairedMotion r = repair(step, {}, on);
  const ConfigVector& staggered = r.q[r.lead_frames + 200];
  EXPECT_LT(std::abs(lean_of(staggered)), 0.25 * on.stance_lean_band_m);
  const auto f = feet_of(staggered);
  EXPECT_GT(com_of(staggered).x() - 0.5 * (f[0].centre.x() + f[1].centre.x()), 0.04);
  RecordProperty("staggered_lean_m", number(lean_of(staggered)));
}

// A pelvis leaning 0.27 rad (15°, within the tilt bound) to the right while it shifts 9 cm to
// the left over its feet, in double support: at the middle of the lean the legs cannot lay
// the left foot flat on its foothold at that pelvis pose (hip roll and ankle roll at their
// ranges' ends). The repair moves the pelvis towards standing over its feet there
// (stance_reach: level, their heading, the standing pose's place) until the legs reach; checked by forward kinematics on the output (every stance corner on
// its foothold, as expect_dancable does for every motion), against the same motion with the
// repair forbidden (`forbid reach`), whose left foot stays centimetres off. The pelvis turns
// towards level only, on every frame that needed it; frames far from the repair keep their
// orientation; no step between frames.
TEST(mocap_feasibility_repair, StanceFootOutOfReachMovesThePelvisToStanding) {
  const int n = 200, a = 60, b = 140;
  std::vector<ConfigVector> q;
  std::vector<ContactLabel> labels(n, ContactLabel::kDoubleSupport);
  ConfigVector guess = standing().q;
  for (int i = 0; i < n; ++i) {
    Keyframe k = stand_key();
    k.base_shift.z() = -0.03;
    if (i > a && i < b) {
      const double s = std::sin(M_PI * (i - a) / (b - a));
      k.base_lean = Vec3(0.27 * s, 0.0, 0.0);
      k.base_shift.y() = 0.09 * s;
    }
    guess = frame_of(k, guess);  // the human's own legs do not matter: the repair re-solves them
    q.push_back(guess);
  }
  const auto solve = [&](const std::vector<RepairOverride>& overrides) {
    RepairedMotion r;
    std::string error;
    EXPECT_TRUE(repair_motion(robot(), q, labels, kRate_hz, {}, overrides, r, error)) << error;
    return r;
  };
  std::vector<RepairOverride> forbid;
  std::string error;
  ASSERT_TRUE(parse_repair_overrides("0 100 forbid reach\n", forbid, error)) << error;
  const RepairedMotion kept = solve(forbid);
  const RepairedMotion r = solve({});
  SCOPED_TRACE(listing(r));
  // The stance corners' largest distance from the floor, by forward kinematics.
  const auto off_floor = [](const ConfigVector& x) {
    double e = 0.0;
    for (const Vec3& c : corners_of(x)) e = std::max(e, std::abs(c.z()));
    return e;
  };
  double kept_worst = 0.0;
  int first_off = -1, last_off = -1;
  for (int i = 0; i < static_cast<int>(kept.q.size()); ++i) {
    const double e = off_floor(kept.q[i]);
    kept_worst = std::max(kept_worst, e);
    if (e > 2e-3) {
      if (first_off < 0) first_off = i;
      last_off = i;
    }
  }
  EXPECT_FALSE(has(kept, RepairKind::kStanceReach));
  ASSERT_GT(kept_worst, 0.02) << "precondition: without the repair a stance foot is out of reach";

  expect_dancable(r, n, {}, false, 2e-3);
  const Repair* reach = first(r, RepairKind::kStanceReach);
  ASSERT_NE(reach, nullptr);
  EXPECT_LE(reach->start_s, first_off / kRate_hz + 1e-9);
  EXPECT_GE(reach->end_s, (last_off + 1) / kRate_hz - 1e-9);
  const auto rot_of = [](const ConfigVector& x) { return Eigen::Quaterniond(x[6], x[3], x[4], x[5]).normalized(); };
  const auto tilt_of = [&](const ConfigVector& x) { return std::acos(std::clamp(rot_of(x).toRotationMatrix()(2, 2), -1.0, 1.0)); };
  double least_turn = 10.0, step_out = 0.0, step_in = 0.0, far_change = 0.0;
  for (int i = 0; i < static_cast<int>(r.q.size()); ++i) {
    EXPECT_LE(tilt_of(r.q[i]), tilt_of(kept.q[i]) + 1e-9) << "frame " << i << " turned away from level";
    const double turn = rot_of(r.q[i]).angularDistance(rot_of(kept.q[i]));
    if (i >= first_off && i <= last_off) least_turn = std::min(least_turn, turn);
    if (i + 1 < static_cast<int>(r.q.size())) {
      step_out = std::max(step_out, rot_of(r.q[i]).angularDistance(rot_of(r.q[i + 1])));
      step_in = std::max(step_in, rot_of(kept.q[i]).angularDistance(rot_of(kept.q[i + 1])));
    }
    // Far from the repair's range (beyond its ±0.25 s spread): the pelvis as it was.
    const double t = i / kRate_hz;
    if (t < reach->start_s - 0.3 || t > reach->end_s + 0.3) far_change = std::max(far_change, turn);
  }
  EXPECT_GT(least_turn, 0.01) << "every frame out of reach was turned";
  EXPECT_LT(far_change, 1e-12);
  // The lean itself turns by up to 0.011 rad a frame; the repair's turn, spread over ±0.25 s,
  // adds less than that.
  EXPECT_LT(step_out, 2.0 * step_in);
  RecordProperty("off_floor_without_m", number(kept_worst));
  RecordProperty("turn_step_rad", number(step_out));
  RecordProperty("lean_step_rad", number(step_in));
}

}  // namespace
}  // namespace kuavo::mocap
