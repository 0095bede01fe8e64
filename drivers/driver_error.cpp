#include "drivers/driver_error.h"

namespace kuavo::drivers {

const char* to_string(DriverError e) {
  switch (e) {
    case DriverError::kOk: return "ok";
    case DriverError::kRxEmpty: return "no frame available";
    case DriverError::kTxQueueFull: return "transmit queue full (ENOBUFS/EAGAIN), frame dropped";
    case DriverError::kIoError: return "socket I/O error";
    case DriverError::kBadDatagram: return "datagram is not a CAN or CAN FD frame";
    case DriverError::kPeerClosed: return "peer closed the connection";
    case DriverError::kFdNotEnabled: return "CAN FD frame on a classic CAN port";
    case DriverError::kErrorFrame: return "CAN controller error frame";
    case DriverError::kBusOff: return "CAN bus-off";
    case DriverError::kWrongCanId: return "frame ID not handled by this decoder";
    case DriverError::kWrongLength: return "frame length not allowed by the protocol";
    case DriverError::kRemoteFrame: return "remote (RTR) frame";
    case DriverError::kUnknownMotor: return "reply from a motor ID not in the configuration";
    case DriverError::kUnknownCommand: return "unknown command byte";
    case DriverError::kSdoAbort: return "SDO transfer aborted by the drive";
    case DriverError::kSdoTimeout: return "SDO transfer timed out";
    case DriverError::kHeartbeatLost: return "CANopen heartbeat lost";
    case DriverError::kDriveFault: return "CiA 402 drive in Fault";
    case DriverError::kFaultResetFailed: return "CiA 402 fault reset failed";
    case DriverError::kBootTimeout: return "CANopen node did not boot";
    case DriverError::kUnexpectedNmtState: return "unexpected CANopen NMT state";
    case DriverError::kEnableTimeout: return "CiA 402 drive did not reach Operation enabled";
    case DriverError::kCommandRefused: return "CSP target not finite or out of range: refused, drive held";
    case DriverError::kReplyTimeout: return "motor reply timeout";
    case DriverError::kMotorFault: return "motor reports a fault";
    case DriverError::kTransmissionUnsolved: return "transmission has no converged solution";
    case DriverError::kBusOverloaded: return "bus load above the allowed limit";
    case DriverError::kDuplicateId: return "duplicate device ID on a bus";
    case DriverError::kBadConfig: return "invalid configuration value";
    case DriverError::kNoCanSupport: return "kernel without CAN support";
    case DriverError::kNoSuchInterface: return "no such network interface";
    case DriverError::kDeviceMissing: return "device node missing";
    case DriverError::kSetupFailed: return "device setup failed";
    case DriverError::kConfigUnreadable: return "configuration file unreadable";
    case DriverError::kMtiBadChecksum: return "MTi packet checksum mismatch";
    case DriverError::kMtiTooLong: return "MTi packet longer than supported";
    case DriverError::kMtiBadItem: return "malformed MTData2 item";
    case DriverError::kMtiNotMtData2: return "MTi message is not MTData2";
    case DriverError::kMtiIncomplete: return "MTData2 lacks orientation, rate of turn or acceleration";
  }
  return "unknown driver error";
}

}  // namespace kuavo::drivers
