// kuavo simulate --stand SECONDS [--ground floor|carpet] [--push T:FX,FY,FZ:DURATION]
//                [--seed N] [--latency-ticks N] [--variant s45|s42] [--mass KG]
//                --log run.csv --summary run.json
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>

#include "sim/closed_loop.h"
#include "tools/cli/commands.h"

namespace kuavo::cli {
namespace {

bool parse_double(const char* text, double& out) {
  char* end = nullptr;
  out = std::strtod(text, &end);
  return end != text && *end == '\0' && std::isfinite(out);
}

// "T:FX,FY,FZ:DURATION", e.g. 5:100,0,0:0.1 is a 10 N·s forward push at t = 5 s.
bool parse_push(const char* text, sim::Push& push) {
  double t, fx, fy, fz, d;
  char tail;
  if (std::sscanf(text, "%lf:%lf,%lf,%lf:%lf%c", &t, &fx, &fy, &fz, &d, &tail) != 5) return false;
  if (!(t >= 0.0) || !(d > 0.0) || !std::isfinite(fx + fy + fz)) return false;
  push.start_s = t;
  push.duration_s = d;
  push.force_N = sim::Vec3(fx, fy, fz);
  return true;
}

int usage() {
  std::fprintf(stderr,
               "usage: kuavo simulate --stand SECONDS [--ground floor|carpet] [--push T:FX,FY,FZ:DURATION]\n"
               "                      [--seed N] [--latency-ticks N] [--integrator euler|cvode|rkm]\n"
               "                      [--variant s45|s42] [--mass KG]\n"
               "                      --log run.csv --summary run.json\n");
  return 2;
}

}  // namespace

int run_simulate(int argc, char** argv) {
  sim::RunConfig cfg;
  model::Variant variant = model::Variant::kS45;
  double mass_kg = model::kDefaultTotalMass_kg;
  std::string summary_path;
  bool stand = false;
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    const char* v = i + 1 < argc ? argv[i + 1] : nullptr;
    auto bad = [&](const char* what) {
      std::fprintf(stderr, "kuavo simulate: %s '%s'\n", what, v ? v : "");
      return 2;
    };
    if (!std::strcmp(a, "--stand") && v) {
      if (!parse_double(v, cfg.duration_s) || cfg.duration_s <= 0.0) return bad("--stand needs seconds > 0, got");
      stand = true;
    } else if (!std::strcmp(a, "--ground") && v) {
      if (!sim::parse_ground(v, cfg.ground)) return bad("--ground must be floor or carpet, got");
    } else if (!std::strcmp(a, "--push") && v) {
      if (!parse_push(v, cfg.push)) return bad("--push must be T:FX,FY,FZ:DURATION (s, N, s), got");
    } else if (!std::strcmp(a, "--seed") && v) {
      char* end = nullptr;
      cfg.seed = std::strtoull(v, &end, 10);
      if (end == v || *end != '\0') return bad("--seed needs an unsigned integer, got");
    } else if (!std::strcmp(a, "--latency-ticks") && v) {
      cfg.command_latency_ticks = std::atoi(v);
      if (cfg.command_latency_ticks < 0 || cfg.command_latency_ticks > 50) return bad("--latency-ticks must be 0..50, got");
    } else if (!std::strcmp(a, "--integrator") && v) {
      if (!sim::parse_integrator(v, cfg.integrator)) return bad("--integrator must be euler, cvode or rkm, got");
    } else if (!std::strcmp(a, "--rtol") && v) {
      if (!parse_double(v, cfg.relative_tolerance) || !(cfg.relative_tolerance > 0.0)) return bad("--rtol needs a positive number, got");
    } else if (!std::strcmp(a, "--variant") && v) {
      if (!model::parse_variant(v, variant)) return bad("--variant must be s45 or s42, got");
    } else if (!std::strcmp(a, "--mass") && v) {
      if (!parse_double(v, mass_kg)) return bad("--mass needs kg, got");
    } else if (!std::strcmp(a, "--log") && v) {
      cfg.log_path = v;
    } else if (!std::strcmp(a, "--summary") && v) {
      summary_path = v;
    } else {
      return usage();
    }
    ++i;
  }
  if (!stand) {
    std::fprintf(stderr, "kuavo simulate: only --stand is available until the dance controller lands\n");
    return usage();
  }
  auto robot = std::make_unique<model::Model>();
  if (const auto err = model::build_model(variant, mass_kg, *robot); err != model::ModelError::kOk) {
    std::fprintf(stderr, "kuavo simulate: %s\n", model::to_string(err));
    return 2;
  }
  const sim::RunSummary s = sim::run_standing(*robot, cfg);
  const std::string json = sim::summary_json(s);
  if (!summary_path.empty()) {
    std::ofstream out(summary_path);
    out << json;
    if (!out) {
      std::fprintf(stderr, "kuavo simulate: cannot write %s\n", summary_path.c_str());
      return 1;
    }
  }
  std::fputs(json.c_str(), stdout);
  if (!s.ok) {
    std::fprintf(stderr, "kuavo simulate: %s\n", s.error.c_str());
    return 1;
  }
  return 0;
}

}  // namespace kuavo::cli
