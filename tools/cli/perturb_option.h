// `kuavo simulate --perturb NAME|FILE.json [--perturb-seed N]`: a perturbation set by
// name (sim/perturbation.h: none, show) or from a JSON file of the same keys the summary
// echoes under "perturbation.ranges", each [lo, hi]; "base": NAME starts from a named set
// and the file's keys override it (absent keys: that set's value, 0 without a base).
#pragma once

#include <string>

#include "sim/perturbation.h"

namespace kuavo::cli {

// False with a message in error for an unknown name, an unreadable file, an unknown key
// or a range the plant cannot represent (validate_perturbation_set).
bool load_perturbation_set(const std::string& name_or_file, sim::PerturbationSet& out, std::string& error);

}  // namespace kuavo::cli
