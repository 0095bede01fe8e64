// The IMU per control cycle: drain the serial port (bounded), parse, and keep
// the newest complete MTData2 sample. Real-time safe (stack buffer, no heap).
#pragma once

#include <cstdint>

#include "controllers/hal/types.h"
#include "drivers/imu/mti_parser.h"

namespace kuavo::drivers {

// At 2 Mbaud a 4 ms cycle carries at most ~800 bytes; 4 KiB bounds the work
// per cycle even after a stall.
inline constexpr int kImuMaxBytesPerCycle = 4096;

struct ImuReceiveReport {
  int bytes = 0;
  int packets = 0;         // MTData2 packets decoded this cycle
  bool updated = false;    // `sample` holds a new valid reading
  bool device_lost = false;  // read returned EOF or an I/O error
  DriverError last_error = DriverError::kOk;  // from the newest packet's conversion
};

// Reads what `fd` has, feeds the parser, converts the newest packet. `sample`
// is left untouched unless a new valid reading arrived (stamped now_ns).
ImuReceiveReport imu_receive_rt(int fd, mti::Parser& parser, hal::TimeNs now_ns, hal::ImuSample& sample);

}  // namespace kuavo::drivers
