// 10⁴ WBC ticks over changing states and contact sets, with the allocation trap armed.
#include <gtest/gtest.h>

#include <random>

#include "tests/support/alloc_trap.h"
#include "tests/wbc/wbc_fixture.h"

namespace kuavo::test {
namespace {

TEST(WbcNoAllocation, TenThousandTicksIncludingFallbacks) {
  const model::Model& m = wbc_robot();
  wbc::WbcWorkspace& ws = wbc_workspace();
  const wbc::WbcConfig cfg;
  wbc::wbc_init(m, cfg, ws);
  static dynamics::ConfigVector qs[32];
  static dynamics::VelocityVector vs[32];
  static wbc::WbcReference refs[32];
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 32; ++i) {
    qs[i] = bent_standing_configuration(0.3 + 0.05 * u(rng));
    wbc::wbc_reference_hold_state(m, ws, qs[i], 0, refs[i]);
    for (int j = 0; j < model::kNumJoints; ++j) qs[i][7 + j] += 0.01 * u(rng);
    vs[i].setZero();
    for (int k = 0; k < model::kNv; ++k) vs[i][k] = 0.1 * u(rng);
    if (i % 4 == 1) for (int c = 0; c < 4; ++c) refs[i].in_contact[c] = false;
    if (i % 4 == 2) for (int c = 4; c < 8; ++c) refs[i].in_contact[c] = false;
  }
  static hal::CommandFrame command;
  int counts[4] = {};
  std::size_t allocations = 0;
  for (int tick = 0; tick < 10000; ++tick) {
    const int i = tick % 32;
    // Every 1000 ticks, 30 stale ticks exercise the hold and the PD fallback too.
    const hal::TimeNs now_ns = (tick % 1000) < 30 ? cfg.max_reference_age_ns + 1 : 0;
    AllocTrap trap;
    const auto s = wbc::wbc_step_rt(m, cfg, ws, qs[i], vs[i], refs[i], now_ns, command);
    allocations += trap.count();
    ++counts[static_cast<int>(s)];
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(counts[0], 9000);
  EXPECT_GT(counts[1], 0);
  EXPECT_GT(counts[2], 0);
  std::printf("ticks: ok %d, hold %d, fallback %d\n", counts[0], counts[1], counts[2]);
}

}  // namespace
}  // namespace kuavo::test
