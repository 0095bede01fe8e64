#include "firmware/fault.h"

namespace kuavo::firmware {

const char* to_string(Fault f) noexcept {
  switch (f) {
    case Fault::kNone: return "none";
    case Fault::kEstop: return "e-stop";
    case Fault::kSensorStale: return "joint sample stale";
    case Fault::kImuStale: return "IMU sample stale";
    case Fault::kMotorSilent: return "motor not answering";
    case Fault::kBusOff: return "CAN bus-off";
    case Fault::kDriveFault: return "drive failed";
    case Fault::kMotorFault: return "motor reported a fault";
    case Fault::kPlanStale: return "MPC result too old";
    case Fault::kEstimatorDiverged: return "estimator diverged";
    case Fault::kTiltExceeded: return "tilt beyond limit";
    case Fault::kSelfCheckTimeout: return "self-check timed out";
    case Fault::kBusIo: return "bus I/O failed";
    case Fault::kSensorImplausible: return "joint reading implausible";
    case Fault::kCommandNonFinite: return "command not finite";
    case Fault::kCommandPositionLimit: return "command position outside limits";
    case Fault::kCommandTorqueLimit: return "command torque above peak";
    case Fault::kCommandGainRange: return "command gain out of range";
    case Fault::kCommandMode: return "command mode unknown";
  }
  return "unknown fault";
}

}  // namespace kuavo::firmware
