// `kuavo retarget` end to end: the report keys the issue lists, the motion file it writes,
// and the exit code and message for a broken input. Skipped when the CLI is not built.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tools/mocap/bvh.h"
#include "tools/mocap/motion_file.h"

namespace kuavo::mocap {
namespace {

const std::string kBin = std::string(KUAVO_BINARY_DIR) + "/kuavo";
const std::string kOut = std::string(KUAVO_BINARY_DIR) + "/mocap_cli_test";

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Runs `kuavo retarget ARGS`; stderr goes to <kOut><tag>.stderr (tests may run in parallel).
int run(const std::string& args, const std::string& tag) {
  const std::string redirect = " >" + kOut + tag + ".stdout 2>" + kOut + tag + ".stderr";
  const int status = std::system((kBin + " retarget " + args + redirect).c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(mocap_cli, DefaultDanceReportAndMotionFile) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  ASSERT_EQ(run("--stage geometric -o " + kOut + ".motion --variant s42 --report " + kOut + ".json", "_dance"), 0)
      << slurp(kOut + "_dance.stderr");
  const auto report = nlohmann::json::parse(slurp(kOut + ".json"));
  for (const char* key : {"frames", "duration_s", "keypoint_pos_err_m", "foot_slide_m_per_s_max", "penetration_m_max",
                          "joint_limit_violations", "velocity_limit_violations", "contact_phases", "frames_per_s"})
    EXPECT_TRUE(report.contains(key)) << key;
  EXPECT_TRUE(report["keypoint_pos_err_m"].contains("mean"));
  EXPECT_TRUE(report["keypoint_pos_err_m"].contains("max"));
  EXPECT_EQ(report["frames"].get<int>(), 3001);
  EXPECT_EQ(report["joint_limit_violations"].get<int>(), 0);
  EXPECT_EQ(report["velocity_limit_violations"].get<int>(), 0);
  EXPECT_LT(report["foot_slide_m_per_s_max"].get<double>(), 0.01);
  EXPECT_LE(report["penetration_m_max"].get<double>(), 0.005);

  model::Model s42, s45;
  model::build_model(model::Variant::kS42, model::kDefaultTotalMass_kg, s42);
  model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, s45);
  MotionHeader h;
  std::vector<dynamics::ConfigVector> q;
  std::vector<ContactLabel> labels;
  std::string error;
  ASSERT_TRUE(load_motion_file(kOut + ".motion", s42, h, q, labels, error)) << error;
  EXPECT_EQ(q.size(), 3001u);
  EXPECT_EQ(h.rate_hz, 100.0);
  EXPECT_FALSE(load_motion_file(kOut + ".motion", s45, h, q, labels, error));  // made for s42
}

// The default (dynamic) stage on the built-in dance: the report's "dynamic" object with the keys,
// the geometric and dynamic results side by side, the repairs with their ranges, and the
// dynamic CSV. The invariants asserted are the TO's constraints as the independent oracle
// (dynamics_check, RNEA) sees them: the base wrench the TO's forces leave unexplained is a
// fraction of the weight on average, and every window converged.
TEST(mocap_cli, DynamicStageReportAndCsv) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  ASSERT_EQ(run("--figures none -o " + kOut + "_dyn.motion --report " + kOut + "_dyn.json --dynamic-csv " + kOut +
                    "_dyn.csv",
                "_dyn"),
            0)
      << slurp(kOut + "_dyn.stderr");
  const auto report = nlohmann::json::parse(slurp(kOut + "_dyn.json"));
  ASSERT_TRUE(report.contains("dynamic"));
  const auto& d = report["dynamic"];
  // The built-in dance dances in the closed-loop check on both grounds with each of the three
  // noise seeds, in MuJoCo, in the firmware loop on both grounds, and on carpet with the show
  // set's model errors of seeds 1001–1024: no round of repair.
  ASSERT_TRUE(d.contains("verification"));
  EXPECT_EQ(d["verification"]["rounds"], 0);
  ASSERT_EQ(d["verification"]["runs"].size(), 33u);
  EXPECT_EQ(d["verification"]["runs"][0]["engine"], "simbody");
  EXPECT_EQ(d["verification"]["runs"][1]["ground"], "carpet");
  EXPECT_EQ(d["verification"]["runs"][5]["seed"], 3);
  EXPECT_EQ(d["verification"]["runs"][6]["engine"], "mujoco");
  for (const int i : {7, 8}) {
    EXPECT_EQ(d["verification"]["runs"][i]["engine"], "firmware");
    EXPECT_EQ(d["verification"]["runs"][i]["ground"], i == 7 ? "floor" : "carpet");
    EXPECT_EQ(d["verification"]["runs"][i]["seed"], 1);
    EXPECT_FALSE(d["verification"]["runs"][i]["fell"].get<bool>());
  }
  for (int i = 9; i < 33; ++i) {
    EXPECT_EQ(d["verification"]["runs"][i]["perturbation"], "show");
    EXPECT_EQ(d["verification"]["runs"][i]["ground"], "carpet");
    EXPECT_EQ(d["verification"]["runs"][i]["seed"], 1001 + (i - 9));
    EXPECT_FALSE(d["verification"]["runs"][i]["fell"].get<bool>());
  }
  EXPECT_TRUE(d["verification"]["danced"].get<bool>()) << d["verification"].dump();
  for (const char* key : {"solve_s", "frames", "windows", "sqp_iterations", "torque_violations", "friction_violations",
                          "zmp_outside_m_max", "max_torque_ratio", "repairs", "geometric", "dynamic"})
    EXPECT_TRUE(d.contains(key)) << key;
  EXPECT_TRUE(d["sqp_iterations"].contains("mean"));
  EXPECT_LE(d["sqp_iterations"]["max"].get<int>(), 200);
  EXPECT_EQ(d["windows_at_iteration_cap"].get<int>(), 0);
  EXPECT_TRUE(d["unsound"].empty()) << d["unsound"].dump();
  for (const char* side : {"geometric", "dynamic"}) {
    const auto& e = d[side]["expressiveness"];
    for (const char* group : {"hands", "feet", "pelvis"}) {
      EXPECT_TRUE(e["keypoint_error_m"][group].contains("mean")) << side << ' ' << group;
    }
    EXPECT_GT(e["com_path_m"].get<double>(), 1.0) << side;  // the dance moves
  }
  // Lead-in first, every repair with a range inside the motion and a reason.
  const auto& repairs = d["repairs"];
  ASSERT_FALSE(repairs.empty());
  EXPECT_EQ(repairs[0]["kind"].get<std::string>(), "lead_in");
  const double duration = d["frames"].get<int>() / 100.0;
  for (const auto& r : repairs) {
    EXPECT_LE(r["start_s"].get<double>(), r["end_s"].get<double>());
    EXPECT_LE(r["end_s"].get<double>(), duration + 0.011);  // within one frame
    EXPECT_FALSE(r["reason"].get<std::string>().empty());
  }
  // The CoM path each stage keeps: the whole motion's as the expressiveness figures have it,
  // and per repair over its range (the lead-in's precedes the clip: no geometric path there).
  const auto& path = d["com_path_m"];
  EXPECT_DOUBLE_EQ(path["geometric"].get<double>(), d["geometric"]["expressiveness"]["com_path_m"].get<double>());
  EXPECT_DOUBLE_EQ(path["dynamic"].get<double>(), d["dynamic"]["expressiveness"]["com_path_m"].get<double>());
  EXPECT_DOUBLE_EQ(path["kept"].get<double>(), path["dynamic"].get<double>() / path["geometric"].get<double>());
  EXPECT_GT(path["reference"].get<double>(), 1.0);
  for (const auto& r : repairs) {
    for (const char* stage : {"geometric", "reference", "dynamic"}) {
      EXPECT_GE(r["com_path_m"][stage].get<double>(), 0.0) << r.dump();
      EXPECT_LE(r["com_path_m"][stage].get<double>(), path[stage].get<double>() + 1e-9) << r.dump();
    }
  }
  EXPECT_EQ(repairs[0]["com_path_m"]["geometric"].get<double>(), 0.0);
  EXPECT_GT(repairs[0]["com_path_m"]["dynamic"].get<double>(), 0.0);  // the blend into the first pose moves
  // The built-in dance's steps survive (the repair may merge, not drop, most of them).
  EXPECT_GE(d["steps"]["robot"].get<int>(), 0.8 * d["steps"]["human"].get<int>());
  // The motion written loads: the loader refuses joints outside the limits, and the dynamic
  // stage reports what it put back within them (the built-in dance: ~0.0075 rad, an arm).
  {
    model::Model s45;
    model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, s45);
    MotionHeader h;
    std::vector<dynamics::ConfigVector> q;
    std::vector<ContactLabel> labels;
    std::string error;
    EXPECT_TRUE(load_motion_file(kOut + "_dyn.motion", s45, h, q, labels, error)) << error;
    ASSERT_TRUE(d.contains("clamped_to_joint_limits"));
    EXPECT_LT(d["clamped_to_joint_limits"]["max_rad"].get<double>(), 0.05);
  }
  // The forces are solved for the final frames (mocap/contact_forces.h): the oracle's base
  // residual is left only where no forces inside the pyramids supply the frames' wrench
  // (mean 1.1 N for the built-in dance; the TO's own forces left 27 N), and no corner leaves
  // its pyramid.
  EXPECT_LT(d["dynamic"]["base_residual"]["force_N_mean"].get<double>(), 10.0);
  EXPECT_EQ(d["friction_violations"].get<int>(), 0);
  for (const char* key : {"frames_over_limit", "frames_base_wrench_out_of_cones", "max_excess_Nm"})
    EXPECT_TRUE(d["forces"].contains(key)) << key;
  // CSV: one row per frame, q + momentum + 24 forces + 28 torques + contact.
  std::ifstream csv(kOut + "_dyn.csv");
  std::string header, line;
  ASSERT_TRUE(std::getline(csv, header));
  EXPECT_NE(header.find("tau_"), std::string::npos);
  EXPECT_NE(header.find("L_x"), std::string::npos);
  int rows = 0;
  while (std::getline(csv, line)) ++rows;
  EXPECT_EQ(rows, d["frames"].get<int>());
  // The dynamic-only options are refused with the geometric stage.
  EXPECT_EQ(run("--stage geometric -o " + kOut + "_x.motion --report " + kOut + "_x.json --horizon 0.8", "_geo_horizon"),
            2);
  EXPECT_NE(slurp(kOut + "_geo_horizon.stderr").find("kuavo retarget: --horizon does not apply to --stage geometric"), std::string::npos);
  EXPECT_EQ(run("--stage dynamic -o " + kOut + "_x.motion --report " + kOut + "_x.json --horizon 2", "_bad_horizon"), 2);
  EXPECT_NE(slurp(kOut + "_bad_horizon.stderr").find("[0.2, 1.4]"), std::string::npos);
}

// --duration: the built-in dance in whole 30 s cycles (default_dance_test.cpp checks the
// cycles themselves); the BVH written with --dance-bvh says how long it is.
TEST(mocap_cli, BuiltInDanceTakesADuration) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  ASSERT_EQ(run("--duration 90 --dance-bvh " + kOut + "_90.bvh", "_d90"), 0) << slurp(kOut + "_d90.stderr");
  Bvh bvh;
  std::string error;
  ASSERT_TRUE(load_bvh_file(kOut + "_90.bvh", bvh, error)) << error;
  EXPECT_EQ(bvh.frame_count, 3 * 1500 + 1);  // 90 s at 50 fps, both ends
  EXPECT_EQ(run("--duration 45 -o " + kOut + "_d45.motion", "_d45"), 2);
  EXPECT_NE(slurp(kOut + "_d45.stderr").find("--duration 45 s: the built-in dance repeats its 30 s cycle"),
            std::string::npos)
      << slurp(kOut + "_d45.stderr");
  EXPECT_EQ(run("--duration 330 -o " + kOut + "_d330.motion", "_d330"), 2);
  EXPECT_NE(slurp(kOut + "_d330.stderr").find("--duration"), std::string::npos) << slurp(kOut + "_d330.stderr");
  const std::string clip = std::string(KUAVO_SHARED_DIR) + "/mocap/cmu_05_20_mb.bvh";
  EXPECT_EQ(run(clip + " --duration 60 -o " + kOut + "_dclip.motion", "_dclip"), 2);
  EXPECT_NE(slurp(kOut + "_dclip.stderr").find("does not apply with INPUT.bvh"), std::string::npos)
      << slurp(kOut + "_dclip.stderr");
}

// A window too short for a real dance: at 0.4 s the receding-horizon optimization cannot see
// cmu_05_20's single supports to their ends and stalls (retarget_dynamic.h). The oracle is the
// independent dynamics check of the frames written (dynamics_check.h): the motion leaves its
// support by metres and needs many times a joint's torque limit, and `kuavo retarget` says so
// in a warning (and in the report's "unsound" if the frames are loadable at all) -- while the
// default window's result of the same clip (mocap_cli.ClosedLoopCheckRepairsWhereTheRobotFalls)
// and of the built-in dance (mocap_cli.DynamicStageReportAndCsv) have none.
TEST(mocap_cli, AWindowTooShortForTheDanceIsReportedUnsound) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  const std::string clip = std::string(KUAVO_SHARED_DIR) + "/mocap/cmu_05_20_mb.bvh";
  const int code = run(clip + " --horizon 0.4 --verify 0 --figures none -o " + kOut + "_h04.motion --report " + kOut +
                           "_h04.json",
                       "_h04");
  const std::string err = slurp(kOut + "_h04.stderr");
  EXPECT_NE(err.find("warning: the dynamic optimization did not converge on this dance with 0.40 s windows"),
            std::string::npos)
      << err;
  // The oracle's figures as the warning gives them: metres outside the support, many times a limit.
  const std::size_t at = err.find("centre of pressure leaves the support by up to ");
  ASSERT_NE(at, std::string::npos) << err;
  EXPECT_GT(std::atof(err.c_str() + at + std::strlen("centre of pressure leaves the support by up to ")), 0.1) << err;
  const std::size_t ratio = err.find("a joint needs ");
  ASSERT_NE(ratio, std::string::npos) << err;
  EXPECT_GT(std::atof(err.c_str() + ratio + std::strlen("a joint needs ")), 20.0) << err;
  if (code == 0) {  // written: the report says it too
    const auto d = nlohmann::json::parse(slurp(kOut + "_h04.json"))["dynamic"];
    EXPECT_GE(d["unsound"].size(), 2u) << d["unsound"].dump();
  } else {  // or its frames are not even ones the robot loads (frame 242's base when this was written)
    EXPECT_EQ(code, 2) << err;
    EXPECT_NE(err.find("not one the robot can load"), std::string::npos) << err;
  }
}

// The closed-loop check: cmu_05_20 as retargeted falls in `kuavo simulate` (at 72f410c on the
// floor, seed 2, at 7.8 s: round 0's third run; before the early touchdown its first); with one
// round the report lists the fall, the range of gestures scaled for it ([fall − 2 s, fall + 0.3 s],
// the output clock) and the run after the repair. The in-process check must be what
// `kuavo simulate` does: the last run's outcome is compared with `kuavo simulate` of the
// written file on the same ground and seed, in its own process (bit-deterministic: equal).
TEST(mocap_cli, ClosedLoopCheckRepairsWhereTheRobotFalls) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  const std::string clip = std::string(KUAVO_SHARED_DIR) + "/mocap/cmu_05_20_mb.bvh";
  // On a stage that sinks 1.5 cm (--verify-carpet-sink): each carpet run's estimator is told so,
  // the floor's is not (the runs echo what their own summaries say).
  ASSERT_EQ(run(clip + " --verify 1 --verify-carpet-sink 0.015 --figures none -o " + kOut + "_ver.motion --report " +
                    kOut + "_ver.json",
                "_ver"),
            0)
      << slurp(kOut + "_ver.stderr");
  const auto report = nlohmann::json::parse(slurp(kOut + "_ver.json"));
  EXPECT_TRUE(report["dynamic"]["unsound"].empty()) << report["dynamic"]["unsound"].dump();  // the default window
  const auto& v = report["dynamic"]["verification"];
  ASSERT_GE(v["runs"].size(), 2u) << v.dump();
  EXPECT_EQ(v["runs"][0]["ground"], "floor");  // the grounds in order: floor first
  // Round 0 stops at its first fall (the order is checked below): its last run.
  std::size_t round0 = 0;
  while (round0 < v["runs"].size() && v["runs"][round0]["round"] == 0) ++round0;
  ASSERT_GE(round0, 1u) << v.dump();
  const auto& first = v["runs"][round0 - 1];
  ASSERT_TRUE(first["fell"].get<bool>()) << "cmu_05_20 no longer falls unrepaired: pick a clip that does";
  EXPECT_EQ(v["rounds"], 1);
  const double fall = first["fell_at_s"].get<double>();
  // The motion written is the best round's: more grounds danced, then the later fall.
  const int kept = v["kept_round"].get<int>();
  std::vector<nlohmann::json> runs[2];
  for (const auto& r : v["runs"]) runs[r["round"].get<int>()].push_back(r);
  const auto score = [&](int round) {
    int passed = 0;
    double reached = 1e9;
    for (const auto& r : runs[round]) {
      if (r["fell"].get<bool>()) {
        reached = r["fell_at_s"].get<double>();
      } else {
        ++passed;
      }
    }
    return std::make_pair(passed, reached);
  };
  EXPECT_EQ(kept, score(1) > score(0) ? 1 : 0) << v.dump();
  // Each round dances floor and carpet with noise seeds 1, 2, 3 in turn, then MuJoCo's floor,
  // then the firmware loop's floor and carpet (seed 1), then carpet with the show set's model
  // errors (seeds 1001, 1002, ...), and stops at its first fall.
  const std::vector<std::pair<std::string, std::uint64_t>> order = {{"floor", 1}, {"carpet", 1}, {"floor", 2},
                                                                    {"carpet", 2}, {"floor", 3}, {"carpet", 3}};
  EXPECT_EQ(v["carpet_sink_m"].get<double>(), 0.015) << v.dump();
  for (const auto& round : runs) {
    std::uint64_t show_seed = 1001;
    for (std::size_t i = 0; i < round.size(); ++i) {
      if (i + 1 < round.size()) {
        EXPECT_FALSE(round[i]["fell"].get<bool>()) << v.dump();
      }
      if (round[i]["ground"] == "carpet") {
        ASSERT_TRUE(round[i].contains("surface_sink_m")) << round[i].dump();
        EXPECT_EQ(round[i]["surface_sink_m"].get<double>(), 0.015) << round[i].dump();
      } else {
        EXPECT_FALSE(round[i].contains("surface_sink_m")) << round[i].dump();
      }
      if (round[i].contains("perturbation")) {
        EXPECT_EQ(round[i]["perturbation"], "show") << v.dump();
        EXPECT_EQ(round[i]["engine"], "simbody") << v.dump();
        EXPECT_EQ(round[i]["ground"], "carpet") << v.dump();
        EXPECT_EQ(round[i]["seed"].get<std::uint64_t>(), show_seed++) << v.dump();
        EXPECT_GT(i, order.size() + 2) << "after the nominal, MuJoCo and firmware runs: " << v.dump();
        continue;
      }
      EXPECT_EQ(show_seed, 1001u) << "a nominal run after a model-error run: " << v.dump();
      if (round[i]["engine"] == "mujoco") {
        EXPECT_EQ(i, order.size()) << v.dump();
        continue;
      }
      if (round[i]["engine"] == "firmware") {
        EXPECT_GT(i, order.size()) << v.dump();
        EXPECT_EQ(round[i]["ground"], i == order.size() + 1 ? "floor" : "carpet") << v.dump();
        EXPECT_EQ(round[i]["seed"].get<std::uint64_t>(), 1u) << v.dump();
        continue;
      }
      ASSERT_LT(i, order.size()) << v.dump();
      EXPECT_EQ(round[i]["ground"], order[i].first) << v.dump();
      EXPECT_EQ(round[i]["seed"].get<std::uint64_t>(), order[i].second) << v.dump();
    }
  }
  // Round 0's fall asked for the repair; it is listed if its round was kept.
  int listed = 0;
  for (const auto& r : report["dynamic"]["repairs"]) {
    if (r["kind"] != "attenuate") continue;
    ++listed;
    EXPECT_NEAR(r["start_s"].get<double>(), fall - 2.0, 0.011) << r.dump();
    EXPECT_NEAR(r["end_s"].get<double>(), fall + 0.3, 0.011) << r.dump();
    char at[32];
    std::snprintf(at, sizeof at, "at %.2f s", fall);
    EXPECT_NE(r["reason"].get<std::string>().find(at), std::string::npos) << r.dump();
    EXPECT_NE(r["reason"].get<std::string>().find("scaled to 50 %"), std::string::npos) << r.dump();
  }
  EXPECT_EQ(listed, kept) << report["dynamic"]["repairs"].dump();
  // The kept round's last run is replayed on the written file in its own process: by
  // `kuavo simulate`, or by kuavo_fw_sim for a firmware-loop run (whose clock starts on the
  // gantry: the check reports the fall or fault on the motion's clock), with the check's
  // recovery-step trigger (the report's "holdable_soles": true by default, as online).
  ASSERT_TRUE(v.contains("holdable_soles")) << v.dump();
  EXPECT_TRUE(v["holdable_soles"].get<bool>()) << "the check dances with the online default's trigger";
  ASSERT_TRUE(v.contains("recovery_fast_swing_s")) << v.dump();
  EXPECT_EQ(v["recovery_fast_swing_s"].get<double>(), 0.0) << "the fast swing is off by default, as online";
  const auto& last = runs[kept].back();
  EXPECT_EQ(v["danced"].get<bool>(), kept == 1 && !last["fell"].get<bool>());
  const bool fw = last["engine"] == "firmware";
  std::string push;  // a model-error run's push (--verify-show-push), replayed with its exact force
  if (last.contains("push")) {
    const auto& p = last["push"];
    char arg[160];
    std::snprintf(arg, sizeof arg, " --push %.17g:%.17g,%.17g,%.17g:%.17g", p["start_s"].get<double>(),
                  p["force_N"][0].get<double>(), p["force_N"][1].get<double>(), p["force_N"][2].get<double>(),
                  p["duration_s"].get<double>());
    push = arg;
  }
  const std::string where = " --ground " + last["ground"].get<std::string>() + " --seed " +
                            std::to_string(last["seed"].get<std::uint64_t>()) +
                            (last.contains("perturbation") ? " --perturb show" : "") + push +
                            // the check's trigger when it ran on the soles (--verify-holdable-soles off)
                            (v["holdable_soles"].get<bool>() ? "" : " --holdable-soles off") +
                            // and its fast swing when it had one (--verify-recovery-fast-swing S)
                            (v["recovery_fast_swing_s"].get<double>() > 0.0
                                 ? " --recovery-fast-swing " + std::to_string(v["recovery_fast_swing_s"].get<double>())
                                 : "") +
                            // and the carpet's sink when it ran on carpet (--verify-carpet-sink M)
                            (last.contains("surface_sink_m")
                                 ? " --surface-sink " + std::to_string(last["surface_sink_m"].get<double>())
                                 : "") +
                            " --summary " + kOut +
                            "_ver_sim.json >" + kOut + "_ver_sim.stdout 2>&1";
  const std::string sim = fw ? std::string(KUAVO_BINARY_DIR) + "/firmware/sitl/kuavo_fw_sim --dance " + kOut + "_ver.motion" + where
                             : kBin + " simulate " + kOut + "_ver.motion --quiet --engine " + last["engine"].get<std::string>() + where;
  ASSERT_EQ(std::system(sim.c_str()) == 0, fw ? !last["fell"].get<bool>() : true) << slurp(kOut + "_ver_sim.stdout");
  const auto summary = nlohmann::json::parse(slurp(kOut + "_ver_sim.json"));
  if (fw) {
    EXPECT_EQ(summary["danced_to_end"].get<bool>(), !last["fell"].get<bool>());
  } else {
    EXPECT_EQ(summary["fell"].get<bool>(), last["fell"].get<bool>());
  }
  if (last["fell"].get<bool>()) {
    double at = summary["fell_at_s"].get<double>();
    if (fw) {
      const double fault = summary["fault_at_s"].get<double>();
      if (!summary["fell"].get<bool>() || (fault >= 0.0 && fault < at)) at = fault;
      at -= summary["dance_started_at_s"].get<double>();
    }
    EXPECT_NEAR(at, last["fell_at_s"].get<double>(), fw ? 2e-3 : 1e-9);
  }
  // Still falling: the user is told where.
  if (!v["danced"].get<bool>()) {
    EXPECT_NE(slurp(kOut + "_ver.stderr").find("still falls in the closed-loop simulation"), std::string::npos);
  }
  // --verify 0: no check, and the report says so.
  ASSERT_EQ(run(clip + " --verify 0 --figures none -o " + kOut + "_nover.motion --report " + kOut + "_nover.json",
                "_nover"),
            0);
  const auto off = nlohmann::json::parse(slurp(kOut + "_nover.json"))["dynamic"]["verification"];
  EXPECT_TRUE(off["runs"].empty());
  EXPECT_TRUE(off["danced"].is_null());
  EXPECT_EQ(off["carpet_sink_m"].get<double>(), 0.0) << "a hard floor by default, as kuavo simulate";
}

// Side inputs must be regular files (a directory read as empty text and was accepted), and the
// outputs are checked writable before the run.
TEST(mocap_cli, DirectoriesAndUnwritableOutputsAreRefusedUpFront) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  const std::string dir = KUAVO_BINARY_DIR;
  std::filesystem::remove(kOut + "_d.motion");
  EXPECT_EQ(run("--stage geometric --map " + dir + " -o " + kOut + "_d.motion", "_map_dir"), 2);
  EXPECT_NE(slurp(kOut + "_map_dir.stderr").find("--map " + dir + ": not a regular file"), std::string::npos)
      << slurp(kOut + "_map_dir.stderr");
  EXPECT_EQ(run("--stage geometric --contacts " + dir + " -o " + kOut + "_d.motion", "_contacts_dir"), 2);
  EXPECT_NE(slurp(kOut + "_contacts_dir.stderr").find("--contacts " + dir + ": not a regular file"), std::string::npos)
      << slurp(kOut + "_contacts_dir.stderr");
  EXPECT_EQ(run("--stage geometric -o " + kOut + "_d.motion --report " + kOut + "_no_dir/r.json", "_report_dir"), 2);
  EXPECT_NE(slurp(kOut + "_report_dir.stderr").find("_no_dir/r.json: cannot write"), std::string::npos)
      << slurp(kOut + "_report_dir.stderr");
  EXPECT_FALSE(std::filesystem::exists(kOut + "_d.motion"));  // refused before anything was written
}

TEST(mocap_cli, BrokenInputExitsTwoWithLineAndProblem) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  const std::string bvh = kOut + "_broken.bvh";
  std::ofstream(bvh) << "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Xrotation Yrotation Zrotation\n}\n"
                        "MOTION\nFrames: 2\nFrame Time: 0.01\n0 0 0\n";
  EXPECT_EQ(run(bvh + " -o " + kOut + "_broken.motion", "_broken"), 2);
  const std::string message = slurp(kOut + "_broken.stderr");
  EXPECT_NE(message.find("line 11: "), std::string::npos) << message;
  EXPECT_NE(message.find("file ends after 1 of 2 motion rows"), std::string::npos) << message;
  EXPECT_EQ(run("-o", "_broken"), 2);  // usage
  EXPECT_EQ(run("--variant s44 -o x.motion", "_broken"), 2);
}

// Issue 22: values no human motion reaches exit 2 with the line and the rule, before any output
// is written (Frame Time 10 s made a 374 MB file; a root channel of 1e300 an all-NaN motion).
// Legal BVH values whose retargeted motion no loader accepts: refused with exit 2 and nothing
// written (before: exit 0 and a file every other command refused). From the shared clip
// cmu_05_20_mb: 600 rows at the slowest legal Frame Time (150 s > the 120 s a motion holds),
// and the hips lifted 200 units from row 500 on (the base above 2 m).
TEST(mocap_cli, MotionsTheLoadersRefuseAreNotWritten) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  std::ifstream in(std::string(KUAVO_SHARED_DIR) + "/mocap/cmu_05_20_mb.bvh");
  std::string line, hierarchy;
  std::vector<std::string> rows;
  bool motion = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line == "MOTION") motion = true;
    if (!motion) hierarchy += line + "\n";
    else if (line.rfind("Frame", 0) != 0 && line != "MOTION" && !line.empty()) rows.push_back(line);
  }
  ASSERT_GE(rows.size(), 600u);
  struct Case {
    const char* tag;
    std::string motion;
    const char* expect;
  };
  // slow: 1300 frames of 0.25 s (the BVH bound) = 324.75 s, past the plan's 310 s.
  std::string slow = "MOTION\nFrames: 1300\nFrame Time: 0.25\n", lifted = "MOTION\nFrames: 600\nFrame Time: 0.0083333\n";
  for (std::size_t k = 0; k < 1300; ++k) slow += rows[k % 600] + "\n";
  for (std::size_t k = 0; k < 600; ++k) {
    std::istringstream values(rows[k]);
    double x, y;
    values >> x >> y;
    std::string rest;
    std::getline(values, rest);
    lifted += std::to_string(x) + " " + std::to_string(k >= 500 ? y + 200.0 : y) + rest + "\n";
  }
  const Case cases[] = {
      {"_long", slow, "32476 frames at 100 Hz, more than the 31000 a robot motion holds"},
      {"_lifted", lifted, "not one the robot can load: frame"},
  };
  for (const Case& c : cases) {
    const std::string bvh = kOut + c.tag + ".bvh", out = kOut + c.tag + ".motion";
    std::ofstream(bvh, std::ios::binary) << hierarchy + c.motion;
    std::filesystem::remove(out);
    EXPECT_EQ(run("--stage geometric " + bvh + " -o " + out, c.tag), 2) << c.tag;
    const std::string message = slurp(kOut + c.tag + ".stderr");
    EXPECT_NE(message.find(c.expect), std::string::npos) << message;
    EXPECT_FALSE(std::filesystem::exists(out)) << c.tag;
  }
}

TEST(mocap_cli, AbsurdValuesExitTwoWithLineAndRule) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  const std::string head =
      "\xEF\xBB\xBFHIERARCHY\rROOT Hips\r{\r  OFFSET 0 0 0\r  CHANNELS 6 Xposition Yposition Zposition "
      "Zrotation Xrotation Yrotation\r  End Site\r  {\r    OFFSET 0 -10 0\r  }\r}\rMOTION\rFrames: 2\r";
  struct Case {
    const char* tag;
    std::string tail;
    const char* expect;
  };
  const Case cases[] = {
      {"_dt", "Frame Time: 10\r0 90 0 0 0 0\r0 90 0 0 0 0\r", "line 13: Frame Time: '10' s is above 0.25 s"},
      {"_huge", "Frame Time: 0.01\r0 90 0 0 0 0\r1e300 90 0 0 0 0\r",
       "line 15: motion row 1, 'Hips' Xposition '1e300' exceeds"},
  };
  for (const Case& c : cases) {
    const std::string bvh = kOut + c.tag + ".bvh", motion = kOut + c.tag + ".motion";
    std::ofstream(bvh, std::ios::binary) << head + c.tail;
    std::filesystem::remove(motion);
    EXPECT_EQ(run(bvh + " -o " + motion, c.tag), 2);
    const std::string message = slurp(kOut + c.tag + ".stderr");
    EXPECT_NE(message.find(c.expect), std::string::npos) << message;
    EXPECT_FALSE(std::filesystem::exists(motion));
  }
}

}  // namespace
}  // namespace kuavo::mocap
