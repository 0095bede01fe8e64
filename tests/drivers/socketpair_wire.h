// A socketpair carrying CAN frames between the host drivers and an emulator.
#pragma once

#include <gtest/gtest.h>

#include <sys/socket.h>
#include <unistd.h>

#include "drivers/can/can_port.h"

namespace kuavo::drivers::test_support {

struct Wire {
  int fd[2]{-1, -1};
  CanPort host, device;
  Wire() {
    EXPECT_EQ(socketpair(AF_UNIX, SOCK_SEQPACKET, 0, fd), 0);
    // Room for a whole cycle's frames in flight.
    const int buf = 1 << 20;
    for (int f : fd) setsockopt(f, SOL_SOCKET, SO_SNDBUF, &buf, sizeof(buf));
    host = attach_can_port(fd[0], false);
    device = attach_can_port(fd[1], false);
  }
  ~Wire() {
    close(fd[0]);
    close(fd[1]);
  }
};

}  // namespace kuavo::drivers::test_support
