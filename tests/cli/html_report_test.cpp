// The HTML report's data (tools/cli/html_report.h) from a synthetic simulator log whose values
// are known: the replay's frame rate, the holds that keep single-tick extremes (the margin's
// minimum, the torque ratio's maximum) visible at 25 Hz, the fall and repair marks, and the
// page's files. The page itself is tested in Chromium (tests/report/html_report_test.py).
#include "tools/cli/html_report.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tools/report/base64.h"

namespace kuavo::cli {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The JSON a data file assigns: "KUAVO.x = {...};" or "KUAVO.runs[\"n\"] = {...};".
nlohmann::json assigned(const fs::path& p) {
  const std::string s = slurp(p);
  const auto from = s.find(" = ") + 3, to = s.rfind(';');
  return nlohmann::json::parse(s.substr(from, to - from));
}

constexpr double kTick_s = 0.002;
constexpr int kTicks = 500;           // 1 s of log
constexpr int kDipTick = 251;         // t = 0.504 s: between the 25 Hz frames at 0.48 and 0.52 s
constexpr double kDipMargin_m = -0.05;
constexpr int kSpikeJoint = 3;        // left knee: twice its peak torque for one tick
constexpr int kSpikeTick = 263;       // t = 0.528 s

class HtmlReportData : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, robot_), model::ModelError::kOk);
    // One folder per test: ctest runs the tests of this file in parallel processes.
    dir_ = fs::temp_directory_path() /
           (std::string("kuavo_html_report_") + ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" +
            std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::ofstream log(dir_ / "run.csv");
    log << "time_s,base_x_m,base_y_m,base_z_m,base_qx,base_qy,base_qz,base_qw";
    for (int j = 0; j < model::kNumJoints; ++j) log << ",q_" << model::joint_name(robot_, j);
    for (int j = 0; j < model::kNumJoints; ++j) log << ",tau_" << model::joint_name(robot_, j);
    for (int c = 0; c < model::kNumContactPoints; ++c) {
      for (const char* a : {"x", "y", "z"}) log << ",f_" << model::frame_name(robot_, c) << "_" << a;
    }
    log << ",zmp_margin_m\n";
    for (int i = 1; i <= kTicks; ++i) {
      const double t = i * kTick_s;
      log << t << "," << 0.1 * t << ",0,0.8,0,0,0,1";
      for (int j = 0; j < model::kNumJoints; ++j) log << "," << (j == kSpikeJoint ? t : 0.0);
      for (int j = 0; j < model::kNumJoints; ++j) {
        const double peak = robot_.limits.peak_torque_Nm[j];
        log << "," << (j == kSpikeJoint && i == kSpikeTick ? 2.0 * peak : 0.25 * peak);
      }
      for (int c = 0; c < model::kNumContactPoints; ++c) log << ",0,0,67.5";
      log << "," << (i == kDipTick ? kDipMargin_m : 0.03) << "\n";
    }
  }
  void TearDown() override { fs::remove_all(dir_); }

  model::Model robot_;
  fs::path dir_;
};

TEST_F(HtmlReportData, ReplayAt25HzKeepsSingleTickExtremesAndMarksTheFall) {
  HtmlReport report;
  report.title = "test";
  report.repairs = {{0.2, 0.4, "repair", "retime: a test"}};
  report.runs = {{"pushed", "a test run", (dir_ / "run.csv").string(), true, 0.9, true, {{0.5, 0.6, "push", "push"}}}};
  std::string error;
  ASSERT_TRUE(write_html_report(robot_, report, (dir_ / "out").string(), error)) << error;

  const auto page = assigned(dir_ / "out/data/report.js");
  ASSERT_EQ(page["runs"].size(), 1u);
  const auto& meta = page["runs"][0];
  std::vector<std::string> kinds;
  for (const auto& m : meta["marks"]) kinds.push_back(m["kind"]);
  EXPECT_EQ(kinds, (std::vector<std::string>{"repair", "push", "fall"}));
  EXPECT_DOUBLE_EQ(meta["marks"][2]["start_s"].get<double>(), 0.9);
  EXPECT_FALSE(meta["human"].get<bool>());  // no skeleton given

  const auto run = assigned(dir_ / "out" / meta["file"].get<std::string>());
  const auto& layout = run["layout"];
  const int size = layout["size"], frames = run["frames"];
  EXPECT_EQ(frames, 26);  // 0.002 s, then 0.04, 0.08, .. 1.00 s: one frame per 40 ms
  std::vector<unsigned char> bytes;
  ASSERT_TRUE(report::base64_decode(run["data"].get<std::string>(), bytes));
  ASSERT_EQ(bytes.size(), sizeof(float) * size * frames);
  std::vector<float> f(bytes.size() / sizeof(float));
  std::memcpy(f.data(), bytes.data(), bytes.size());
  auto at = [&](int frame, const char* channel, int k = 0) { return f[frame * size + layout[channel].get<int>() + k]; };
  for (int k = 0; k < frames; ++k) {
    const double t = at(k, "time");
    EXPECT_NEAR(t, std::max(kTick_s, 0.04 * k), 1e-6) << k;
    EXPECT_NEAR(at(k, "base", 0), 0.1 * t, 1e-6);
    EXPECT_NEAR(at(k, "q", kSpikeJoint), t, 1e-6);
    EXPECT_TRUE(std::isnan(at(k, "qref", 0)));  // not in this log
    // The frame at 0.52 s stands for the ticks after 0.48 s up to it: the dip (0.504 s) is its
    // margin; the spike (0.528 s) belongs to the next frame.
    EXPECT_NEAR(at(k, "margin"), k == 13 ? kDipMargin_m : 0.03, 1e-6) << k;
    EXPECT_NEAR(at(k, "tau_ratio"), k == 14 ? 2.0 : 0.25, 1e-6) << k;
  }
  EXPECT_NEAR(meta["tau_ratio_max"].get<double>(), 2.0, 1e-9);
}

TEST_F(HtmlReportData, WritesThePageTheModelAndEveryMeshItNames) {
  HtmlReport report;
  report.runs = {{"r", "", (dir_ / "run.csv").string(), false, -1.0, false, {}}};
  std::string error;
  ASSERT_TRUE(write_html_report(robot_, report, (dir_ / "out").string(), error)) << error;
  for (const char* f : {"index.html", "app.js", "style.css", "vendor/three.LICENSE"}) EXPECT_TRUE(fs::exists(dir_ / "out" / f)) << f;
  const std::string three = slurp(dir_ / "out/vendor/three.js");
  EXPECT_EQ(three.rfind("(function(){\"use strict\";", 0), 0u);
  EXPECT_NE(three.find("window.THREE={"), std::string::npos);
  EXPECT_NE(three.find("WebGLRenderer:"), std::string::npos);
  EXPECT_EQ(three.find("export{"), std::string::npos);

  const auto model = assigned(dir_ / "out/data/model.js");
  const auto meshes = assigned(dir_ / "out/data/meshes.js");
  ASSERT_EQ(model["bodies"].size(), static_cast<std::size_t>(model::kNumBodies));
  int visuals = 0;
  for (const auto& b : model["bodies"]) {
    if (b["visual"].is_null()) continue;
    ++visuals;
    EXPECT_TRUE(meshes.contains(b["visual"]["mesh"].get<std::string>())) << b["name"];
  }
  EXPECT_EQ(visuals, model::kNumBodies);  // Leju's URDF gives every body of the model a mesh
  // The check pose's body positions are the model's FK (the page compares its own against them).
  EXPECT_EQ(model["fk_check"]["body_positions_m"].size(), static_cast<std::size_t>(model::kNumBodies));
  EXPECT_NEAR(model["fk_check"]["body_positions_m"][0][2].get<double>(), 0.9, 1e-12);  // the base
  EXPECT_LE(model["mesh_triangles"]["shown"].get<int>(), static_cast<int>(kMeshTriangles * meshes.size()));
}

}  // namespace
}  // namespace kuavo::cli
