#include "firmware/timing.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <atomic>
#include <vector>

#include "controllers/dynamics/rigid_body.h"
#include "firmware/emulated_buses.h"
#include "rtos_shim/clock.h"
#include "rtos_shim/periodic_task.h"

namespace kuavo::firmware {
namespace {

std::int64_t clock_ns() noexcept { return rtos::now_ns(); }

// Past the motion: settle, finish fade, damping and slack (firmware_config.h).
constexpr hal::TimeNs kAfterMotion_ns = 5'000'000'000;
// Boot, self-check and the 2 s stand-up take ~2.1 s.
constexpr hal::TimeNs kBringUp_ns = 10'000'000'000;

// The sensors the motion implies at motion time t: joint state to the emulated motors, the
// IMU as the motion's base would read it (at rest in the world: specific force = gravity).
void sense_motion_rt(const model::Model& m, dynamics::Data& data, const planner::MotionPlan& motion, hal::TimeNs t_ns,
                     hal::TimeNs stamp_ns, planner::PlanKnot& knot, drivers::emulator::PlantJoints& joints,
                     hal::ImuSample& imu) noexcept {
  planner::motion_plan_sample_rt(m, data, motion, t_ns, knot);
  for (int j = 0; j < model::kNumJoints; ++j) {
    joints.position_rad[j] = knot.q[7 + j];
    joints.velocity_rad_s[j] = knot.v[6 + j];
  }
  const Eigen::Quaterniond base(knot.q[6], knot.q[3], knot.q[4], knot.q[5]);
  const Eigen::Vector3d f = base.conjugate() * Eigen::Vector3d(0.0, 0.0, model::kGravity_m_s2);
  imu.orientation_xyzw = {knot.q[3], knot.q[4], knot.q[5], knot.q[6]};
  imu.angular_rate_rad_s = {knot.v[3], knot.v[4], knot.v[5]};
  imu.acceleration_m_s2 = {f.x(), f.y(), f.z()};
  imu.stamp_ns = stamp_ns;
  imu.valid = true;
}

// Rank floor(n p / 100) of the sorted samples (tools/bench's rule), in us; at_s: each
// sample's motion time (empty: not kept).
StageFigures figures(std::vector<double>& us, double deadline_us, const std::vector<double>& at_s = {}) {
  StageFigures f;
  f.samples = us.size();
  if (us.empty()) return f;
  for (double x : us) f.deadline_misses += x > deadline_us;
  if (at_s.size() == us.size()) {
    const auto slowest = std::max_element(us.begin(), us.end()) - us.begin();
    f.max_at_s = at_s[static_cast<std::size_t>(slowest)];
  }
  std::sort(us.begin(), us.end());
  const auto at = [&](double p) {
    return us[std::min(us.size() - 1, static_cast<std::size_t>(static_cast<double>(us.size()) * p / 100.0))];
  };
  f.p50_us = at(50.0);
  f.p99_us = at(99.0);
  f.p9999_us = at(99.99);
  f.max_us = us.back();
  return f;
}

}  // namespace

namespace {

// The control task's body for the timing run: the motion's sensors onto the emulated buses,
// the firmware's control task (control_task.h), the stages' times while the stack runs.
struct TimedControl {
  const model::Model* model;
  const planner::MotionPlan* motion;
  ControlTask* task;
  DanceControl* dance;
  EmulatedBuses* buses;
  dynamics::Data* data;
  planner::PlanKnot* knot;
  std::vector<unsigned char>* evict;
  std::vector<double>*drivers_us, *estimator_us, *wbc_us, *output_us, *cycle_us, *motion_s;
  std::uint64_t* dance_ticks;
  std::atomic<bool>* done;
  drivers::emulator::PlantJoints joints{};
  hal::ImuSample imu{};
  hal::TimeNs start_ns = -1;

  void operator()(const rtos::CycleInfo& info) noexcept {
    // The firmware's clock: the scheduled releases (2 ms apart however late a wake is), so
    // the run's sequence -- stand-up, dance, finish -- is the same tick for tick on any machine.
    if (start_ns < 0) start_ns = info.deadline_ns;
    const hal::TimeNs now = info.deadline_ns - start_ns;
    const hal::TimeNs t_motion = dance->running ? now - dance->start_ns : 0;
    sense_motion_rt(*model, *data, *motion, t_motion, now, *knot, joints, imu);
    buses->drives_answer_rt(joints, now);
    if (!evict->empty()) std::memset(evict->data(), static_cast<int>(info.cycle & 0xff), evict->size());
    const std::int64_t stack_before = dance->stack.stamps.start_ns;
    control_task_step_rt(*task, info.cycle, now, CycleInputs{}, &imu);
    buses->ruiwo_answer_rt();
    const ControlTask::Stamps& s = task->stamps;
    const stack::StageStamps& st = dance->stack.stamps;
    if (st.start_ns != stack_before && st.start_ns >= s.received_ns) {  // the stack ran this tick
      ++*dance_ticks;
      drivers_us->push_back(1e-3 * static_cast<double>((s.received_ns - s.start_ns) + (s.sent_ns - s.cycled_ns)));
      estimator_us->push_back(1e-3 * static_cast<double>(st.estimator_done_ns - st.start_ns));
      wbc_us->push_back(1e-3 * static_cast<double>(st.wbc_done_ns - st.estimator_done_ns));
      output_us->push_back(1e-3 * static_cast<double>((s.cycled_ns - s.received_ns) - (st.wbc_done_ns - st.start_ns)));
      cycle_us->push_back(1e-3 * static_cast<double>(s.sent_ns - s.start_ns));
      motion_s->push_back(1e-9 * static_cast<double>(t_motion));
    }
    if (task->done || task->firmware->mode.latched != Fault::kNone || cycle_us->size() == cycle_us->capacity()) {
      done->store(true, std::memory_order_release);
    }
  }
};

// The planning task's body (its own thread, as on the robot), each iteration timed.
struct TimedPlanner {
  DancePlanner* planner;
  DanceChannels* channels;
  std::vector<double>* mpc_us;
  void operator()(const rtos::CycleInfo&) noexcept {
    const std::int64_t t0 = clock_ns();
    if (!planning_task_step_rt(*planner, *channels)) return;
    const std::int64_t t1 = clock_ns();
    channels->plan.publish_rt();
    if (mpc_us->size() < mpc_us->capacity()) mpc_us->push_back(1e-3 * static_cast<double>(t1 - t0));
  }
};

// The stall probe's body: half of each period spinning on the clock (stall_probe.h).
struct StallProbeBody {
  rtos::StallStats* stats;
  hal::TimeNs spin_ns;
  void operator()(const rtos::CycleInfo&) noexcept { rtos::stall_probe_spin_rt(rtos::MonotonicClock{}, spin_ns, *stats); }
};

}  // namespace

bool run_timing(const model::Model& m, const drivers::DriversConfig& drivers, const FirmwareConfig& fw_config,
                const planner::MotionPlan& motion, const TimingConfig& config, Firmware& firmware, DanceControl& dance,
                DancePlanner& planner, DanceChannels& channels, RobotIo& io, TimingReport& report) {
  report = TimingReport{};
  std::string msg;
  if (!build_robot_io(drivers, fw_config.ruiwo_divider, io, msg)) return report.error = msg, false;
  auto buses = std::make_unique<EmulatedBuses>();
  if (!buses->init(drivers, io, config.seed, msg)) return report.error = msg, false;
  auto data = std::make_unique<dynamics::Data>();
  auto knot = std::make_unique<planner::PlanKnot>();
  std::vector<unsigned char> evict(config.evict_caches ? kEvictBytes : 0);
  const hal::TimeNs period_ns = fw_config.control_period_ns;
  const hal::TimeNs motion_ns = static_cast<hal::TimeNs>(std::llround(planner::motion_plan_duration_s(motion) * 1e9));
  const std::size_t max_ticks = static_cast<std::size_t>((kBringUp_ns + motion_ns + kAfterMotion_ns) / period_ns);
  std::vector<double> drivers_us, estimator_us, wbc_us, output_us, cycle_us, motion_s, mpc_us;
  for (auto* v : {&drivers_us, &estimator_us, &wbc_us, &output_us, &cycle_us, &motion_s}) v->reserve(max_ticks);
  mpc_us.reserve(max_ticks / 5 + 1);

  ControlTask task;
  task.firmware = &firmware;
  task.io = &io;
  task.dance = &dance;
  task.stand = true;
  task.dance_pending = true;
  task.stage_clock = &clock_ns;
  dance.stack.stage_clock = &clock_ns;
  start_devices(io, 0);

  std::atomic<bool> done{false};
  TimedControl control{&m, &motion, &task, &dance, buses.get(), data.get(), knot.get(), &evict, &drivers_us, &estimator_us,
                       &wbc_us, &output_us, &cycle_us, &motion_s, &report.dance_ticks, &done};
  TimedPlanner plan{&planner, &channels, &mpc_us};
  // As kuavo_fw runs them: the planner first (lower priority), then the control task.
  rtos::PeriodicTask planner_task, control_task;
  rtos::PeriodicConfig ppc;
  ppc.period_ns = fw_config.planner_period_ns;
  ppc.rt = config.rt;
  ppc.rt.fifo_priority = fw_config.planner_fifo_priority;
  ppc.rt.cpu = fw_config.planner_cpu;
  const rtos::RtStatus planner_rt = planner_task.start(ppc, plan);
  rtos::PeriodicConfig pc;
  pc.period_ns = period_ns;
  pc.max_cycles = max_ticks;
  pc.rt = config.rt;
  const rtos::RtStatus control_rt = control_task.start(pc, control);
  report.realtime = planner_rt.ok() && control_rt.ok();
  report.realtime_status = report.realtime ? "ok" : (control_rt.ok() ? planner_rt : control_rt).describe();
  if (!report.realtime && config.rt.on_failure == rtos::RtFailurePolicy::kRequire) {
    control_task.request_stop();
    planner_task.request_stop();
    control_task.join();
    planner_task.join();
    report.error = "real-time set-up refused: " + report.realtime_status;
    return false;
  }
  while (!done.load(std::memory_order_acquire) && !control_task.finished()) rtos::sleep_until_ns_rt(rtos::now_ns() + 50'000'000);
  control_task.request_stop();
  control_task.join();
  planner_task.request_stop();
  planner_task.join();
  report.control_overruns = control_task.perf().overruns;
  report.planner_overruns = planner_task.perf().overruns;
  report.rehearsals = planner.rehearsals;
  report.rehearsal_failures = planner.rehearsal_failures;
  report.control_rehearsals = dance.rehearsals;
  report.control_rehearsal_failures = dance.rehearsal_failures;
  report.control_skipped_periods = control_task.perf().skipped_periods;
  report.max_wake_latency_us = 1e-3 * static_cast<double>(control_task.perf().max_wake_latency_ns);

  if (config.stall_probe_s > 0.0) {
    StallProbeBody probe{&report.machine, period_ns / 2};
    rtos::PeriodicTask probe_task;
    rtos::PeriodicConfig probe_config = pc;
    probe_config.max_cycles = static_cast<std::uint64_t>(std::llround(config.stall_probe_s * 1e9 / static_cast<double>(period_ns)));
    (void)probe_task.start(probe_config, probe);  // the set-up the control task had (reported above)
    while (!probe_task.finished()) rtos::sleep_until_ns_rt(rtos::now_ns() + 50'000'000);
    probe_task.join();
    report.machine_wake_latency_us = 1e-3 * static_cast<double>(probe_task.perf().max_wake_latency_ns);
  }

  report.fault = firmware.mode.latched;
  report.danced_to_end = task.danced_until_ns >= 0 && report.fault == Fault::kNone;
  const double control_deadline_us = 1e-3 * static_cast<double>(period_ns);
  report.drivers = figures(drivers_us, control_deadline_us, motion_s);
  report.estimator = figures(estimator_us, control_deadline_us, motion_s);
  report.wbc = figures(wbc_us, control_deadline_us, motion_s);
  report.output = figures(output_us, control_deadline_us, motion_s);
  report.cycle = figures(cycle_us, control_deadline_us, motion_s);
  report.mpc = figures(mpc_us, 1e-3 * static_cast<double>(fw_config.planner_period_ns));
  return true;
}

std::string timing_table(const TimingReport& r, hal::TimeNs control_period_ns, hal::TimeNs planner_period_ns) {
  std::string out;
  char line[512];
  std::snprintf(line, sizeof line, "%-10s %8s %10s %10s %10s %10s %8s %8s %9s\n", "stage", "samples", "p50 us", "p99 us",
                "p99.99 us", "max us", "deadline", "misses", "max at s");
  out += line;
  const auto row = [&](const char* name, const StageFigures& f, hal::TimeNs deadline_ns) {
    char at[32] = "        -";
    if (f.max_at_s >= 0.0) std::snprintf(at, sizeof at, "%9.2f", f.max_at_s);
    std::snprintf(line, sizeof line, "%-10s %8llu %10.1f %10.1f %10.1f %10.1f %6.0fms %8llu %s\n", name,
                  static_cast<unsigned long long>(f.samples), f.p50_us, f.p99_us, f.p9999_us, f.max_us,
                  1e-6 * static_cast<double>(deadline_ns), static_cast<unsigned long long>(f.deadline_misses), at);
    out += line;
  };
  row("drivers", r.drivers, control_period_ns);
  row("estimator", r.estimator, control_period_ns);
  row("wbc", r.wbc, control_period_ns);
  row("output", r.output, control_period_ns);
  row("cycle", r.cycle, control_period_ns);
  row("mpc", r.mpc, planner_period_ns);
  std::snprintf(line, sizeof line,
                "control task: %llu overruns (%llu periods skipped), worst wake latency %.1f us, %llu rehearsals of the "
                "first tick before the dance (%llu failed); planning task: %llu overruns, "
                "%llu rehearsals of the opening before the dance (%llu failed)\n",
                static_cast<unsigned long long>(r.control_overruns),
                static_cast<unsigned long long>(r.control_skipped_periods), r.max_wake_latency_us,
                static_cast<unsigned long long>(r.control_rehearsals),
                static_cast<unsigned long long>(r.control_rehearsal_failures),
                static_cast<unsigned long long>(r.planner_overruns), static_cast<unsigned long long>(r.rehearsals),
                static_cast<unsigned long long>(r.rehearsal_failures));
  out += line;
  if (r.machine.reads > 0) {
    const auto& m = r.machine;
    std::snprintf(line, sizeof line,
                  "machine: spinning %.1f s on the control task's CPU and priority (half of each period), the CPU was "
                  "taken away for up to %.1f us (%llu times over 50 us, %llu over 150 us); wake latency up to %.1f us\n",
                  1e-9 * static_cast<double>(m.spun_ns), 1e-3 * static_cast<double>(m.max_gap_ns),
                  static_cast<unsigned long long>(m.gaps_over[1]), static_cast<unsigned long long>(m.gaps_over[3]),
                  r.machine_wake_latency_us);
    out += line;
  }
  return out;
}

}  // namespace kuavo::firmware
