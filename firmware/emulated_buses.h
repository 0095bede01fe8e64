// The robot's buses without the robot: one socketpair per bus of a DriversConfig, the
// firmware's end attached to RobotIo, the other served by the drivers' emulators (Ruiwo
// boards, CiA 402 drives), whose motors read the joint state the caller gives. The
// firmware's drivers binding then encodes and decodes real frames. Used by the
// firmware-in-the-loop rig (sitl/, joints from the Simbody plant) and by the timing command
// (timing.h, joints from the motion), so kuavo_fw links no simulator. Start-up allocates;
// the per-tick calls do not.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "drivers/config/drivers_config.h"
#include "drivers/emulator/cia402_emulator.h"
#include "drivers/emulator/plant_binding.h"
#include "drivers/emulator/ruiwo_emulator.h"
#include "firmware/robot_io.h"

namespace kuavo::firmware {

class EmulatedBuses {
 public:
  EmulatedBuses();
  ~EmulatedBuses();
  EmulatedBuses(const EmulatedBuses&) = delete;
  EmulatedBuses& operator=(const EmulatedBuses&) = delete;

  // One wire and one emulator per bus of `config`, attached to io.ports (io built by
  // build_robot_io from the same config). Each bus's fault injection is armed with its own
  // generator seeded from `seed` (faults stay off until a test sets one).
  bool init(const drivers::DriversConfig& config, RobotIo& io, std::uint64_t seed, std::string& error);

  // Before the control task: the motors sample `joints` (the leg drives through the
  // transmissions), the drives answer last tick's SYNC. Returns the ankle states the
  // linkage could not reach (the drives then report their last position).
  std::uint64_t drives_answer_rt(const drivers::emulator::PlantJoints& joints, hal::TimeNs now_ns) noexcept;
  // After the control task: the Ruiwo boards answer this tick's commands.
  void ruiwo_answer_rt() noexcept;
  // Frames each bus's emulator received in its last answer.
  std::uint32_t frames_received(std::size_t bus) const { return received_[bus]; }

  std::size_t buses() const { return ruiwo_.size(); }
  drivers::emulator::RuiwoEmulator* ruiwo(std::size_t b) { return ruiwo_[b].get(); }
  drivers::emulator::Cia402Emulator* drives(std::size_t b) { return drives_[b].get(); }
  const drivers::emulator::RuiwoEmulator* ruiwo(std::size_t b) const { return ruiwo_[b].get(); }
  const drivers::emulator::Cia402Emulator* drives(std::size_t b) const { return drives_[b].get(); }
  const std::vector<std::unique_ptr<drivers::emulator::Cia402Emulator>>& all_drives() const { return drives_; }
  const std::array<drivers::emulator::LegWiring, 2>& legs() const { return legs_; }
  drivers::CanPort& device_port(std::size_t b);

 private:
  struct Wire;
  const RobotIo* io_ = nullptr;
  std::vector<std::unique_ptr<Wire>> wires_;
  std::vector<std::unique_ptr<drivers::emulator::RuiwoEmulator>> ruiwo_;
  std::vector<std::unique_ptr<drivers::emulator::Cia402Emulator>> drives_;
  std::vector<std::uint32_t> received_;
  std::array<drivers::emulator::LegWiring, 2> legs_{};
};

}  // namespace kuavo::firmware
