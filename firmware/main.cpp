// kuavo_fw: the image for the Kuavo 4Pro's control computer. Start-up
// (configuration, real-time setup, buses) happens here, before real time;
// the cycle itself lives in the kuavo_firmware library so the tests run it.
//
// Exit codes: 0 ok; 1 runtime failure (CAN/serial cannot be opened, real time
// refused under --require-rt, out of memory); 2 bad usage, configuration or motion file
// (nothing sent). Arguments: the shared strict parser (rtos_shim/args.h).
//
// Threads: the 500 Hz control task (drivers, cycle, dance control side) and, with
// --dance, the 50 Hz planning task (MPC) at a lower priority; they meet only in the two
// LatestValue buffers of firmware/dance.h. Both are allocation-free once started.
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <string>

#include "controllers/estimator/estimator.h"
#include "controllers/model/model.h"
#include "controllers/motion/load_motion.h"
#include "drivers/bus/open_buses.h"
#include "drivers/config/drivers_config_json.h"
#include "drivers/imu/serial_port.h"
#include "firmware/control_cycle.h"
#include "firmware/control_task.h"
#include "firmware/dance.h"
#include "firmware/robot_io.h"
#include "firmware/timing.h"
#include "rtos_shim/args.h"
#include "rtos_shim/periodic_task.h"

namespace fw = kuavo::firmware;
namespace d = kuavo::drivers;
namespace hal = kuavo::hal;
namespace rtos = kuavo::rtos;

namespace {

constexpr const char* kUsage =
    "usage: kuavo_fw [--config FILE] [--legs csp|cst] [--check] [--require-rt] [--stand] [--dance MOTION_FILE]\n"
    "                [--timing MOTION_FILE [--evict-cache]] [--balance-filter on|off] [--holdable-soles on|off]\n"
    "                [--recovery-fast-swing SECONDS] [--surface-sink M]\n"
    "  --config FILE        drivers configuration (JSON overlay on the built-in defaults)\n"
    "  --legs csp|cst       the CiA 402 drives' mode, legs and shoulder pitches (firmware/README.md,\n"
    "                       leg binding). csp (default): the drives close the PD in their own loop\n"
    "                       (gains written at start-up), the only binding that steps; cst: torque\n"
    "                       from the 500 Hz sample (stands and dances in place, unstable at a foot's\n"
    "                       lift-off)\n"
    "  --check              validate the configuration (and the --dance motion), print the bus plan\n"
    "                       and loads, exit\n"
    "  --require-rt         refuse to run without mlockall, SCHED_FIFO, CPU affinity and the CPU\n"
    "                       idle-latency request (/dev/cpu_dma_latency)\n"
    "  --stand              request stand-up once the self-check has passed\n"
    "  --dance MOTION_FILE  a robot motion file from `kuavo retarget` (this robot's variant): stand up\n"
    "                       to its first frame, dance it with the online stack (estimator, MPC 50 Hz,\n"
    "                       WBC 500 Hz), finish, and exit 0 after 0.5 s of damping\n"
    "  --timing MOTION_FILE worst-case timing (no buses needed): the whole dance's control ticks and\n"
    "                       MPC iterations through the task bodies under the real-time set-up,\n"
    "                       sensors simulated from the motion through emulated buses; prints\n"
    "                       p50/p99/p99.99/max per stage and deadline misses, then 10 s of the\n"
    "                       machine's own stalls on the control CPU. Run before every show\n"
    "  --evict-cache        with --timing: write 64 MB before each control tick (cold caches)\n"
    "  --balance-filter on|off  cart-table ZMP filter of the dance at load (default off: `kuavo\n"
    "                       retarget`'s dynamic stage makes feasible motions; on for --stage geometric)\n"
    "  --holdable-soles on|off  the recovery step's trigger on the part of the soles the ankles hold\n"
    "                       (default on; off: on the soles)\n"
    "  --recovery-fast-swing SECONDS  opt-in: a recovery step no 0.40 s swing captures is planned\n"
    "                       again with this shorter swing (0.2..0.4 s; default off)\n"
    "  --surface-sink M     the stage surface's sink under the standing robot, measured at set-up\n"
    "                       (0..0.05 m; default 0: a hard floor); the estimator puts loaded soles\n"
    "                       that deep (a carpet: ARCHITECTURE.md, estimator)\n"
    "  --require-rt applies to a run and --timing, --stand to a run, --dance to a run and --check,\n"
    "  --evict-cache to --timing; an option outside its mode is refused\n"
    "exit codes: 0 ok, 1 runtime failure (buses, real time, out of memory), 2 bad usage, configuration\n"
    "            or motion file,\n"
    "            3 --timing: a deadline was missed, 4 --timing: the dance did not run to its end\n"
    "SIGINT/SIGTERM: e-stop (damping), then exit after 0.5 s.\n";

std::atomic<bool> g_estop{false};
void on_signal(int) { g_estop.store(true); }

void print_plan(const d::DriversConfig& c, const d::BusLoadReport& r) {
  std::printf("bus plan: %zu buses, %zu devices\n", c.plan.buses.size(), c.plan.devices.size());
  for (std::size_t b = 0; b < c.plan.buses.size(); ++b) {
    const d::BusConfig& bus = c.plan.buses[b];
    int ruiwo = 0, drives = 0;
    for (const d::DeviceConfig& dev : c.plan.devices) {
      if (dev.bus == static_cast<int>(b)) (dev.kind == d::DeviceKind::kRuiwoMotor ? ruiwo : drives)++;
    }
    std::printf("  %-6s %5.0f kbit/s %4.0f Hz  %2d Ruiwo  %2d CiA 402  load %5.1f %%  %6.0f frames/s\n",
                bus.interface.c_str(), bus.bitrate_bps / 1e3, bus.cycle_rate_hz, ruiwo, drives,
                100.0 * r.load[b], r.frames_per_s[b]);
  }
  int csp = 0;
  for (const d::DriveEntry& e : c.drives) csp += e.config.mode == d::canopen::kModeCyclicSyncPosition;
  std::printf("CiA 402 drives: %d in CSP, %d in CST\n", csp, static_cast<int>(c.drives.size()) - csp);
  std::printf("imu: %s at %d baud\n", c.imu_device.c_str(), c.imu_baud);
}

// The control task's body on the robot: the firmware's (firmware/control_task.h) with the
// SIGINT/SIGTERM e-stop as its input.
struct FirmwareTask {
  fw::ControlTask* task;
  std::atomic<bool>* done;
  void operator()(const rtos::CycleInfo& info) noexcept {
    fw::CycleInputs in;
    in.estop = g_estop.load(std::memory_order_relaxed);
    // Kernel receive stamps are not enabled until rtos_shim offers the
    // CLOCK_REALTIME -> CLOCK_MONOTONIC offset; samples carry the cycle time.
    fw::control_task_step_rt(*task, info.cycle, info.wake_ns, in, nullptr);
    if (task->done) done->store(true);
  }
};

// The planning task's body: the latest estimate -> one MPC iteration -> the plan, published.
struct PlannerTask {
  fw::DancePlanner* planner;
  fw::DanceChannels* channels;
  void operator()(const rtos::CycleInfo&) noexcept {
    if (fw::planning_task_step_rt(*planner, *channels)) channels->plan.publish_rt();
  }
};

// --timing: the control task's real-time set-up on the timing loop's own thread.
int run_timing_command(const kuavo::model::Model& model, const d::DriversConfig& drivers, const fw::FirmwareConfig& fw_config,
                       const kuavo::planner::MotionPlan& motion, const rtos::RtConfig& rt, bool evict_cache,
                       fw::DanceControl& dance, fw::DancePlanner& planner, fw::DanceChannels& channels) {
  static fw::Firmware firmware;
  static fw::RobotIo io;
  static fw::LogSink log;
  fw::firmware_init(firmware, model, fw_config, &log);
  fw::dance_standing_pose(firmware, motion);
  fw::TimingConfig config;
  config.evict_caches = evict_cache;
  config.rt = rt;
  fw::TimingReport report;
  if (!fw::run_timing(model, drivers, fw_config, motion, config, firmware, dance, planner, channels, io, report)) {
    std::fprintf(stderr, "kuavo_fw: --timing: %s\n", report.error.c_str());
    return 1;
  }
  std::printf("timing: real time %s; caches %s; %llu control ticks with the stack, dance %s\n",
              report.realtime_status.c_str(), evict_cache ? "evicted before each tick" : "warm",
              static_cast<unsigned long long>(report.dance_ticks),
              report.danced_to_end ? "ran to its end" : fw::to_string(report.fault));
  std::fputs(fw::timing_table(report, fw_config.control_period_ns, fw_config.planner_period_ns).c_str(), stdout);
  const std::uint64_t misses =
      report.cycle.deadline_misses + report.mpc.deadline_misses + (evict_cache ? 0 : report.control_overruns);
  if (misses > 0) {
    std::printf("timing: %llu deadline misses\n", static_cast<unsigned long long>(misses));
    return 3;
  }
  return report.danced_to_end ? 0 : 4;
}

// The image's three modes (rtos_shim/args.h refuses an option outside the mode it applies to).
constexpr kuavo::args::ModeMask kRunMode = 1, kCheckMode = 2, kTimingMode = 4;

// The dance's state, ~22 MB (the MPC workspace ~13 MB, the motion 8.74 MB): one checked
// allocation at start-up, before real time (mlockall then locks it). In static storage it made
// the image's BSS 20 MB, which the kernel could not map under an address-space limit
// (`ulimit -v 20000`): SIGSEGV before main, with nothing to say why.
struct DanceMemory {
  kuavo::planner::MotionPlan motion;  // read-only once loaded
  fw::DanceChannels channels;
  fw::DanceControl dance;
  fw::DancePlanner planner;
};

int run(int argc, char** argv) {
  std::string config_path, dance_path, timing_path, legs = "csp", balance = "off", holdable = "on";
  double fast_swing_s = 0.0;  // --recovery-fast-swing (0: off)
  double surface_sink_m = 0.0;  // --surface-sink (0: a hard floor)
  bool check = false, require_rt = false, stand = false, evict_cache = false;
  kuavo::args::Parser args("kuavo_fw");
  args.text("--config", "FILE", &config_path);
  args.choice("--legs", {"csp", "cst"}, &legs);
  args.flag("--check", &check);
  args.flag("--require-rt", &require_rt).modes = kRunMode | kTimingMode;
  args.flag("--stand", &stand).modes = kRunMode;
  args.text("--dance", "MOTION_FILE", &dance_path).modes = kRunMode | kCheckMode;
  args.text("--timing", "MOTION_FILE", &timing_path).modes = kTimingMode;
  args.flag("--evict-cache", &evict_cache).modes = kTimingMode;
  args.choice("--balance-filter", {"on", "off"}, &balance);
  args.choice("--holdable-soles", {"on", "off"}, &holdable);
  args.number("--recovery-fast-swing", "SECONDS", 0.2, 0.4, "s", &fast_swing_s);
  args.number("--surface-sink", "M", 0.0, kuavo::estimator::kMaxStanceSink_m, "m", &surface_sink_m);
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
  const bool timing = args.given("--timing");
  if (check && timing) {
    std::fprintf(stderr, "kuavo_fw: --check and --timing are two modes; give one\n%s", kUsage);
    return 2;
  }
  if (!args.refuse_inapplicable(timing ? kTimingMode : check ? kCheckMode : kRunMode,
                                timing ? "--timing" : check ? "--check" : "a run")) {
    std::fprintf(stderr, "%s\n%s", args.error().c_str(), kUsage);
    return 2;
  }
  if (timing) dance_path = timing_path;
  for (const char* option : {"--balance-filter", "--holdable-soles", "--recovery-fast-swing", "--surface-sink"}) {
    if (args.given(option) && dance_path.empty()) {
      std::fprintf(stderr, "kuavo_fw: %s applies to a motion (--dance or --timing)\n%s", option, kUsage);
      return 2;
    }
  }
  const bool balance_filter = balance == "on", csp_legs = legs == "csp";

  // --- Configuration (before real time; nothing is sent on failure) ---
  static kuavo::model::Model model;
  if (kuavo::model::build_model(kuavo::model::Variant::kS45, kuavo::model::kDefaultTotalMass_kg, model) !=
      kuavo::model::ModelError::kOk) {
    std::fprintf(stderr, "kuavo_fw: model: cannot build\n");
    return 2;
  }
  d::DriversConfig drivers;
  d::BusLoadReport loads;
  std::string msg;
  const d::DriverError derr = config_path.empty()
                                  ? (drivers = d::default_drivers_config(model), d::validate_drivers_config(drivers, loads, msg))
                                  : d::load_drivers_config(config_path, model, drivers, loads, msg);
  if (derr != d::DriverError::kOk) {
    std::fprintf(stderr, "kuavo_fw: configuration %s: %s (%s)\n", config_path.empty() ? "(defaults)" : config_path.c_str(),
                 msg.c_str(), d::to_string(derr));
    return 2;
  }
  if (csp_legs && (!fw::dance_use_csp_drives(drivers, msg) ||
                   d::validate_drivers_config(drivers, loads, msg) != d::DriverError::kOk)) {
    std::fprintf(stderr, "kuavo_fw: --legs csp: %s\n", msg.c_str());
    return 2;
  }
  const fw::FirmwareConfig fw_config{};
  if (!fw::validate_firmware_config(fw_config, msg)) {
    std::fprintf(stderr, "kuavo_fw: firmware settings: %s\n", msg.c_str());
    return 2;
  }
  // The dance: loaded, validated and balance-filtered before anything is sent.
  kuavo::stack::StackConfig stack_config = fw::firmware_stack_config(fw_config);
  kuavo::planner::set_holdable_soles(stack_config.recovery, holdable == "on");
  stack_config.recovery.fast_swing_s = fast_swing_s;
  stack_config.estimator.stance_sink_m = surface_sink_m;
  std::unique_ptr<DanceMemory> memory;
  if (!dance_path.empty()) {
    memory.reset(new (std::nothrow) DanceMemory);
    if (memory == nullptr) {
      std::fprintf(stderr, "kuavo_fw: out of memory: the dance needs %.0f MB (is the address space limited? ulimit -v)\n",
                   sizeof(DanceMemory) / 1e6);
      return 1;
    }
  }
  if (!dance_path.empty()) {
    kuavo::planner::MotionPlan& motion = memory->motion;
    kuavo::planner::BalanceFilterReport report;
    if (!kuavo::motion::load_motion(dance_path, model, {.balance_filter = balance_filter}, motion, report, msg)) {
      std::fprintf(stderr, "kuavo_fw: --dance: %s\n", msg.c_str());
      return 2;
    }
    const char* why = nullptr;
    if (!fw::dance_init(memory->dance, memory->planner, memory->channels, model, stack_config, fw_config, motion, why)) {
      std::fprintf(stderr, "kuavo_fw: --dance: %s\n", why);
      return 2;
    }
    fw::dance_set_ankle_motors(memory->dance, drivers);  // the WBC plans what the ankle motors can deliver
    fw::dance_set_serial_leg_drives(memory->dance, drivers);  // ... and the CSP hip and knee drives
    std::printf("dance: %s, %d frames at %.0f Hz (%.2f s)", dance_path.c_str(), motion.frame_count, motion.rate_hz,
                kuavo::planner::motion_plan_duration_s(motion));
    if (balance_filter) std::printf("; balance filter moved the CoM by up to %.3f m", report.max_correction_m);
    std::printf("\n");
  }
  if (check) {
    print_plan(drivers, loads);
    std::printf("configuration ok\n");
    return 0;
  }

  rtos::RtConfig rt;
  rt.fifo_priority = fw_config.fifo_priority;
  rt.cpu = fw_config.cpu;
  rt.lock_memory = true;
  rt.cpu_dma_latency_us = fw_config.cpu_dma_latency_us;
  rt.on_failure = require_rt ? rtos::RtFailurePolicy::kRequire : rtos::RtFailurePolicy::kBestEffort;
  if (timing) {
    return run_timing_command(model, drivers, fw_config, memory->motion, rt, evict_cache, memory->dance, memory->planner,
                              memory->channels);
  }

  // --- Real time: probed on a short-lived thread; mlockall is process-wide and stays ---
  rtos::RtStatus rt_status;
  std::thread([&] { rt_status = rtos::apply_realtime_to_this_thread(rt); }).join();
  if (!rt_status.ok()) {
    std::fprintf(stderr, "kuavo_fw: real-time setup: %s\n", rt_status.describe().c_str());
    if (require_rt) {
      std::fprintf(stderr, "kuavo_fw: --require-rt: refusing to run\n");
      return 1;
    }
    std::fprintf(stderr, "kuavo_fw: continuing without full real time (desktop)\n");
  }

  // --- Buses and IMU ---
  static fw::RobotIo io;
  if (!fw::build_robot_io(drivers, fw_config.ruiwo_divider, io, msg)) {
    std::fprintf(stderr, "kuavo_fw: configuration: %s\n", msg.c_str());
    return 2;
  }
  std::vector<d::CanPort> ports;
  if (d::open_buses(drivers.plan, ports, msg) != d::DriverError::kOk) {
    std::fprintf(stderr, "kuavo_fw: %s\n", msg.c_str());
    return 1;
  }
  if (d::open_serial_port(drivers.imu_device, drivers.imu_baud, io.imu_fd, msg) != d::DriverError::kOk) {
    std::fprintf(stderr, "kuavo_fw: %s\n", msg.c_str());
    d::close_buses(ports);
    return 1;
  }
  io.ports = ports;

  // --- Run ---
  static fw::LogSink log;
  static fw::Firmware firmware;
  fw::firmware_init(firmware, model, fw_config, &log);
  const bool dancing = !dance_path.empty();
  if (dancing) fw::dance_standing_pose(firmware, memory->motion);  // stand up to the dance's first frame
  fw::LogWriter writer;
  writer.start(log, stderr);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::atomic<bool> done{false};
  static fw::ControlTask control;
  control.firmware = &firmware;
  control.io = &io;
  control.dance = dancing ? &memory->dance : nullptr;
  control.stand = stand || dancing;
  control.dance_pending = dancing;
  static FirmwareTask task{&control, &done};
  static PlannerTask planner_body{dancing ? &memory->planner : nullptr, dancing ? &memory->channels : nullptr};
  rtos::PeriodicTask planner_task;
  if (dancing) {
    rtos::PeriodicConfig ppc;
    ppc.period_ns = fw_config.planner_period_ns;
    ppc.rt = rt;
    ppc.rt.fifo_priority = fw_config.planner_fifo_priority;
    ppc.rt.cpu = fw_config.planner_cpu;
    const rtos::RtStatus ps = planner_task.start(ppc, planner_body);
    if (!ps.ok()) {
      std::fprintf(stderr, "kuavo_fw: planning task: %s\n", ps.describe().c_str());
      if (require_rt) {
        d::close_buses(ports);
        return 1;
      }
    }
  }
  fw::start_devices(io, rtos::now_ns());
  rtos::PeriodicTask periodic;
  rtos::PeriodicConfig pc;
  pc.period_ns = fw_config.control_period_ns;
  pc.rt = rt;
  const rtos::RtStatus s = periodic.start(pc, task);
  if (!s.ok() && require_rt) {
    std::fprintf(stderr, "kuavo_fw: control task: %s\n", s.describe().c_str());
    d::close_buses(ports);
    return 1;
  }
  while (!done.load() && !periodic.finished()) rtos::sleep_until_ns_rt(rtos::now_ns() + 50'000'000);
  periodic.request_stop();
  periodic.join();
  planner_task.request_stop();
  planner_task.join();
  writer.stop();
  d::close_buses(ports);
  if (dancing) {
    // After real time: what the dance's output stage changed or refused is reported, never silent.
    const fw::DanceCounters& c = memory->dance.counters;
    std::printf("dance: the planner rehearsed the opening %llu times before it (%llu failed)\n",
                static_cast<unsigned long long>(memory->planner.rehearsals),
                static_cast<unsigned long long>(memory->planner.rehearsal_failures));
    std::printf("dance: the control task rehearsed the first tick %llu times before it (%llu failed)\n",
                static_cast<unsigned long long>(memory->dance.rehearsals),
                static_cast<unsigned long long>(memory->dance.rehearsal_failures));
    std::printf("dance: %llu plans taken, %llu rejected (non-finite), %llu kinematic fallbacks, %llu WBC ticks not ok, "
                "%llu joint references put on a stop (%llu more in finish), %llu torques clipped at peak (largest demand %.2f x peak)\n",
                static_cast<unsigned long long>(c.plans_taken), static_cast<unsigned long long>(c.plans_rejected),
                static_cast<unsigned long long>(c.kinematic_fallbacks), static_cast<unsigned long long>(c.wbc_not_ok_ticks),
                static_cast<unsigned long long>(c.references_limited),
                static_cast<unsigned long long>(c.finish_references_limited), static_cast<unsigned long long>(c.torques_saturated),
                c.max_torque_demand_x);
  }
  return 0;
}

}  // namespace

// Start-up may throw (the standard library allocates while loading); no exception leaves the
// image: it becomes one line and exit 1, never an abort. The cycle itself does not throw.
int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "kuavo_fw: out of memory\n");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "kuavo_fw: internal error: %s\n", e.what());
  }
  return 1;
}
