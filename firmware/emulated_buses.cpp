#include "firmware/emulated_buses.h"

#include <sys/socket.h>
#include <unistd.h>

#include "drivers/emulator/fault_injection.h"

namespace kuavo::firmware {

namespace d = drivers;
namespace emu = drivers::emulator;

// One bus: a socketpair, the firmware's end and the emulator's.
struct EmulatedBuses::Wire {
  int fd[2]{-1, -1};
  d::CanPort host, device;
  bool ok = false;
  Wire() {
    ok = socketpair(AF_UNIX, SOCK_SEQPACKET, 0, fd) == 0;
    if (!ok) return;
    const int buf = 1 << 20;  // a whole cycle's frames in flight
    for (int f : fd) setsockopt(f, SOL_SOCKET, SO_SNDBUF, &buf, sizeof(buf));
    host = d::attach_can_port(fd[0], false);
    device = d::attach_can_port(fd[1], false);
  }
  ~Wire() {
    if (fd[0] >= 0) close(fd[0]);
    if (fd[1] >= 0) close(fd[1]);
  }
};

EmulatedBuses::EmulatedBuses() = default;
EmulatedBuses::~EmulatedBuses() = default;

bool EmulatedBuses::init(const d::DriversConfig& config, RobotIo& io, std::uint64_t seed, std::string& error) {
  io_ = &io;
  const std::size_t n = io.ports.size();
  ruiwo_.resize(n);
  drives_.resize(n);
  received_.assign(n, 0);
  for (std::size_t b = 0; b < n; ++b) {
    wires_.push_back(std::make_unique<Wire>());
    if (!wires_[b]->ok) {
      error = "socketpair failed";
      return false;
    }
    io.ports[b] = wires_[b]->host;
    const auto fault_seed = static_cast<std::uint32_t>(seed * 1000 + b);
    if (io.is_ruiwo[b]) {
      ruiwo_[b] = std::make_unique<emu::RuiwoEmulator>();
      std::uint8_t ids[d::ruiwo::kMaxMotorsPerBus];
      for (int i = 0; i < io.ruiwo[b].count; ++i) ids[i] = io.ruiwo[b].motors[i].motor_id;
      emu::init_ruiwo_emulator(*ruiwo_[b], ids, io.ruiwo[b].count);
      emu::arm_fault_injection(ruiwo_[b]->faults, 100 + fault_seed);
    } else {
      drives_[b] = std::make_unique<emu::Cia402Emulator>();
      for (const auto& c : io.canopen[b].cfg) emu::add_drive(*drives_[b], c);
      emu::arm_fault_injection(drives_[b]->faults, 200 + fault_seed);
    }
  }
  for (int side = 0; side < 2; ++side) {
    legs_[side].transmission = config.legs[side];
    legs_[side].first_joint = side == 0 ? model::kLeftLegFirst : model::kRightLegFirst;
    for (const d::DriveEntry& e : config.drives) {
      const int k = e.slot - legs_[side].first_joint;
      if (k >= 0 && k < d::kLegActuators) legs_[side].node_ids[k] = e.config.node_id;
    }
  }
  return true;
}

std::uint64_t EmulatedBuses::drives_answer_rt(const emu::PlantJoints& pj, hal::TimeNs now_ns) noexcept {
  std::uint64_t unreachable = 0;
  for (std::size_t b = 0; b < buses(); ++b) {
    if (ruiwo_[b]) {
      emu::write_ruiwo_motors(io_->ruiwo[b], pj, *ruiwo_[b]);
      continue;
    }
    emu::Cia402Emulator& e = *drives_[b];
    for (const auto& leg : legs_) unreachable += emu::write_leg_drives(leg, pj, e) != d::DriverError::kOk;
    for (int i = 0; i < e.count; ++i) {
      const int slot = io_->canopen[b].slot[i];
      if (slot == model::kLeftArmFirst || slot == model::kRightArmFirst) {
        e.drives[i].position_rad = pj.position_rad[slot];
        e.drives[i].velocity_rad_s = pj.velocity_rad_s[slot];
      }
    }
    const std::uint32_t before = e.frames_in;
    emu::serve_rt(e, wires_[b]->device, now_ns);
    received_[b] = e.frames_in - before;
  }
  return unreachable;
}

void EmulatedBuses::ruiwo_answer_rt() noexcept {
  for (std::size_t b = 0; b < buses(); ++b) {
    if (!ruiwo_[b]) continue;
    const std::uint32_t before = ruiwo_[b]->frames_in;
    emu::serve_rt(*ruiwo_[b], wires_[b]->device);
    received_[b] = ruiwo_[b]->frames_in - before;
  }
}

drivers::CanPort& EmulatedBuses::device_port(std::size_t b) { return wires_[b]->device; }

}  // namespace kuavo::firmware
