#include "drivers/bus/open_buses.h"

#include "drivers/can/can_socket.h"

namespace kuavo::drivers {

DriverError open_buses(const BusPlan& plan, std::vector<CanPort>& ports, std::string& message) {
  close_buses(ports);
  ports.reserve(plan.buses.size());
  for (const BusConfig& bus : plan.buses) {
    CanSocketOptions options;
    options.fd_frames = bus.fd;
    CanPort port;
    const DriverError e = open_can_socket(bus.interface, options, port, message);
    if (e != DriverError::kOk) {
      close_buses(ports);
      return e;
    }
    ports.push_back(port);
  }
  return DriverError::kOk;
}

void close_buses(std::vector<CanPort>& ports) {
  for (CanPort& p : ports) close_can_port(p);
  ports.clear();
}

}  // namespace kuavo::drivers
