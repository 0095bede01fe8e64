#include "drivers/config/drivers_config_json.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace kuavo::drivers {

namespace {

using nlohmann::json;

// Collects the first error; every reader returns false once one is set.
struct Reader {
  std::string error;

  bool fail(const std::string& where, const std::string& what) {
    if (error.empty()) error = where + ": " + what;
    return false;
  }
  bool keys(const json& j, const std::string& where, std::initializer_list<const char*> allowed) {
    if (!j.is_object()) return fail(where, "expected an object");
    for (auto it = j.begin(); it != j.end(); ++it) {
      bool ok = false;
      for (const char* a : allowed) ok = ok || it.key() == a;
      if (!ok) return fail(where, "unknown key '" + it.key() + "'");
    }
    return true;
  }
  bool number(const json& j, const char* key, const std::string& where, double& out) {
    if (!j.contains(key)) return true;
    if (!j[key].is_number()) return fail(where + "." + key, "expected a number");
    out = j[key].get<double>();
    return true;
  }
  bool integer(const json& j, const char* key, const std::string& where, long long lo, long long hi, int& out) {
    if (!j.contains(key)) return true;
    if (!j[key].is_number_integer()) return fail(where + "." + key, "expected an integer");
    const long long v = j[key].get<long long>();
    if (v < lo || v > hi) return fail(where + "." + key, "outside " + std::to_string(lo) + ".." + std::to_string(hi));
    out = static_cast<int>(v);
    return true;
  }
  bool boolean(const json& j, const char* key, const std::string& where, bool& out) {
    if (!j.contains(key)) return true;
    if (!j[key].is_boolean()) return fail(where + "." + key, "expected true or false");
    out = j[key].get<bool>();
    return true;
  }
  bool string(const json& j, const char* key, const std::string& where, std::string& out) {
    if (!j.contains(key)) return true;
    if (!j[key].is_string()) return fail(where + "." + key, "expected a string");
    out = j[key].get<std::string>();
    return true;
  }
  bool required(const json& j, const char* key, const std::string& where) {
    return j.contains(key) || fail(where, std::string("missing '") + key + "'");
  }
};

bool read_buses(Reader& r, const json& arr, BusPlan& plan) {
  if (!arr.is_array()) return r.fail("buses", "expected an array");
  plan.buses.clear();
  for (std::size_t i = 0; i < arr.size(); ++i) {
    const json& b = arr[i];
    const std::string where = "buses[" + std::to_string(i) + "]";
    BusConfig c;
    if (!r.keys(b, where, {"interface", "bitrate_bps", "fd", "data_bitrate_bps", "cycle_rate_hz", "heartbeat_rate_hz"}) ||
        !r.required(b, "interface", where) || !r.string(b, "interface", where, c.interface) ||
        !r.number(b, "bitrate_bps", where, c.bitrate_bps) || !r.boolean(b, "fd", where, c.fd) ||
        !r.number(b, "data_bitrate_bps", where, c.data_bitrate_bps) ||
        !r.number(b, "cycle_rate_hz", where, c.cycle_rate_hz) ||
        !r.number(b, "heartbeat_rate_hz", where, c.heartbeat_rate_hz)) {
      return false;
    }
    plan.buses.push_back(c);
  }
  return true;
}

bool read_devices(Reader& r, const json& arr, BusPlan& plan) {
  if (!arr.is_array()) return r.fail("devices", "expected an array");
  plan.devices.clear();
  for (std::size_t i = 0; i < arr.size(); ++i) {
    const json& d = arr[i];
    const std::string where = "devices[" + std::to_string(i) + "]";
    DeviceConfig c;
    std::string kind;
    int id = 0;
    if (!r.keys(d, where, {"bus", "kind", "id", "slot"}) || !r.required(d, "bus", where) ||
        !r.required(d, "kind", where) || !r.required(d, "id", where) || !r.required(d, "slot", where) ||
        !r.integer(d, "bus", where, 0, 255, c.bus) || !r.string(d, "kind", where, kind) ||
        !r.integer(d, "id", where, 1, 127, id) || !r.integer(d, "slot", where, 0, model::kNumJoints - 1, c.slot)) {
      return false;
    }
    if (kind == "cia402") {
      c.kind = DeviceKind::kCia402Drive;
    } else if (kind == "ruiwo") {
      c.kind = DeviceKind::kRuiwoMotor;
    } else {
      return r.fail(where + ".kind", "expected \"cia402\" or \"ruiwo\"");
    }
    c.id = static_cast<std::uint8_t>(id);
    plan.devices.push_back(c);
  }
  return true;
}

bool read_ruiwo(Reader& r, const json& arr, DriversConfig& config) {
  if (!arr.is_array()) return r.fail("ruiwo_motors", "expected an array");
  for (std::size_t i = 0; i < arr.size(); ++i) {
    const json& m = arr[i];
    const std::string where = "ruiwo_motors[" + std::to_string(i) + "]";
    int id = 0;
    if (!r.keys(m, where, {"id", "sign", "zero_offset_rad", "torque_max_Nm", "velocity_max_rad_s"}) ||
        !r.required(m, "id", where) || !r.integer(m, "id", where, 1, 127, id)) {
      return false;
    }
    ruiwo::MotorConfig* target = nullptr;
    for (ruiwo::MotorConfig& c : config.ruiwo_motors)
      if (c.motor_id == id) target = &c;
    if (target == nullptr) return r.fail(where + ".id", "no Ruiwo motor with ID " + std::to_string(id));
    if (!r.integer(m, "sign", where, -1, 1, target->sign) ||
        !r.number(m, "zero_offset_rad", where, target->zero_offset_rad) ||
        !r.number(m, "torque_max_Nm", where, target->torque_max_Nm) ||
        !r.number(m, "velocity_max_rad_s", where, target->velocity_max_rad_s)) {
      return false;
    }
  }
  return true;
}

bool read_drives(Reader& r, const json& arr, DriversConfig& config) {
  if (!arr.is_array()) return r.fail("drives", "expected an array");
  for (std::size_t i = 0; i < arr.size(); ++i) {
    const json& d = arr[i];
    const std::string where = "drives[" + std::to_string(i) + "]";
    int slot = -1;
    if (!r.keys(d, where, {"slot", "counts_per_rev", "rated_torque_Nm", "torque_limit_Nm"}) ||
        !r.required(d, "slot", where) || !r.integer(d, "slot", where, 0, model::kNumJoints - 1, slot)) {
      return false;
    }
    DriveEntry* target = nullptr;
    for (DriveEntry& e : config.drives)
      if (e.slot == slot) target = &e;
    if (target == nullptr) return r.fail(where + ".slot", "no CiA 402 drive on slot " + std::to_string(slot));
    if (!r.number(d, "counts_per_rev", where, target->config.counts_per_rev) ||
        !r.number(d, "rated_torque_Nm", where, target->config.rated_torque_Nm) ||
        !r.number(d, "torque_limit_Nm", where, target->config.torque_limit_Nm)) {
      return false;
    }
  }
  return true;
}

}  // namespace

namespace {

// Line and column (1-based) of byte `offset` (0-based) in text.
std::string line_and_column(const std::string& text, std::size_t offset) {
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < offset && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

}  // namespace

DriverError apply_drivers_json(const std::string& text, DriversConfig& config, std::string& message) {
  // Parsed at start-up (exceptions allowed here, never in the cycle). A syntax error is given
  // with its line and column; a key given twice in one object is refused (JSON leaves it
  // undefined and nlohmann keeps the last one silently).
  struct Object {
    std::vector<std::string> keys;
    std::string name;
  };
  std::vector<Object> objects;
  std::string last_key = "drivers configuration", duplicate;
  const json::parser_callback_t track = [&](int, json::parse_event_t event, json& parsed) {
    if (event == json::parse_event_t::object_start) {
      objects.push_back({{}, last_key});
    } else if (event == json::parse_event_t::object_end && !objects.empty()) {
      objects.pop_back();
    } else if (event == json::parse_event_t::key && !objects.empty()) {
      last_key = parsed.get<std::string>();
      std::vector<std::string>& keys = objects.back().keys;
      if (duplicate.empty() && std::find(keys.begin(), keys.end(), last_key) != keys.end())
        duplicate = "'" + last_key + "' given twice in '" + objects.back().name + "'";
      keys.push_back(last_key);
    }
    return true;
  };
  json root;
  try {
    root = json::parse(text, track, /*allow_exceptions=*/true, /*ignore_comments=*/true);
  } catch (const json::parse_error& e) {
    message = "drivers configuration: not valid JSON at " + line_and_column(text, e.byte > 0 ? e.byte - 1 : 0);
    return DriverError::kBadConfig;
  } catch (const json::exception& e) {
    // A number literal no double holds (1e999) is out_of_range, not a parse_error; it escaped
    // as an exception. nlohmann gives no position for it: its message names the literal.
    const std::string what = e.what();
    const std::size_t at = what.find("] ");
    message = "drivers configuration: not valid JSON: " + (at == std::string::npos ? what : what.substr(at + 2));
    return DriverError::kBadConfig;
  }
  if (!duplicate.empty()) {
    message = "drivers configuration: duplicate key " + duplicate;
    return DriverError::kBadConfig;
  }
  Reader r;
  DriversConfig c = config;  // all or nothing
  if (!r.keys(root, "drivers configuration",
              {"buses", "devices", "ruiwo_motors", "drives", "knee_ratio_motor_per_joint", "ankle_motor_offset_rad", "imu"})) {
    message = r.error;
    return DriverError::kBadConfig;
  }
  bool ok = true;
  if (root.contains("buses")) ok = ok && read_buses(r, root["buses"], c.plan);
  if (root.contains("devices")) ok = ok && read_devices(r, root["devices"], c.plan);
  if (ok) sync_drives_with_plan(c);
  if (root.contains("ruiwo_motors")) ok = ok && read_ruiwo(r, root["ruiwo_motors"], c);
  if (root.contains("drives")) ok = ok && read_drives(r, root["drives"], c);
  double knee = c.legs[0].serial[3].ratio_motor_per_joint;
  ok = ok && r.number(root, "knee_ratio_motor_per_joint", "drivers configuration", knee);
  if (ok) c.legs[0].serial[3].ratio_motor_per_joint = c.legs[1].serial[3].ratio_motor_per_joint = knee;
  if (ok && root.contains("ankle_motor_offset_rad")) {
    const json& a = root["ankle_motor_offset_rad"];
    if (!a.is_array() || a.size() != 2 || !a[0].is_number() || !a[1].is_number()) {
      ok = r.fail("ankle_motor_offset_rad", "expected [motor A, motor B] in rad");
    } else {
      for (LegTransmission& leg : c.legs) {
        leg.ankle_motor[0].motor_offset_rad = a[0].get<double>();
        leg.ankle_motor[1].motor_offset_rad = a[1].get<double>();
      }
    }
  }
  if (ok && root.contains("imu")) {
    const json& imu = root["imu"];
    ok = r.keys(imu, "imu", {"device", "baud"}) && r.string(imu, "device", "imu", c.imu_device) &&
         r.integer(imu, "baud", "imu", 1, 100'000'000, c.imu_baud);
  }
  if (!ok) {
    message = r.error;
    return DriverError::kBadConfig;
  }
  config = std::move(c);
  message.clear();
  return DriverError::kOk;
}

DriverError load_drivers_config(const std::string& path, const model::Model& model, DriversConfig& out,
                                BusLoadReport& report, std::string& message) {
  // A missing file or a directory is a configuration problem, said as such (a directory read
  // as empty text, "not valid JSON"; a missing file was a "device node missing").
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) {
    message = path + ": cannot read the drivers configuration: no such file";
    return DriverError::kConfigUnreadable;
  }
  if (!std::filesystem::is_regular_file(status)) {
    message = path + ": cannot read the drivers configuration: not a regular file";
    return DriverError::kConfigUnreadable;
  }
  // The overlay that sets every key of the robot is ~12 KB; 1 MiB bounds what start-up reads
  // (a multi-gigabyte file given by mistake was read whole before being refused).
  constexpr std::uintmax_t kMaxConfigBytes = 1u << 20;
  if (const std::uintmax_t bytes = std::filesystem::file_size(path, ec); ec || bytes > kMaxConfigBytes) {
    message = path + ": " + (ec ? std::string("cannot read the drivers configuration")
                                : std::to_string(bytes) + " bytes, more than a drivers configuration holds (1 MiB)");
    return DriverError::kBadConfig;
  }
  std::ifstream in(path);
  if (!in) {
    message = path + ": cannot read the drivers configuration";
    return DriverError::kConfigUnreadable;
  }
  std::stringstream text;
  text << in.rdbuf();
  DriversConfig c = default_drivers_config(model);
  if (const DriverError e = apply_drivers_json(text.str(), c, message); e != DriverError::kOk) {
    message = path + ": " + message;
    return e;
  }
  if (const DriverError e = validate_drivers_config(c, report, message); e != DriverError::kOk) {
    message = path + ": " + message;
    return e;
  }
  out = std::move(c);
  return DriverError::kOk;
}

}  // namespace kuavo::drivers
