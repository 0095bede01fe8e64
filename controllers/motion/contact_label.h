// Contact labels: which feet support the robot. Stable numbers: motion files store them.
// Part of the motion file format (motion_reader.h); the offline contact detector
// (tools/mocap/contacts.h) makes them.
#pragma once

#include <cstdint>

namespace kuavo::motion {

enum class ContactLabel : std::uint8_t { kFlight = 0, kLeftSupport = 1, kRightSupport = 2, kDoubleSupport = 3 };

inline bool left_in_contact(ContactLabel c) {
  return c == ContactLabel::kLeftSupport || c == ContactLabel::kDoubleSupport;
}
inline bool right_in_contact(ContactLabel c) {
  return c == ContactLabel::kRightSupport || c == ContactLabel::kDoubleSupport;
}
inline ContactLabel make_label(bool left, bool right) {
  return left ? (right ? ContactLabel::kDoubleSupport : ContactLabel::kLeftSupport)
              : (right ? ContactLabel::kRightSupport : ContactLabel::kFlight);
}

}  // namespace kuavo::motion
