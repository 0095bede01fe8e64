// One error enum for every driver. The numbers are stable: they appear in logs
// and fault records, so a value is never renumbered or reused; new errors take
// a fresh number in their block. Real-time functions return these; start-up
// functions also fill a human-readable message.
#pragma once

#include <cstdint>

namespace kuavo::drivers {

enum class DriverError : std::uint16_t {
  kOk = 0,

  // Frame I/O (1..19)
  kRxEmpty = 1,        // non-blocking read found nothing: not a fault
  kTxQueueFull = 2,    // ENOBUFS/EAGAIN: frame dropped, counted; resend next cycle
  kIoError = 3,        // any other errno from send/recv
  kBadDatagram = 4,    // datagram size is neither CAN_MTU nor CANFD_MTU
  kPeerClosed = 5,     // socketpair peer gone (emulator ended)
  kFdNotEnabled = 6,   // CAN FD frame on a port opened classic-only
  kErrorFrame = 7,     // a controller error frame; CanPort::health updated
  kBusOff = 8,         // bus-off seen on this port (latched until restart)

  // Frame decoding (20..39)
  kWrongCanId = 20,      // frame is not for this decoder
  kWrongLength = 21,     // payload length the protocol does not allow
  kRemoteFrame = 22,     // RTR frames carry no data we use
  kUnknownMotor = 23,    // Ruiwo reply from an ID not in the configuration
  kUnknownCommand = 24,  // recognised ID, unknown command byte

  // CANopen / CiA 402 (40..59)
  kSdoAbort = 40,          // drive refused a configuration write
  kSdoTimeout = 41,        // no SDO answer within kSdoTimeout_ns
  kHeartbeatLost = 42,     // no heartbeat within the consumer time
  kDriveFault = 43,        // statusword reports Fault
  kFaultResetFailed = 44,  // fault persisted after kMaxFaultResets attempts
  kBootTimeout = 45,       // no boot-up message after the NMT reset
  kUnexpectedNmtState = 46,
  kEnableTimeout = 47,     // 402 state machine did not reach Operation enabled
  kCommandRefused = 48,    // CSP target non-finite or beyond the i32 counts: not sent, drive held

  // Ruiwo motors (60..69)
  kReplyTimeout = 60,  // a commanded motor did not answer in time
  kMotorFault = 61,    // status frame fault byte non-zero

  // Transmissions (70..79)
  kTransmissionUnsolved = 70,  // closed chain: no converged/reachable solution

  // Configuration, checked at start-up (80..99)
  kBusOverloaded = 80,     // a bus exceeds the allowed load
  kDuplicateId = 81,       // two devices share an ID on one bus
  kBadConfig = 82,         // out-of-range or inconsistent value
  kNoCanSupport = 83,      // socket(AF_CAN) failed: kernel without CAN
  kNoSuchInterface = 84,   // interface name unknown to the kernel
  kDeviceMissing = 85,     // serial device node absent
  kSetupFailed = 86,       // setsockopt/bind/termios failed
  kConfigUnreadable = 87,  // the configuration file is missing, not a regular file or unreadable

  // Xsens MTi (100..119)
  kMtiBadChecksum = 100,
  kMtiTooLong = 101,       // length field beyond kMaxPayload_bytes
  kMtiBadItem = 102,       // MTData2 item overruns the packet or has a bad size
  kMtiNotMtData2 = 103,    // valid packet of another message type (ignored)
  kMtiIncomplete = 104,    // MTData2 without quaternion, rate of turn and acceleration
};

const char* to_string(DriverError e);

}  // namespace kuavo::drivers
