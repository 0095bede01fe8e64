// Contact schedule: which feet support the robot at each 100 Hz frame.
//
// Automatic detection works per foot on the robot-proportioned targets: a foot touches down
// when it is low AND slow, and lifts off when it is high OR fast (hysteresis), then phases
// shorter than a minimum duration are merged into their neighbours. The per-foot booleans
// become one label per frame. A manual override file can replace labels over time ranges
// (the paper annotated its schedule by hand; the override keeps that possible).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tools/mocap/contact_label.h"
#include "tools/mocap/human_targets.h"

namespace kuavo::mocap {

const char* to_string(ContactLabel c);  // "flight", "left", "right", "double"
bool parse_contact_label(const std::string& text, ContactLabel& out);

struct ContactThresholds {
  // Lowest foot point above the ground [m]: the lower of (ankle above its flat-foot height)
  // and (toe keypoint above the sole). A flat foot reads 0, but the human toe keypoint is
  // the ball joint, which sits 2–4 cm up while a dancer stands on the ball (relevé), so
  // contact reads up to ~4 cm; 6 cm is clearly lifted (a swing clears 5–10 cm). With 2.5/5 cm
  // the CMU ballet clips read as flight for 60–65 % of their frames, with 4/6 cm for 30–35 %.
  double touchdown_height_m = 0.04;
  double liftoff_height_m = 0.06;
  // Horizontal speed of the faster of ankle and toe [m/s]: a planted foot reads < 0.1 m/s
  // of capture noise; a swing foot, or one pivoting on heel or ball (which a pinned robot
  // foot cannot do), moves its far end faster than 0.4 m/s.
  double touchdown_speed_m_s = 0.2;
  double liftoff_speed_m_s = 0.4;
  // Phases shorter than this are merged (at 100 Hz, 8 frames = 80 ms, shorter than any
  // human step's stance or swing).
  double min_phase_s = 0.08;
};

// Labels for every target frame.
std::vector<ContactLabel> detect_contacts(const HumanTargets& targets, const model::Model& robot,
                                          const ContactThresholds& thresholds = {});

// Override file: lines "start_s end_s label" (label: flight, left, right, double), '#'
// comments. Frames with start_s <= t < end_s get the label. Errors name the line.
bool apply_contact_overrides(const std::string& text, double rate_hz, std::vector<ContactLabel>& labels,
                             std::string& error);

// Number of maximal runs of equal labels.
int count_contact_phases(const std::vector<ContactLabel>& labels);

}  // namespace kuavo::mocap
