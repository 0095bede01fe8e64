#include "tests/fuzz/fuzz_inputs.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <exception>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/standing/standing_controller.h"
#include "drivers/config/drivers_config.h"
#include "drivers/config/drivers_config_json.h"
#include "rtos_shim/args.h"
#include "tools/mocap/bvh.h"
#include "tools/mocap/motion_file.h"

namespace kuavo::fuzz {
namespace {

std::size_t pick(Rng& rng, std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(rng() % n); }

template <typename T>
const T& pick_of(Rng& rng, const std::vector<T>& v) {
  return v[pick(rng, v.size())];
}

std::string slurp(const std::string& path, bool& ok) {
  std::ifstream in(path, std::ios::binary);
  ok = static_cast<bool>(in);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Numbers as they appear in text: where a run of [0-9.eE+-] starting with a digit, a sign or
// a point begins and ends.
std::vector<std::pair<std::size_t, std::size_t>> number_spans(const std::string& s, std::size_t from) {
  std::vector<std::pair<std::size_t, std::size_t>> spans;
  std::size_t i = from;
  while (i < s.size()) {
    const char c = s[i];
    const bool starts = std::isdigit(static_cast<unsigned char>(c)) || ((c == '-' || c == '.') && i + 1 < s.size() &&
                                                                       std::isdigit(static_cast<unsigned char>(s[i + 1])));
    if (!starts || (i > 0 && std::isalnum(static_cast<unsigned char>(s[i - 1])))) {
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    while (j < s.size() && (std::isdigit(static_cast<unsigned char>(s[j])) || s[j] == '.' || s[j] == 'e' || s[j] == 'E' ||
                            ((s[j] == '-' || s[j] == '+') && (s[j - 1] == 'e' || s[j - 1] == 'E')))) {
      ++j;
    }
    spans.emplace_back(i, j);
    i = j;
  }
  return spans;
}

void put_u32(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) {
  if (at + 4 > b.size()) return;
  for (int i = 0; i < 4; ++i) b[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
}

void recompute_checksums(std::vector<std::uint8_t>& b) {
  if (b.size() < mocap::kMotionHeaderBytes) return;
  const std::size_t frames = mocap::motion_get_u32(b.data() + 32);
  const std::size_t available = (b.size() - mocap::kMotionHeaderBytes) / mocap::kMotionRecordBytes;
  const std::size_t payload = std::min(frames, available) * mocap::kMotionRecordBytes;
  put_u32(b, mocap::kMotionPayloadCrcOffset, mocap::crc32(b.data() + mocap::kMotionHeaderBytes, payload));
  put_u32(b, mocap::kMotionHeaderCrcOffset, mocap::motion_header_crc(b.data()));
}

std::string describe_exception() {
  try {
    throw;
  } catch (const std::exception& e) {
    return std::string("exception: ") + e.what();
  } catch (...) {
    return "exception of unknown type";
  }
}

}  // namespace

std::uint64_t case_seed(std::uint64_t seed, std::uint64_t index) {
  std::uint64_t z = seed * 0x9E3779B97F4A7C15ull + index + 0x632BE59BD9B4E019ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

const std::vector<std::string>& hostile_numbers() {
  static const std::vector<std::string> v = {
      "nan", "NaN", "inf", "-inf", "1e308", "-1e308", "1e999", "-1e999", "1e-320", "4.9e-324", "0", "-0", "-1",
      "0.5", "1", "2", "7", "100", "600", "601", "1e9", "99999999999999999999999", "18446744073709551615",
      "18446744073709551616", "-9223372036854775809", "2147483648", "5x", "5abc", " 5", "5 ", "", "0x10", "1e",
      ".", "-", "+", "1,5", "1.5.5", "00000000000000000000000000001", "1e-9", "0.2", "1.4", "10", "0.25", "1e-4"};
  return v;
}

bool load_corpus(const std::string& shared_dir, Corpus& corpus, std::string& error) {
  if (model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, corpus.robot) != model::ModelError::kOk) {
    error = "model: cannot build";
    return false;
  }
  for (const char* name : {"cmu_05_20_mb.bvh", "cmu_05_07_iclone_ccrig.bvh", "perfume_C_test.bvh"}) {
    bool ok = false;
    std::string text = slurp(shared_dir + "/mocap/" + name, ok);
    if (!ok || text.empty()) {
      error = shared_dir + "/mocap/" + name + ": cannot read";
      return false;
    }
    corpus.bvh_names.push_back(name);
    corpus.bvh_clips.push_back(std::move(text));
  }
  // The motion: standing, the arms swaying within their limits (so a small shift can cross one).
  const model::Model& robot = corpus.robot;
  auto data = std::make_unique<dynamics::Data>();
  dynamics::ConfigVector q0 = dynamics::neutral_configuration(robot);
  q0.tail<model::kNumJoints>() = control::centred_standing_pose(robot, *data, 0.78);
  control::place_on_ground(robot, *data, q0);
  std::vector<dynamics::ConfigVector> q(60, q0);
  for (std::size_t f = 0; f < q.size(); ++f) {
    for (int j = model::kLeftArmFirst; j < model::kNumJoints; ++j) {
      const double lo = robot.limits.position_min_rad[j] + 0.01, hi = robot.limits.position_max_rad[j] - 0.01;
      q[f][7 + j] = std::clamp(q0[7 + j] + 0.2 * std::sin(0.1 * static_cast<double>(f) + j), lo, hi);
    }
  }
  const std::vector<mocap::ContactLabel> labels(q.size(), mocap::ContactLabel::kDoubleSupport);
  corpus.motion = mocap::encode_motion(robot, 100.0, q, labels);

  // The drivers overlay: every key, with the defaults' values.
  const drivers::DriversConfig c = drivers::default_drivers_config(robot);
  nlohmann::ordered_json j;
  j["buses"] = nlohmann::ordered_json::array();
  for (const drivers::BusConfig& b : c.plan.buses) {
    j["buses"].push_back({{"interface", b.interface},
                          {"bitrate_bps", b.bitrate_bps},
                          {"fd", b.fd},
                          {"data_bitrate_bps", b.data_bitrate_bps},
                          {"cycle_rate_hz", b.cycle_rate_hz},
                          {"heartbeat_rate_hz", b.heartbeat_rate_hz}});
  }
  j["devices"] = nlohmann::ordered_json::array();
  for (const drivers::DeviceConfig& d : c.plan.devices) {
    j["devices"].push_back({{"bus", d.bus},
                            {"kind", d.kind == drivers::DeviceKind::kRuiwoMotor ? "ruiwo" : "cia402"},
                            {"id", d.id},
                            {"slot", d.slot}});
  }
  j["ruiwo_motors"] = nlohmann::ordered_json::array();
  for (const auto& m : c.ruiwo_motors) {
    j["ruiwo_motors"].push_back({{"id", m.motor_id},
                                 {"sign", m.sign},
                                 {"zero_offset_rad", m.zero_offset_rad},
                                 {"torque_max_Nm", m.torque_max_Nm},
                                 {"velocity_max_rad_s", m.velocity_max_rad_s}});
  }
  j["drives"] = nlohmann::ordered_json::array();
  for (const drivers::DriveEntry& e : c.drives) {
    j["drives"].push_back({{"slot", e.slot},
                           {"counts_per_rev", e.config.counts_per_rev},
                           {"rated_torque_Nm", e.config.rated_torque_Nm},
                           {"torque_limit_Nm", e.config.torque_limit_Nm}});
  }
  j["knee_ratio_motor_per_joint"] = c.legs[0].serial[3].ratio_motor_per_joint;
  j["ankle_motor_offset_rad"] = {c.legs[0].ankle_motor[0].motor_offset_rad, c.legs[0].ankle_motor[1].motor_offset_rad};
  j["imu"] = {{"device", c.imu_device}, {"baud", c.imu_baud}};
  corpus.config_json = j.dump(2) + "\n";
  const std::string why = check_config_text(corpus.config_json, robot);
  drivers::DriversConfig probe = drivers::default_drivers_config(robot);
  drivers::BusLoadReport report;
  if (drivers::apply_drivers_json(corpus.config_json, probe, error) != drivers::DriverError::kOk ||
      drivers::validate_drivers_config(probe, report, error) != drivers::DriverError::kOk || !why.empty()) {
    error = "the base drivers overlay is not valid: " + error + why;
    return false;
  }
  return true;
}

std::string mutate_bvh(const std::string& clip, int max_frames, Rng& rng) {
  // Cut to the header and the first frames (found in place: the clips are up to 1.8 MB).
  std::string s;
  const std::size_t motion_at = clip.find("MOTION");
  const std::size_t frames_at = clip.find("Frames:", motion_at == std::string::npos ? 0 : motion_at);
  const std::size_t time_at = clip.find("Frame Time:", frames_at == std::string::npos ? 0 : frames_at);
  if (frames_at != std::string::npos && time_at != std::string::npos) {
    const std::size_t data_at = clip.find('\n', time_at);
    const int keep = 1 + static_cast<int>(pick(rng, static_cast<std::size_t>(std::max(1, max_frames))));
    std::size_t end = data_at == std::string::npos ? clip.size() : data_at + 1;
    int kept = 0;
    while (kept < keep && end < clip.size()) {
      const std::size_t nl = clip.find('\n', end);
      end = nl == std::string::npos ? clip.size() : nl + 1;
      ++kept;
    }
    s = clip.substr(0, end);
    const std::size_t line_end = s.find('\n', frames_at);
    s.replace(frames_at, line_end - frames_at, "Frames: " + std::to_string(kept) + (s[line_end - 1] == '\r' ? "\r" : ""));
  } else {
    s = clip.substr(0, std::min<std::size_t>(clip.size(), 100000));
  }
  const int mutations = 1 + static_cast<int>(pick(rng, 3));
  for (int m = 0; m < mutations && !s.empty(); ++m) {
    switch (pick(rng, 10)) {
      case 0:  // a byte flipped
        s[pick(rng, s.size())] = static_cast<char>(rng());
        break;
      case 1:  // a byte inserted or deleted
        if (rng() % 2) s.insert(s.begin() + static_cast<std::ptrdiff_t>(pick(rng, s.size())), static_cast<char>(rng()));
        else s.erase(pick(rng, s.size()), 1);
        break;
      case 2:
      case 3: {  // a number replaced (offsets and channel values most of all)
        const auto spans = number_spans(s, pick(rng, 2) ? 0 : s.size() / 2);
        if (spans.empty()) break;
        const auto [a, b] = spans[pick(rng, spans.size())];
        s.replace(a, b - a, pick_of(rng, hostile_numbers()));
        break;
      }
      case 4: {  // line endings: CRLF, CR only, or mixed; a byte-order mark
        const int how = static_cast<int>(pick(rng, 4));
        if (how == 3) {
          s.insert(0, "\xEF\xBB\xBF");
          break;
        }
        std::string t;
        t.reserve(s.size() + s.size() / 8);
        for (char c : s) {
          if (c == '\n' && (how == 0 || (how == 2 && rng() % 2))) t += "\r\n";
          else if (c == '\n' && how == 1) t += '\r';
          else t += c;
        }
        s = std::move(t);
        break;
      }
      case 5: {  // a line duplicated or dropped
        const std::size_t at = s.rfind('\n', pick(rng, s.size()));
        const std::size_t from = at == std::string::npos ? 0 : at + 1;
        const std::size_t to = s.find('\n', from);
        const std::string line = s.substr(from, (to == std::string::npos ? s.size() : to + 1) - from);
        if (rng() % 2) s.insert(from, line);
        else s.erase(from, line.size());
        break;
      }
      case 6: {  // Frames forged
        const std::size_t at = s.find("Frames:");
        if (at == std::string::npos) break;
        const std::size_t end = s.find_first_of("\r\n", at);
        const char* counts[] = {"0", "-1", "1", "2", "1000000", "2147483647", "99999999999", "nan", ""};
        s.replace(at, (end == std::string::npos ? s.size() : end) - at, std::string("Frames: ") + counts[pick(rng, 9)]);
        break;
      }
      case 7: {  // Frame Time forged
        const std::size_t at = s.find("Frame Time:");
        if (at == std::string::npos) break;
        const std::size_t end = s.find_first_of("\r\n", at);
        s.replace(at, (end == std::string::npos ? s.size() : end) - at, "Frame Time: " + pick_of(rng, hostile_numbers()));
        break;
      }
      case 8: {  // garbage or the clip's own hierarchy appended
        if (rng() % 2) s += s.substr(0, std::min<std::size_t>(s.size(), 200 + pick(rng, 2000)));
        else s.append(1 + pick(rng, 64), static_cast<char>(rng()));
        break;
      }
      default: {  // a hierarchy keyword damaged
        const char* words[] = {"OFFSET", "CHANNELS", "JOINT", "End Site", "{", "}", "ROOT", "HIERARCHY", "MOTION"};
        const std::string w = words[pick(rng, 9)];
        const std::size_t at = s.find(w, pick(rng, s.size() / 2 + 1));
        if (at == std::string::npos) break;
        const char* repl[] = {"", "XX", "{", "}", "JOINT J", "CHANNELS 99999", "CHANNELS -1", "OFFSET 1 2"};
        s.replace(at, w.size(), repl[pick(rng, 8)]);
        break;
      }
    }
  }
  return s;
}

std::vector<std::uint8_t> mutate_motion(const std::vector<std::uint8_t>& good, Rng& rng) {
  std::vector<std::uint8_t> b = good;
  const std::size_t frames = (good.size() - mocap::kMotionHeaderBytes) / mocap::kMotionRecordBytes;
  static const double specials[] = {std::nan(""), INFINITY, -INFINITY, 1e308, -1e308, 100.0, -100.0, 0.0,
                                    2.6, -0.01, 1e-320, 0.1, 2.0, 50.0, 1.0 + 1e-7};
  const int mutations = 1 + static_cast<int>(pick(rng, 3));
  for (int m = 0; m < mutations; ++m) {
    const std::size_t frame = pick(rng, frames), value = pick(rng, model::kNq);
    const std::size_t at = mocap::kMotionHeaderBytes + frame * mocap::kMotionRecordBytes + 8 * value;
    switch (pick(rng, 7)) {
      case 0:  // a special value
        if (at + 8 <= b.size()) std::memcpy(&b[at], &specials[pick(rng, std::size(specials))], 8);
        break;
      case 1: {  // a small change (stays plausible or just crosses a limit)
        if (at + 8 > b.size()) break;
        double v;
        std::memcpy(&v, &b[at], 8);
        v += std::uniform_real_distribution<double>(-3.0, 3.0)(rng);
        std::memcpy(&b[at], &v, 8);
        break;
      }
      case 2:  // a random byte anywhere
        b[pick(rng, b.size())] = static_cast<std::uint8_t>(rng());
        break;
      case 3:  // bytes appended (garbage, or the file once more) or cut
        if (rng() % 3 == 0) b.resize(pick(rng, b.size()));
        else if (rng() % 2) b.insert(b.end(), good.begin(), good.end());
        else b.resize(b.size() + 1 + pick(rng, 300), static_cast<std::uint8_t>(rng()));
        break;
      case 4:  // a frame count that lies
        put_u32(b, 32, static_cast<std::uint32_t>(rng() % 2 ? pick(rng, 130) : rng()));
        break;
      case 5: {  // a header field: version, variant, rate, counts, a joint name
        if (b.size() < mocap::kMotionHeaderBytes) break;
        const std::size_t field = 8 + pick(rng, mocap::kMotionFixedHeaderBytes - 8);
        if (rng() % 2) {
          b[field] = static_cast<std::uint8_t>(rng());
        } else {
          const double rate = specials[pick(rng, std::size(specials))];
          std::memcpy(&b[24], &rate, 8);  // the frame rate [Hz]
        }
        break;
      }
      default: {  // a contact label byte
        const std::size_t label_at = mocap::kMotionHeaderBytes + frame * mocap::kMotionRecordBytes + 8 * model::kNq;
        if (label_at < b.size()) b[label_at] = static_cast<std::uint8_t>(rng() % 6);
        break;
      }
    }
  }
  recompute_checksums(b);
  return b;
}

std::string mutate_config(const std::string& good, Rng& rng) {
  nlohmann::ordered_json j = nlohmann::ordered_json::parse(good);
  std::string text;
  const int mutations = 1 + static_cast<int>(pick(rng, 3));
  for (int m = 0; m < mutations; ++m) {
    const nlohmann::ordered_json flat = j.is_structured() ? j.flatten() : nlohmann::ordered_json::object();
    std::vector<std::string> leaves;
    for (auto it = flat.begin(); it != flat.end(); ++it) leaves.push_back(it.key());
    const std::size_t kind = pick(rng, 10);
    if (kind >= 8 && !leaves.empty()) {  // a number scaled by 0.5..2 (often still plausible)
      const nlohmann::ordered_json::json_pointer p(pick_of(rng, leaves));
      nlohmann::ordered_json& v = j[p];
      if (v.is_number_float()) v = v.get<double>() * std::uniform_real_distribution<double>(0.5, 2.0)(rng);
      else if (v.is_number_integer()) v = v.get<long long>() + static_cast<long long>(pick(rng, 5)) - 2;
    } else if (kind <= 2 && !leaves.empty()) {  // a leaf set to a hostile value
      const nlohmann::ordered_json::json_pointer p(pick_of(rng, leaves));
      static const std::vector<nlohmann::ordered_json> values = {
          1e308, -1e308, -1, 0, 0.5, 1e-320, 1e9, 2147483648.0, -2147483649.0, 255, 256, 128, 65536, "x", "",
          std::string("/dev/ttyUSB0\0/etc/passwd", 24), "ttyUSB0", "/", nullptr, true,
          nlohmann::ordered_json::array(), nlohmann::ordered_json::object(), nlohmann::ordered_json::array({1, 2, 3}),
          0.02, 1000, 1e6, 8e6, 4000000, 115200, 3, -0.0};
      try {
        j[p] = values[pick(rng, values.size())];
      } catch (const std::exception&) {
      }
    } else if (kind == 3 && !leaves.empty()) {  // a key dropped (an array element or an object member)
      nlohmann::ordered_json::json_pointer p(pick_of(rng, leaves));
      if (rng() % 2 && !p.empty()) p = p.parent_pointer();
      if (!p.empty()) {
        const std::string last = p.back();
        nlohmann::ordered_json::json_pointer parent = p.parent_pointer();
        try {
          nlohmann::ordered_json& container = j[parent];
          if (container.is_object()) container.erase(last);
          else if (container.is_array() && !container.empty()) container.erase(std::min<std::size_t>(std::stoul(last), container.size() - 1));
        } catch (const std::exception&) {
        }
      }
    } else if (kind == 4) {  // a key added or misspelt
      const char* keys[] = {"bussses", "imu", "drives", "extra", "knee_ratio_motor_per_joint"};
      j[keys[pick(rng, 5)]] = pick(rng, 2) ? nlohmann::ordered_json(1.0) : nlohmann::ordered_json::array();
    } else {
      text = j.dump(static_cast<int>(pick(rng, 3)) - 1);
      switch (kind) {
        case 5: {  // a key given twice (the text repeats a member)
          const std::size_t at = text.find("\"imu\"");
          if (at != std::string::npos) text.insert(at, R"("imu": {"device": "/dev/ttyS0", "baud": 115200}, )");
          break;
        }
        case 6: {  // deep nesting, where a value stands
          const std::size_t depth = 1 + pick(rng, rng() % 4 == 0 ? 100000 : 200);
          const std::size_t at = text.find(':', pick(rng, text.size()));
          if (at != std::string::npos) text.insert(at + 1, std::string(depth, '[') + "1" + std::string(depth, ']') + ",");
          break;
        }
        default:  // text damage: truncation, bytes, a huge literal
          if (rng() % 3 == 0) text.resize(pick(rng, text.size()));
          else if (rng() % 2) text[pick(rng, text.size())] = static_cast<char>(rng());
          else {
            const auto spans = number_spans(text, 0);
            if (!spans.empty()) {
              const auto [a, b] = spans[pick(rng, spans.size())];
              text.replace(a, b - a, pick_of(rng, hostile_numbers()));
            }
          }
          break;
      }
      return text;  // text-level damage ends the case (the text may no longer parse)
    }
  }
  return j.dump(2);
}

std::vector<std::string> mutate_command_line(const std::vector<std::string>& fixed, const std::vector<std::string>& base,
                                             const std::vector<std::string>& options,
                                             const std::vector<std::string>& values, Rng& rng) {
  std::vector<std::string> t = base;
  auto any_value = [&]() -> const std::string& {
    return rng() % 3 ? pick_of(rng, values) : pick_of(rng, hostile_numbers());
  };
  const int mutations = 1 + static_cast<int>(pick(rng, 2));
  for (int m = 0; m < mutations; ++m) {
    switch (pick(rng, 6)) {
      case 0:  // a token replaced by a value
        if (!t.empty()) t[pick(rng, t.size())] = any_value();
        break;
      case 1:  // a token dropped (a missing value, a lost option)
        if (!t.empty()) t.erase(t.begin() + static_cast<std::ptrdiff_t>(pick(rng, t.size())));
        break;
      case 2:
      case 3: {  // an option inserted with a value (or without)
        const std::size_t at = pick(rng, t.size() + 1);
        std::vector<std::string> ins = {pick_of(rng, options)};
        if (rng() % 4 != 0) ins.push_back(any_value());
        t.insert(t.begin() + static_cast<std::ptrdiff_t>(at), ins.begin(), ins.end());
        break;
      }
      case 4:  // a token repeated
        if (!t.empty()) {
          const std::size_t i = pick(rng, t.size());
          t.insert(t.begin() + static_cast<std::ptrdiff_t>(pick(rng, t.size() + 1)), t[i]);
        }
        break;
      default:  // two tokens swapped
        if (t.size() >= 2) std::swap(t[pick(rng, t.size())], t[pick(rng, t.size())]);
        break;
    }
  }
  std::vector<std::string> out = fixed;
  out.insert(out.end(), t.begin(), t.end());
  return out;
}

std::string check_bvh_text(const std::string& text) {
  try {
    mocap::Bvh bvh;
    std::string error;
    if (!mocap::parse_bvh(text, bvh, error)) return error.empty() ? "refused without a message" : "";
    if (bvh.frame_count < 1 || bvh.channel_count < 0 ||
        bvh.motion.size() != static_cast<std::size_t>(bvh.frame_count) * static_cast<std::size_t>(bvh.channel_count)) {
      return "accepted with inconsistent frame and channel counts";
    }
    if (!(bvh.frame_time_s >= mocap::kBvhMinFrameTime_s && bvh.frame_time_s <= mocap::kBvhMaxFrameTime_s)) {
      return "accepted a frame time of " + std::to_string(bvh.frame_time_s) + " s";
    }
    if (!((bvh.frame_count - 1) * bvh.frame_time_s <= mocap::kBvhMaxDuration_s)) return "accepted a motion too long";
    for (const mocap::BvhJoint& j : bvh.joints) {
      if (!j.offset.allFinite() || j.offset.cwiseAbs().maxCoeff() > mocap::kBvhMaxLength) return "accepted an absurd OFFSET";
      for (std::size_t c = 0; c < j.channels.size(); ++c) {
        const bool angle = j.channels[c] >= mocap::BvhChannel::kXrotation;
        for (int f = 0; f < bvh.frame_count; ++f) {
          const double v = bvh.row(f)[j.first_column + static_cast<int>(c)];
          if (!std::isfinite(v) || std::abs(v) > (angle ? mocap::kBvhMaxAngle_deg : mocap::kBvhMaxLength)) {
            return "accepted channel value " + std::to_string(v) + " of joint " + j.name;
          }
        }
      }
    }
    return "";
  } catch (...) {
    return describe_exception();
  }
}

std::string check_motion_bytes(const std::vector<std::uint8_t>& bytes, const model::Model& robot) {
  try {
    mocap::MotionHeader h;
    if (mocap::read_motion_header(bytes.data(), bytes.size(), robot, h) != mocap::MotionError::kOk) return "";
    if (bytes.size() != mocap::kMotionHeaderBytes + static_cast<std::size_t>(h.frame_count) * mocap::kMotionRecordBytes) {
      return "accepted a file of " + std::to_string(bytes.size()) + " bytes for " + std::to_string(h.frame_count) + " frames";
    }
    if (!(std::isfinite(h.rate_hz) && h.rate_hz > 0.0 && h.rate_hz <= 1000.0)) return "accepted a rate of " + std::to_string(h.rate_hz);
    for (std::uint32_t f = 0; f < h.frame_count; ++f) {
      dynamics::ConfigVector q;
      mocap::ContactLabel label;
      int joint = -1;
      if (mocap::read_motion_frame(bytes.data(), bytes.size(), f, q, label) != mocap::MotionError::kOk ||
          mocap::check_motion_frame(robot, q, joint) != mocap::MotionError::kOk) {
        return "";  // refused (by the frame rules every loader applies)
      }
      if (!q.allFinite()) return "accepted a non-finite value in frame " + std::to_string(f);
      if (std::abs(q.segment<4>(3).norm() - 1.0) > 1e-6) return "accepted a non-unit quaternion in frame " + std::to_string(f);
      if (!(q[2] >= 0.1 && q[2] <= 2.0) || std::abs(q[0]) > 50.0 || std::abs(q[1]) > 50.0) {
        return "accepted a base off the stage in frame " + std::to_string(f);
      }
      for (int j = 0; j < model::kNumJoints; ++j) {
        if (q[7 + j] < robot.limits.position_min_rad[j] - 1e-6 || q[7 + j] > robot.limits.position_max_rad[j] + 1e-6) {
          return "accepted joint " + std::to_string(j) + " at " + std::to_string(q[7 + j]) + " rad in frame " + std::to_string(f);
        }
      }
    }
    return "";
  } catch (...) {
    return describe_exception();
  }
}

std::string check_config_text(const std::string& text, const model::Model& robot) {
  try {
    drivers::DriversConfig c = drivers::default_drivers_config(robot);
    std::string message;
    if (drivers::apply_drivers_json(text, c, message) != drivers::DriverError::kOk) {
      return message.empty() ? "refused without a message" : "";
    }
    drivers::BusLoadReport report;
    if (drivers::validate_drivers_config(c, report, message) != drivers::DriverError::kOk) {
      return message.empty() ? "refused without a message" : "";
    }
    for (const drivers::BusConfig& b : c.plan.buses) {
      if (!std::isfinite(b.bitrate_bps + b.data_bitrate_bps + b.cycle_rate_hz + b.heartbeat_rate_hz)) return "accepted a non-finite bus rate";
    }
    for (double load : report.load)
      if (!(load >= 0.0 && load <= 0.7)) return "accepted a bus load of " + std::to_string(load);
    for (const auto& m : c.ruiwo_motors) {
      if (!std::isfinite(m.zero_offset_rad) || !(m.torque_max_Nm > 0.0 && m.torque_max_Nm <= 50.0) ||
          !(m.velocity_max_rad_s > 0.0 && m.velocity_max_rad_s <= 10.0)) {
        return "accepted Ruiwo motor " + std::to_string(m.motor_id) + " limits outside the wire's";
      }
    }
    for (const drivers::DriveEntry& e : c.drives) {
      if (!(e.config.counts_per_rev >= 1024.0) || !(e.config.torque_limit_Nm > 0.0 && e.config.torque_limit_Nm <= 1000.0)) {
        return "accepted drive slot " + std::to_string(e.slot) + " numbers outside their ranges";
      }
    }
    for (const drivers::LegTransmission& t : c.legs) {
      for (const drivers::LinearTransmission& s : t.serial) {
        if (!std::isfinite(s.ratio_motor_per_joint) || !std::isfinite(s.motor_offset_rad) || std::abs(s.ratio_motor_per_joint) < 0.01) {
          return "accepted a leg transmission ratio or offset outside its range";
        }
      }
    }
    if (c.imu_device.empty() || c.imu_device[0] != '/' || c.imu_device.find('\0') != std::string::npos) return "accepted IMU path";
    return "";
  } catch (...) {
    return describe_exception();
  }
}

std::string check_argument_tokens(const std::vector<std::string>& tokens) {
  try {
    double seconds = 0.0, ms = 0.0;
    long long steps = 0;
    std::uint64_t seed = 0;
    std::string ground, text, out;
    bool flag = false;
    std::vector<std::string> positionals;
    args::Parser p("fuzz");
    p.number("--stand", "SECONDS", 0.0, 600.0, "s", &seconds, true).modes = 1;
    p.number("--plan-latency-ms", "MS", 0.0, 18.0, "ms", &ms);
    p.integer("--step-in-place", "STEPS", 1, 200, "steps", &steps).modes = 2;
    p.uint64("--seed", "N", &seed);
    p.choice("--ground", {"floor", "carpet"}, &ground);
    p.text("--config", "FILE", &text);
    p.flag("--check", &flag);
    p.custom("--push", "T:F", [](const char* v) { return v[0] == '1'; });
    p.positionals("MOTION", &positionals, 1);
    std::vector<std::string> storage = {"fuzz"};
    storage.insert(storage.end(), tokens.begin(), tokens.end());
    std::vector<char*> argv;
    for (std::string& s : storage) argv.push_back(s.data());
    argv.push_back(nullptr);
    const args::Parser::Result r = p.parse(static_cast<int>(storage.size()), argv.data());
    if (r == args::Parser::Result::kError) return p.error().empty() ? "refused without a message" : "";
    if (r == args::Parser::Result::kHelp) return "";
    p.refuse_inapplicable(p.given("--stand") ? 1 : 2, "mode");
    if (p.given("--stand") && !(seconds > 0.0 && seconds <= 600.0)) return "accepted --stand " + std::to_string(seconds);
    if (p.given("--plan-latency-ms") && !(ms >= 0.0 && ms <= 18.0)) return "accepted --plan-latency-ms " + std::to_string(ms);
    if (p.given("--step-in-place") && !(steps >= 1 && steps <= 200)) return "accepted --step-in-place " + std::to_string(steps);
    if (p.given("--ground") && ground != "floor" && ground != "carpet") return "accepted --ground " + ground;
    if (positionals.size() > 1) return "accepted two positionals";
    return "";
  } catch (...) {
    return describe_exception();
  }
}

std::string check_output_text(const std::string& text) {
  std::size_t i = 0;
  while (i < text.size()) {
    if (!std::isalpha(static_cast<unsigned char>(text[i]))) {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j < text.size() && std::isalpha(static_cast<unsigned char>(text[j]))) ++j;
    std::string word = text.substr(i, j - i);
    std::transform(word.begin(), word.end(), word.begin(), [](unsigned char c) { return std::tolower(c); });
    if (word == "nan" || word == "inf" || word == "infinity") return "output holds '" + text.substr(i, j - i) + "'";
    i = j;
  }
  return "";
}

namespace {

// "" or where a null or non-finite number sits (flatten() would turn an empty array into null).
std::string find_null(const nlohmann::json& j, const std::string& where) {
  if (j.is_null()) return "JSON output holds null at " + (where.empty() ? "/" : where);
  if (j.is_number_float() && !std::isfinite(j.get<double>())) return "JSON output holds a non-finite number at " + where;
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it)
      if (std::string why = find_null(*it, where + "/" + it.key()); !why.empty()) return why;
  } else if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i)
      if (std::string why = find_null(j[i], where + "/" + std::to_string(i)); !why.empty()) return why;
  }
  return "";
}

}  // namespace

std::string check_output_json(const std::string& text) {
  if (const std::string why = check_output_text(text); !why.empty()) return why;
  try {
    return find_null(nlohmann::json::parse(text), "");
  } catch (const std::exception& e) {
    return std::string("JSON output does not parse: ") + e.what();
  }
}

std::string check_motion_file(const std::string& path, const model::Model& robot) {
  bool ok = false;
  const std::string text = slurp(path, ok);
  if (!ok) return path + ": not written";
  const std::vector<std::uint8_t> bytes(text.begin(), text.end());
  mocap::MotionHeader h;
  if (const mocap::MotionError e = mocap::read_motion_header(bytes.data(), bytes.size(), robot, h); e != mocap::MotionError::kOk) {
    return path + ": written but unreadable (" + mocap::to_string(e) + ")";
  }
  for (std::uint32_t f = 0; f < h.frame_count; ++f) {
    dynamics::ConfigVector q;
    mocap::ContactLabel label;
    int joint = -1;
    if (mocap::read_motion_frame(bytes.data(), bytes.size(), f, q, label) != mocap::MotionError::kOk ||
        mocap::check_motion_frame(robot, q, joint) != mocap::MotionError::kOk) {
      return path + ": written with frame " + std::to_string(f) + " the loaders refuse";
    }
  }
  return check_motion_bytes(bytes, robot);
}

}  // namespace kuavo::fuzz
