// Opening a SocketCAN CAN_RAW socket for one interface. Start-up only (not
// real-time): it may allocate the error message. The bitrate itself is set
// outside the process (ip link set canX type can bitrate ...); the bus plan
// records it for the load check.
#pragma once

#include <string>

#include "drivers/can/can_port.h"
#include "drivers/driver_error.h"

namespace kuavo::drivers {

struct CanSocketOptions {
  bool fd_frames = false;      // enable CAN_RAW_FD_FRAMES (bus configured for CAN FD)
  int receive_buffer_bytes = 0;  // SO_RCVBUF; 0 keeps the kernel default
};

// Opens, configures and binds. On success `out` owns the descriptor (close it
// with close_can_port). Error frames enabled: TX timeout, controller problems,
// bus-off, restarted, protocol violations. Receive timestamps enabled.
// On failure returns the error and a message naming the interface and the
// cause, e.g. "can0: socket(AF_CAN) failed: Address family not supported by
// protocol - kernel without CAN support?".
DriverError open_can_socket(const std::string& interface_name, const CanSocketOptions& options,
                            CanPort& out, std::string& message);

void close_can_port(CanPort& port);

}  // namespace kuavo::drivers
