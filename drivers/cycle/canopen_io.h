// One CANopen bus per control cycle, split where the controller runs:
//   canopen_receive_rt - TPDOs (sampled at last cycle's SYNC), heartbeats,
//                        EMCY and SDO answers -> the drive supervisors
//   (transmissions, controller)
//   canopen_send_rt    - each supervisor's frame (RPDO1 / SDO / NMT), then SYNC
// Real-time safe.
#pragma once

#include <span>

#include "controllers/hal/types.h"
#include "drivers/can/can_port.h"
#include "drivers/canopen/cia402_drive.h"

namespace kuavo::drivers {

struct CanopenReceiveReport {
  int frames = 0;        // frames some drive accepted
  int unclaimed = 0;     // frames no drive on this bus claimed
  int error_frames = 0;  // see port.health
  bool peer_closed = false;
};

struct CanopenSendReport {
  int sent = 0;
  int dropped = 0;  // kTxQueueFull
  int failed = 0;   // bus-off or I/O error
  bool sync_sent = false;
};

CanopenReceiveReport canopen_receive_rt(CanPort& port, std::span<const canopen::DriveConfig> configs,
                                        std::span<canopen::DriveState> states, hal::TimeNs now_ns,
                                        hal::TimeNs realtime_to_monotonic_ns);

// commands[i] goes to drive i. SYNC last, so every RPDO of this cycle is
// latched by the same SYNC and the TPDOs it triggers are read next cycle.
CanopenSendReport canopen_send_rt(CanPort& port, std::span<const canopen::DriveConfig> configs,
                                  std::span<canopen::DriveState> states,
                                  std::span<const canopen::DriveCommand> commands, hal::TimeNs now_ns);

}  // namespace kuavo::drivers
