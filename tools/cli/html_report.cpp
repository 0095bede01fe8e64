#include "tools/cli/html_report.h"

#include <tinyxml2.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "controllers/dynamics/data.h"
#include "controllers/dynamics/rigid_body.h"
#include "tools/mocap/skeleton_map.h"
#include "tools/report/base64.h"
#include "tools/report/mesh_decimate.h"

#ifndef KUAVO_REPORT_WEB_DIR
#error "KUAVO_REPORT_WEB_DIR (tools/report/web) must be defined by the build"
#endif

namespace kuavo::cli {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

bool read_file(const std::string& path, std::string& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream ss;
  ss << in.rdbuf();
  out = ss.str();
  return true;
}

bool write_file(const std::string& path, const std::string& text, std::string& error) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  if (!out) error = path + ": cannot write";
  return static_cast<bool>(out);
}

// A variable the page reads: `KUAVO.<name> = <json>;` (classic scripts work from file://).
std::string js_assign(const std::string& lhs, const Json& value) { return "KUAVO." + lhs + " = " + value.dump() + ";\n"; }

std::vector<double> to_vector(const Eigen::Ref<const Eigen::MatrixXd>& m) {
  std::vector<double> v;
  for (int r = 0; r < m.rows(); ++r) {
    for (int c = 0; c < m.cols(); ++c) v.push_back(m(r, c));
  }
  return v;
}

// ---- the replay: the simulator's CSV log decimated to kReplayRate_hz -------------------

// Channels of one replay frame, in order; a column the log lacks is NaN.
struct Layout {
  int time = 0, base = 1, quat = 4, q = 8, qref = q + model::kNumJoints, tau = qref + model::kNumJoints,
      force = tau + model::kNumJoints, com = force + 3 * model::kNumContactPoints, comref = com + 3, zmp = comref + 3,
      margin = zmp + 2, tau_ratio = margin + 1, size = tau_ratio + 1;
};

Json layout_json(const Layout& l) {
  return Json{{"time", l.time}, {"base", l.base}, {"quat", l.quat}, {"q", l.q}, {"qref", l.qref}, {"tau", l.tau},
              {"force", l.force}, {"com", l.com}, {"comref", l.comref}, {"zmp", l.zmp}, {"margin", l.margin},
              {"tau_ratio", l.tau_ratio}, {"size", l.size}};
}

struct Replay {
  std::vector<float> frames;  // Layout::size per frame
  int count = 0;
  double duration_s = 0.0;
  double tau_ratio_max = 0.0;
};

bool read_replay(const model::Model& robot, const std::string& path, Replay& out, std::string& error) {
  std::ifstream in(path);
  std::string line;
  if (!in || !std::getline(in, line)) {
    error = path + ": cannot read the log";
    return false;
  }
  std::map<std::string, int> column;
  {
    std::istringstream h(line);
    std::string name;
    for (int i = 0; std::getline(h, name, ','); ++i) column[name] = i;
  }
  const Layout L;
  std::vector<int> source(L.size, -1);  // replay channel -> log column
  auto bind = [&](int channel, const std::string& name) {
    const auto it = column.find(name);
    if (it != column.end()) source[channel] = it->second;
  };
  bind(L.time, "time_s");
  const char* base[] = {"base_x_m", "base_y_m", "base_z_m", "base_qx", "base_qy", "base_qz", "base_qw"};
  for (int k = 0; k < 7; ++k) bind(L.base + k, base[k]);
  for (int j = 0; j < model::kNumJoints; ++j) {
    const std::string name = model::joint_name(robot, j);
    bind(L.q + j, "q_" + name);
    bind(L.qref + j, "qref_" + name);
    bind(L.tau + j, "tau_" + name);
  }
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    for (int a = 0; a < 3; ++a) bind(L.force + 3 * c + a, std::string("f_") + model::frame_name(robot, c) + "_" + "xyz"[a]);
  }
  for (int a = 0; a < 3; ++a) {
    bind(L.com + a, std::string("com_") + "xyz"[a] + "_m");
    bind(L.comref + a, std::string("comref_") + "xyz"[a] + "_m");
  }
  bind(L.zmp, "zmp_x_m");
  bind(L.zmp + 1, "zmp_y_m");
  bind(L.margin, "zmp_margin_m");
  for (int k : {L.time, L.base, L.base + 1, L.base + 2, L.quat, L.quat + 3, L.q}) {
    if (source[k] < 0) {
      error = path + ": not a simulator log (needs time_s, base pose and joint columns)";
      return false;
    }
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> row(column.size());
  double next_s = 0.0, margin_min = nan, ratio_max = nan;
  int rows = 0;
  while (std::getline(in, line)) {
    const char* p = line.c_str();
    std::size_t n = 0;
    for (; n < row.size(); ++n) {
      char* end = nullptr;
      row[n] = std::strtod(p, &end);
      if (end == p) row[n] = nan;
      p = end;
      while (*p != '\0' && *p != ',') ++p;
      if (*p == ',') ++p; else { ++n; break; }
    }
    if (n < row.size()) continue;  // a truncated last line (a run cut short)
    ++rows;
    // The holds: the worst margin and torque ratio over the ticks a frame stands for.
    if (source[L.margin] >= 0 && std::isfinite(row[source[L.margin]])) {
      margin_min = std::isnan(margin_min) ? row[source[L.margin]] : std::min(margin_min, row[source[L.margin]]);
    }
    if (source[L.tau] >= 0) {
      double r = 0.0;
      for (int j = 0; j < model::kNumJoints; ++j) {
        if (source[L.tau + j] >= 0) r = std::max(r, std::abs(row[source[L.tau + j]]) / robot.limits.peak_torque_Nm[j]);
      }
      ratio_max = std::isnan(ratio_max) ? r : std::max(ratio_max, r);
      out.tau_ratio_max = std::max(out.tau_ratio_max, r);
    }
    const double t = row[source[L.time]];
    if (!(t >= next_s - 1e-9)) continue;
    next_s = (std::floor(t * kReplayRate_hz + 1e-6) + 1.0) / kReplayRate_hz;
    for (int k = 0; k < L.size; ++k) {
      double v = source[k] >= 0 ? row[source[k]] : nan;
      if (k == L.margin) v = margin_min;
      if (k == L.tau_ratio) v = ratio_max;
      out.frames.push_back(static_cast<float>(v));
    }
    margin_min = ratio_max = nan;
    ++out.count;
    out.duration_s = t;
  }
  if (out.count < 2) {
    error = path + ": fewer than two rows";
    return false;
  }
  return true;
}

// ---- the robot: kinematic tree, visuals from Leju's URDF, meshes --------------------------

struct Visual {
  std::string mesh;  // file name in the meshes folder
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
};

Eigen::Vector3d parse_vec3(const char* text) {
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  if (text != nullptr) {
    std::istringstream s(text);
    s >> v.x() >> v.y() >> v.z();
  }
  return v;
}

// URDF rpy: fixed-axis roll, pitch, yaw = Rz(yaw) Ry(pitch) Rx(roll).
Eigen::Matrix3d rpy_matrix(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// link name -> its first visual mesh.
bool read_visuals(const std::string& urdf_path, std::map<std::string, Visual>& out, std::string& error) {
  tinyxml2::XMLDocument doc;
  if (doc.LoadFile(urdf_path.c_str()) != tinyxml2::XML_SUCCESS || doc.FirstChildElement("robot") == nullptr) {
    error = urdf_path + ": cannot read the URDF";
    return false;
  }
  for (auto* link = doc.FirstChildElement("robot")->FirstChildElement("link"); link != nullptr;
       link = link->NextSiblingElement("link")) {
    const auto* visual = link->FirstChildElement("visual");
    const auto* mesh = visual ? visual->FirstChildElement("geometry") : nullptr;
    mesh = mesh ? mesh->FirstChildElement("mesh") : nullptr;
    const char* file = mesh ? mesh->Attribute("filename") : nullptr;
    if (file == nullptr || link->Attribute("name") == nullptr) continue;
    Visual v;
    v.mesh = fs::path(file).filename().string();
    if (const auto* origin = visual->FirstChildElement("origin")) {
      v.position_m = parse_vec3(origin->Attribute("xyz"));
      v.rotation = rpy_matrix(parse_vec3(origin->Attribute("rpy")));
    }
    out[link->Attribute("name")] = v;
  }
  return true;
}

Json pose_json(const Eigen::Matrix3d& r, const Eigen::Vector3d& p) {
  return Json{{"R", to_vector(r)}, {"p", to_vector(p)}};
}

// The model as the page needs it, the meshes it names, and a check pose.
bool robot_json(const model::Model& robot, Json& model_out, Json& meshes_out, std::string& error) {
  const fs::path urdf = fs::path(KUAVO_DEFAULT_SHARED_DIR) / "robot" / robot.tables->source_urdf;
  std::map<std::string, Visual> visuals;
  if (!read_visuals(urdf.string(), visuals, error)) return false;
  const fs::path mesh_dir = urdf.parent_path().parent_path() / "meshes";
  Json bodies = Json::array();
  std::map<std::string, bool> meshes_used;
  auto visual_json = [&](const std::string& link) -> Json {
    const auto it = visuals.find(link);
    if (it == visuals.end()) return nullptr;
    meshes_used[it->second.mesh] = true;
    Json v = pose_json(it->second.rotation, it->second.position_m);
    v["mesh"] = it->second.mesh;
    return v;
  };
  for (int b = 0; b < model::kNumBodies; ++b) {
    const model::Body& body = robot.bodies[b];
    bodies.push_back(Json{{"name", robot.tables->bodies[b].link_name},
                          {"joint", b > 0 ? b - 1 : -1},
                          {"parent", body.parent},
                          {"R", to_vector(body.joint_rotation)},
                          {"p", to_vector(body.joint_position_m)},
                          {"axis", to_vector(body.axis)},
                          {"visual", visual_json(robot.tables->bodies[b].link_name)}});
  }
  Json frames = Json::array();
  for (int f = 0; f < model::kNumFrames; ++f) {
    const model::Frame& fr = robot.frames[f];
    Json j = pose_json(fr.rotation, fr.position_m);
    j["name"] = model::frame_name(robot, f);
    j["body"] = fr.body;
    j["visual"] = visual_json(model::frame_name(robot, f));  // camera, radar: links fixed to the head
    frames.push_back(j);
  }
  Json joints = Json::array();
  for (int j = 0; j < model::kNumJoints; ++j) {
    joints.push_back(Json{{"name", model::joint_name(robot, j)},
                          {"min_rad", robot.limits.position_min_rad[j]},
                          {"max_rad", robot.limits.position_max_rad[j]},
                          {"peak_torque_Nm", robot.limits.peak_torque_Nm[j]}});
  }
  // A pose with every joint moved and the base turned: the page's FK must put the bodies where
  // controllers/dynamics puts them.
  auto data = std::make_unique<dynamics::Data>();
  dynamics::ConfigVector q = dynamics::neutral_configuration(robot);
  q.head<3>() << 0.3, -0.2, 0.9;
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, 0.3, 1.0).normalized()));
  q.segment<4>(3) << turn.x(), turn.y(), turn.z(), turn.w();  // conventions.h: x, y, z, w
  for (int j = 0; j < model::kNumJoints; ++j) {
    q[7 + j] = std::clamp(0.3 * std::sin(1.7 * j + 0.5), robot.limits.position_min_rad[j], robot.limits.position_max_rad[j]);
  }
  dynamics::forward_kinematics(robot, *data, q);
  Json check_bodies = Json::array();
  for (int b = 0; b < model::kNumBodies; ++b) check_bodies.push_back(to_vector(data->position_m[b]));
  model_out = Json{{"variant", model::to_string(robot.variant)},
                   {"source", robot.tables->source_urdf},
                   {"bodies", bodies},
                   {"frames", frames},
                   {"contact_points", model::kNumContactPoints},
                   {"joints", joints},
                   {"fk_check", {{"q", to_vector(q)}, {"body_positions_m", check_bodies}}}};
  meshes_out = Json::object();
  std::size_t triangles_in = 0, triangles_out = 0;
  for (const auto& [name, used] : meshes_used) {
    report::Mesh mesh;
    if (!report::read_stl((mesh_dir / name).string(), mesh, error)) return false;
    triangles_in += mesh.triangles.size();
    const report::DecimateResult d = report::decimate(mesh, kMeshTriangles);
    triangles_out += d.mesh.triangles.size();
    meshes_out[name] = report::base64_encode(report::encode_mesh(d.mesh));
  }
  model_out["mesh_triangles"] = {{"leju", triangles_in}, {"shown", triangles_out}};
  return true;
}

// ---- the human skeleton --------------------------------------------------------------------

bool human_json(const std::string& path, Json& out, std::string& error) {
  std::ifstream in(path);
  std::string line;
  if (!in || !std::getline(in, line)) {
    error = path + ": cannot read";
    return false;
  }
  std::vector<std::string> names;
  {
    std::istringstream h(line);
    std::string c;
    std::getline(h, c, ',');  // time_s
    while (std::getline(h, c, ',')) {
      if (c.size() > 2 && c.compare(c.size() - 2, 2, "_x") == 0) names.push_back(c.substr(0, c.size() - 2));
    }
  }
  std::vector<float> frames;
  int count = 0;
  double next_s = -1e9, t0 = 0.0;
  while (std::getline(in, line)) {
    std::vector<float> row;
    const char* p = line.c_str();
    while (*p != '\0') {
      char* end = nullptr;
      row.push_back(static_cast<float>(std::strtod(p, &end)));
      p = *end == ',' ? end + 1 : end;
      if (end == p && *p != '\0') break;
    }
    if (row.size() != 1 + 3 * names.size()) continue;
    if (count == 0) t0 = row[0], next_s = row[0];
    if (row[0] < next_s - 1e-9) continue;
    next_s += 1.0 / kReplayRate_hz;
    frames.insert(frames.end(), row.begin() + 1, row.end());
    ++count;
  }
  if (count < 2) {
    error = path + ": fewer than two frames";
    return false;
  }
  Json bones = Json::array();
  for (int k = 0; k < mocap::kNumKeypoints; ++k) {
    const int parent = mocap::keypoint_parent(k);
    if (parent < 0) continue;
    const auto a = std::find(names.begin(), names.end(), mocap::keypoint_name(parent));
    const auto b = std::find(names.begin(), names.end(), mocap::keypoint_name(k));
    if (a != names.end() && b != names.end()) bones.push_back({a - names.begin(), b - names.begin()});
  }
  out = Json{{"names", names},   {"bones", bones}, {"t0_s", t0}, {"rate_hz", kReplayRate_hz},
             {"frames", count}, {"data", report::base64_encode(frames.data(), frames.size() * sizeof(float))}};
  return true;
}

// ---- the page's assets ---------------------------------------------------------------------

// three.js ships as an ES module (its UMD build is gone since r160), and file:// pages cannot
// import modules from files. The module is self-contained and ends with one `export{a as B,…}`:
// wrapped in a function whose export becomes `window.THREE = {B: a, …}`, it is a classic script.
bool classic_three(const std::string& module_source, std::string& out, std::string& error) {
  const std::size_t at = module_source.rfind("export{");
  const std::size_t close = at == std::string::npos ? at : module_source.find('}', at);
  // The shape this relies on: nothing but ";" and space after the export list, no imports.
  const bool tail_clean = close != std::string::npos &&
                          module_source.find_first_not_of("; \n\r\t", close + 1) == std::string::npos;
  if (!tail_clean || module_source.find("from\"./") != std::string::npos || module_source.find("from\"three") != std::string::npos) {
    error = "three.module.min.js: not one self-contained module ending with its export list";
    return false;
  }
  std::string object;
  std::istringstream list(module_source.substr(at + 7, close - at - 7));
  std::string item;
  while (std::getline(list, item, ',')) {
    const std::size_t as = item.find(" as ");
    object += (object.empty() ? "" : ",") + (as == std::string::npos ? item : item.substr(as + 4) + ":" + item.substr(0, as));
  }
  out = "(function(){\"use strict\";" + module_source.substr(0, at) + "window.THREE={" + object + "};})();\n";
  return true;
}

bool copy_web(const fs::path& dir, std::string& error) {
  const fs::path web = KUAVO_REPORT_WEB_DIR;
  std::error_code ec;
  fs::create_directories(dir / "vendor", ec);
  for (const char* f : {"index.html", "app.js", "style.css"}) {
    fs::copy_file(web / f, dir / f, fs::copy_options::overwrite_existing, ec);
    if (ec) {
      error = (web / f).string() + ": cannot copy: " + ec.message();
      return false;
    }
  }
  std::string module, classic;
  if (!read_file((web / "vendor/three/three.module.min.js").string(), module)) {
    error = (web / "vendor/three/three.module.min.js").string() + ": cannot read";
    return false;
  }
  if (!classic_three(module, classic, error) || !write_file((dir / "vendor/three.js").string(), classic, error)) return false;
  fs::copy_file(web / "vendor/three/LICENSE", dir / "vendor/three.LICENSE", fs::copy_options::overwrite_existing, ec);
  if (ec) error = "three.js LICENSE: " + ec.message();
  return !ec;
}

Json table_json(const HtmlTable& t) {
  return Json{{"title", t.title}, {"header", t.header}, {"rows", t.rows}, {"note", t.note}};
}

Json mark_json(const TimelineMark& m) {
  return Json{{"start_s", m.start_s}, {"end_s", m.end_s}, {"kind", m.kind}, {"label", m.label}};
}

}  // namespace

bool read_repairs(const std::string& retarget_report_json, std::vector<TimelineMark>& out, std::string& error) {
  std::string text;
  if (!read_file(retarget_report_json, text)) {
    error = retarget_report_json + ": cannot read";
    return false;
  }
  const Json j = Json::parse(text, nullptr, false);
  if (j.is_discarded()) {
    error = retarget_report_json + ": not JSON";
    return false;
  }
  if (!j.contains("dynamic") || !j["dynamic"].contains("repairs")) return true;
  for (const auto& r : j["dynamic"]["repairs"]) {
    out.push_back({r.value("start_s", 0.0), r.value("end_s", 0.0), "repair",
                   r.value("kind", std::string()) + ": " + r.value("reason", std::string())});
  }
  return true;
}

std::string markdown_table(const HtmlTable& t) {
  std::string s;
  auto line = [&](const std::vector<std::string>& cells) {
    s += "|";
    for (const auto& c : cells) s += " " + c + " |";
    s += "\n";
  };
  line(t.header);
  s += "|";
  for (std::size_t i = 0; i < t.header.size(); ++i) s += "---|";
  s += "\n";
  for (const auto& r : t.rows) line(r);
  return s;
}

bool write_html_report(const model::Model& robot, const HtmlReport& report, const std::string& dir_text,
                       std::string& error) {
  const fs::path dir = dir_text;
  std::error_code ec;
  fs::create_directories(dir / "data", ec);
  if (ec) {
    error = (dir / "data").string() + ": " + ec.message();
    return false;
  }
  if (!copy_web(dir, error)) return false;
  Json model_j, meshes_j;
  if (!robot_json(robot, model_j, meshes_j, error)) return false;
  if (!write_file((dir / "data/model.js").string(), js_assign("model", model_j), error) ||
      !write_file((dir / "data/meshes.js").string(), js_assign("meshes", meshes_j), error)) {
    return false;
  }
  Json human = nullptr;
  if (!report.human_csv.empty() && !human_json(report.human_csv, human, error)) return false;
  if (!write_file((dir / "data/human.js").string(), js_assign("human", human), error)) return false;

  const Layout layout;
  Json runs = Json::array();
  for (std::size_t i = 0; i < report.runs.size(); ++i) {
    const ReplayRun& run = report.runs[i];
    Replay replay;
    if (!read_replay(robot, run.log_csv, replay, error)) return false;
    Json marks = Json::array();
    if (run.follows_motion) {
      for (const auto& m : report.repairs) marks.push_back(mark_json(m));
    }
    for (const auto& m : run.marks) marks.push_back(mark_json(m));
    if (run.fell) marks.push_back(mark_json({run.fell_at_s, run.fell_at_s, "fall", "fell at " + std::to_string(run.fell_at_s).substr(0, 5) + " s"}));
    const std::string file = "data/run_" + std::to_string(i) + ".js";
    Json meta{{"name", run.name},
              {"description", run.description},
              {"file", file},
              {"frames", replay.count},
              {"rate_hz", kReplayRate_hz},
              {"duration_s", replay.duration_s},
              {"fell", run.fell},
              {"fell_at_s", run.fell_at_s},
              {"human", run.follows_motion && !human.is_null()},
              {"tau_ratio_max", replay.tau_ratio_max},
              {"marks", marks}};
    runs.push_back(meta);
    Json data{{"layout", layout_json(layout)},
              {"frames", replay.count},
              {"data", report::base64_encode(replay.frames.data(), replay.frames.size() * sizeof(float))}};
    if (!write_file((dir / file).string(), "KUAVO.runs[" + Json(run.name).dump() + "] = " + data.dump() + ";\n", error)) {
      return false;
    }
  }
  Json tables = Json::array();
  for (const auto& t : report.tables) tables.push_back(table_json(t));
  Json figures = Json::array();
  for (const auto& [file, caption] : report.figures) figures.push_back({{"file", file}, {"caption", caption}});
  Json blocks = Json::array();
  for (const auto& [title, text] : report.text_blocks) blocks.push_back({{"title", title}, {"text", text}});
  const Json page{{"title", report.title}, {"subtitle", report.subtitle}, {"runs", runs},
                  {"tables", tables},      {"figures", figures},          {"text_blocks", blocks}};
  return write_file((dir / "data/report.js").string(), js_assign("report", page), error);
}

}  // namespace kuavo::cli
