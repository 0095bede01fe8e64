// The contact labels are the motion file's (controllers/motion/contact_label.h, defined with
// the online reader); the offline pipeline, which makes them, names them in its own namespace.
#pragma once

#include "controllers/motion/contact_label.h"

namespace kuavo::mocap {

using motion::ContactLabel;
using motion::left_in_contact;
using motion::make_label;
using motion::right_in_contact;

}  // namespace kuavo::mocap
