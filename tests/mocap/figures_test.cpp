// The paper's figures from the CLI: `kuavo retarget --stage dynamic` draws Fig. 4 and 5 next to
// its report and lists them there; `kuavo retarget-sweep` writes the horizon sweep (Fig. 6 and
// the solve-time benchmark). Three dynamic runs of the built-in dance in all (~7 s each).
// Whether the speeds grow with the horizon is the result the sweep reports, not asserted.
// Skipped when the CLI is not built.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace kuavo::mocap {
namespace {

namespace fs = std::filesystem;

const std::string kBin = std::string(KUAVO_BINARY_DIR) + "/kuavo";
const std::string kOut = std::string(KUAVO_BINARY_DIR) + "/mocap_figures_test";

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A fresh directory of its own per test (tests may run in parallel).
std::string fresh_dir(const std::string& name) {
  const std::string dir = kOut + "/" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Runs `kuavo ARGS` with stdout and stderr in DIR/run.stdout, DIR/run.stderr.
int run(const std::string& args, const std::string& dir) {
  const int status = std::system((kBin + " " + args + " >" + dir + "/run.stdout 2>" + dir + "/run.stderr").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// An SVG document with at least one drawn line.
void expect_svg_with_lines(const std::string& path) {
  ASSERT_TRUE(fs::exists(path)) << path;
  const std::string svg = slurp(path);
  EXPECT_TRUE(svg.rfind("<svg", 0) == 0 || svg.rfind("<?xml", 0) == 0) << path;
  EXPECT_NE(svg.find("</svg>"), std::string::npos) << path;
  EXPECT_TRUE(svg.find("<polyline") != std::string::npos || svg.find("<path") != std::string::npos) << path;
}

TEST(mocap_figures, DynamicStageDrawsFig4And5NextToTheReport) {
  if (!fs::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  const std::string dir = fresh_dir("dynamic");
  // --verify 0: the figures are drawn from the dynamic stage's result; the built-in dance
  // passes the closed-loop check at its round 0 (mocap_cli.DynamicStageReportAndCsv), so the
  // check would only cost this test its ~3 minutes.
  ASSERT_EQ(run("retarget --stage dynamic --verify 0 -o " + dir + "/out.motion --report " + dir + "/report.json", dir), 0)
      << slurp(dir + "/run.stderr");
  const auto report = nlohmann::json::parse(slurp(dir + "/report.json"));
  const auto& d = report["dynamic"];
  ASSERT_TRUE(d.contains("figures"));
  std::vector<std::string> files;
  for (const auto& f : d["figures"]) files.push_back(f.get<std::string>());
  EXPECT_EQ(files, (std::vector<std::string>{"fig4_knee.svg", "fig5_dynamics.svg"}));
  for (const std::string& f : files) expect_svg_with_lines(dir + "/" + f);
  // Both knees' panels, and Fig. 5's four.
  const std::string fig4 = slurp(dir + "/fig4_knee.svg"), fig5 = slurp(dir + "/fig5_dynamics.svg");
  EXPECT_NE(fig4.find("leg_l4_joint (knee)"), std::string::npos);
  EXPECT_NE(fig4.find("leg_r4_joint (knee)"), std::string::npos);
  for (const char* panel : {"Fig. 5a", "Fig. 5b", "Fig. 5c", "Fig. 5d"}) EXPECT_NE(fig5.find(panel), std::string::npos);
  // The numbers the figures print are in the report, finite, for both motions.
  const auto& numbers = d["figure_numbers"];
  for (const char* key : {"leg_l4_joint_torque_ratio_max", "leg_r4_joint_frames_over_torque_limit",
                          "leg_l3_joint_swing_speed_rad_s_mean", "zarm_l1_joint_speed_rad_s_max",
                          "left_foot_lateral_force_N_max", "zmp_outside_m_mean"}) {
    ASSERT_TRUE(numbers.contains(key)) << key;
    for (const char* side : {"geometric", "dynamic"}) {
      EXPECT_TRUE(std::isfinite(numbers[key][side].get<double>())) << key << ' ' << side;
      EXPECT_GE(numbers[key][side].get<double>(), 0.0) << key << ' ' << side;
    }
  }
  EXPECT_GT(numbers["leg_l4_joint_torque_ratio_max"]["dynamic"].get<double>(), 0.0);
  EXPECT_GT(numbers["zarm_l1_joint_speed_rad_s_max"]["geometric"].get<double>(), 0.0);
}

// Refused before any work: --figures with the geometric stage, and a directory that is not one.
TEST(mocap_figures, FiguresOptionChecks) {
  if (!fs::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  const std::string dir = fresh_dir("options");
  EXPECT_EQ(run("retarget --stage geometric -o " + dir + "/x.motion --report " + dir + "/x.json --figures " + dir, dir), 2);
  EXPECT_NE(slurp(dir + "/run.stderr").find("--figures does not apply to --stage geometric"), std::string::npos);
  EXPECT_EQ(run("retarget --stage dynamic -o " + dir + "/x.motion --figures " + dir + "/missing", dir), 2);
  EXPECT_NE(slurp(dir + "/run.stderr").find("not a directory"), std::string::npos);
  EXPECT_EQ(run("retarget-sweep --horizons 0.4,2 --out " + dir, dir), 2);
  EXPECT_NE(slurp(dir + "/run.stderr").find("[0.2, 1.4]"), std::string::npos);
  EXPECT_EQ(run("retarget-sweep", dir), 2);
}

TEST(mocap_figures, HorizonSweepJsonAndFig6) {
  if (!fs::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  const std::string dir = fresh_dir("sweep");
  ASSERT_EQ(run("retarget-sweep --horizons 1.0,0.4 --out " + dir, dir), 0) << slurp(dir + "/run.stderr");
  const auto sweep = nlohmann::json::parse(slurp(dir + "/sweep.json"));
  for (const char* key : {"swing_leg_speed_rad_s", "com_speed_m_s"})
    EXPECT_GT(sweep["geometric"][key].get<double>(), 0.0) << key;
  const auto& rows = sweep["horizons"];
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_DOUBLE_EQ(rows[0]["horizon_s"].get<double>(), 0.4);  // sorted for the plot
  EXPECT_DOUBLE_EQ(rows[1]["horizon_s"].get<double>(), 1.0);
  EXPECT_FALSE(rows[1].contains("error")) << rows[1]["error"];  // the default horizon solves
  ASSERT_TRUE(rows[1]["unsound"].is_array());
  EXPECT_TRUE(rows[1]["unsound"].empty()) << rows[1]["unsound"].dump();  // ... to a result it stands behind
  for (const auto& row : rows) {
    if (row.contains("error")) {  // a failed horizon keeps its message
      EXPECT_FALSE(row["error"].get<std::string>().empty());
      continue;
    }
    for (const char* key : {"solve_s", "solve_s_per_1e4_frames", "swing_leg_speed_rad_s", "com_speed_m_s"}) {
      const double v = row[key].get<double>();
      EXPECT_TRUE(std::isfinite(v) && v > 0.0) << key << " = " << v;
    }
    EXPECT_GT(row["windows"].get<int>(), 0);
    EXPECT_GE(row["sqp_iterations"]["mean"].get<double>(), 1.0);
    EXPECT_GE(row["sqp_iterations"]["max"].get<int>(), 1);
    for (const char* key : {"windows_at_iteration_cap", "torque_violations", "friction_violations"})
      EXPECT_GE(row[key].get<int>(), 0) << key;
  }
  expect_svg_with_lines(dir + "/fig6_horizon.svg");
}

}  // namespace
}  // namespace kuavo::mocap
