#include "drivers/can/can_socket.h"

#include <cerrno>
#include <cstring>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

namespace kuavo::drivers {

namespace {

DriverError fail(int fd, DriverError e, const std::string& ifname, const char* what, int err,
                 const char* hint, std::string& message) {
  if (fd >= 0) ::close(fd);
  message = ifname + ": " + what + " failed: " + std::strerror(err);
  if (hint != nullptr) message += std::string(" - ") + hint;
  return e;
}

}  // namespace

DriverError open_can_socket(const std::string& ifname, const CanSocketOptions& options,
                            CanPort& out, std::string& message) {
  out = CanPort{};
  if (ifname.empty() || ifname.size() >= IFNAMSIZ) {
    message = "'" + ifname + "': CAN interface name empty or longer than " +
              std::to_string(IFNAMSIZ - 1) + " characters";
    return DriverError::kBadConfig;
  }
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    const int err = errno;
    const bool no_family = err == EAFNOSUPPORT || err == EPROTONOSUPPORT;
    return fail(-1, no_family ? DriverError::kNoCanSupport : DriverError::kSetupFailed, ifname,
                "socket(AF_CAN)", err,
                no_family ? "kernel without CAN support? (modprobe can can_raw)" : nullptr, message);
  }

  const can_err_mask_t err_mask =
      CAN_ERR_TX_TIMEOUT | CAN_ERR_CRTL | CAN_ERR_BUSOFF | CAN_ERR_RESTARTED | CAN_ERR_PROT;
  if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof(err_mask)) != 0) {
    return fail(fd, DriverError::kSetupFailed, ifname, "setsockopt(CAN_RAW_ERR_FILTER)", errno,
                nullptr, message);
  }
  if (options.fd_frames) {
    const int on = 1;
    if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof(on)) != 0) {
      return fail(fd, DriverError::kSetupFailed, ifname, "setsockopt(CAN_RAW_FD_FRAMES)", errno,
                  "kernel or driver without CAN FD", message);
    }
  }
  if (!enable_rx_timestamps(fd)) {
    return fail(fd, DriverError::kSetupFailed, ifname, "setsockopt(SO_TIMESTAMPNS)", errno, nullptr,
                message);
  }
  if (options.receive_buffer_bytes > 0 &&
      setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &options.receive_buffer_bytes,
                 sizeof(options.receive_buffer_bytes)) != 0) {
    return fail(fd, DriverError::kSetupFailed, ifname, "setsockopt(SO_RCVBUF)", errno, nullptr,
                message);
  }

  ifreq ifr{};
  std::memcpy(ifr.ifr_name, ifname.c_str(), ifname.size() + 1);
  if (::ioctl(fd, SIOCGIFINDEX, &ifr) != 0) {
    const int err = errno;
    return fail(fd, err == ENODEV ? DriverError::kNoSuchInterface : DriverError::kSetupFailed,
                ifname, "SIOCGIFINDEX", err, "interface missing or not a CAN device?", message);
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifr.ifr_ifindex;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
    return fail(fd, DriverError::kSetupFailed, ifname, "bind", errno, "interface down?", message);
  }
  out = attach_can_port(fd, options.fd_frames);
  message.clear();
  return DriverError::kOk;
}

void close_can_port(CanPort& port) {
  if (port.fd >= 0) ::close(port.fd);
  port.fd = -1;
}

}  // namespace kuavo::drivers
