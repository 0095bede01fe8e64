// kuavo_fw_sim's run (firmware/sitl/sitl_run.h): deterministic (same seed, same log bytes;
// another seed, other bytes), and its summary says what happened -- checked against
// what lies outside the summary: the log's own bytes and last row, the JSON parsed back.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "firmware/sitl/sitl_run.h"
#include "tests/firmware/firmware_test_support.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::firmware::sitl {
namespace {

SitlConfig standing(std::uint64_t seed, const std::string& log_path = "") {
  SitlConfig c;
  c.loop.legs = LegBinding::kCsp;
  c.loop.seed = seed;
  c.stand_s = 0.5;
  c.log_path = log_path;
  c.count_allocations = &kuavo::test::thread_allocation_count;
  return c;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(SitlRun, SameSeedSameLogBytesOtherSeedOtherBytes) {
  const model::Model& m = test_support::test_model();
  const std::string path = ::testing::TempDir() + "sitl_run_test.csv";
  const SitlSummary a = run_firmware_sim(m, nullptr, standing(3, path));
  const std::string bytes_a = read_file(path);
  const SitlSummary b = run_firmware_sim(m, nullptr, standing(3, path));
  const std::string bytes_b = read_file(path);
  const SitlSummary c = run_firmware_sim(m, nullptr, standing(4));
  ASSERT_TRUE(a.motion.run.ok) << a.motion.run.error;
  EXPECT_GT(bytes_a.size(), 100000u);
  EXPECT_EQ(bytes_a, bytes_b);
  EXPECT_EQ(a.motion.run.log_sha256, b.motion.run.log_sha256);
  EXPECT_NE(a.motion.run.log_sha256, c.motion.run.log_sha256);  // the IMU noise is the seed's
  std::printf("[ figures  ] standing 0.5 s after ready, seed 3: %llu ticks, log %zu bytes, sha256 %.16s...\n",
              static_cast<unsigned long long>(a.motion.run.control_ticks), bytes_a.size(), a.motion.run.log_sha256.c_str());
  // The summary against the log: the last row's mode (ready, 4) and the run's final mode.
  const std::string last = bytes_a.substr(bytes_a.rfind('\n', bytes_a.size() - 2) + 1);
  double t_s = 0.0;
  int mode = -1, fault = -1;
  ASSERT_EQ(std::sscanf(last.c_str(), "%lf,%d,%d", &t_s, &mode, &fault), 3);
  EXPECT_EQ(mode, static_cast<int>(Mode::kReady));
  EXPECT_EQ(fault, 0);
  EXPECT_EQ(a.final_mode, std::string(to_string(Mode::kReady)));
  EXPECT_NEAR(t_s, a.motion.run.sim_time_s, 1e-3);
  EXPECT_TRUE(a.faults.empty());
  EXPECT_FALSE(a.motion.run.fell);
  EXPECT_EQ(a.wire.bad_values, 0u);
}

TEST(SitlRun, SummaryJsonCarriesTheSimulatorsAndTheFirmwaresKeys) {
  const model::Model& m = test_support::test_model();
  const SitlSummary s = run_firmware_sim(m, nullptr, standing(1));
  const nlohmann::json j = nlohmann::json::parse(sitl_summary_json(s));
  for (const char* key : {"ok", "fell", "sim_time_s", "max_tilt_deg", "log_sha256", "tracking_rms_rad", "mpc_ms", "wbc_us",
                          "final_mode", "faults", "output_stage", "drivers", "wire", "buses"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["final_mode"], "ready");
  EXPECT_TRUE(j["faults"].empty());
  ASSERT_EQ(j["buses"].size(), 7u);  // the default bus plan: can0..can6
  for (const auto& b : j["buses"]) {
    EXPECT_GT(b["frames_per_s"].get<double>(), 1000.0);
    EXPECT_GT(b["planned_load"].get<double>(), 0.0);
    EXPECT_LT(b["planned_load"].get<double>(), 0.7);  // the plan's own limit (bus_plan.h)
  }
}

}  // namespace
}  // namespace kuavo::firmware::sitl
