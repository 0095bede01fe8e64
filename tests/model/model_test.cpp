// The built model against the published fact sheet (shared/robot/FACTS.md),
// typed in here by hand as the independent record.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>

#include "controllers/dynamics/rigid_body.h"

namespace kuavo::test {
namespace {

using model::Model;

TEST(Model, TorsoIsRescaledToTheWeighedMass) {
  Model m;
  ASSERT_EQ(model::build_model(model::Variant::kS45, 55.0, m), model::ModelError::kOk);
  // FACTS §3.2: s45 non-torso mass 29.60 kg, URDF total 51.715 kg.
  EXPECT_NEAR(m.tables->urdf_total_mass_kg, 51.715, 1e-3);
  EXPECT_NEAR(m.bodies[0].mass_kg, 55.0 - 29.60, 0.01);
  double sum = 0;
  for (const auto& b : m.bodies) sum += b.mass_kg;
  EXPECT_NEAR(sum, 55.0, 1e-12);
  // Torso CoM and inertia unchanged by the rescale (Leju's update_mass.sh).
  EXPECT_NEAR(m.bodies[0].com_m.z(), 0.1929569, 1e-12);
  EXPECT_NEAR(m.bodies[0].inertia_com_kgm2(0, 0), 0.93103133, 1e-12);

  Model heavy;
  ASSERT_EQ(model::build_model(model::Variant::kS45, 58.2, heavy), model::ModelError::kOk);
  EXPECT_NEAR(heavy.bodies[0].mass_kg - m.bodies[0].mass_kg, 3.2, 1e-12);
  EXPECT_EQ(model::build_model(model::Variant::kS45, 20.0, heavy), model::ModelError::kMassTooSmall);
  EXPECT_EQ(model::build_model(model::Variant::kS45, std::nan(""), heavy), model::ModelError::kMassNotFinite);
}

TEST(Model, S42IsPublishedAt55KgAndHasShortArms) {
  Model m42, m45;
  ASSERT_EQ(model::build_model(model::Variant::kS42, 55.0, m42), model::ModelError::kOk);
  ASSERT_EQ(model::build_model(model::Variant::kS45, 55.0, m45), model::ModelError::kOk);
  EXPECT_NEAR(m42.tables->urdf_total_mass_kg, 55.000, 1e-3);
  EXPECT_NEAR(m42.bodies[0].mass_kg, 26.308, 1e-3);  // nothing to rescale
  // Upper arm (elbow joint below the shoulder): 0.2837 m long arm, 0.1646 m short arm (FACTS §2.2/2.3).
  const int l_elbow_body = 1 + model::kLeftArmFirst + 3;
  EXPECT_NEAR(-m45.bodies[l_elbow_body].joint_position_m.z(), 0.2837, 1e-6);
  EXPECT_NEAR(-m42.bodies[l_elbow_body].joint_position_m.z(), 0.1646, 1e-6);
  // Wrist joints 6/7 swap axes between the variants.
  const int l_wrist6 = 1 + model::kLeftArmFirst + 5;
  EXPECT_TRUE(m45.bodies[l_wrist6].axis.isApprox(Eigen::Vector3d::UnitX()));
  EXPECT_TRUE(m42.bodies[l_wrist6].axis.isApprox(Eigen::Vector3d::UnitY()));
}

TEST(Model, JointOrderAndLimitsFollowTheFactSheet) {
  Model m;
  ASSERT_EQ(model::build_model(model::Variant::kS45, 55.0, m), model::ModelError::kOk);
  EXPECT_STREQ(model::joint_name(m, 0), "leg_l1_joint");
  EXPECT_STREQ(model::joint_name(m, 11), "leg_r6_joint");
  EXPECT_STREQ(model::joint_name(m, 12), "zarm_l1_joint");
  EXPECT_STREQ(model::joint_name(m, 26), "zhead_1_joint");
  EXPECT_STREQ(model::joint_name(m, 27), "zhead_2_joint");
  const auto& l = m.limits;
  // Knee: URDF 0..145°, WBC 130 Nm, peak 135 Nm, 6.5 / 11.62 rad/s (FACTS §2.2, §2.5).
  EXPECT_NEAR(l.position_min_rad[3], 0.0, 1e-9);
  EXPECT_NEAR(l.position_max_rad[3], 2.5307, 1e-4);
  EXPECT_DOUBLE_EQ(l.torque_Nm[3], 130.0);
  EXPECT_DOUBLE_EQ(l.peak_torque_Nm[3], 135.0);
  EXPECT_DOUBLE_EQ(l.velocity_rad_s[3], 6.5);
  EXPECT_DOUBLE_EQ(l.peak_velocity_rad_s[3], 11.62);
  // Hip yaw: WBC 20 Nm, but the drive trips at 22.2.
  EXPECT_DOUBLE_EQ(l.torque_Nm[1], 20.0);
  // Wrist yaw: the WBC's 60 Nm exceeds the 14.1 Nm trip, so plan within 14.1;
  // kuavo.json's continuous 10 rad/s exceeds its 7 rad/s peak, so plan within 7.
  EXPECT_DOUBLE_EQ(l.torque_Nm[16], 14.1);
  EXPECT_DOUBLE_EQ(l.velocity_rad_s[16], 7.0);
  // Ankle pitch and roll, both legs: the joint box is Leju's WBC limit, 60 Nm (FACTS §2.5);
  // the two 27 Nm motors behind the linkage bound them jointly (drivers/transmission).
  for (const int j : {4, 5, 10, 11}) {
    EXPECT_DOUBLE_EQ(l.torque_Nm[j], 60.0) << j;
    EXPECT_DOUBLE_EQ(l.peak_torque_Nm[j], 60.0) << j;
  }
  // Head: kuavo.json protection is off; URDF effort and velocity are used.
  EXPECT_DOUBLE_EQ(l.torque_Nm[26], 1.5);
  EXPECT_DOUBLE_EQ(l.torque_Nm[27], 12.0);
  EXPECT_NEAR(l.velocity_rad_s[27], 5.2333, 1e-3);
  for (int j = 0; j < model::kNumJoints; ++j) {
    EXPECT_LT(l.position_min_rad[j], l.position_max_rad[j]) << j;
    EXPECT_LE(l.torque_Nm[j], l.peak_torque_Nm[j]) << j;
    EXPECT_LE(l.velocity_rad_s[j], l.peak_velocity_rad_s[j]) << j;
  }
}

TEST(Model, ZeroPoseGeometryMatchesTheFactSheet) {
  static Model m;
  static dynamics::Data d;
  ASSERT_EQ(model::build_model(model::Variant::kS45, 55.0, m), model::ModelError::kOk);
  dynamics::ConfigVector q = dynamics::ConfigVector::Zero();
  q[6] = 1.0;
  dynamics::forward_kinematics(m, d, q);
  // Contact points: toe +0.171 / heel -0.073 from the ankle, ±0.0477, 0.8842 m below the base (FACTS §2.2).
  for (int f = 0; f < model::kNumContactPoints; ++f) {
    const Eigen::Vector3d p = dynamics::frame_position(m, d, f);
    EXPECT_NEAR(p.z(), -0.8842, 1e-4) << model::frame_name(m, f);
  }
  const Eigen::Vector3d toe = dynamics::frame_position(m, d, 0), heel = dynamics::frame_position(m, d, 2);
  EXPECT_NEAR(toe.x() - heel.x(), 0.244, 1e-3);
  EXPECT_NEAR(dynamics::frame_position(m, d, 0).y() - dynamics::frame_position(m, d, 1).y(), 0.0955, 1e-4);
  // The neutral configuration puts the soles on the ground.
  dynamics::forward_kinematics(m, d, dynamics::neutral_configuration(m));
  for (int f = 0; f < model::kNumContactPoints; ++f) EXPECT_NEAR(dynamics::frame_position(m, d, f).z(), 0.0, 1e-4);
}

// The planners' narrower soles (model::inset_sole_corners) against the fact sheet's corners
// (FACTS.md §2.2, typed in: toe x +0.17084, heel x −0.073164, y ±0.04773, z −0.0595 on each
// ankle roll link): each corner d closer to the sole's centre in x and y, z and the other
// frames untouched; an inset beyond the half-width ends on the centre line.
TEST(Model, InsetSoleCornersMovesEachCornerInByTheInset) {
  Model m;
  ASSERT_EQ(model::build_model(model::Variant::kS45, 55.0, m), model::ModelError::kOk);
  const double toe = 0.17084, heel = -0.073164, side = 0.04773, z = -0.0595;
  const double centre_x = 0.5 * (toe + heel);
  for (const double d : {0.0, 0.01, 0.025}) {
    Model inset = m;
    model::inset_sole_corners(inset, d);
    for (int c = 0; c < model::kNumContactPoints; ++c) {
      const Eigen::Vector3d& p = inset.frames[c].position_m;
      const Eigen::Vector3d& o = m.frames[c].position_m;
      ASSERT_NEAR(std::abs(o.x() - centre_x), 0.5 * (toe - heel), 1e-9) << "corner " << c;  // the fact sheet's sole
      ASSERT_NEAR(std::abs(o.y()), side, 1e-9) << "corner " << c;
      EXPECT_NEAR(p.x(), centre_x + (o.x() > centre_x ? 1.0 : -1.0) * (0.5 * (toe - heel) - d), 1e-12) << c << " " << d;
      EXPECT_NEAR(p.y(), (o.y() > 0.0 ? 1.0 : -1.0) * (side - d), 1e-12) << c << " " << d;
      EXPECT_EQ(p.z(), o.z());
      EXPECT_NEAR(p.z(), z, 1e-9);
      EXPECT_EQ(inset.frames[c].body, m.frames[c].body);
    }
    for (int f = model::kNumContactPoints; f < model::kNumFrames; ++f) {
      EXPECT_EQ(inset.frames[f].position_m, m.frames[f].position_m) << "frame " << f;
    }
  }
  Model past = m;
  model::inset_sole_corners(past, 0.06);  // wider than the sole's half-width (0.0477)
  for (int c = 0; c < model::kNumContactPoints; ++c) EXPECT_NEAR(past.frames[c].position_m.y(), 0.0, 1e-12) << c;
}

TEST(ModelCli, JsonSummaryHasTheDocumentedShape) {
  const std::string cmd = std::string(KUAVO_BINARY_DIR) + "/kuavo model --variant s42 --mass 56 --json";
  FILE* pipe = ::popen(cmd.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string out;
  char buf[4096];
  while (size_t n = std::fread(buf, 1, sizeof buf, pipe)) out.append(buf, n);
  ASSERT_EQ(::pclose(pipe), 0) << out;
  const auto j = nlohmann::json::parse(out);
  EXPECT_EQ(j["variant"], "s42");
  EXPECT_EQ(j["dof"], 28);
  EXPECT_NEAR(j["total_mass_kg"].get<double>(), 56.0, 1e-9);
  ASSERT_EQ(j["com_zero_m"].size(), 3u);
  ASSERT_EQ(j["contact_points_zero_m"].size(), 8u);
  EXPECT_NEAR(j["contact_points_zero_m"][5][2].get<double>(), -0.8842, 1e-4);
  ASSERT_EQ(j["joint_names"].size(), 28u);
  EXPECT_EQ(j["joint_names"][18], "zarm_l7_joint");

  const std::string bad = std::string(KUAVO_BINARY_DIR) + "/kuavo model --variant s44 --json 2>/dev/null";
  FILE* p2 = ::popen(bad.c_str(), "r");
  ASSERT_NE(p2, nullptr);
  while (std::fread(buf, 1, sizeof buf, p2)) {
  }
  EXPECT_EQ(WEXITSTATUS(::pclose(p2)), 2);
}

}  // namespace
}  // namespace kuavo::test
