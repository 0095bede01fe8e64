// Cost of the drivers' real-time pieces: codecs, supervisors, transmissions,
// MTi parsing and socketpair frame I/O (the kernel path of CAN_RAW differs,
// the user-space cost is the same).
//   build-drv/bench/drivers_bench --benchmark_min_time=0.2
#include <benchmark/benchmark.h>

#include <sys/socket.h>
#include <unistd.h>

#include <vector>

#include "drivers/can/can_port.h"
#include "drivers/bus/bus_plan.h"
#include "drivers/canopen/cia402_drive.h"
#include "drivers/canopen/pdo_layout.h"
#include "drivers/cycle/ruiwo_io.h"
#include "drivers/emulator/ruiwo_emulator.h"
#include "drivers/imu/mti_parser.h"
#include "drivers/ruiwo/ruiwo_codec.h"
#include "drivers/transmission/ankle_linkage.h"
#include "drivers/transmission/leg_transmission.h"

namespace kd = kuavo::drivers;

static void BM_RuiwoEncodePtm(benchmark::State& s) {
  kd::ruiwo::PtmCommand c{0.4, -1.0, 30, 2, 3.5};
  can_frame f;
  for (auto _ : s) {
    benchmark::DoNotOptimize(kd::ruiwo::encode_ptm_rt(5, c, f));
    benchmark::DoNotOptimize(f);
    c.position_rad += 1e-9;
  }
}
BENCHMARK(BM_RuiwoEncodePtm);

static void BM_RuiwoDecodeStatus(benchmark::State& s) {
  can_frame f;
  kd::ruiwo::encode_status_rt({3, 0.5, 1.0, -2.0, 30, 0}, f);
  kd::ruiwo::Status st;
  for (auto _ : s) {
    benchmark::DoNotOptimize(kd::ruiwo::decode_status_rt(f, st));
    benchmark::DoNotOptimize(st);
  }
}
BENCHMARK(BM_RuiwoDecodeStatus);

static void BM_CanopenTpdoDecode(benchmark::State& s) {
  can_frame f{};
  f.can_id = 0x183;
  f.len = 8;
  kd::canopen::TxPdo1 t;
  for (auto _ : s) {
    benchmark::DoNotOptimize(kd::canopen::decode_tpdo1_rt(f, 3, t));
    benchmark::DoNotOptimize(t);
  }
}
BENCHMARK(BM_CanopenTpdoDecode);

static void BM_Cia402DriveStep(benchmark::State& s) {
  kd::canopen::DriveConfig cfg;
  cfg.node_id = 3;
  cfg.rated_torque_Nm = 88.9;
  cfg.torque_limit_Nm = 127;
  kd::canopen::DriveState st;
  st.phase = kd::canopen::DrivePhase::kOperational;
  st.nmt = kd::canopen::NmtState::kOperational;
  st.power = kd::canopen::Cia402State::kOperationEnabled;
  kd::canopen::DriveCommand cmd{true, 12.0, 0.3};
  can_frame f;
  kuavo::hal::TimeNs now = 0;
  for (auto _ : s) {
    st.heartbeat_ns = now;
    st.tpdo1_ns = now;
    st.have_tpdo1 = true;
    benchmark::DoNotOptimize(kd::canopen::step_rt(cfg, st, now, cmd, f));
    now += 2'000'000;
  }
}
BENCHMARK(BM_Cia402DriveStep);

static void BM_AnkleJointToMotor(benchmark::State& s) {
  const kd::AnkleGeometry g = kd::make_left_ankle();
  kd::Vec2 q(-0.3, 0.1), m;
  for (auto _ : s) {
    benchmark::DoNotOptimize(kd::ankle_motor_from_joint_rt(g, q, m));
    benchmark::DoNotOptimize(m);
  }
}
BENCHMARK(BM_AnkleJointToMotor);

static void BM_AnkleMotorToJointWarm(benchmark::State& s) {
  const kd::AnkleGeometry g = kd::make_left_ankle();
  kd::Vec2 m;
  kd::ankle_motor_from_joint_rt(g, kd::Vec2(-0.3, 0.1), m);
  for (auto _ : s) {
    kd::Vec2 q(-0.301, 0.099);  // last cycle's solution, 1 mrad away
    benchmark::DoNotOptimize(kd::ankle_joint_from_motor_rt(g, m, q));
    benchmark::DoNotOptimize(q);
  }
}
BENCHMARK(BM_AnkleMotorToJointWarm);

static void BM_LegJointsFromMotors(benchmark::State& s) {
  const kd::LegTransmission t = kd::default_leg_transmission(true);
  std::array<kd::canopen::MotorSample, kd::kLegActuators> motors{};
  for (auto& m : motors) m.valid = true;
  std::array<kuavo::hal::JointSample, kd::kLegActuators> joints{};
  for (auto _ : s) {
    benchmark::DoNotOptimize(kd::leg_joints_from_motors_rt(t, motors, joints));
    benchmark::DoNotOptimize(joints);
  }
}
BENCHMARK(BM_LegJointsFromMotors);

static void BM_MtiParsePacket(benchmark::State& s) {
  // FA FF 36 LEN | quaternion, rate of turn, acceleration (float32) | CS
  std::vector<std::uint8_t> p{0xFA, 0xFF, 0x36, 0};
  auto item = [&](std::uint8_t hi, std::uint8_t lo, int floats, std::uint8_t first_byte) {
    p.push_back(hi);
    p.push_back(lo);
    p.push_back(static_cast<std::uint8_t>(4 * floats));
    for (int i = 0; i < 4 * floats; ++i) p.push_back(i == 0 ? first_byte : 0);
  };
  item(0x20, 0x10, 4, 0x3F);  // quaternion (1, 0, 0, 0): 0x3F800000
  p[8] = 0x80;
  item(0x80, 0x20, 3, 0);     // rate of turn
  item(0x40, 0x20, 3, 0);     // acceleration
  p[3] = static_cast<std::uint8_t>(p.size() - 4);
  unsigned sum = 0;
  for (std::size_t i = 1; i < p.size(); ++i) sum += p[i];
  p.push_back(static_cast<std::uint8_t>(-static_cast<int>(sum) & 0xFF));
  kd::mti::Parser parser;
  kd::mti::MtData2 d;
  for (auto _ : s) {
    std::size_t used = 0;
    benchmark::DoNotOptimize(kd::mti::parse_rt(parser, p.data(), p.size(), used, d));
  }
  if (parser.stats.packets != s.iterations()) s.SkipWithError("packet did not parse");
  s.SetBytesProcessed(static_cast<std::int64_t>(s.iterations() * p.size()));
}
BENCHMARK(BM_MtiParsePacket);

static void BM_SocketpairSendReceive(benchmark::State& s) {
  int fd[2];
  socketpair(AF_UNIX, SOCK_SEQPACKET, 0, fd);
  kd::CanPort tx = kd::attach_can_port(fd[0], false), rx = kd::attach_can_port(fd[1], false);
  can_frame f{};
  f.can_id = 0x123;
  f.len = 8;
  kd::RxFrame got;
  for (auto _ : s) {
    benchmark::DoNotOptimize(kd::send_rt(tx, f));
    benchmark::DoNotOptimize(kd::receive_rt(rx, got));
  }
  close(fd[0]);
  close(fd[1]);
}
BENCHMARK(BM_SocketpairSendReceive);

// A whole 8-motor Ruiwo bus cycle over a socketpair: commands out, the
// emulated boards answer (their cost is included), replies in, timeouts.
static void BM_RuiwoBusCycle8Motors(benchmark::State& s) {
  int fd[2];
  socketpair(AF_UNIX, SOCK_SEQPACKET, 0, fd);
  kd::CanPort host = kd::attach_can_port(fd[0], false), dev = kd::attach_can_port(fd[1], false);
  std::vector<kd::ruiwo::MotorConfig> motors;
  std::uint8_t ids[8];
  for (int i = 0; i < 8; ++i) {
    kd::ruiwo::MotorConfig m;
    m.motor_id = static_cast<std::uint8_t>(i + 1);
    m.joint = 13 + i;
    m.position_min_rad = -1.0;
    m.position_max_rad = 1.0;
    motors.push_back(m);
    ids[i] = m.motor_id;
  }
  kd::ruiwo::Bus bus;
  std::string msg;
  kd::ruiwo::build_bus(motors, bus, msg);
  kd::emulator::RuiwoEmulator emu;
  kd::emulator::init_ruiwo_emulator(emu, ids, 8);
  kuavo::hal::CommandFrame cmds;
  kuavo::hal::SensorFrame sensors;
  kuavo::hal::TimeNs now = 0;
  for (auto _ : s) {
    kd::ruiwo_send_rt(host, bus, cmds, now);
    kd::emulator::serve_rt(emu, dev);
    now += 4'000'000;
    benchmark::DoNotOptimize(kd::ruiwo_receive_rt(host, bus, now, 0, sensors));
  }
  close(fd[0]);
  close(fd[1]);
}
BENCHMARK(BM_RuiwoBusCycle8Motors);

// Start-up cost of the plan check; the counters are the default plan's
// worst-case load per bus in percent.
static void BM_DefaultBusPlanCheck(benchmark::State& s) {
  const kd::BusPlan plan = kd::default_bus_plan();
  kd::BusLoadReport report;
  std::string msg;
  for (auto _ : s) benchmark::DoNotOptimize(kd::check_bus_plan(plan, report, msg));
  for (std::size_t b = 0; b < plan.buses.size(); ++b) {
    s.counters[plan.buses[b].interface + "_load_pct"] = 100.0 * report.load[b];
  }
}
BENCHMARK(BM_DefaultBusPlanCheck);

BENCHMARK_MAIN();
