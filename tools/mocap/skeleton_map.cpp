#include "tools/mocap/skeleton_map.h"

#include <cctype>
#include <sstream>
#include <vector>

namespace kuavo::mocap {
namespace {

constexpr const char* kNames[kNumKeypoints] = {
    "left_hip",       "left_knee",   "left_ankle",    "left_toe",   "right_hip",  "right_knee",
    "right_ankle",    "right_toe",   "left_shoulder", "left_elbow", "left_wrist", "left_hand",
    "right_shoulder", "right_elbow", "right_wrist",   "right_hand", "head",       "left_thumb",
    "right_thumb",    "left_heel",   "right_heel",    "pelvis",     "neck"};

// Candidate names per keypoint, normalized (lower case, alphanumerics only, namespace
// prefix dropped), most specific first. The first one present wins; the order resolves the
// one real clash: "LeftShoulder" is the clavicle in CMU/Mixamo (which also have "LeftArm")
// but the upper arm in Perfume (which has no "LeftArm").
struct Candidates {
  const char* names[12];
};
constexpr Candidates kCandidates[kNumMappedKeypoints] = {
    {{"leftupleg", "lefthip", "ccbaselthigh", "leftthigh", "leftupperleg", "lhip", "lthigh", "lupleg", "legl1link"}},
    {{"leftleg", "leftknee", "ccbaselcalf", "leftshin", "leftlowerleg", "lknee", "lshin", "lcalf", "legl4link"}},
    {{"leftfoot", "leftankle", "ccbaselfoot", "lankle", "lfoot", "legl6link"}},
    {{"lefttoebase", "lefttoe", "ccbaseltoebase", "lefttoes", "ltoe", "ltoes", "lefttoeend", "legl6linkend",
      "leftfootend", "leftankleend"}},
    {{"rightupleg", "righthip", "ccbaserthigh", "rightthigh", "rightupperleg", "rhip", "rthigh", "rupleg",
      "legr1link"}},
    {{"rightleg", "rightknee", "ccbasercalf", "rightshin", "rightlowerleg", "rknee", "rshin", "rcalf", "legr4link"}},
    {{"rightfoot", "rightankle", "ccbaserfoot", "rankle", "rfoot", "legr6link"}},
    {{"righttoebase", "righttoe", "ccbasertoebase", "righttoes", "rtoe", "rtoes", "righttoeend", "legr6linkend",
      "rightfootend", "rightankleend"}},
    {{"leftarm", "leftupperarm", "ccbaselupperarm", "lupperarm", "lshoulder", "leftshoulder", "zarml1link"}},
    {{"leftforearm", "leftelbow", "ccbaselforearm", "leftlowerarm", "lforearm", "lelbow", "zarml4link"}},
    {{"lefthand", "leftwrist", "ccbaselhand", "lwrist", "lhand", "zarml7link"}},
    {{"lefthandmiddle1", "lefthandindex1", "ccbaselmid1", "lefthandindex1end", "leftwristend", "lefthandend",
      "lwristend", "lhandend", "zarml7linkend"}},
    {{"rightarm", "rightupperarm", "ccbaserupperarm", "rupperarm", "rshoulder", "rightshoulder", "zarmr1link"}},
    {{"rightforearm", "rightelbow", "ccbaserforearm", "rightlowerarm", "rforearm", "relbow", "zarmr4link"}},
    {{"righthand", "rightwrist", "ccbaserhand", "rwrist", "rhand", "zarmr7link"}},
    {{"righthandmiddle1", "righthandindex1", "ccbasermid1", "righthandindex1end", "rightwristend", "righthandend",
      "rwristend", "rhandend", "zarmr7linkend"}},
    {{"headtopend", "headend", "headtop", "ccbasehead", "head", "zhead2linkend"}},
    // CMU's LThumb sits on the wrist: its End Site is the thumb.
    {{"lefthandthumb2", "lefthandthumb1", "ccbaselthumb2", "lthumbend", "leftthumb", "lthumb", "zarml7thumb"}},
    {{"righthandthumb2", "righthandthumb1", "ccbaserthumb2", "rthumbend", "rightthumb", "rthumb", "zarmr7thumb"}},
    {{"leftheel", "lheel", "legl6heel"}},
    {{"rightheel", "rheel", "legr6heel"}},
};

std::string normalize(const std::string& name) {
  std::string s = name;
  if (const auto colon = s.rfind(':'); colon != std::string::npos) s = s.substr(colon + 1);
  std::string out;
  for (char c : s)
    if (std::isalnum(static_cast<unsigned char>(c)))
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  // "mixamorig_LeftArm" style prefixes without a colon.
  if (out.rfind("mixamorig", 0) == 0) out = out.substr(9);
  return out;
}

const char* detect_family(const Bvh& bvh) {
  bool cc = false, leftarm = false, leftelbow = false, robot = false, mixamo = false;
  for (const BvhJoint& j : bvh.joints) {
    const std::string n = normalize(j.name);
    cc |= n.rfind("ccbase", 0) == 0;
    leftarm |= n == "leftarm";
    leftelbow |= n == "leftelbow";
    robot |= n == "legl1link";
    mixamo |= j.name.rfind("mixamorig", 0) == 0;
  }
  if (robot) return "robot";
  if (cc) return "cc_base";
  if (mixamo) return "mixamo";
  if (leftarm) return "cmu";
  if (leftelbow) return "perfume";
  return "generic";
}

bool finish(const Bvh& bvh, SkeletonMap& out, std::string& error) {
  std::string missing;
  for (int k = 0; k < kNumMappedKeypoints; ++k) {
    if (out.joint[k] >= 0 || keypoint_optional(k)) continue;
    missing += std::string(missing.empty() ? "" : ", ") + kNames[k] + " (tried";
    for (const char* c : kCandidates[k].names) {
      if (!c) break;
      missing += std::string(" ") + c;
    }
    missing += ")";
  }
  if (missing.empty()) return true;
  std::string joints;
  for (const BvhJoint& j : bvh.joints)
    if (!j.end_site) joints += (joints.empty() ? "" : ", ") + j.name;
  error = "cannot map the skeleton (family '" + out.family + "'): unmapped keypoints: " + missing +
          ". BVH joints: " + joints +
          ". Write a mapping file with lines like 'left_knee = MyKneeJoint' and pass it with --map.";
  return false;
}

void map_by_tables(const Bvh& bvh, SkeletonMap& out) {
  std::vector<std::string> normalized;
  normalized.reserve(bvh.joints.size());
  for (const BvhJoint& j : bvh.joints) normalized.push_back(normalize(j.name));
  for (int k = 0; k < kNumMappedKeypoints; ++k) {
    if (out.joint[k] >= 0) continue;
    for (const char* c : kCandidates[k].names) {
      if (!c) break;
      for (std::size_t i = 0; i < normalized.size() && out.joint[k] < 0; ++i)
        if (normalized[i] == c) out.joint[k] = static_cast<int>(i);
      if (out.joint[k] >= 0) break;
    }
  }
  // Toe / hand fallbacks: the End Site (or the only child) below the ankle / wrist.
  const int pairs[4][2] = {{kKpLeftToe, kKpLeftAnkle},
                           {kKpRightToe, kKpRightAnkle},
                           {kKpLeftHand, kKpLeftWrist},
                           {kKpRightHand, kKpRightWrist}};
  for (const auto& p : pairs) {
    if (out.joint[p[0]] >= 0 || out.joint[p[1]] < 0) continue;
    for (std::size_t i = 0; i < bvh.joints.size(); ++i)
      if (bvh.joints[i].parent == out.joint[p[1]] && bvh.joints[i].offset.norm() > 0.0) {
        out.joint[p[0]] = static_cast<int>(i);
        break;
      }
  }
}

}  // namespace

const char* keypoint_name(int kp) {
  return kp >= 0 && kp < kNumKeypoints ? kNames[kp] : "?";
}

bool keypoint_optional(int kp) {
  return kp == kKpLeftToe || kp == kKpRightToe || kp == kKpLeftHand || kp == kKpRightHand || kp == kKpHead ||
         kp == kKpLeftThumb || kp == kKpRightThumb || kp == kKpLeftHeel || kp == kKpRightHeel;
}

bool map_skeleton(const Bvh& bvh, SkeletonMap& out, std::string& error) {
  out.joint.fill(-1);
  out.family = detect_family(bvh);
  map_by_tables(bvh, out);
  return finish(bvh, out, error);
}

bool map_skeleton_with_file(const Bvh& bvh, const std::string& mapping_text, SkeletonMap& out, std::string& error) {
  out.joint.fill(-1);
  out.family = "file";
  std::istringstream in(mapping_text);
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    const auto trim = [](std::string s) {
      const auto b = s.find_first_not_of(" \t\r");
      const auto e = s.find_last_not_of(" \t\r");
      return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
    };
    line = trim(line);
    if (line.empty()) continue;
    const auto eq = line.find('=');
    if (eq == std::string::npos) {
      error = "mapping line " + std::to_string(line_no) + ": expected 'keypoint = joint name'";
      return false;
    }
    const std::string key = trim(line.substr(0, eq)), joint = trim(line.substr(eq + 1));
    int kp = -1;
    for (int k = 0; k < kNumMappedKeypoints; ++k)
      if (key == kNames[k]) kp = k;
    if (kp < 0) {
      std::string all;
      for (int k = 0; k < kNumMappedKeypoints; ++k) all += std::string(k ? ", " : "") + kNames[k];
      error = "mapping line " + std::to_string(line_no) + ": unknown keypoint '" + key + "' (known: " + all + ")";
      return false;
    }
    const int j = bvh.find(joint);
    if (j < 0) {
      error = "mapping line " + std::to_string(line_no) + ": the BVH has no joint named '" + joint + "'";
      return false;
    }
    out.joint[kp] = j;
  }
  map_by_tables(bvh, out);
  return finish(bvh, out, error);
}

}  // namespace kuavo::mocap
