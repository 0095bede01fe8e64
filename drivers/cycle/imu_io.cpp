#include "drivers/cycle/imu_io.h"

#include "drivers/imu/serial_port.h"

namespace kuavo::drivers {

ImuReceiveReport imu_receive_rt(int fd, mti::Parser& parser, hal::TimeNs now_ns, hal::ImuSample& sample) {
  ImuReceiveReport r;
  std::uint8_t buf[512];
  mti::MtData2 newest;
  bool have = false;
  while (r.bytes < kImuMaxBytesPerCycle) {
    std::size_t n = 0;
    const DriverError e = read_serial_rt(fd, buf, sizeof(buf), n);
    if (e == DriverError::kRxEmpty) break;
    if (e != DriverError::kOk) {
      r.device_lost = true;
      break;
    }
    r.bytes += static_cast<int>(n);
    std::size_t pos = 0;
    while (pos < n) {
      std::size_t used = 0;
      mti::MtData2 d;
      if (mti::parse_rt(parser, buf + pos, n - pos, used, d) == DriverError::kOk) {
        ++r.packets;
        newest = d;
        have = true;
      }
      pos += used;
    }
  }
  if (have) {
    hal::ImuSample s;
    r.last_error = mti::to_imu_sample(newest, now_ns, s);
    if (r.last_error == DriverError::kOk) {
      sample = s;
      r.updated = true;
    }
  }
  return r;
}

}  // namespace kuavo::drivers
