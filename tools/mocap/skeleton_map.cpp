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

enum class Side : char { kLeft = 'L', kRight = 'R', kCentre = 'C' };

Side side_of(int kp) {
  switch (kp) {
    case kKpLeftHip:
    case kKpLeftKnee:
    case kKpLeftAnkle:
    case kKpLeftToe:
    case kKpLeftShoulder:
    case kKpLeftElbow:
    case kKpLeftWrist:
    case kKpLeftHand:
    case kKpLeftThumb:
    case kKpLeftHeel:
      return Side::kLeft;
    case kKpHead:
      return Side::kCentre;
    default:
      return Side::kRight;
  }
}

// Body-part words per keypoint: what is left of a joint name once its side and rig prefix are
// taken off, lower-cased, letters and digits only. A word must equal the whole rest, so
// "LeftHandThumb1" (word "handthumb1") is never the wrist ("hand") and "Leg" never reads as
// l + "eg". Most specific first; the first word some joint carries wins. The order resolves the
// real clashes: "Shoulder" is the clavicle in CMU, Mixamo and Blender (which also have "Arm" or
// "upper_arm") but the upper arm in Perfume (which has no other); "Hip" is the thigh joint in
// Perfume but "UpLeg"/"Thigh" win where both exist; CMU's "LHipJoint" (a pelvis helper) matches
// nothing. Where both exist, "Ankle" and "Wrist" are the joints and "Foot" and "Hand" lie beyond
// them (SMPL, ASF); elsewhere "Foot" and "Hand" are the ankle and the wrist. A joint already taken
// by one keypoint is not another ("Foot", the ankle, is not also the toe). ASF bone names (femur,
// tibia, humerus, radius) read too. End Sites read as their parent's word plus "end".
struct Words {
  const char* words[16];
};
constexpr Words kHipWords = {{"upleg", "upperleg", "thigh", "thighbend", "hip", "femur"}};
constexpr Words kKneeWords = {{"leg", "lowerleg", "shin", "calf", "knee", "loleg", "tibia"}};
constexpr Words kAnkleWords = {{"ankle", "foot"}};
constexpr Words kToeWords = {
    {"toebase", "toe", "toes", "toe0", "ball", "foot", "toeend", "toebaseend", "toesend", "footend", "ankleend"}};
constexpr Words kShoulderWords = {{"arm", "upperarm", "uparm", "uarm", "shldr", "shldrbend", "shoulder", "humerus"}};
constexpr Words kElbowWords = {{"forearm", "lowerarm", "forearmbend", "farm", "elbow", "loarm", "radius"}};
constexpr Words kWristWords = {{"wrist", "hand"}};
// The hand point: the base of the middle (else index) finger, else the hand's End Site.
constexpr Words kHandWords = {{"handmiddle1", "middle1", "mid1", "middle01", "middleproximal", "fmiddle01",
                               "handindex1", "index1", "index01", "finger2", "fingers", "handindex1end", "handend",
                               "wristend"}};
// CMU's "LThumb" sits on the wrist: its End Site is the thumb. Biped's thumb is "Finger0",
// "Finger01".
constexpr Words kThumbWords = {{"handthumb2", "thumb2", "thumbintermediate", "thumb02", "finger01", "handthumb1",
                                "thumb1", "thumbproximal", "thumb01", "finger0", "thumbend", "thumb"}};
constexpr Words kHeelWords = {{"heel", "heelend"}};
constexpr Words kHeadWords = {{"headtopend", "headend", "headtop", "head"}};

const Words& words_of(int kp) {
  switch (kp) {
    case kKpLeftHip:
    case kKpRightHip:
      return kHipWords;
    case kKpLeftKnee:
    case kKpRightKnee:
      return kKneeWords;
    case kKpLeftAnkle:
    case kKpRightAnkle:
      return kAnkleWords;
    case kKpLeftToe:
    case kKpRightToe:
      return kToeWords;
    case kKpLeftShoulder:
    case kKpRightShoulder:
      return kShoulderWords;
    case kKpLeftElbow:
    case kKpRightElbow:
      return kElbowWords;
    case kKpLeftWrist:
    case kKpRightWrist:
      return kWristWords;
    case kKpLeftHand:
    case kKpRightHand:
      return kHandWords;
    case kKpLeftThumb:
    case kKpRightThumb:
      return kThumbWords;
    case kKpLeftHeel:
    case kKpRightHeel:
      return kHeelWords;
    default:
      return kHeadWords;
  }
}

// The robot's own link names (robot_bvh.h), matched exactly after normalizing.
constexpr const char* kRobotNames[kNumMappedKeypoints] = {
    "legl1link",    "legl4link",     "legl6link",     "legl6linkend", "legr1link",     "legr4link",  "legr6link",
    "legr6linkend", "zarml1link",    "zarml4link",    "zarml7link",   "zarml7linkend", "zarmr1link", "zarmr4link",
    "zarmr7link",   "zarmr7linkend", "zhead2linkend", "zarml7thumb",  "zarmr7thumb",   "legl6heel",  "legr6heel"};

std::string lower_alnum(std::string_view s) {
  std::string out;
  for (char c : s)
    if (std::isalnum(static_cast<unsigned char>(c)))
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

bool is_separator(char c) {
  return c == '_' || c == '.' || c == '-' || c == ' ';
}

bool starts_with_nocase(std::string_view s, std::string_view prefix) {
  if (s.size() < prefix.size()) return false;
  for (std::size_t i = 0; i < prefix.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(s[i])) != prefix[i]) return false;
  return true;
}

// How a joint name was read: its side, its body-part word and how the side was written.
struct Reading {
  Side side = Side::kCentre;
  std::string word;
  const char* style = "";  // "prefix word", "prefix letter", "suffix word", "suffix .L", "suffix _L"
};

// Rig prefixes that carry no meaning: a namespace ("mixamorig:", "Armature|"), Mixamo's
// "mixamorig" without a colon, Character Creator's "CC_Base_", 3ds Max Biped's "Bip01 ",
// Rigify's deform bones "DEF-".
std::string_view strip_rig_prefix(std::string_view name) {
  if (const auto cut = name.find_last_of(":|"); cut != std::string_view::npos) name.remove_prefix(cut + 1);
  for (std::string_view p : {"mixamorig", "cc_base", "bip0", "def"}) {
    if (!starts_with_nocase(name, p)) continue;
    std::size_t n = p.size();
    while (n < name.size() && std::isdigit(static_cast<unsigned char>(name[n]))) ++n;  // mixamorig1, Bip01
    if (p == "def" && (n >= name.size() || !is_separator(name[n]))) continue;          // "Default" stays
    while (n < name.size() && is_separator(name[n])) ++n;
    name.remove_prefix(n);
    break;
  }
  return name;
}

// Every way to read a name: centre ("Head"), side word ("LeftLeg", "ThighLeft", "Left_Thigh"),
// side letter after a separator ("thigh.L", "UpperLeg_L", "L_Thigh", "l hip") or before the part
// ("lThigh", "rShin", "LHip"), case-insensitive. A reading only counts if its word is a part word
// of a keypoint on that side, so "Leg" (centre) and "Lowerleg" (l + "owerleg") stay unread.
std::vector<Reading> readings(std::string_view raw) {
  std::vector<Reading> out;
  const std::string_view name = strip_rig_prefix(raw);
  if (name.empty()) return out;
  out.push_back({Side::kCentre, lower_alnum(name), ""});
  const auto side_of_letter = [](char c) {
    const char l = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return l == 'l' ? Side::kLeft : l == 'r' ? Side::kRight : Side::kCentre;
  };
  for (const auto& [word, side] : {std::pair{std::string_view("left"), Side::kLeft}, {"right", Side::kRight}}) {
    if (starts_with_nocase(name, word) && name.size() > word.size())
      out.push_back({side, lower_alnum(name.substr(word.size())), "prefix word"});
    if (name.size() > word.size() && starts_with_nocase(name.substr(name.size() - word.size()), word))
      out.push_back({side, lower_alnum(name.substr(0, name.size() - word.size())), "suffix word"});
  }
  if (name.size() >= 3 && is_separator(name[name.size() - 2])) {
    const Side s = side_of_letter(name.back());
    if (s != Side::kCentre)
      out.push_back(
          {s, lower_alnum(name.substr(0, name.size() - 2)), name[name.size() - 2] == '.' ? "suffix .L" : "suffix _L"});
  }
  if (name.size() >= 2) {
    const Side s = side_of_letter(name.front());
    if (s != Side::kCentre) out.push_back({s, lower_alnum(name.substr(1)), "prefix letter"});
  }
  return out;
}

bool is_word_of(int kp, const std::string& word, int& rank) {
  const Words& w = words_of(kp);
  for (int i = 0; i < 16 && w.words[i]; ++i)
    if (word == w.words[i]) {
      rank = i;
      return true;
    }
  return false;
}

bool below(const Bvh& bvh, int joint, int ancestor) {
  for (int j = bvh.joints[joint].parent; j >= 0; j = bvh.joints[j].parent)
    if (j == ancestor) return true;
  return false;
}

std::string normalize_robot(const std::string& name) {
  return lower_alnum(name);
}

struct Match {
  std::array<const char*, kNumMappedKeypoints> style{};
  std::string ambiguity;  // first ambiguous keypoint, for the error
};

// Length of the prefix every joint name shares up to and including a separator: a character or
// take name the exporter put in front ("Character1_LeftUpLeg", "Skeleton_LThigh", "Take 1 ...").
// It carries no meaning, so it is dropped before reading.
std::size_t shared_prefix(const Bvh& bvh) {
  const BvhJoint* first = nullptr;
  std::size_t n = std::string::npos;
  int joints = 0;
  for (const BvhJoint& j : bvh.joints) {
    if (j.end_site) continue;
    ++joints;
    if (!first) {
      first = &j;
      n = j.name.size();
      continue;
    }
    std::size_t k = 0;
    while (k < n && k < j.name.size() && j.name[k] == first->name[k]) ++k;
    n = k;
  }
  if (!first || joints < 3) return 0;
  while (n > 0 && !is_separator(first->name[n - 1]) && first->name[n - 1] != ':' && first->name[n - 1] != '|') --n;
  return n < first->name.size() ? n : 0;  // keep at least something of the shortest name
}

// Taken by a name-matched keypoint (a mapping file may give one joint two keypoints).
bool taken(const SkeletonMap& map, const std::array<bool, kNumMappedKeypoints>& by_name, int joint) {
  for (int k = 0; k < kNumMappedKeypoints; ++k)
    if (by_name[k] && map.joint[k] == joint) return true;
  return false;
}

// Name matching for keypoints not set yet. An End Site reads as its parent's readings with
// "end" appended to the word.
void map_by_names(const Bvh& bvh, const std::array<bool, kNumMappedKeypoints>& by_name, SkeletonMap& out,
                  Match& match) {
  const std::size_t shared = shared_prefix(bvh);
  std::vector<std::vector<Reading>> read(bvh.joints.size());
  for (std::size_t i = 0; i < bvh.joints.size(); ++i) {
    const BvhJoint& j = bvh.joints[i];
    if (!j.end_site) {
      read[i] = readings(std::string_view(j.name).substr(shared));
    } else {
      read[i] = read[static_cast<std::size_t>(j.parent)];
      for (Reading& r : read[i]) r.word += "end";
    }
  }
  for (int k = 0; k < kNumMappedKeypoints; ++k) {
    if (out.joint[k] >= 0) continue;
    int best_rank = 1 << 20, best = -1, second = -1;
    const char* style = "";
    for (std::size_t i = 0; i < read.size(); ++i) {
      if (taken(out, by_name, static_cast<int>(i))) continue;
      for (const Reading& r : read[i]) {
        int rank = 0;
        if (r.side != side_of(k) || !is_word_of(k, r.word, rank)) continue;
        if (rank < best_rank) {
          best_rank = rank, best = static_cast<int>(i), second = -1, style = r.style;
        } else if (rank == best_rank && best != static_cast<int>(i) && second < 0) {
          second = static_cast<int>(i);
        }
        break;  // one reading per joint and keypoint
      }
    }
    if (best < 0) continue;
    if (second >= 0 && match.ambiguity.empty())
      match.ambiguity = std::string(kNames[k]) + ": both '" + bvh.joints[best].name + "' and '" +
                        bvh.joints[second].name + "' read as '" + words_of(k).words[best_rank] + "'";
    out.joint[k] = best;
    match.style[k] = style;
  }
  // Hand point fallback: the wrist's End Site, else its first child that is not a thumb.
  for (const auto& [hand, wrist] : {std::pair{kKpLeftHand, kKpLeftWrist}, std::pair{kKpRightHand, kKpRightWrist}}) {
    if (out.joint[hand] >= 0 || out.joint[wrist] < 0) continue;
    int pick = -1;
    for (std::size_t i = 0; i < bvh.joints.size(); ++i) {
      const BvhJoint& j = bvh.joints[i];
      if (j.parent != out.joint[wrist] || !(j.offset.norm() > 0.0) ||
          lower_alnum(j.name).find("thumb") != std::string::npos)
        continue;
      if (pick < 0 || j.end_site) pick = static_cast<int>(i);
    }
    out.joint[hand] = pick;
  }
  // Toe fallback: the ankle's End Site, else its first child (a foot without a named toe).
  for (const auto& [toe, ankle] : {std::pair{kKpLeftToe, kKpLeftAnkle}, std::pair{kKpRightToe, kKpRightAnkle}}) {
    if (out.joint[toe] >= 0 || out.joint[ankle] < 0) continue;
    int pick = -1;
    for (std::size_t i = 0; i < bvh.joints.size(); ++i) {
      const BvhJoint& j = bvh.joints[i];
      if (j.parent == out.joint[ankle] && j.offset.norm() > 0.0 && (pick < 0 || j.end_site)) pick = static_cast<int>(i);
    }
    out.joint[toe] = pick;
  }
}

const char* detect_family(const Bvh& bvh, const Match& match) {
  bool cc = false, leftarm = false, leftelbow = false, robot = false, mixamo = false, biped = false;
  for (const BvhJoint& j : bvh.joints) {
    const std::string n = lower_alnum(j.name);
    cc |= n.rfind("ccbase", 0) == 0;
    leftarm |= n == "leftarm" || n == "leftupleg";
    leftelbow |= std::string_view(strip_rig_prefix(j.name)) == "LeftElbow";
    robot |= n == "legl1link";
    mixamo |= n.rfind("mixamorig", 0) == 0;
    biped |= n.rfind("bip0", 0) == 0;
  }
  if (robot) return "robot";
  if (cc) return "cc_base";
  if (mixamo) return "mixamo";
  if (biped) return "biped";
  if (leftarm) return "cmu";
  if (leftelbow) return "perfume";
  // Otherwise by how the mapped joints write their side.
  int dot = 0, underscore = 0, letter = 0;
  for (const char* s : match.style) {
    if (!s) continue;
    const std::string_view v(s);
    dot += v == "suffix .L";
    underscore += v == "suffix _L";
    letter += v == "prefix letter";
  }
  if (dot > 0 && dot >= underscore && dot >= letter) return "blender";
  if (underscore > 0 && underscore >= letter) return "side_suffix";
  if (letter > 0) return "side_prefix";
  return "generic";
}

// Every name-matched keypoint must sit below its chain parent, and the two legs and the two arms
// must be separate branches: a name that misled the matcher stops the import here, loudly.
std::string check_chains(const Bvh& bvh, const SkeletonMap& map, const std::array<bool, kNumMappedKeypoints>& by_name) {
  for (int k = 0; k < kNumMappedKeypoints; ++k) {
    const int p = keypoint_parent(k);  // hips, shoulders, head: the pelvis or neck, not mapped
    if (p < 0 || p >= kNumMappedKeypoints || map.joint[k] < 0 || map.joint[p] < 0 || !by_name[k] || !by_name[p]) continue;
    if (!below(bvh, map.joint[k], map.joint[p]))
      return std::string(kNames[k]) + " '" + bvh.joints[map.joint[k]].name + "' is not below " + kNames[p] + " '" +
             bvh.joints[map.joint[p]].name + "' in the hierarchy";
  }
  for (const auto& [a, b] : {std::pair{kKpLeftHip, kKpRightHip}, std::pair{kKpLeftShoulder, kKpRightShoulder}}) {
    const int ja = map.joint[a], jb = map.joint[b];
    if (ja < 0 || jb < 0 || !by_name[a] || !by_name[b]) continue;
    if (ja == jb || below(bvh, ja, jb) || below(bvh, jb, ja))
      return std::string(kNames[a]) + " '" + bvh.joints[ja].name + "' and " + kNames[b] + " '" + bvh.joints[jb].name +
             "' are not separate branches of the hierarchy";
  }
  return "";
}

std::string joint_list(const Bvh& bvh) {
  std::string joints;
  for (const BvhJoint& j : bvh.joints)
    if (!j.end_site) joints += (joints.empty() ? "" : ", ") + j.name;
  return joints;
}

constexpr const char* kMapHint =
    ". Write a mapping file with lines like 'left_knee = MyKneeJoint' and pass it with --map.";

bool finish(const Bvh& bvh, SkeletonMap& out, const Match& match, const std::array<bool, kNumMappedKeypoints>& by_name,
            std::string& error) {
  std::string missing;
  for (int k = 0; k < kNumMappedKeypoints; ++k) {
    if (out.joint[k] >= 0 || keypoint_optional(k)) continue;
    missing += std::string(missing.empty() ? "" : "; ") + kNames[k] + " (a joint named by one of";
    const Words& w = words_of(k);
    for (int i = 0; i < 16 && w.words[i]; ++i) missing += std::string(i ? ", " : " ") + w.words[i];
    missing += ")";
  }
  if (!missing.empty()) {
    error = "cannot map the skeleton (family '" + out.family + "'): unmapped keypoints: " + missing +
            ". Names are read case-insensitively as a side (Left/Right or l/r before the part, _L/.L/_Left after it) "
            "plus one of the part words, after a rig prefix (mixamorig:, CC_Base_, Bip01, DEF-). BVH joints: " +
            joint_list(bvh) + kMapHint;
    return false;
  }
  if (!match.ambiguity.empty()) {
    error = "cannot map the skeleton (family '" + out.family + "'): ambiguous names: " + match.ambiguity + kMapHint;
    return false;
  }
  if (const std::string wrong = check_chains(bvh, out, by_name); !wrong.empty()) {
    error = "cannot map the skeleton (family '" + out.family + "'): " + wrong +
            ", so the names do not mean what they seem. BVH joints: " + joint_list(bvh) + kMapHint;
    return false;
  }
  return true;
}

// The robot's own links: exact names.
bool map_robot(const Bvh& bvh, SkeletonMap& out) {
  bool robot = false;
  for (const BvhJoint& j : bvh.joints) robot |= normalize_robot(j.name) == "legl1link";
  if (!robot) return false;
  for (std::size_t i = 0; i < bvh.joints.size(); ++i) {
    const std::string n = normalize_robot(bvh.joints[i].name);
    for (int k = 0; k < kNumMappedKeypoints; ++k)
      if (out.joint[k] < 0 && n == kRobotNames[k]) out.joint[k] = static_cast<int>(i);
  }
  return true;
}

bool map_all(const Bvh& bvh, SkeletonMap& out, std::string& error) {
  std::array<bool, kNumMappedKeypoints> by_name{};
  for (int k = 0; k < kNumMappedKeypoints; ++k) by_name[k] = out.joint[k] < 0;
  Match match;
  if (!map_robot(bvh, out)) map_by_names(bvh, by_name, out, match);
  if (out.family.empty()) out.family = detect_family(bvh, match);
  return finish(bvh, out, match, by_name, error);
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
  out.family.clear();
  return map_all(bvh, out, error);
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
  return map_all(bvh, out, error);
}

int keypoint_parent(int k) {
  switch (k) {
    case kKpLeftHip:
    case kKpRightHip:
    case kKpNeck:
      return kKpPelvis;
    case kKpLeftKnee:
      return kKpLeftHip;
    case kKpLeftAnkle:
      return kKpLeftKnee;
    case kKpLeftToe:
    case kKpLeftHeel:
      return kKpLeftAnkle;
    case kKpRightKnee:
      return kKpRightHip;
    case kKpRightAnkle:
      return kKpRightKnee;
    case kKpRightToe:
    case kKpRightHeel:
      return kKpRightAnkle;
    case kKpLeftShoulder:
    case kKpRightShoulder:
    case kKpHead:
      return kKpNeck;
    case kKpLeftElbow:
      return kKpLeftShoulder;
    case kKpLeftWrist:
      return kKpLeftElbow;
    case kKpLeftHand:
    case kKpLeftThumb:
      return kKpLeftWrist;
    case kKpRightElbow:
      return kKpRightShoulder;
    case kKpRightWrist:
      return kKpRightElbow;
    case kKpRightHand:
    case kKpRightThumb:
      return kKpRightWrist;
    default:
      return -1;  // the pelvis is the root
  }
}

}  // namespace kuavo::mocap
