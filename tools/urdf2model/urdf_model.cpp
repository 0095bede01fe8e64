#include "tools/urdf2model/urdf_model.h"

#include <tinyxml2.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <cstdio>
#include <algorithm>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "controllers/model/model_tables.h"

namespace kuavo::tools {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr std::array<const char*, model::kNumJoints> kJointNames = {
    "leg_l1_joint",  "leg_l2_joint",  "leg_l3_joint",  "leg_l4_joint",  "leg_l5_joint",
    "leg_l6_joint",  "leg_r1_joint",  "leg_r2_joint",  "leg_r3_joint",  "leg_r4_joint",
    "leg_r5_joint",  "leg_r6_joint",  "zarm_l1_joint", "zarm_l2_joint", "zarm_l3_joint",
    "zarm_l4_joint", "zarm_l5_joint", "zarm_l6_joint", "zarm_l7_joint", "zarm_r1_joint",
    "zarm_r2_joint", "zarm_r3_joint", "zarm_r4_joint", "zarm_r5_joint", "zarm_r6_joint",
    "zarm_r7_joint", "zhead_1_joint", "zhead_2_joint"};

constexpr std::array<const char*, model::kNumFrames> kFrameNames = {
    "ll_foot_toe", "lr_foot_toe", "ll_foot_heel", "lr_foot_heel",
    "rl_foot_toe", "rr_foot_toe", "rl_foot_heel", "rr_foot_heel",
    "zarm_l7_end_effector", "zarm_r7_end_effector", "camera", "radar"};

constexpr const char* kBaseLink = "base_link";

struct Error {
  std::string message;
};

struct Inertial {
  double mass_kg = 0.0;
  Vector3d com_m = Vector3d::Zero();
  Matrix3d inertia_com = Matrix3d::Zero();  // body axes, about the CoM
};

struct Link {
  std::string name;
  bool has_inertial = false;
  Inertial inertial;
  int line = 0;
};

struct Joint {
  std::string name, type, parent, child;
  Vector3d xyz = Vector3d::Zero();
  Vector3d rpy = Vector3d::Zero();
  Vector3d axis = Vector3d::UnitX();
  double lower = 0.0, upper = 0.0, effort = 0.0, velocity = 0.0;
  bool has_limit = false;
  int line = 0;
};

Matrix3d rpy_to_matrix(const Vector3d& rpy) {
  // URDF: R = Rz(yaw) * Ry(pitch) * Rx(roll)
  return (Eigen::AngleAxisd(rpy.z(), Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rpy.y(), Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Vector3d::UnitX()))
      .toRotationMatrix();
}

bool parse_vec3(const char* text, Vector3d& out) {
  if (text == nullptr) return false;
  std::istringstream in(text);
  for (int i = 0; i < 3; ++i) {
    if (!(in >> out[i]) || !std::isfinite(out[i])) return false;
  }
  std::string rest;
  return !(in >> rest);
}

bool parse_double(const tinyxml2::XMLElement* e, const char* attr, double& out) {
  const char* text = e == nullptr ? nullptr : e->Attribute(attr);
  if (text == nullptr) return false;
  char* end = nullptr;
  out = std::strtod(text, &end);
  while (end != nullptr && *end == ' ') ++end;
  return end != text && end != nullptr && *end == '\0' && std::isfinite(out);
}

std::string where(const std::string& file, int line) {
  return file + ":" + std::to_string(line) + ": ";
}

// Reads <origin xyz rpy> if present (defaults are zero, as in URDF).
bool read_origin(const tinyxml2::XMLElement* parent, Vector3d& xyz, Vector3d& rpy) {
  xyz.setZero();
  rpy.setZero();
  const auto* origin = parent->FirstChildElement("origin");
  if (origin == nullptr) return true;
  if (origin->Attribute("xyz") != nullptr && !parse_vec3(origin->Attribute("xyz"), xyz)) return false;
  if (origin->Attribute("rpy") != nullptr && !parse_vec3(origin->Attribute("rpy"), rpy)) return false;
  return true;
}

std::string check_inertia(const std::string& link, const Inertial& in) {
  if (!(in.mass_kg > 0.0)) {
    return "link '" + link + "': mass must be positive, got " + std::to_string(in.mass_kg);
  }
  Eigen::SelfAdjointEigenSolver<Matrix3d> es(in.inertia_com);
  const Vector3d ev = es.eigenvalues();
  if (!(ev.minCoeff() > 0.0)) {
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "link '%s': inertia is not positive definite (eigenvalues %.6g %.6g %.6g)",
                  link.c_str(), ev[0], ev[1], ev[2]);
    return buf;
  }
  // Principal moments of a real body satisfy the triangle inequality.
  const double tol = 1e-12 * ev.maxCoeff();
  if (ev[0] + ev[1] < ev[2] - tol) {
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "link '%s': inertia violates the triangle inequality (principal %.6g + %.6g < %.6g)",
                  link.c_str(), ev[0], ev[1], ev[2]);
    return buf;
  }
  return "";
}

Error read_urdf(const std::string& path, std::map<std::string, Link>& links,
                std::vector<Joint>& joints) {
  tinyxml2::XMLDocument doc;
  if (doc.LoadFile(path.c_str()) != tinyxml2::XML_SUCCESS) {
    return {"cannot read URDF '" + path + "': " + (doc.ErrorStr() ? doc.ErrorStr() : "unknown")};
  }
  const auto* robot = doc.FirstChildElement("robot");
  if (robot == nullptr) return {"URDF '" + path + "': no <robot> element"};
  for (const auto* e = robot->FirstChildElement("link"); e; e = e->NextSiblingElement("link")) {
    Link link;
    link.line = e->GetLineNum();
    link.name = e->Attribute("name") ? e->Attribute("name") : "";
    if (link.name.empty()) return {where(path, link.line) + "<link> without a name"};
    if (const auto* in = e->FirstChildElement("inertial")) {
      link.has_inertial = true;
      Vector3d xyz, rpy;
      if (!read_origin(in, xyz, rpy)) {
        return {where(path, in->GetLineNum()) + "link '" + link.name + "': bad inertial <origin>"};
      }
      if (!parse_double(in->FirstChildElement("mass"), "value", link.inertial.mass_kg)) {
        return {where(path, in->GetLineNum()) + "link '" + link.name + "': missing or bad <mass value>"};
      }
      const auto* ie = in->FirstChildElement("inertia");
      double v[6];
      const char* names[6] = {"ixx", "iyy", "izz", "ixy", "ixz", "iyz"};
      for (int i = 0; i < 6; ++i) {
        if (!parse_double(ie, names[i], v[i])) {
          return {where(path, in->GetLineNum()) + "link '" + link.name + "': missing or bad inertia '" +
                  names[i] + "'"};
        }
      }
      Matrix3d inertia;
      inertia << v[0], v[3], v[4], v[3], v[1], v[5], v[4], v[5], v[2];
      const Matrix3d r = rpy_to_matrix(rpy);
      link.inertial.com_m = xyz;
      link.inertial.inertia_com = r * inertia * r.transpose();
      const std::string bad = check_inertia(link.name, link.inertial);
      if (!bad.empty()) return {where(path, in->GetLineNum()) + bad};
    }
    if (links.count(link.name)) return {where(path, link.line) + "duplicate link '" + link.name + "'"};
    links[link.name] = link;
  }
  for (const auto* e = robot->FirstChildElement("joint"); e; e = e->NextSiblingElement("joint")) {
    Joint j;
    j.line = e->GetLineNum();
    j.name = e->Attribute("name") ? e->Attribute("name") : "";
    j.type = e->Attribute("type") ? e->Attribute("type") : "";
    const auto* p = e->FirstChildElement("parent");
    const auto* c = e->FirstChildElement("child");
    if (j.name.empty() || j.type.empty() || !p || !c || !p->Attribute("link") || !c->Attribute("link")) {
      return {where(path, j.line) + "joint needs a name, a type, <parent link> and <child link>"};
    }
    j.parent = p->Attribute("link");
    j.child = c->Attribute("link");
    if (!read_origin(e, j.xyz, j.rpy)) return {where(path, j.line) + "joint '" + j.name + "': bad <origin>"};
    if (const auto* a = e->FirstChildElement("axis")) {
      if (!parse_vec3(a->Attribute("xyz"), j.axis) || j.axis.norm() < 1e-9) {
        return {where(path, j.line) + "joint '" + j.name + "': bad <axis xyz>"};
      }
      j.axis.normalize();
    }
    if (const auto* l = e->FirstChildElement("limit")) {
      j.has_limit = parse_double(l, "lower", j.lower) && parse_double(l, "upper", j.upper) &&
                    parse_double(l, "effort", j.effort) && parse_double(l, "velocity", j.velocity);
    }
    if (!links.count(j.parent) || !links.count(j.child)) {
      return {where(path, j.line) + "joint '" + j.name + "' refers to an unknown link"};
    }
    joints.push_back(j);
  }
  return {};
}

struct Pose {
  Matrix3d R = Matrix3d::Identity();
  Vector3d p = Vector3d::Zero();
};

// Adds `part` (expressed in a frame at `pose` relative to the body) into `acc`.
void lump(Inertial& acc, const Inertial& part, const Pose& pose) {
  const double m = acc.mass_kg + part.mass_kg;
  const Vector3d c_part = pose.p + pose.R * part.com_m;
  const Vector3d c = (acc.mass_kg * acc.com_m + part.mass_kg * c_part) / m;
  auto shift = [](const Matrix3d& i_com, double mass, const Vector3d& d) {
    return Matrix3d(i_com + mass * (d.squaredNorm() * Matrix3d::Identity() - d * d.transpose()));
  };
  const Matrix3d i = shift(acc.inertia_com, acc.mass_kg, acc.com_m - c) +
                     shift(pose.R * part.inertia_com * pose.R.transpose(), part.mass_kg, c_part - c);
  acc.mass_kg = m;
  acc.com_m = c;
  acc.inertia_com = i;
}

Vector3d matrix_to_rpy(const Matrix3d& r) {
  // Inverse of rpy_to_matrix for |pitch| < pi/2.
  return Vector3d(std::atan2(r(2, 1), r(2, 2)), std::asin(-std::clamp(r(2, 0), -1.0, 1.0)),
                  std::atan2(r(1, 0), r(0, 0)));
}

Error read_limits(const GeneratorInput& in, std::array<model::JointLimitTable, model::kNumJoints>& lim,
                  const std::vector<const Joint*>& movable) {
  std::ifstream jf(in.kuavo_json_path);
  if (!jf) return {"cannot read '" + in.kuavo_json_path + "'"};
  nlohmann::json j;
  try {
    jf >> j;
  } catch (const std::exception& e) {
    return {"'" + in.kuavo_json_path + "': " + e.what()};
  }
  auto vec = [&](const char* key, std::vector<double>& out) -> std::string {
    if (!j.contains(key) || !j[key].is_array() || j[key].size() != model::kNumJoints) {
      return "'" + in.kuavo_json_path + "': '" + key + "' must be an array of 28 numbers";
    }
    for (const auto& v : j[key]) {
      if (!v.is_number()) return "'" + in.kuavo_json_path + "': '" + key + "' has a non-number";
      out.push_back(v.get<double>());
    }
    return "";
  };
  std::vector<double> vel, peak_vel, peak_tau;
  for (auto [key, out] : {std::pair{"joint_velocity_limits", &vel},
                          std::pair{"joint_peak_velocity_limits", &peak_vel},
                          std::pair{"joint_peak_torque_limits", &peak_tau}}) {
    const std::string e = vec(key, *out);
    if (!e.empty()) return {e};
  }
  // task.info torqueLimitsTask: rows 0-5 one leg, rows 6-12 one arm, mirrored to both sides.
  std::ifstream tf(in.task_info_path);
  if (!tf) return {"cannot read '" + in.task_info_path + "'"};
  std::string line;
  bool inside = false, seen = false;
  std::array<double, 13> wbc{};
  std::array<bool, 13> have{};
  int line_no = 0;
  while (std::getline(tf, line)) {
    ++line_no;
    if (!seen && line.rfind("torqueLimitsTask", 0) == 0) {
      seen = true;
      continue;
    }
    if (seen && !inside && line.find('{') != std::string::npos) {
      inside = true;
      continue;
    }
    if (inside && line.find('}') != std::string::npos) break;
    if (inside) {
      int row = -1, col = -1;
      double v = 0.0;
      if (std::sscanf(line.c_str(), " (%d,%d) %lf", &row, &col, &v) == 3) {
        if (row < 0 || row >= 13 || col != 0 || !(v > 0.0)) {
          return {in.task_info_path + ":" + std::to_string(line_no) + ": bad torqueLimitsTask row"};
        }
        wbc[row] = v;
        have[row] = true;
      }
    }
  }
  for (int r = 0; r < 13; ++r) {
    if (!have[r]) {
      return {"'" + in.task_info_path + "': torqueLimitsTask row " + std::to_string(r) + " missing"};
    }
  }
  for (int i = 0; i < model::kNumJoints; ++i) {
    const Joint& jt = *movable[i];
    if (!jt.has_limit) return {"URDF joint '" + jt.name + "' has no complete <limit>"};
    auto& l = lim[i];
    l.position_min_rad = jt.lower;
    l.position_max_rad = jt.upper;
    const bool head = i >= model::kHeadFirst;
    if (head) {
      // kuavo.json marks head protection as off (200 rad/s, 140/200 Nm); the URDF
      // values are the only real ones, and the WBC does not drive the head.
      l.velocity_rad_s = jt.velocity;
      l.peak_velocity_rad_s = jt.velocity;
      l.peak_torque_Nm = jt.effort;
      l.torque_Nm = jt.effort;
    } else if (i < 12 && i % 6 >= 4) {
      // The ankle pitch and roll joints are virtual: two motors drive them through the
      // linkage (FACTS.md §2.4), and kuavo.json's limits are those motors' (27 N·m each),
      // which bound pitch and roll jointly (drivers/transmission/ankle_motors.h: about 54 N·m
      // of pitch alone). The joint box is Leju's WBC limit (task.info, 60 N·m), an outer
      // bound; the controller and the simulator bound the motors themselves. With the
      // URDF's 36 N·m instead, the WBC held both ankle pitches at 36 while the motors had
      // more to give, and the show campaign fell in 64 of 90 runs against 50 (perfume,
      // cmu_05_07, cmu_05_20 × 30 seeds: 14 saved, none lost).
      const int wbc_row = i % 6;
      l.velocity_rad_s = std::min(vel[i], peak_vel[i]);
      l.peak_velocity_rad_s = peak_vel[i];
      l.peak_torque_Nm = wbc[wbc_row];
      l.torque_Nm = wbc[wbc_row];
    } else {
      const int wbc_row = i < 12 ? i % 6 : 6 + (i - 12) % 7;
      // kuavo.json lists wrist joints with continuous 10 > peak 7 rad/s; plan within the lower.
      l.velocity_rad_s = std::min(vel[i], peak_vel[i]);
      l.peak_velocity_rad_s = peak_vel[i];
      l.peak_torque_Nm = peak_tau[i];
      // Plan within the WBC limit, but never beyond what trips the drive.
      l.torque_Nm = std::min(wbc[wbc_row], peak_tau[i]);
    }
    if (!(l.position_min_rad < l.position_max_rad) || !(l.velocity_rad_s > 0) ||
        !(l.torque_Nm > 0) || l.peak_velocity_rad_s < l.velocity_rad_s ||
        l.peak_torque_Nm < l.torque_Nm) {
      return {"inconsistent limits for joint '" + jt.name + "'"};
    }
  }
  return {};
}

std::string num(double v) {
  if (v == 0.0) return "0.0";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  std::string s(buf);
  if (s.find_first_of(".eE") == std::string::npos) s += ".0";
  return s;
}

std::string vec3(const Vector3d& v) {
  return "{" + num(v.x()) + ", " + num(v.y()) + ", " + num(v.z()) + "}";
}

}  // namespace

GeneratorInput default_generator_input(const std::string& robot_dir, const std::string& variant) {
  GeneratorInput in;
  in.variant = variant;
  const std::string folder =
      variant == "s42" ? "biped_s42_kuavo4pro_short_arm" : "biped_s45_kuavo4pro_long_arm";
  const std::string v = variant == "s42" ? "42" : "45";
  in.urdf_path = robot_dir + "/" + folder + "/urdf/biped_" + (variant == "s42" ? "s42" : "s45") + ".urdf";
  in.kuavo_json_path = robot_dir + "/leju_params/kuavo_v" + v + "/kuavo.json";
  in.task_info_path = robot_dir + "/leju_params/kuavo_v" + v + "/task.info";
  return in;
}

GeneratorResult generate_model_tables(const GeneratorInput& input) {
  GeneratorResult result;
  auto fail = [&](const std::string& msg) {
    result.ok = false;
    result.error = msg;
    return result;
  };
  if (input.variant != "s45" && input.variant != "s42") {
    return fail("unknown robot variant '" + input.variant + "' (expected s45 or s42)");
  }
  std::map<std::string, Link> links;
  std::vector<Joint> joints;
  if (Error e = read_urdf(input.urdf_path, links, joints); !e.message.empty()) return fail(e.message);

  std::map<std::string, const Joint*> by_child;
  int revolute = 0;
  for (const Joint& j : joints) {
    if (by_child.count(j.child)) return fail("link '" + j.child + "' has two parent joints");
    by_child[j.child] = &j;
    if (j.type == "revolute") {
      ++revolute;
    } else if (j.type != "fixed") {
      return fail(where(input.urdf_path, j.line) + "joint '" + j.name + "' has type '" + j.type +
                  "'; the Kuavo 4Pro model has only revolute and fixed joints");
    }
  }
  if (!links.count(kBaseLink)) return fail("URDF '" + input.urdf_path + "': no link 'base_link'");

  // Bodies: base_link, then the 28 revolute joints in controller order.
  std::vector<const Joint*> movable;
  std::map<std::string, int> body_of_link = {{kBaseLink, 0}};
  for (int i = 0; i < model::kNumJoints; ++i) {
    const Joint* found = nullptr;
    for (const Joint& j : joints) {
      if (j.name == kJointNames[i]) found = &j;
    }
    if (found == nullptr) {
      return fail("URDF '" + input.urdf_path + "': joint '" + kJointNames[i] + "' (controller index " +
                  std::to_string(i) + ") not found");
    }
    if (found->type != "revolute") {
      return fail("URDF joint '" + found->name + "' must be revolute, is '" + found->type + "'");
    }
    movable.push_back(found);
  }
  if (revolute != model::kNumJoints) {
    return fail("URDF '" + input.urdf_path + "' has " + std::to_string(revolute) +
                " revolute joints; the Kuavo 4Pro model needs exactly " +
                std::to_string(model::kNumJoints));
  }

  // Resolve each link to (body, pose in body) by walking fixed joints up to a movable body.
  std::map<std::string, std::pair<int, Pose>> link_in_body;
  for (int i = 0; i < model::kNumJoints; ++i) body_of_link[movable[i]->child] = i + 1;
  std::function<bool(const std::string&, std::pair<int, Pose>&, int)> resolve =
      [&](const std::string& link, std::pair<int, Pose>& out, int depth) -> bool {
    if (depth > 64) return false;
    if (auto it = body_of_link.find(link); it != body_of_link.end()) {
      out = {it->second, Pose{}};
      return true;
    }
    auto jt = by_child.find(link);
    if (jt == by_child.end() || jt->second->type != "fixed") return false;
    std::pair<int, Pose> parent;
    if (!resolve(jt->second->parent, parent, depth + 1)) return false;
    const Matrix3d r = rpy_to_matrix(jt->second->rpy);
    out.first = parent.first;
    out.second.p = parent.second.p + parent.second.R * jt->second->xyz;
    out.second.R = parent.second.R * r;
    return true;
  };

  std::array<Inertial, model::kNumBodies> body_inertia{};
  double total_mass = 0.0;
  for (const auto& [name, link] : links) {
    if (!link.has_inertial) continue;
    std::pair<int, Pose> at;
    if (!resolve(name, at, 0)) {
      // Links above base_link (the massless dummy root) have nowhere to go.
      if (link.inertial.mass_kg > 0.0) return fail("link '" + name + "' is not attached to base_link");
      continue;
    }
    Inertial& acc = body_inertia[at.first];
    if (acc.mass_kg == 0.0) {
      acc.mass_kg = link.inertial.mass_kg;
      acc.com_m = at.second.p + at.second.R * link.inertial.com_m;
      acc.inertia_com = at.second.R * link.inertial.inertia_com * at.second.R.transpose();
    } else {
      lump(acc, link.inertial, at.second);
    }
    total_mass += link.inertial.mass_kg;
  }
  for (int b = 0; b < model::kNumBodies; ++b) {
    const std::string name = b == 0 ? kBaseLink : movable[b - 1]->child;
    const std::string bad = check_inertia(name, body_inertia[b]);
    if (!bad.empty()) return fail(bad);
  }

  std::array<model::JointLimitTable, model::kNumJoints> lim{};
  if (Error e = read_limits(input, lim, movable); !e.message.empty()) return fail(e.message);

  std::ostringstream o;
  const std::string ident = input.variant == "s42" ? "kBipedS42" : "kBipedS45";
  const std::string urdf_rel = input.urdf_path.substr(input.urdf_path.find("biped_s4"));
  o << "// GENERATED by tools/urdf2model from shared/robot/" << urdf_rel << ",\n"
    << "// leju_params/kuavo_v" << (input.variant == "s42" ? "42" : "45")
    << "/{kuavo.json,task.info}. Do not edit: tests/model regenerates and compares.\n"
    << "#pragma once\n\n#include \"controllers/model/model_tables.h\"\n\n"
    << "namespace kuavo::model {\n\n"
    << "inline constexpr ModelTables " << ident << " = {\n"
    << "    \"" << input.variant << "\",\n    \"" << urdf_rel << "\",\n    " << num(total_mass)
    << ",\n    {\n";
  for (int b = 0; b < model::kNumBodies; ++b) {
    const Inertial& in = body_inertia[b];
    const Matrix3d& i = in.inertia_com;
    if (b == 0) {
      o << "        {\"base_link\", \"\", -1, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0},\n";
    } else {
      const Joint& j = *movable[b - 1];
      std::pair<int, Pose> parent;
      if (!resolve(j.parent, parent, 0)) return fail("joint '" + j.name + "': parent not attached");
      if (parent.first >= b) {
        return fail("joint '" + j.name + "': its parent body comes later in the controller order");
      }
      const Vector3d xyz = parent.second.p + parent.second.R * j.xyz;
      const Vector3d rpy = matrix_to_rpy(parent.second.R * rpy_to_matrix(j.rpy));
      o << "        {\"" << j.child << "\", \"" << j.name << "\", " << parent.first << ", " << vec3(xyz)
        << ", " << vec3(rpy) << ", " << vec3(j.axis) << ",\n";
    }
    o << "         " << num(in.mass_kg) << ", " << vec3(in.com_m) << ",\n         {" << num(i(0, 0))
      << ", " << num(i(1, 1)) << ", " << num(i(2, 2)) << ", " << num(i(0, 1)) << ", " << num(i(0, 2))
      << ", " << num(i(1, 2)) << "}},\n";
  }
  o << "    },\n    {\n";
  for (int k = 0; k < model::kNumJoints; ++k) {
    const auto& l = lim[k];
    o << "        {" << num(l.position_min_rad) << ", " << num(l.position_max_rad) << ", "
      << num(l.velocity_rad_s) << ", " << num(l.torque_Nm) << ", " << num(l.peak_velocity_rad_s)
      << ", " << num(l.peak_torque_Nm) << "},  // " << kJointNames[k] << "\n";
  }
  o << "    },\n    {\n";
  for (int f = 0; f < model::kNumFrames; ++f) {
    std::pair<int, Pose> at;
    if (!links.count(kFrameNames[f]) || !resolve(kFrameNames[f], at, 0)) {
      return fail("URDF '" + input.urdf_path + "': frame link '" + kFrameNames[f] +
                  "' not found or not attached by fixed joints");
    }
    o << "        {\"" << kFrameNames[f] << "\", " << at.first << ", " << vec3(at.second.p) << ", "
      << vec3(matrix_to_rpy(at.second.R)) << "},\n";
  }
  o << "    },\n};\n\n}  // namespace kuavo::model\n";
  result.ok = true;
  result.source = o.str();
  return result;
}

}  // namespace kuavo::tools
