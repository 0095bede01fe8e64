// Raw, non-blocking serial port for the IMU (the MTi on USB shows up as
// /dev/ttyUSB0; Leju's factory setting is 2 Mbaud, FACTS.md §5.3). Opening is
// start-up only; reading is real-time safe (never waits).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "drivers/driver_error.h"

namespace kuavo::drivers {

inline constexpr int kMtiDefaultBaud = 2'000'000;

// The rates open_serial_port can set (the MTi's: 115200 .. 4000000 baud); the configuration
// check refuses any other, so `kuavo_fw --check` fails where opening the port would.
bool serial_baud_supported(int baud);

// Opens `device` raw 8N1, no flow control, O_NONBLOCK. On failure `message`
// names the device and the cause, e.g. "/dev/ttyUSB0: open failed: No such
// file or directory - IMU not connected or udev rule missing?".
// kDeviceMissing (absent node), kBadConfig (unsupported baud), kSetupFailed.
DriverError open_serial_port(const std::string& device, int baud, int& fd, std::string& message);

// Reads what is available: kOk with n > 0, kRxEmpty, kPeerClosed (device
// unplugged), kIoError.
DriverError read_serial_rt(int fd, std::uint8_t* buf, std::size_t capacity, std::size_t& n);

}  // namespace kuavo::drivers
