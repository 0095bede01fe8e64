#include "firmware/mode_machine.h"

namespace kuavo::firmware {

const char* to_string(Mode m) noexcept {
  switch (m) {
    case Mode::kBoot: return "boot";
    case Mode::kSelfCheck: return "self-check";
    case Mode::kDamping: return "damping";
    case Mode::kStandUp: return "stand-up";
    case Mode::kReady: return "ready";
    case Mode::kDance: return "dance";
    case Mode::kFinish: return "finish";
  }
  return "unknown";
}

namespace {
bool enter(ModeState& s, Mode m, hal::TimeNs now_ns) noexcept {
  if (s.mode == m) return false;
  s.mode = m;
  s.since_ns = now_ns;
  ++s.transitions;
  return true;
}
}  // namespace

bool latch_fault_rt(ModeState& s, Fault f, hal::TimeNs now_ns) noexcept {
  if (f == Fault::kNone) return false;
  if (s.latched == Fault::kNone) {
    s.latched = f;
    s.latched_ns = now_ns;
  }
  return enter(s, Mode::kDamping, now_ns);
}

bool step_mode_rt(ModeState& s, const ModeInputs& in, hal::TimeNs now_ns, hal::TimeNs self_check_timeout_ns,
                  hal::TimeNs stand_up_duration_ns, hal::TimeNs finish_duration_ns) noexcept {
  // Safety first: e-stop and faults win over any request, in every mode.
  if (in.estop) return latch_fault_rt(s, Fault::kEstop, now_ns);
  if (in.fault != Fault::kNone) return latch_fault_rt(s, in.fault, now_ns);

  const hal::TimeNs in_mode_ns = now_ns - s.since_ns;
  switch (s.mode) {
    case Mode::kBoot:
      return enter(s, Mode::kSelfCheck, now_ns);
    case Mode::kSelfCheck:
      if (in.self_check_passed) return enter(s, Mode::kDamping, now_ns);
      if (in_mode_ns > self_check_timeout_ns) return latch_fault_rt(s, Fault::kSelfCheckTimeout, now_ns);
      return false;
    case Mode::kDamping:
      if (in.request == Request::kClearFaults) {
        s.latched = Fault::kNone;
        return false;
      }
      if (in.request == Request::kStandUp && s.latched == Fault::kNone) return enter(s, Mode::kStandUp, now_ns);
      return false;
    case Mode::kStandUp:
      if (in_mode_ns >= stand_up_duration_ns) return enter(s, Mode::kReady, now_ns);
      return false;
    case Mode::kReady:
      if (in.request == Request::kDance) return enter(s, Mode::kDance, now_ns);
      if (in.request == Request::kFinish) return enter(s, Mode::kFinish, now_ns);
      return false;
    case Mode::kDance:
      if (in.request == Request::kFinish || in.dance_done) return enter(s, Mode::kFinish, now_ns);
      return false;
    case Mode::kFinish:
      if (in_mode_ns >= finish_duration_ns) return enter(s, Mode::kDamping, now_ns);
      return false;
  }
  return false;
}

}  // namespace kuavo::firmware
