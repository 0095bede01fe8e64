// Seeded fuzzing of every decoder: random and mutated CAN frames into the
// Ruiwo, CANopen and error-frame decoders and the supervisors that consume
// them; random and mutated byte streams into the MTi parser. Passing means no
// crash (run under ASan/UBSan to catch memory errors) and invariants held.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "controllers/model/model.h"
#include "drivers/can/bus_health.h"
#include "drivers/canopen/canopen_frames.h"
#include "drivers/canopen/cia402_drive.h"
#include "drivers/canopen/pdo_layout.h"
#include "drivers/imu/mti_parser.h"
#include "drivers/ruiwo/ruiwo_bus.h"
#include "drivers/ruiwo/ruiwo_codec.h"

namespace kuavo::drivers {
namespace {

constexpr int kIterations = 200'000;

can_frame random_frame(std::mt19937& rng) {
  can_frame f{};
  // Bias IDs toward the interesting ranges so decoders go past the ID check.
  const std::uint32_t bases[] = {0x000, 0x080, 0x180, 0x280, 0x580, 0x700, 0x000};
  f.can_id = (bases[rng() % 7] + rng() % 0x80) & CAN_SFF_MASK;
  if (rng() % 16 == 0) f.can_id |= CAN_RTR_FLAG;
  if (rng() % 16 == 0) f.can_id |= CAN_ERR_FLAG;
  if (rng() % 32 == 0) f.can_id = (rng() & CAN_EFF_MASK) | CAN_EFF_FLAG;
  f.len = static_cast<std::uint8_t>(rng() % 16);  // includes illegal lengths > 8
  for (auto& b : f.data) b = static_cast<std::uint8_t>(rng());
  return f;
}

TEST(DecoderFuzz, CanDecodersAndConsumers) {
  std::mt19937 rng(20240601);
  model::Model m;
  ASSERT_EQ(model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, m), model::ModelError::kOk);
  ruiwo::Bus bus;
  std::string msg;
  ASSERT_EQ(ruiwo::build_bus(ruiwo::default_motors(m), bus, msg), DriverError::kOk);
  hal::SensorFrame sensors;
  canopen::DriveConfig cfg;
  cfg.node_id = 3;
  cfg.rated_torque_Nm = 10;
  cfg.torque_limit_Nm = 20;
  canopen::DriveState st;
  can_frame boot;
  canopen::start_drive(cfg, st, 0, boot);
  BusHealth health;
  int decoded = 0;
  for (int i = 0; i < kIterations; ++i) {
    const can_frame f = random_frame(rng);
    ruiwo::Status s;
    if (ruiwo::decode_status_rt(f, s) == DriverError::kOk) {
      ++decoded;
      EXPECT_TRUE(std::isfinite(s.position_rad) && std::abs(s.position_rad) <= 12.5);
      EXPECT_TRUE(std::abs(s.velocity_rad_s) <= 10.0 && std::abs(s.torque_Nm) <= 50.0);
    }
    ruiwo::PtmCommand c;
    (void)ruiwo::decode_ptm_rt(f, c);
    (void)ruiwo::handle_reply_rt(bus, f, i, sensors);
    std::uint8_t node;
    canopen::NmtState nmt;
    (void)canopen::decode_heartbeat_rt(f, node, nmt);
    std::uint32_t abort_code;
    (void)canopen::decode_sdo_reply_rt(f, 3, canopen::SdoWrite{0x6060, 0, 1, 10}, abort_code);
    canopen::Emergency em;
    (void)canopen::decode_emergency_rt(f, em);
    canopen::TxPdo1 t1;
    canopen::TxPdo2 t2;
    (void)canopen::decode_tpdo1_rt(f, 3, t1);
    (void)canopen::decode_tpdo2_rt(f, 3, t2);
    (void)canopen::handle_frame_rt(cfg, st, f, i);
    can_frame out;
    canopen::DriveCommand cmd;
    cmd.enable = true;
    cmd.torque_Nm = std::uniform_real_distribution<double>(-100, 100)(rng);
    if (canopen::step_rt(cfg, st, i * 1000, cmd, out) && (out.can_id & 0x780) == 0x200) {
      // Whatever the drive said, the torque sent stays inside the limit.
      const auto pm = static_cast<std::int16_t>(canopen::get_u16(&out.data[2]));
      EXPECT_LE(std::abs(pm * cfg.rated_torque_Nm / 1000.0), cfg.torque_limit_Nm + 1e-9);
    }
    if (st.phase == canopen::DrivePhase::kFailed) canopen::start_drive(cfg, st, i * 1000, boot);
    apply_error_frame_rt(f, health);
  }
  for (const auto& j : sensors.joints) EXPECT_TRUE(std::isfinite(j.position_rad));
  EXPECT_GT(decoded, 1000);  // the fuzzer did reach the payload decoding
}

TEST(DecoderFuzz, MtiParserOnRandomAndMutatedStreams) {
  std::mt19937 rng(77);
  // A valid packet to mutate: FA FF 36 LEN items CS.
  std::vector<std::uint8_t> valid{0xFA, 0xFF, 0x36, 0x00};
  const std::uint8_t items[] = {0x20, 0x10, 0x10, 0x3F, 0x80, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
                                0x80, 0x20, 0x0C, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
                                0x40, 0x20, 0x0C, 0, 0, 0, 0, 0, 0, 0, 0, 0x41, 0x1C, 0xF5, 0xC3};
  valid.insert(valid.end(), std::begin(items), std::end(items));
  valid[3] = static_cast<std::uint8_t>(sizeof(items));
  unsigned sum = 0;
  for (std::size_t i = 1; i < valid.size(); ++i) sum += valid[i];
  valid.push_back(static_cast<std::uint8_t>(-static_cast<int>(sum) & 0xFF));

  mti::Parser p;
  std::vector<std::uint8_t> chunk;
  std::uint32_t packets = 0;
  for (int i = 0; i < kIterations / 20; ++i) {
    chunk.clear();
    if (rng() % 2) {
      chunk = valid;
      const int flips = static_cast<int>(rng() % 3);
      for (int k = 0; k < flips; ++k) chunk[rng() % chunk.size()] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
    } else {
      const int n = static_cast<int>(rng() % 64);
      for (int k = 0; k < n; ++k) chunk.push_back(rng() % 4 == 0 ? 0xFA : static_cast<std::uint8_t>(rng()));
    }
    std::size_t pos = 0;
    while (pos < chunk.size()) {
      std::size_t used = 0;
      mti::MtData2 d;
      if (mti::parse_rt(p, chunk.data() + pos, chunk.size() - pos, used, d) == DriverError::kOk) {
        ++packets;
        hal::ImuSample s;
        if (mti::to_imu_sample(d, 0, s) == DriverError::kOk) {
          for (double v : s.orientation_xyzw) EXPECT_TRUE(std::isfinite(v));
        }
      }
      ASSERT_LE(p.len, static_cast<int>(p.buf.size()));
      ASSERT_GE(p.len, 0);
      pos += used;
    }
    std::uint8_t raw[80];
    const int n = static_cast<int>(rng() % sizeof(raw));
    for (int k = 0; k < n; ++k) raw[k] = static_cast<std::uint8_t>(rng());
    mti::MtData2 d;
    (void)mti::decode_mtdata2_rt(raw, n, d);
  }
  EXPECT_EQ(p.stats.packets, packets);
  EXPECT_GT(packets, 100u);  // unmutated copies still parse amid the noise
}

}  // namespace
}  // namespace kuavo::drivers
