// kuavo_fw_sim: the firmware in the loop, as PX4 keeps its SITL -- a separate build of the
// same code. The firmware's task bodies, modes, watchdogs, safety filter, drivers'
// encoders/decoders, transmissions and bus plan (the kuavo_firmware library that kuavo_fw
// runs) against the drivers' bus emulators bound to the Simbody plant, in lockstep virtual
// time. Deterministic: same options and seed, same log bytes. Simbody stays out of kuavo_fw.
//
// Exit codes: 0 the dance was danced to its end (or the stand held) without a fault or a
// fall; 1 it was not (the summary says why: faults, fell, error); 2 bad usage,
// configuration or motion file.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <memory>
#include <new>
#include <string>

#include "controllers/estimator/estimator.h"
#include "controllers/motion/load_motion.h"
#include "drivers/config/drivers_config_json.h"
#include "firmware/sitl/sitl_run.h"
#include "rtos_shim/args.h"
#include "sim/push_option.h"
#include "tests/support/alloc_trap.h"

namespace fw = kuavo::firmware;
namespace sitl = kuavo::firmware::sitl;
namespace d = kuavo::drivers;

namespace {

constexpr const char* kUsage =
    "usage: kuavo_fw_sim [--dance MOTION_FILE | --stand SECONDS] [--config FILE] [--legs csp|cst]\n"
    "                    [--ground floor|carpet] [--seed N] [--push T:FX,FY,FZ:DURATION]\n"
    "                    [--plan-latency-ms MS] [--log run.csv] [--summary run.json] [--balance-filter on|off]\n"
    "                    [--holdable-soles on|off] [--recovery-fast-swing SECONDS] [--surface-sink M]\n"
    "                    [--inject KIND@SECONDS]\n"
    "  --dance MOTION_FILE  a motion file from `kuavo retarget`, loaded as kuavo_fw --dance loads it:\n"
    "                       stand up on the gantry to its first frame, released in ready, dance,\n"
    "                       back on the gantry, finish, damping\n"
    "  --stand SECONDS      no motion: stand up and stand this long (default 5)\n"
    "  --config FILE        drivers configuration (kuavo_fw's JSON overlay on the built-in defaults)\n"
    "  --legs csp|cst       the CiA 402 drives' mode, legs and shoulder pitches (default csp;\n"
    "                       firmware/README.md)\n"
    "  --balance-filter on|off  as kuavo_fw (default off)\n"
    "  --holdable-soles on|off  as kuavo_fw (default on)\n"
    "  --recovery-fast-swing SECONDS  as kuavo_fw (0.2..0.4 s; default off)\n"
    "  --surface-sink M     as kuavo_fw (0..0.05 m; default 0); the summary echoes it\n"
    "  --ground, --seed, --push, --log, --summary: as `kuavo simulate`; --seed seeds the IMU model\n"
    "                       and the emulators' fault injection (default 1)\n"
    "  --plan-latency-ms MS the planning task's plan applied this long after its state, 0..18 ms (default 4)\n"
    "  --inject KIND@SECONDS  a fault drill, armed SECONDS (virtual time) after the dance began, at most\n"
    "                       the motion's length; KIND: silent-leg-drive (left knee), silent-arm-motor (left\n"
    "                       elbow), bus-off (the left knee's bus), frame-loss-1pct (every bus), imu-dropout,\n"
    "                       starved-planner (no planning task from then on). The summary's \"injection\"\n"
    "                       says when it was armed, the fault latched and the time to damping\n"
    "  --stand applies without --dance; --balance-filter, --holdable-soles, --recovery-fast-swing and\n"
    "  --surface-sink with it; in the other mode they are refused\n"
    "exit codes: 0 danced to the end (or stood) without a fault or a fall, 1 not, 2 bad usage or input\n";

constexpr kuavo::args::ModeMask kDanceMode = 1, kStandMode = 2;

int run(int argc, char** argv) {
  sitl::SitlConfig cfg;
  cfg.loop.legs = sitl::kImageLegBinding;
  cfg.loop.seed = 1;
  std::string dance_path, config_path, summary_path, legs = "csp", balance = "off", holdable = "on", ground = "floor";
  double plan_latency_ms = static_cast<double>(cfg.plan_latency_ns) * 1e-6;
  kuavo::args::Parser args("kuavo_fw_sim");
  args.text("--dance", "MOTION_FILE", &dance_path).modes = kDanceMode;
  args.number("--stand", "SECONDS", 0.0, kuavo::sim::kMaxRunDuration_s, "s", &cfg.stand_s, /*lo_open=*/true).modes = kStandMode;
  args.text("--config", "FILE", &config_path);
  args.choice("--legs", {"csp", "cst"}, &legs);
  args.choice("--balance-filter", {"on", "off"}, &balance).modes = kDanceMode;
  args.choice("--holdable-soles", {"on", "off"}, &holdable).modes = kDanceMode;
  args.number("--recovery-fast-swing", "SECONDS", 0.2, 0.4, "s", &cfg.recovery_fast_swing_s).modes = kDanceMode;
  args.number("--surface-sink", "M", 0.0, kuavo::estimator::kMaxStanceSink_m, "m", &cfg.surface_sink_m).modes = kDanceMode;
  args.choice("--ground", {"floor", "carpet"}, &ground);
  args.uint64("--seed", "N", &cfg.loop.seed);
  args.custom("--push", kuavo::sim::kPushValueName, [&](const char* v) { return kuavo::sim::parse_push(v, cfg.loop.push); });
  args.number("--plan-latency-ms", "MS", 0.0, 18.0, "ms", &plan_latency_ms);
  args.output_file("--log", "CSV", &cfg.log_path);
  args.output_file("--summary", "JSON", &summary_path);
  args.custom("--inject", sitl::kInjectValueName, [&](const char* v) { return sitl::parse_injection(v, cfg.inject); }).modes =
      kDanceMode;
  switch (args.parse(argc, argv)) {
    case kuavo::args::Parser::Result::kHelp:
      std::fputs(kUsage, stdout);
      return 0;
    case kuavo::args::Parser::Result::kError:
      std::fprintf(stderr, "%s\n%s", args.error().c_str(), kUsage);
      return 2;
    case kuavo::args::Parser::Result::kOk:
      break;
  }
  const bool dancing = args.given("--dance");
  if (!args.refuse_inapplicable(dancing ? kDanceMode : kStandMode, dancing ? "a --dance run" : "a --stand run")) {
    std::fprintf(stderr, "%s\n%s", args.error().c_str(), kUsage);
    return 2;
  }
  const bool balance_filter = balance == "on";
  if (!sitl::parse_leg_binding(legs.c_str(), cfg.loop.legs) || !kuavo::sim::parse_ground(ground.c_str(), cfg.loop.ground)) {
    return 2;  // unreachable: the parser allowed only their names
  }
  cfg.plan_latency_ns = static_cast<kuavo::hal::TimeNs>(std::llround(plan_latency_ms * 1e6));
  cfg.inject_fault = args.given("--inject");
  cfg.holdable_soles = holdable == "on";

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
  auto motion = std::make_unique<kuavo::planner::MotionPlan>();  // 8.74 MB at 5 min capacity
  if (!dance_path.empty()) {
    kuavo::planner::BalanceFilterReport report;
    std::string msg;
    if (!kuavo::motion::load_motion(dance_path, model, {.balance_filter = balance_filter}, *motion, report, msg)) {
      std::fprintf(stderr, "kuavo_fw_sim: --dance: %s\n", msg.c_str());
      return 2;
    }
    std::fprintf(stderr, "dance: %s, %d frames at %.0f Hz (%.2f s)", dance_path.c_str(), motion->frame_count,
                 motion->rate_hz, kuavo::planner::motion_plan_duration_s(*motion));
    if (balance_filter) std::fprintf(stderr, "; balance filter moved the CoM by up to %.3f m", report.max_correction_m);
    std::fprintf(stderr, "\n");
    const double motion_s = kuavo::planner::motion_plan_duration_s(*motion);
    if (cfg.inject_fault && cfg.inject.at_s > motion_s) {
      std::fprintf(stderr, "kuavo_fw_sim: --inject at %.3f s: the dance is %.3f s long\n", cfg.inject.at_s, motion_s);
      return 2;
    }
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
  if (s.injected) {
    const sitl::InjectionReport& r = s.injection;
    if (!r.armed && r.error.empty()) {
      std::fprintf(stderr, "inject: %s not armed: the dance ended (finish, a fault or a fall) before %.3f s into it\n",
                   sitl::to_string(r.requested.kind), r.requested.at_s);
    } else if (r.armed) {
      std::fprintf(stderr, "inject: %s (%s) at %.3f s (%.3f s into the dance): ", sitl::to_string(r.requested.kind), r.target.c_str(),
                   r.armed_at_s, r.requested.at_s);
      if (r.fault == fw::Fault::kNone) {
        std::fprintf(stderr, "no fault, final mode %s\n", s.final_mode.c_str());
      } else {
        std::fprintf(stderr, "fault %d (%s), damping after %.1f ms\n", static_cast<int>(r.fault), fw::to_string(r.fault),
                     r.latency_to_damping_ms);
      }
    }
  }
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
