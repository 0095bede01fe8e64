// Fault injection for the bus emulators (PX4 style): off by default, and
// while disarmed every request to inject is refused, so a production or a
// normal simulation run cannot be perturbed by accident. Seeded: a run with
// the same seed drops and corrupts the same frames.
#pragma once

#include <cstdint>
#include <random>

namespace kuavo::drivers::emulator {

struct FaultInjection {
  bool armed = false;
  double drop_probability = 0.0;     // reply frames silently lost
  double corrupt_probability = 0.0;  // reply frames with one bit flipped
  std::mt19937 rng{1};
};

// Arms injection with a seed; only then can probabilities be set.
inline void arm_fault_injection(FaultInjection& f, std::uint32_t seed) {
  f.armed = true;
  f.rng.seed(seed);
}

// Returns false (and changes nothing) while disarmed or for p outside [0, 1].
inline bool set_frame_faults(FaultInjection& f, double drop_probability, double corrupt_probability) {
  if (!f.armed || !(drop_probability >= 0.0 && drop_probability <= 1.0) ||
      !(corrupt_probability >= 0.0 && corrupt_probability <= 1.0)) {
    return false;
  }
  f.drop_probability = drop_probability;
  f.corrupt_probability = corrupt_probability;
  return true;
}

inline bool roll(FaultInjection& f, double p) {
  if (!f.armed || p <= 0.0) return false;
  return std::uniform_real_distribution<double>(0.0, 1.0)(f.rng) < p;
}

}  // namespace kuavo::drivers::emulator
