// CiA 402 power state machine: statusword decoding and controlword sequences.
#include <gtest/gtest.h>

#include <vector>

#include "drivers/canopen/cia402_state.h"
#include "tests/drivers/canopen_test_support.h"

namespace kuavo::drivers::canopen {
namespace {

using namespace canopen::test_support;

TEST(Cia402, StatuswordDecoding) {
  EXPECT_EQ(decode_statusword(0x0000), Cia402State::kNotReadyToSwitchOn);
  EXPECT_EQ(decode_statusword(0x0250), Cia402State::kSwitchOnDisabled);
  EXPECT_EQ(decode_statusword(0x0231), Cia402State::kReadyToSwitchOn);
  EXPECT_EQ(decode_statusword(0x0233), Cia402State::kSwitchedOn);
  EXPECT_EQ(decode_statusword(0x0237), Cia402State::kOperationEnabled);
  EXPECT_EQ(decode_statusword(0x0217), Cia402State::kQuickStopActive);
  EXPECT_EQ(decode_statusword(0x021F), Cia402State::kFaultReactionActive);
  EXPECT_EQ(decode_statusword(0x0218), Cia402State::kFault);
  EXPECT_EQ(decode_statusword(0x0208), Cia402State::kFault);
}

TEST(Cia402, EnableSequenceIsShutdownSwitchOnEnable) {
  FakeDrive d;
  Cia402Control ctl;
  DriverError e;
  std::vector<std::uint16_t> sent;
  for (int i = 0; i < 5; ++i) {
    const std::uint16_t cw = next_controlword_rt(d.state, true, ctl, e);
    EXPECT_EQ(e, DriverError::kOk);
    sent.push_back(cw);
    d.apply(cw);
  }
  EXPECT_EQ(sent, (std::vector<std::uint16_t>{0x06, 0x07, 0x0F, 0x0F, 0x0F}));
  EXPECT_EQ(d.state, Cia402State::kOperationEnabled);
  // Disabling walks straight to switch-on disabled.
  d.apply(next_controlword_rt(d.state, false, ctl, e));
  EXPECT_EQ(d.state, Cia402State::kSwitchOnDisabled);
}

TEST(Cia402, FaultResetUsesRisingEdgeThenGivesUp) {
  FakeDrive d;
  d.state = Cia402State::kFault;
  Cia402Control ctl;
  DriverError e;
  std::uint16_t cw = next_controlword_rt(d.state, true, ctl, e);
  EXPECT_EQ(cw, 0x80);
  d.apply(cw);
  EXPECT_EQ(d.state, Cia402State::kSwitchOnDisabled);
  // A sticky fault: edges 0x80, 0x00, 0x80, 0x00, 0x80, then the budget is spent.
  d.state = Cia402State::kFault;
  d.fault_sticky = true;
  ctl = Cia402Control{};
  std::vector<std::uint16_t> sent;
  for (int i = 0; i < 8; ++i) {
    cw = next_controlword_rt(d.state, true, ctl, e);
    sent.push_back(cw);
    d.apply(cw);
  }
  EXPECT_EQ(sent, (std::vector<std::uint16_t>{0x80, 0x00, 0x80, 0x00, 0x80, 0x00, 0x00, 0x00}));
  EXPECT_EQ(e, DriverError::kFaultResetFailed);
  // Asking for disable re-arms the budget.
  next_controlword_rt(d.state, false, ctl, e);
  EXPECT_EQ(next_controlword_rt(d.state, true, ctl, e), 0x80);
}

}  // namespace
}  // namespace kuavo::drivers::canopen
