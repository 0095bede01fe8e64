// `kuavo simulate` against hostile input (issue 22): every case ends with exit 1 or 2 and one
// clear line, never an abort (exit 134) or an unbounded run.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/support/test_robot.h"
#include "tools/mocap/motion_file.h"

namespace kuavo::cli {
namespace {

const std::string kBin = std::string(KUAVO_BINARY_DIR) + "/kuavo";
const std::string kOut = std::string(KUAVO_BINARY_DIR) + "/simulate_cli_test";

struct CliRun {
  int exit_code = -1;
  std::string err;
};

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// `kuavo simulate ARGS` in a shell (`prefix` e.g. a ulimit), limited to 60 s of wall time so
// an unbounded run fails the test instead of hanging it (timeout's exit 124).
CliRun simulate(const std::string& args, const std::string& tag, const std::string& prefix = "") {
  const std::string err = kOut + tag + ".stderr";
  const std::string cmd = "sh -c '" + prefix + "timeout 60 " + kBin + " simulate " + args + " >/dev/null 2>" + err + "'";
  const int status = std::system(cmd.c_str());
  CliRun r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = read_text(err);
  return r;
}

// `kuavo simulate ARGS --summary PATH` that must succeed; the summary's text.
std::string summary_of(const std::string& args, const std::string& tag) {
  const std::string path = kOut + tag + ".json";
  const CliRun r = simulate(args + " --summary " + path, tag);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return read_text(path);
}

// A 2 s standing motion (valid: loads and runs).
std::string standing_motion() {
  model::Model robot;
  EXPECT_EQ(model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, robot), model::ModelError::kOk);
  const std::vector<dynamics::ConfigVector> q(201, test::standing_configuration());
  const std::vector<mocap::ContactLabel> labels(q.size(), mocap::ContactLabel::kDoubleSupport);
  const std::string path = kOut + "_stand.motion";
  std::string error;
  EXPECT_TRUE(mocap::write_motion_file(path, mocap::encode_motion(robot, 100.0, q, labels), error)) << error;
  return path;
}

// One motion path: `kuavo simulate` loads a motion file with the firmware's own loader
// (controllers/motion/load_motion.h), so a motion the robot refuses -- here one whose first
// frame has the soles 3 cm up (the robot dances from standing) -- is refused by both, with the
// same reason. kuavo simulate accepted it before the two shared the loader.
TEST(SimulateCli, RefusesWhatTheFirmwareRefuses) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  model::Model robot;
  ASSERT_EQ(model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, robot), model::ModelError::kOk);
  std::vector<dynamics::ConfigVector> q(201, test::standing_configuration());
  for (auto& f : q) f[2] += 0.03;
  const std::vector<mocap::ContactLabel> labels(q.size(), mocap::ContactLabel::kDoubleSupport);
  const std::string path = kOut + "_lifted.motion";
  std::string error;
  ASSERT_TRUE(mocap::write_motion_file(path, mocap::encode_motion(robot, 100.0, q, labels), error)) << error;
  const std::string reason = "the first frame does not stand";
  const CliRun sim = simulate(path + " --duration 1", "_lifted");
  EXPECT_EQ(sim.exit_code, 2) << sim.err;
  EXPECT_NE(sim.err.find(reason), std::string::npos) << sim.err;
  const std::string fw_err = kOut + "_lifted_fw.stderr";
  const int status = std::system((std::string(KUAVO_BINARY_DIR) + "/firmware/kuavo_fw --check --dance " + path +
                                  " >/dev/null 2>" + fw_err).c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 2);
  std::ifstream in(fw_err);
  std::ostringstream fw;
  fw << in.rdbuf();
  EXPECT_NE(fw.str().find(reason), std::string::npos) << fw.str();
  // The same file standing is accepted by both (the refusal is the first frame, nothing else).
  EXPECT_EQ(simulate(standing_motion() + " --duration 0.1", "_standing_ok").exit_code, 0);
}

TEST(SimulateCli, DirectoryAsMotionIsRefused) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  const CliRun r = simulate(std::string(KUAVO_BINARY_DIR) + " --duration 1", "_dir");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("not a regular file"), std::string::npos) << r.err;
}

TEST(SimulateCli, RunLengthIsBoundedUpFront) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  // 1e7 s made the run reserve its per-tick statistics and die of std::bad_alloc (exit 134);
  // --stand 1e9 ran without end.
  CliRun r = simulate(standing_motion() + " --duration 1e7", "_duration");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--duration needs SECONDS in (0, 600] s, got '1e7'"), std::string::npos) << r.err;
  r = simulate("--stand 1e9", "_stand");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--stand needs SECONDS in (0, 600] s, got '1e9'"), std::string::npos) << r.err;
}

// Whole-token numbers in range, no wrapping, options that do not apply refused, a missing
// value named, unwritable outputs reported before the run (each case ran, or wrapped, before).
TEST(SimulateCli, ArgumentsAreStrict) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  const std::string motion = standing_motion();
  const std::pair<std::string, std::string> cases[] = {
      {motion + " --duration 0.1 --latency-ticks 5abc", "--latency-ticks needs a whole number TICKS in 0..50 ticks of 2 ms, got '5abc'"},
      {"--step-in-place 5x --duration 0.1", "--step-in-place needs a whole number STEPS in 1..200 steps, got '5x'"},
      {"--stand 0.1 --seed -1", "--seed needs a whole number N in 0..2^64-1, got '-1'"},
      {"--stand 0.1 --seed 99999999999999999999999", "--seed needs a whole number N in 0..2^64-1"},
      {motion + " --duration 0.1 --rtol nan", "--rtol needs TOLERANCE in [1e-12, 0.1], got 'nan'"},
      {"--stand 0.1 --horizon -1", "--horizon needs SECONDS in [0.6, 1.4] s, got '-1'"},
      {"--stand 0.1 --horizon 1.2", "--horizon does not apply to a --stand run"},
      {motion + " --duration 0.1 --recovery-fast-swing 0.5", "--recovery-fast-swing needs SECONDS in [0.2, 0.4] s, got '0.5'"},
      {"--stand 0.1 --recovery-fast-swing 0.25", "--recovery-fast-swing does not apply to a --stand run"},
      {motion + " --duration 0.1 --surface-sink 0.06", "--surface-sink needs M in [0, 0.05] m, got '0.06'"},
      {motion + " --duration 0.1 --surface-sink nan", "--surface-sink needs M in [0, 0.05] m, got 'nan'"},
      {"--stand 0.1 --surface-sink 0.015", "--surface-sink does not apply to a --stand run"},
      {"--step-in-place 4 --stand 1", "give exactly one of --stand SECONDS, a MOTION file or --step-in-place STEPS"},
      {"--stand 0.1 --seed 1 --seed 2", "--seed given twice"},
      {"--stand 0.1 --push 1:10,0,0:inf", "--push must be T:FX,FY,FZ:DURATION"},
      {"--stand 0.1 --push 1:1e9,0,0:0.1", "--push must be T:FX,FY,FZ:DURATION"},
      {"--stand 0.1 --push ' 1:10,0,0:0.1'", "--push must be T:FX,FY,FZ:DURATION"},
      {"--stand 0.1 --log --summary", "--log needs a value (CSV), got option '--summary'"},
      // A directory as the perturbation file threw from its first read: "internal error", exit 1.
      {motion + " --duration 0.1 --perturb " + std::string(KUAVO_BINARY_DIR), "nor a readable file"},
      {"--stand 0.1 --seed", "--seed needs a value (N)"},
      {"--stand 0.1 --summary " + kOut + "_missing_dir/run.json", "_missing_dir/run.json: cannot write"},
      {"--stand 0.1 --log " + std::string(KUAVO_BINARY_DIR), ": is a directory"},
  };
  for (const auto& [args, message] : cases) {
    const CliRun r = simulate(args, "_args");
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << args << "\n" << r.err;
  }
  // The largest seed is still one.
  EXPECT_EQ(simulate("--stand 0.05 --seed 18446744073709551615", "_seed_max").exit_code, 0);
}

// --recovery-fast-swing reaches the run: its summary names the fast swing and counts the steps
// that took it; a run without it says nothing of it.
TEST(SimulateCli, RecoveryFastSwingIsEchoedWhenOn) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  const std::string run = standing_motion() + " --duration 0.2";
  EXPECT_NE(summary_of(run + " --recovery-fast-swing 0.25", "_swing").find("\"recovery_fast_swing\": {\"swing_s\": 0.250, \"steps\": 0}"),
            std::string::npos);
  EXPECT_EQ(summary_of(run, "_swing_default").find("recovery_fast_swing"), std::string::npos);
}

// --surface-sink reaches the run's stack (its summary echoes the estimator's stance sink); a run
// without it says nothing of it. The estimator's use of it is tested in tests/estimator.
TEST(SimulateCli, SurfaceSinkIsEchoedWhenGiven) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  const std::string run = standing_motion() + " --duration 0.2 --ground carpet";
  EXPECT_NE(summary_of(run + " --surface-sink 0.015", "_sink").find("\"surface_sink_m\": 0.0150"), std::string::npos);
  EXPECT_EQ(summary_of(run, "_sink_default").find("surface_sink"), std::string::npos);
}

// kuavo campaign's counts are whole numbers (atoi took "5abc" as 5, and --jobs "4x" went to
// GNU parallel as given).
TEST(CampaignCli, CountsAreWholeNumbers) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  const std::pair<std::string, std::string> cases[] = {
      {"--seeds 5abc", "--seeds needs a whole number N in 1..100000 seeds, got '5abc'"},
      {"--seeds 99999999999999999999", "--seeds needs a whole number N in 1..100000 seeds"},
      {"--jobs 4x", "--jobs needs a whole number N in 1..4096 jobs, got '4x'"},
      {"--jobs 0", "--jobs needs a whole number N in 1..4096 jobs, got '0'"},
      {"--example --seeds 3", "--seeds does not apply to --example"},
  };
  for (const auto& [args, message] : cases) {
    const std::string err = kOut + "_campaign.stderr";
    const int status = std::system((kBin + " campaign /nonexistent/spec.json " + args + " >/dev/null 2>" + err).c_str());
    EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 2) << args;
    std::ifstream in(err);
    std::ostringstream ss;
    ss << in.rdbuf();
    EXPECT_NE(ss.str().find(message), std::string::npos) << args << "\n" << ss.str();
  }
}

// Every command's parser names what it refuses (the shared parser, rtos_shim/args.h): kuavo
// demo's --planner said only the usage; retarget-sweep took ' 0.4' and a trailing comma in
// --horizons; urdf2model --variant bogus generated nothing and exited 0.
TEST(CommandsCli, EveryCommandRefusesWithTheOptionNamed) {
  const std::string urdf2model = std::string(KUAVO_BINARY_DIR) + "/urdf2model";
  const std::pair<std::string, std::string> cases[] = {
      {kBin + " demo --planner fast", "kuavo demo: --planner must be mpc|kinematic, got 'fast'"},
      {kBin + " demo --out", "kuavo demo: --out needs a value (DIR)"},
      {kBin + " retarget-sweep --out x --horizons 0.2,", "--horizons must be S,S,... with each S in [0.2, 1.4] s, got '0.2,'"},
      {kBin + " retarget-sweep --out x --horizons ' 0.4'", "--horizons must be S,S,... with each S in [0.2, 1.4] s"},
      {kBin + " retarget --stage geometric --dance-bvh d.bvh in.bvh", "--dance-bvh writes the built-in dance"},
      {kBin + " retarget --verify-recovery-fast-swing 0.45",
       "--verify-recovery-fast-swing needs SECONDS in [0.2, 0.4] s, got '0.45'"},
      {kBin + " retarget --stage geometric --verify-recovery-fast-swing 0.25",
       "--verify-recovery-fast-swing does not apply to --stage geometric"},
      {kBin + " retarget --verify-carpet-sink 0.06", "--verify-carpet-sink needs M in [0, 0.05] m, got '0.06'"},
      {kBin + " retarget --verify-carpet-sink nan", "--verify-carpet-sink needs M in [0, 0.05] m, got 'nan'"},
      {kBin + " retarget --stage geometric --verify-carpet-sink 0.015",
       "--verify-carpet-sink does not apply to --stage geometric"},
      {kBin + " model --mass 55 --mass 56", "kuavo model: --mass given twice"},
      {urdf2model + " --variant bogus", "urdf2model: --variant must be s45|s42|all, got 'bogus'"},
      // A directory as the spec threw from its first read: "internal error", exit 1.
      {kBin + " campaign " + std::string(KUAVO_BINARY_DIR), "kuavo campaign: " KUAVO_BINARY_DIR ": not a regular file"},
  };
  for (const auto& [cmd, message] : cases) {
    const std::string err = kOut + "_commands.stderr";
    const int status = std::system((cmd + " >/dev/null 2>" + err).c_str());
    EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 2) << cmd;
    std::ifstream in(err);
    std::ostringstream ss;
    ss << in.rdbuf();
    EXPECT_NE(ss.str().find(message), std::string::npos) << cmd << "\n" << ss.str();
  }
}

// --help prints the usage on stdout and exits 0 for every command (simulate and campaign
// printed it on stderr, leaving stdout empty: kuavo_fuzz seed 1, args:simulate case 10597).
TEST(CommandsCli, HelpIsTheUsageOnStdout) {
  for (const char* command : {"simulate", "campaign", "retarget", "retarget-sweep", "demo", "model"}) {
    const std::string out = kOut + "_help.stdout";
    const int status = std::system((kBin + " " + command + " --help >" + out + " 2>/dev/null").c_str());
    EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 0) << command;
    std::ifstream in(out);
    std::ostringstream ss;
    ss << in.rdbuf();
    EXPECT_EQ(ss.str().rfind("usage: kuavo ", 0), 0u) << command << ": stdout was '" << ss.str() << "'";
  }
}

// --engine mujoco: Simbody-only options and the carpet are refused with a reason; a short
// stand runs and its summary names the engine.
TEST(SimulateCli, EngineMujocoRefusesSimbodyOptionsAndNamesItself) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  const CliRun carpet = simulate("--stand 0.1 --engine mujoco --ground carpet", "_mj_carpet");
  EXPECT_EQ(carpet.exit_code, 2) << carpet.err;
  EXPECT_NE(carpet.err.find("carpet"), std::string::npos) << carpet.err;
  const CliRun rkm = simulate("--stand 0.1 --engine mujoco --integrator rkm", "_mj_rkm");
  EXPECT_EQ(rkm.exit_code, 2) << rkm.err;
  EXPECT_NE(rkm.err.find("--integrator applies to the simbody engine"), std::string::npos) << rkm.err;
  EXPECT_EQ(simulate("--stand 0.1 --engine ode", "_mj_bad").exit_code, 2);
  const std::string summary = kOut + "_mj.json";
  const CliRun ok = simulate("--stand 0.2 --engine mujoco --summary " + summary, "_mj_ok");
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  std::ifstream in(summary);
  std::ostringstream ss;
  ss << in.rdbuf();
  EXPECT_NE(ss.str().find("\"engine\": \"mujoco\""), std::string::npos) << ss.str();
  EXPECT_NE(ss.str().find("\"fell\": false"), std::string::npos) << ss.str();
}

// --engine both: one summary holding both runs and whether they agree; MuJoCo's log beside.
TEST(SimulateCli, EngineBothWritesOneSummaryAndTwoLogs) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
  const std::string summary = kOut + "_both.json", log = kOut + "_both.csv";
  const CliRun r = simulate("--stand 0.2 --engine both --log " + log + " --summary " + summary, "_both");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(summary);
  std::ostringstream ss;
  ss << in.rdbuf();
  for (const char* key : {"\"engine\": \"both\"", "\"agree\": true", "\"simbody\": {", "\"mujoco\": {",
                          "\"engine\": \"simbody\"", "\"engine\": \"mujoco\""}) {
    EXPECT_NE(ss.str().find(key), std::string::npos) << key << " in\n" << ss.str();
  }
  EXPECT_TRUE(std::filesystem::exists(log));
  EXPECT_TRUE(std::filesystem::exists(kOut + "_both.mujoco.csv"));
}

// Memory exhaustion becomes one line and exit 1, not an abort: the run under address-space
// limits around the point where start-up stops fitting (32..64 MB).
TEST(SimulateCli, OutOfMemoryIsOneLineAndExitOne) {
  if (!std::filesystem::exists(kBin)) GTEST_SKIP() << kBin << " not built";
#ifdef KUAVO_SANITIZE
  GTEST_SKIP() << "AddressSanitizer's shadow memory does not fit an address-space limit";
#endif
  const std::string motion = standing_motion();
  int out_of_memory = 0;
  for (int limit_kb = 32000; limit_kb <= 64000; limit_kb += 4000) {
    const CliRun r = simulate(motion + " --duration 0.1", "_oom", "ulimit -v " + std::to_string(limit_kb) + "; ");
    if (r.exit_code == 127) continue;  // the dynamic loader itself did not fit
    EXPECT_TRUE(r.exit_code == 0 || r.exit_code == 1) << limit_kb << " kB: exit " << r.exit_code << "\n" << r.err;
    if (r.exit_code == 1 && r.err == "kuavo simulate: out of memory\n") ++out_of_memory;
  }
  if (out_of_memory == 0) GTEST_SKIP() << "no limit in 32..64 MB ran out of memory after start-up on this build";
}

}  // namespace
}  // namespace kuavo::cli
