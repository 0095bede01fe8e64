// Contact schedule: detection on a synthetic stepping pattern, minimum phase duration,
// and the manual override file.
#include "tools/mocap/contacts.h"

#include <gtest/gtest.h>

namespace kuavo::mocap {
namespace {

struct Fixture {
  model::Model robot;
  HumanTargets t;
  Fixture() {
    model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, robot);
    t.rate_hz = 100.0;
    t.present.fill(true);
  }
  // Left foot steps forward during [0.5, 0.9) s; the right stays planted; a 40 ms blip of
  // the right foot (shorter than the minimum phase) must be merged away.
  void build() {
    const double ankle_h = robot_ankle_height_m(robot);
    for (int i = 0; i < 200; ++i) {
      const double time = i / 100.0;
      TargetFrame f;
      double lift = 0.0, fwd = 0.0;
      if (time >= 0.5 && time < 0.9) {
        const double u = (time - 0.5) / 0.4;
        lift = 0.08 * std::sin(M_PI * u);
        fwd = 0.3 * u;
      } else if (time >= 0.9) {
        fwd = 0.3;
      }
      f.position_m[kKpLeftAnkle] = Vec3(fwd, 0.1, ankle_h + lift);
      f.position_m[kKpLeftToe] = Vec3(fwd + 0.17, 0.1, lift);
      const double blip = (time >= 1.40 && time < 1.44) ? 0.06 : 0.0;
      f.position_m[kKpRightAnkle] = Vec3(0, -0.1, ankle_h + blip);
      f.position_m[kKpRightToe] = Vec3(0.17, -0.1, blip);
      t.frames.push_back(f);
    }
  }
};

TEST(mocap_contacts, DetectsStepsWithHysteresisAndMinimumDuration) {
  Fixture fx;
  fx.build();
  const auto labels = detect_contacts(fx.t, fx.robot);
  ASSERT_EQ(labels.size(), 200u);
  EXPECT_EQ(labels[10], ContactLabel::kDoubleSupport);
  EXPECT_EQ(labels[70], ContactLabel::kRightSupport);  // left foot in the air
  EXPECT_EQ(labels[150], ContactLabel::kDoubleSupport);
  EXPECT_EQ(labels[142], ContactLabel::kDoubleSupport);  // the 40 ms blip is merged
  EXPECT_EQ(count_contact_phases(labels), 3);
}

TEST(mocap_contacts, OverrideFileReplacesRanges) {
  Fixture fx;
  fx.build();
  auto labels = detect_contacts(fx.t, fx.robot);
  std::string error;
  ASSERT_TRUE(
      apply_contact_overrides("# manual fix\n0.0 0.2 flight\n1.0 1.5   left  # comment\n\n", 100.0, labels, error))
      << error;
  EXPECT_EQ(labels[0], ContactLabel::kFlight);
  EXPECT_EQ(labels[19], ContactLabel::kFlight);
  EXPECT_EQ(labels[20], ContactLabel::kDoubleSupport);
  EXPECT_EQ(labels[120], ContactLabel::kLeftSupport);
  EXPECT_EQ(labels[150], ContactLabel::kDoubleSupport);
}

TEST(mocap_contacts, OverrideErrorsNameTheLine) {
  std::vector<ContactLabel> labels(10, ContactLabel::kDoubleSupport);
  std::string error;
  EXPECT_FALSE(apply_contact_overrides("0 1 left\n1 0.5 right\n", 100.0, labels, error));
  EXPECT_NE(error.find("contacts line 2: times must be numbers with 0 <= start_s < end_s"), std::string::npos) << error;
  EXPECT_FALSE(apply_contact_overrides("0 1 hop\n", 100.0, labels, error));
  EXPECT_NE(error.find("contacts line 1: unknown label 'hop'"), std::string::npos) << error;
  EXPECT_FALSE(apply_contact_overrides("0 1\n", 100.0, labels, error));
  EXPECT_NE(error.find("contacts line 1: expected 'start_s end_s label'"), std::string::npos) << error;
}

}  // namespace
}  // namespace kuavo::mocap
