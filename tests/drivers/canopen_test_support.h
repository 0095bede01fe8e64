// Test helpers shared by the CANopen tests: frames from byte lists, byte
// comparison, and a minimal CiA 402 drive.
#pragma once

#include <gtest/gtest.h>

#include <initializer_list>
#include <linux/can.h>

#include "drivers/canopen/cia402_state.h"

namespace kuavo::drivers::canopen::test_support {

inline void expect_bytes(const can_frame& f, std::uint32_t id, std::initializer_list<int> bytes) {
  EXPECT_EQ(f.can_id, id);
  ASSERT_EQ(f.len, bytes.size());
  int i = 0;
  for (int b : bytes) {
    EXPECT_EQ(f.data[i], b) << "byte " << i;
    ++i;
  }
}

inline can_frame frame(std::uint32_t id, std::initializer_list<int> bytes) {
  can_frame f{};
  f.can_id = id;
  f.len = static_cast<std::uint8_t>(bytes.size());
  int i = 0;
  for (int b : bytes) f.data[i++] = static_cast<std::uint8_t>(b);
  return f;
}

// A minimal drive following the CiA 402 transitions the master relies on.
struct FakeDrive {
  Cia402State state = Cia402State::kSwitchOnDisabled;
  bool last_reset_bit = false;
  bool fault_sticky = false;  // reset does not clear it
  void apply(std::uint16_t cw) {
    const bool reset_edge = (cw & 0x80) && !last_reset_bit;
    last_reset_bit = cw & 0x80;
    if (state == Cia402State::kFault) {
      if (reset_edge && !fault_sticky) state = Cia402State::kSwitchOnDisabled;
      return;
    }
    if ((cw & 0x02) == 0) {  // disable voltage
      state = Cia402State::kSwitchOnDisabled;
      return;
    }
    const std::uint16_t low = cw & 0x0F;
    if (low == 0x06) state = Cia402State::kReadyToSwitchOn;
    else if (low == 0x07 && state == Cia402State::kReadyToSwitchOn) state = Cia402State::kSwitchedOn;
    else if (low == 0x07 && state == Cia402State::kOperationEnabled) state = Cia402State::kSwitchedOn;
    else if (low == 0x0F && (state == Cia402State::kSwitchedOn || state == Cia402State::kOperationEnabled))
      state = Cia402State::kOperationEnabled;
  }
  std::uint16_t statusword() const {
    switch (state) {
      case Cia402State::kSwitchOnDisabled: return 0x0250;
      case Cia402State::kReadyToSwitchOn: return 0x0231;
      case Cia402State::kSwitchedOn: return 0x0233;
      case Cia402State::kOperationEnabled: return 0x0237;
      case Cia402State::kFault: return 0x0218;
      default: return 0x0000;
    }
  }
};

}  // namespace kuavo::drivers::canopen::test_support
