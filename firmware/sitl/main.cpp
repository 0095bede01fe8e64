// kuavo_fw_sim: the firmware in the loop, as PX4 keeps its SITL -- a separate build of the
// same code. The firmware's task bodies, modes, watchdogs, safety filter, drivers'
// encoders/decoders, transmissions and bus plan (the kuavo_firmware library that kuavo_fw
// runs) against the drivers' bus emulators bound to the Simbody plant, in lockstep virtual
// time. Deterministic: same options and seed, same log bytes. Simbody stays out of kuavo_fw.
//
// Exit codes: 0 the dance was danced to its end (or the stand held) without a fault or a
// fall; 1 it was not (the summary says why: faults, fell, error); 2 bad usage,
// configuration or motion file.
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <memory>
#include <new>
#include <string>

#include "drivers/config/drivers_config_json.h"
#include "firmware/dance_motion.h"
#include "firmware/sitl/sitl_run.h"
#include "tests/support/alloc_trap.h"

namespace fw = kuavo::firmware;
namespace sitl = kuavo::firmware::sitl;
namespace d = kuavo::drivers;

namespace {

constexpr const char* kUsage =
    "usage: kuavo_fw_sim [--dance MOTION_FILE | --stand SECONDS] [--config FILE] [--legs csp|cst]\n"
    "                    [--ground floor|carpet] [--seed N] [--push T:FX,FY,FZ:DURATION]\n"
    "                    [--plan-latency-ms MS] [--log run.csv] [--summary run.json] [--balance-filter on|off]\n"
    "  --dance MOTION_FILE  a motion file from `kuavo retarget`, loaded as kuavo_fw --dance loads it:\n"
    "                       stand up on the gantry to its first frame, released in ready, dance,\n"
    "                       finish, damping\n"
    "  --stand SECONDS      no motion: stand up and stand this long (default 5)\n"
    "  --config FILE        drivers configuration (kuavo_fw's JSON overlay on the built-in defaults)\n"
    "  --legs csp|cst       the leg drives' CiA 402 mode (default csp; firmware/README.md)\n"
    "  --balance-filter on|off  as kuavo_fw (default off)\n"
    "  --ground, --seed, --push, --log, --summary: as `kuavo simulate`; --seed seeds the IMU model\n"
    "                       and the emulators' fault injection (default 1)\n"
    "  --plan-latency-ms MS the planning task's plan applied this long after its state (default 4)\n"
    "exit codes: 0 danced to the end (or stood) without a fault or a fall, 1 not, 2 bad usage or input\n";

bool parse_double(const char* text, double& out) {
  char* end = nullptr;
  out = std::strtod(text, &end);
  return end != text && *end == '\0' && std::isfinite(out);
}

// "T:FX,FY,FZ:DURATION" (s, N, s), as kuavo simulate takes it.
bool parse_push(const char* text, kuavo::sim::Push& push) {
  double t, fx, fy, fz, dur;
  char tail;
  if (std::sscanf(text, "%lf:%lf,%lf,%lf:%lf%c", &t, &fx, &fy, &fz, &dur, &tail) != 5) return false;
  if (!(t >= 0.0) || !(dur > 0.0) || !std::isfinite(fx + fy + fz)) return false;
  push.start_s = t;
  push.duration_s = dur;
  push.force_N = kuavo::sim::Vec3(fx, fy, fz);
  return true;
}

constexpr double kMaxStand_s = 600.0;

int bad(const char* what, const char* value) {
  std::fprintf(stderr, "kuavo_fw_sim: %s '%s'\n%s", what, value ? value : "", kUsage);
  return 2;
}

int run(int argc, char** argv) {
  sitl::SitlConfig cfg;
  cfg.loop.legs = sitl::LegBinding::kCsp;
  cfg.loop.seed = 1;
  std::string dance_path, config_path, summary_path;
  bool balance_filter = false;
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    const char* v = i + 1 < argc ? argv[i + 1] : nullptr;
    if (!std::strcmp(a, "--help") || !std::strcmp(a, "-h")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (v == nullptr) return bad("missing value after", a);
    if (!std::strcmp(a, "--dance")) {
      dance_path = v;
    } else if (!std::strcmp(a, "--stand")) {
      // Bounded like kuavo simulate's --stand (a run's log and time grow with it).
      if (!parse_double(v, cfg.stand_s) || !(cfg.stand_s > 0.0 && cfg.stand_s <= kMaxStand_s)) {
        return bad("--stand needs seconds in (0, 600], got", v);
      }
    } else if (!std::strcmp(a, "--config")) {
      config_path = v;
    } else if (!std::strcmp(a, "--legs")) {
      if (!sitl::parse_leg_binding(v, cfg.loop.legs)) return bad("--legs must be csp or cst, got", v);
    } else if (!std::strcmp(a, "--balance-filter")) {
      if (std::strcmp(v, "on") != 0 && std::strcmp(v, "off") != 0) return bad("--balance-filter must be on or off, got", v);
      balance_filter = !std::strcmp(v, "on");
    } else if (!std::strcmp(a, "--ground")) {
      if (!kuavo::sim::parse_ground(v, cfg.loop.ground)) return bad("--ground must be floor or carpet, got", v);
    } else if (!std::strcmp(a, "--seed")) {
      char* end = nullptr;
      errno = 0;
      cfg.loop.seed = std::strtoull(v, &end, 10);
      // strtoull takes "-1" as 2^64 - 1 and saturates an overflow: both refused.
      if (end == v || *end != '\0' || v[0] == '-' || v[0] == '+' || errno == ERANGE) {
        return bad("--seed needs an unsigned 64-bit integer, got", v);
      }
    } else if (!std::strcmp(a, "--push")) {
      if (!parse_push(v, cfg.loop.push)) return bad("--push must be T:FX,FY,FZ:DURATION (s, N, s), got", v);
    } else if (!std::strcmp(a, "--plan-latency-ms")) {
      double ms = 0.0;
      if (!parse_double(v, ms) || ms < 0.0 || ms > 18.0) return bad("--plan-latency-ms must be 0..18, got", v);
      cfg.plan_latency_ns = static_cast<kuavo::hal::TimeNs>(std::llround(ms * 1e6));
    } else if (!std::strcmp(a, "--log")) {
      cfg.log_path = v;
    } else if (!std::strcmp(a, "--summary")) {
      summary_path = v;
    } else {
      return bad("unknown argument", a);
    }
    ++i;
  }

  static kuavo::model::Model model;
  if (kuavo::model::build_model(kuavo::model::Variant::kS45, kuavo::model::kDefaultTotalMass_kg, model) !=
      kuavo::model::ModelError::kOk) {
    std::fprintf(stderr, "kuavo_fw_sim: model: cannot build\n");
    return 2;
  }
  // The drivers configuration and the motion: kuavo_fw's own loaders and checks.
  d::DriversConfig drivers = d::default_drivers_config(model);
  if (!config_path.empty()) {
    d::BusLoadReport loads;
    std::string msg;
    if (d::load_drivers_config(config_path, model, drivers, loads, msg) != d::DriverError::kOk) {
      std::fprintf(stderr, "kuavo_fw_sim: configuration %s: %s\n", config_path.c_str(), msg.c_str());
      return 2;
    }
  }
  cfg.loop.drivers = &drivers;
  auto motion = std::make_unique<kuavo::planner::MotionPlan>();  // ~6.6 MB
  if (!dance_path.empty()) {
    kuavo::planner::BalanceFilterReport report;
    std::string msg;
    if (!fw::load_dance_motion(dance_path, model, balance_filter, *motion, report, msg)) {
      std::fprintf(stderr, "kuavo_fw_sim: --dance: %s\n", msg.c_str());
      return 2;
    }
    std::fprintf(stderr, "dance: %s, %d frames at %.0f Hz (%.2f s)", dance_path.c_str(), motion->frame_count,
                 motion->rate_hz, kuavo::planner::motion_plan_duration_s(*motion));
    if (balance_filter) std::fprintf(stderr, "; balance filter moved the CoM by up to %.3f m", report.max_correction_m);
    std::fprintf(stderr, "\n");
  }
  cfg.count_allocations = &kuavo::test::thread_allocation_count;

  const sitl::SitlSummary s = sitl::run_firmware_sim(model, dance_path.empty() ? nullptr : motion.get(), cfg);
  const std::string json = sitl::sitl_summary_json(s);
  if (!summary_path.empty()) {
    std::ofstream out(summary_path);
    out << json;
    if (!out) {
      std::fprintf(stderr, "kuavo_fw_sim: cannot write %s\n", summary_path.c_str());
      return 1;
    }
  }
  std::fputs(json.c_str(), stdout);
  if (!s.motion.run.ok) {
    std::fprintf(stderr, "kuavo_fw_sim: %s\n", s.motion.run.error.c_str());
    return 1;
  }
  const bool good = s.faults.empty() && !s.motion.run.fell && (dance_path.empty() || s.danced_to_end);
  return good ? 0 : 1;
}

}  // namespace

// No exception leaves the program: one line and exit 1, never an abort.
int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "kuavo_fw_sim: out of memory\n");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "kuavo_fw_sim: internal error: %s\n", e.what());
  }
  return 1;
}
