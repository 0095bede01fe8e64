#include "drivers/imu/serial_port.h"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <termios.h>
#include <unistd.h>

namespace kuavo::drivers {

namespace {

bool baud_constant(int baud, speed_t& out) {
  switch (baud) {
    case 115200: out = B115200; return true;
    case 230400: out = B230400; return true;
    case 460800: out = B460800; return true;
    case 921600: out = B921600; return true;
    case 1000000: out = B1000000; return true;
    case 2000000: out = B2000000; return true;
    case 4000000: out = B4000000; return true;
    default: return false;
  }
}

}  // namespace

bool serial_baud_supported(int baud) {
  speed_t unused;
  return baud_constant(baud, unused);
}

DriverError open_serial_port(const std::string& device, int baud, int& fd, std::string& message) {
  fd = -1;
  speed_t speed;
  if (!baud_constant(baud, speed)) {
    message = device + ": unsupported baud rate " + std::to_string(baud);
    return DriverError::kBadConfig;
  }
  const int f = ::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (f < 0) {
    const int err = errno;
    message = device + ": open failed: " + std::strerror(err);
    if (err == ENOENT || err == ENODEV || err == ENXIO) {
      message += " - IMU not connected (USB) or udev rule missing?";
      return DriverError::kDeviceMissing;
    }
    if (err == EACCES) message += " - add the user to the dialout group?";
    return DriverError::kSetupFailed;
  }
  termios tio{};
  if (::tcgetattr(f, &tio) != 0) {
    message = device + ": not a serial port (tcgetattr: " + std::strerror(errno) + ")";
    ::close(f);
    return DriverError::kSetupFailed;
  }
  ::cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~(CSTOPB | CRTSCTS);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  if (::cfsetispeed(&tio, speed) != 0 || ::cfsetospeed(&tio, speed) != 0 ||
      ::tcsetattr(f, TCSANOW, &tio) != 0) {
    message = device + ": termios setup failed: " + std::strerror(errno);
    ::close(f);
    return DriverError::kSetupFailed;
  }
  ::tcflush(f, TCIOFLUSH);
  fd = f;
  message.clear();
  return DriverError::kOk;
}

DriverError read_serial_rt(int fd, std::uint8_t* buf, std::size_t capacity, std::size_t& n) {
  n = 0;
  const ssize_t r = ::read(fd, buf, capacity);
  if (r > 0) {
    n = static_cast<std::size_t>(r);
    return DriverError::kOk;
  }
  if (r == 0) return DriverError::kPeerClosed;
  if (errno == EAGAIN || errno == EWOULDBLOCK) return DriverError::kRxEmpty;
  return DriverError::kIoError;
}

}  // namespace kuavo::drivers
