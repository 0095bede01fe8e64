#include "tools/cli/perturb_option.h"

#include <fstream>
#include <nlohmann/json.hpp>

#include "tools/cli/args.h"

namespace kuavo::cli {

bool load_perturbation_set(const std::string& arg, sim::PerturbationSet& out, std::string& error) {
  if (sim::perturbation_set_by_name(arg, out)) return true;
  // A directory opened as a stream threw from its first read ("internal error", exit 1).
  std::string why;
  if (!check_input_file(arg, why)) {
    error = "--perturb: '" + arg + "' is neither a set name (none, show) nor a readable file (" + why + ")";
    return false;
  }
  std::ifstream in(arg);
  if (!in) {
    error = "--perturb: '" + arg + "' is neither a set name (none, show) nor a readable file";
    return false;
  }
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object()) {
    error = "--perturb: " + arg + " is not a JSON object";
    return false;
  }
  sim::PerturbationSet set;
  if (j.contains("base")) {
    if (!j["base"].is_string() || !sim::perturbation_set_by_name(j["base"].get<std::string>(), set)) {
      error = "--perturb: " + arg + ": \"base\" must be none or show";
      return false;
    }
  }
  set.name = arg;
  for (const auto& [key, value] : j.items()) {
    if (key == "base" || key == "name") continue;
    bool known = false;
    for (const sim::NamedRange& r : sim::perturbation_ranges()) {
      if (key != r.key) continue;
      known = true;
      if (!value.is_array() || value.size() != 2 || !value[0].is_number() || !value[1].is_number()) {
        error = "--perturb: " + arg + ": \"" + key + "\" must be [lo, hi]";
        return false;
      }
      set.*r.member = {value[0].get<double>(), value[1].get<double>()};
    }
    if (!known) {
      error = "--perturb: " + arg + ": unknown key \"" + key + "\"";
      return false;
    }
  }
  if (j.contains("name") && j["name"].is_string()) set.name = j["name"].get<std::string>();
  if (const char* why = sim::validate_perturbation_set(set)) {
    error = "--perturb: " + arg + ": " + why;
    return false;
  }
  out = set;
  return true;
}

}  // namespace kuavo::cli
