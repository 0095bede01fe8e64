#include "tools/mocap/human_targets.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>

#include "controllers/dynamics/rigid_body.h"

namespace kuavo::mocap {
namespace {

// Body indices of the Kuavo tree (controllers/model/model_tables.h order, body = joint + 1).
constexpr int kBodyLeftHipRoll = 1, kBodyLeftKnee = 4, kBodyLeftFoot = 6;
constexpr int kBodyRightHipRoll = 7, kBodyRightKnee = 10, kBodyRightFoot = 12;
constexpr int kBodyLeftShoulder = 13, kBodyLeftElbow = 16, kBodyLeftWrist = 19;
constexpr int kBodyRightShoulder = 20, kBodyRightElbow = 23, kBodyRightWrist = 26;
constexpr int kBodyHead = 28;
// The toe keypoint: the front edge of the sole, on the centre line (FACTS.md §2.2 l_foot_toe).
const Vec3 kToePoint_m(0.17084, 0.0, -0.0595);
const Vec3 kHeelPoint_m(-0.073164, 0.0, -0.0595);  // back edge of the sole (l_foot_heel)
// A point on the face, so head pitch and yaw both move it (stature 1.66 m puts the crown
// about 0.18 m above the head joints).
const Vec3 kHeadPoint_m(0.06, 0.0, 0.15);
// The thumb: in front of the palm, where a human thumb points with the arm hanging.
const Vec3 kThumbPoint_m(0.05, 0.0, -0.08);

// Order in which the chain is rebuilt (parents first).
constexpr int kChainOrder[kNumKeypoints] = {kKpPelvis,     kKpLeftHip,   kKpLeftKnee,  kKpLeftAnkle,     kKpLeftToe,
                                            kKpLeftHeel,   kKpRightHip,  kKpRightKnee, kKpRightAnkle,    kKpRightToe,
                                            kKpRightHeel,  kKpNeck,      kKpHead,      kKpLeftShoulder,  kKpLeftElbow,
                                            kKpLeftWrist,  kKpLeftHand,  kKpLeftThumb, kKpRightShoulder, kKpRightElbow,
                                            kKpRightWrist, kKpRightHand, kKpRightThumb};

struct Unit {
  const char* name;
  double to_m;
};
constexpr Unit kUnits[] = {{"m", 1.0}, {"cm", 0.01}, {"mm", 0.001}, {"inch", 0.0254}, {"cmu", 0.056444}};
// Hip-to-ankle length over stature for adults (anthropometric tables put it at 0.45–0.49).
constexpr double kLegToStature = 0.47;
constexpr double kTypicalStature_m = 1.7;
// In the closest unit, the dancer's stature is within this factor of typical (0.57 .. 5.1 m):
// a child dancer is about 1.2 m; outside the band the skeleton is no human in any unit (a clip
// scaled by 1e4 gave a root scale of 0 and a motion of NaN).
constexpr double kStatureFactor = 3.0;

using KpArray = std::array<Vec3, kNumKeypoints>;

// Mapped keypoints of one BVH pose, plus the derived pelvis and neck (midpoints).
void keypoints_from_pose(const SkeletonMap& map, const std::vector<Vec3>& pose, KpArray& kp) {
  for (int k = 0; k < kNumMappedKeypoints; ++k) kp[k] = map.joint[k] >= 0 ? pose[map.joint[k]] : Vec3::Zero();
  kp[kKpPelvis] = 0.5 * (kp[kKpLeftHip] + kp[kKpRightHip]);
  kp[kKpNeck] = 0.5 * (kp[kKpLeftShoulder] + kp[kKpRightShoulder]);
}

// Leading reference frames (T-pose, calibration or origin pose that converters and capture
// software put before the motion). A reference is a held pose followed by a jump no human
// motion makes; the rule reads the motion itself, so it holds whatever the dialect. Lengths are
// in units of the dancer's leg (hip to ankle, about 0.8 m), so they hold whatever the unit.
// How far into the clip a reference may reach: a calibration pose is held a few seconds.
constexpr double kReferenceSearch_s = 5.0;
// A held pose stays within this of its first frame: a person holding still sways and jitters
// by 1-2 cm (0.05 leg is about 4 cm); more is motion, and motion is never dropped.
constexpr double kHeldPose_leg = 0.05;
// A jump smaller than this (about 16 cm, half a forearm) leaves a pose close enough to the
// motion's first one that keeping it is harmless.
constexpr double kMinJump_leg = 0.2;
// No keypoint of a human moves faster: about 25 m/s, above a kicking foot (about 20 m/s) and a
// punching fist (about 13 m/s). A larger step in one frame time is a discontinuity.
constexpr double kMaxKeypointSpeed_leg_per_s = 30.0;
// At low frame rates a fast move can take a large step in one frame, but then the frames after
// it move as much: a jump is a discontinuity only if it is this many times the median step over
// the next kJumpContext_s (motion changes speed smoothly; a reference jump lands on a still or
// slow start).
constexpr double kJumpRatio = 5.0;
constexpr double kJumpContext_s = 0.25;

double percentile(std::vector<double> v, double p);

double largest_step(const KpArray& a, const KpArray& b, const std::array<bool, kNumKeypoints>& present) {
  double d = 0.0;
  for (int k = 0; k < kNumKeypoints; ++k)
    if (present[k]) d = std::max(d, (b[k] - a[k]).norm());
  return d;
}

// Number of leading reference frames: repeatedly, a held run of frames that ends in a
// discontinuity is dropped; the first run that moves before any jump is the motion.
int count_reference_frames(const std::vector<KpArray>& src, const std::array<bool, kNumKeypoints>& present, double leg,
                           double dt_s) {
  const int frames = static_cast<int>(src.size());
  // In doubles first: a Bvh built in code need not respect the parser's frame-time bounds.
  const int last = static_cast<int>(std::min<double>(frames - 3, std::floor(kReferenceSearch_s / dt_s)));  // keep 2
  const int context = static_cast<int>(std::max(3.0, std::min<double>(std::ceil(kJumpContext_s / dt_s), frames)));
  const auto discontinuity = [&](int t) {
    const double step = largest_step(src[t], src[t + 1], present);
    if (!(step > kMinJump_leg * leg)) return false;
    if (step > kMaxKeypointSpeed_leg_per_s * leg * dt_s) return true;
    std::vector<double> next;
    for (int u = t + 1; u < std::min(frames - 1, t + 1 + context); ++u)
      next.push_back(largest_step(src[u], src[u + 1], present));
    return step > kJumpRatio * percentile(next, 0.5);
  };
  int start = 0;
  for (int t = 0; t <= last; ++t) {
    if (largest_step(src[start], src[t], present) > kHeldPose_leg * leg) break;  // moving: the motion
    if (discontinuity(t)) start = t + 1;
  }
  return start;
}

// Sides as named: in any human stance the toes point ahead of the pelvis or sideways (a ballet
// turnout, 90 degrees, at the extreme), never backward. The median over the clip of the cosine
// between the foot (ankle to toe) and the facing direction (left hip minus right hip, crossed
// with up) is well above zero for a correctly named skeleton and near -1 when left and right are
// swapped (a skeleton named from the viewer's side). A median below this cosine (120 degrees,
// further back than any turnout) means swapped.
constexpr double kSwappedSidesCos = -0.5;
// Feet whose ankle-to-toe vector is less than this share horizontal (steeper than 70 degrees)
// are left out of that median.
constexpr double kFootHorizontalShare = 0.33;

double feet_forward_cos(const std::vector<KpArray>& src, const std::array<bool, kNumKeypoints>& present,
                        const Vec3& up) {
  if (!present[kKpLeftToe] || !present[kKpRightToe]) return 1.0;  // nothing to tell by
  std::vector<double> cos;
  cos.reserve(src.size());
  const auto horizontal = [&](Vec3 v) { return Vec3(v - v.dot(up) * up); };
  for (const KpArray& kp : src) {
    const Vec3 forward = horizontal(kp[kKpLeftHip] - kp[kKpRightHip]).cross(up);
    double sum = 0.0;
    int feet = 0;
    for (const auto& [toe, ankle] : {std::pair{kKpLeftToe, kKpLeftAnkle}, std::pair{kKpRightToe, kKpRightAnkle}}) {
      const Vec3 foot = horizontal(kp[toe] - kp[ankle]);
      // A foot pointing down (tiptoe, or a toe End Site below the ankle) tells no direction.
      if (!(foot.norm() > kFootHorizontalShare * (kp[toe] - kp[ankle]).norm()) || !(forward.norm() > 1e-9)) continue;
      sum += foot.normalized().dot(forward.normalized());
      ++feet;
    }
    if (feet > 0) cos.push_back(sum / feet);
  }
  return cos.empty() ? 1.0 : percentile(cos, 0.5);
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  const std::size_t i = static_cast<std::size_t>(std::clamp(p, 0.0, 1.0) * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(i), v.end());
  return v[i];
}

}  // namespace

std::array<RobotKeypoint, kNumKeypoints> robot_keypoints(const model::Model& robot) {
  std::array<RobotKeypoint, kNumKeypoints> k{};
  k[kKpLeftHip] = {kBodyLeftHipRoll, Vec3::Zero()};
  k[kKpLeftKnee] = {kBodyLeftKnee, Vec3::Zero()};
  k[kKpLeftAnkle] = {kBodyLeftFoot, Vec3::Zero()};
  k[kKpLeftToe] = {kBodyLeftFoot, kToePoint_m};
  k[kKpRightHip] = {kBodyRightHipRoll, Vec3::Zero()};
  k[kKpRightKnee] = {kBodyRightKnee, Vec3::Zero()};
  k[kKpRightAnkle] = {kBodyRightFoot, Vec3::Zero()};
  k[kKpRightToe] = {kBodyRightFoot, kToePoint_m};
  k[kKpLeftShoulder] = {kBodyLeftShoulder, Vec3::Zero()};
  k[kKpLeftElbow] = {kBodyLeftElbow, Vec3::Zero()};
  k[kKpLeftWrist] = {kBodyLeftWrist, Vec3::Zero()};
  k[kKpLeftHand] = {robot.frames[model::kFrameLeftHand].body, robot.frames[model::kFrameLeftHand].position_m};
  k[kKpRightShoulder] = {kBodyRightShoulder, Vec3::Zero()};
  k[kKpRightElbow] = {kBodyRightElbow, Vec3::Zero()};
  k[kKpRightWrist] = {kBodyRightWrist, Vec3::Zero()};
  k[kKpRightHand] = {robot.frames[model::kFrameRightHand].body, robot.frames[model::kFrameRightHand].position_m};
  k[kKpHead] = {kBodyHead, kHeadPoint_m};
  k[kKpLeftHeel] = {kBodyLeftFoot, kHeelPoint_m};
  k[kKpRightHeel] = {kBodyRightFoot, kHeelPoint_m};
  k[kKpLeftThumb] = {kBodyLeftWrist, kThumbPoint_m};
  k[kKpRightThumb] = {kBodyRightWrist, kThumbPoint_m};
  // Pelvis and neck: midpoints of points fixed on the base (hip roll axes, shoulder axes).
  const Vec3 lh = robot.bodies[kBodyLeftHipRoll].joint_position_m,
             rh = robot.bodies[kBodyRightHipRoll].joint_position_m;
  const Vec3 ls = robot.bodies[kBodyLeftShoulder].joint_position_m,
             rs = robot.bodies[kBodyRightShoulder].joint_position_m;
  k[kKpPelvis] = {0, 0.5 * (lh + rh)};
  k[kKpNeck] = {0, 0.5 * (ls + rs)};
  return k;
}

std::array<Vec3, kNumKeypoints> robot_rest_keypoints(const model::Model& robot) {
  const auto kps = robot_keypoints(robot);
  // Zero pose with the base at the origin: world axes are base axes.
  dynamics::ConfigVector q = dynamics::ConfigVector::Zero();
  q[6] = 1.0;
  const auto data = std::make_unique<dynamics::Data>();
  dynamics::forward_kinematics(robot, *data, q);
  std::array<Vec3, kNumKeypoints> out{};
  for (int k = 0; k < kNumKeypoints; ++k)
    out[k] = data->position_m[kps[k].body] + data->rotation[kps[k].body] * kps[k].point_m;
  return out;
}

double robot_ankle_height_m(const model::Model& robot) {
  return -robot.frames[0].position_m.z();
}
double robot_toe_height_m(const model::Model& robot) {
  return kToePoint_m.z() - robot.frames[0].position_m.z();
}

Mat3 pelvis_frame(const std::array<Vec3, kNumKeypoints>& p) {
  Vec3 y = p[kKpLeftHip] - p[kKpRightHip];
  y.normalize();
  Vec3 z = p[kKpNeck] - p[kKpPelvis];
  z -= z.dot(y) * y;
  z.normalize();
  Mat3 r;
  r.col(0) = y.cross(z);
  r.col(1) = y;
  r.col(2) = z;
  return r;
}

bool make_targets(const Bvh& bvh, const SkeletonMap& map, const model::Model& robot, const ImportOptions& options,
                  HumanTargets& out, std::string& error) {
  out = HumanTargets{};
  out.family = map.family;
  out.rate_hz = options.rate_hz;
  out.source_frames = bvh.frame_count;
  out.source_rate_hz = 1.0 / bvh.frame_time_s;
  for (int k = 0; k < kNumKeypoints; ++k) out.present[k] = k >= kNumMappedKeypoints || map.joint[k] >= 0;
  if (!(options.rate_hz > 0.0) || options.rate_hz > 10000.0) {
    error = "output rate must be in (0, 10000] Hz";
    return false;
  }
  if (bvh.frame_count < 2) {
    error = "the BVH has " + std::to_string(bvh.frame_count) + " frames; at least 2 are needed";
    return false;
  }

  // Keypoints of every source frame, file axes and units.
  std::vector<Vec3> pose;
  std::vector<Mat3> rot;
  std::vector<KpArray> src(static_cast<std::size_t>(bvh.frame_count));
  for (int f = 0; f < bvh.frame_count; ++f) {
    bvh_pose(bvh, f, pose, rot);
    keypoints_from_pose(map, pose, src[f]);
  }

  // Segment lengths. The hierarchy's zero-rotation pose is the natural rest pose (T-pose for
  // CMU and Perfume), but some rigs (iClone CC_Base) only make sense with their channels
  // applied: a rest length more than 10 % off the median over the clip is replaced by the
  // median. Rigid bones agree exactly; an identical skeleton keeps its rest lengths.
  bvh_rest_pose(bvh, pose);
  KpArray human_rest{};
  keypoints_from_pose(map, pose, human_rest);
  const auto robot_rest = robot_rest_keypoints(robot);
  std::array<double, kNumKeypoints> human_length{}, segment_scale{};
  std::vector<double> lengths(src.size());
  for (int k = 0; k < kNumKeypoints; ++k) {
    const int p = keypoint_parent(k);
    if (p < 0 || !out.present[k]) continue;
    for (std::size_t f = 0; f < src.size(); ++f) lengths[f] = (src[f][k] - src[f][p]).norm();
    const double median = percentile(lengths, 0.5);
    const double rest = (human_rest[k] - human_rest[p]).norm();
    human_length[k] = std::abs(rest - median) <= 0.1 * median ? rest : median;
    if (!(human_length[k] > 1e-9) && keypoint_optional(k)) {  // e.g. a thumb joint on the wrist
      out.present[k] = false;
      continue;
    }
    if (!(human_length[k] > 1e-9)) {
      error = std::string("keypoint '") + keypoint_name(k) + "' coincides with '" + keypoint_name(p) +
              "' (zero-length segment): map it to another joint";
      return false;
    }
    segment_scale[k] = (robot_rest[k] - robot_rest[p]).norm() / human_length[k];
  }
  const double human_leg = 0.5 * (human_length[kKpLeftKnee] + human_length[kKpLeftAnkle] + human_length[kKpRightKnee] +
                                  human_length[kKpRightAnkle]);
  const double robot_leg = 0.5 * ((robot_rest[kKpLeftKnee] - robot_rest[kKpLeftHip]).norm() +
                                  (robot_rest[kKpLeftAnkle] - robot_rest[kKpLeftKnee]).norm() +
                                  (robot_rest[kKpRightKnee] - robot_rest[kKpRightHip]).norm() +
                                  (robot_rest[kKpRightAnkle] - robot_rest[kKpRightKnee]).norm());
  out.root_scale = robot_leg / human_leg;
  const double stature_units = human_leg / kLegToStature;
  double best = 1e300;
  for (const Unit& u : kUnits) {
    const double miss = std::abs(std::log(stature_units * u.to_m / kTypicalStature_m));
    if (miss < best) {
      best = miss;
      out.unit = u.name;
      out.unit_to_m = u.to_m;
    }
  }
  out.human_height_m = stature_units * out.unit_to_m;
  if (!(best <= std::log(kStatureFactor))) {
    error = "the skeleton fits no human size in any unit: its leg (hip to ankle) is " + std::to_string(human_leg) +
            " file units, a dancer of " + std::to_string(out.human_height_m) + " m in the closest unit (" + out.unit +
            "), outside " + std::to_string(kTypicalStature_m / kStatureFactor) + " .. " +
            std::to_string(kTypicalStature_m * kStatureFactor) + " m";
    return false;
  }

  // 1. Leading reference frames: held poses that end in a jump no human makes.
  int drop = options.drop_first_frames;
  if (drop < 0) drop = count_reference_frames(src, out.present, human_leg, bvh.frame_time_s);
  if (bvh.frame_count - drop < 2) {
    error = "fewer than 2 motion frames remain after dropping " + std::to_string(drop);
    return false;
  }
  out.dropped_frames = drop;
  src.erase(src.begin(), src.begin() + drop);

  // 3. Axes: up from the mean pelvis→neck, heading from the first half second of hips.
  Vec3 up_mean = Vec3::Zero();
  for (const KpArray& kp : src) up_mean += kp[kKpNeck] - kp[kKpPelvis];
  int up_axis = 0;
  up_mean.cwiseAbs().maxCoeff(&up_axis);
  const double up_sign = up_mean[up_axis] >= 0.0 ? 1.0 : -1.0;
  const Vec3 up = up_sign * Vec3::Unit(up_axis);
  out.up_axis[0] = up_sign > 0 ? '+' : '-';
  out.up_axis[1] = static_cast<char>('X' + up_axis);
  Vec3 lateral = Vec3::Zero();
  const std::size_t head_frames = std::min<std::size_t>(
      src.size(),
      static_cast<std::size_t>(std::ceil(std::max(0.0, options.heading_window_s) * out.source_rate_hz)) + 1);
  for (std::size_t f = 0; f < head_frames; ++f) lateral += src[f][kKpLeftHip] - src[f][kKpRightHip];
  lateral -= lateral.dot(up) * up;
  if (!(lateral.norm() > 1e-9)) {
    error = "cannot find the dancer's heading: the hips coincide in the first frames";
    return false;
  }
  lateral.normalize();
  Mat3 to_robot;  // rows: robot x (forward), y (left), z (up) in file axes
  to_robot.row(0) = lateral.cross(up).transpose();
  to_robot.row(1) = lateral.transpose();
  to_robot.row(2) = up.transpose();
  if (const double cos = feet_forward_cos(src, out.present, up); cos < kSwappedSidesCos) {
    error = "left and right look swapped: with the joints as named, the toes point backward (median cosine " +
            std::to_string(cos) + " between foot and facing direction, below " + std::to_string(kSwappedSidesCos) +
            "); the skeleton names its sides as seen from the front. Map it with --map (left_hip = <the joint on "
            "the dancer's left> ...)";
    return false;
  }

  // 4. Robot-proportioned keypoints per source frame.
  std::vector<KpArray> scaled(src.size());
  for (std::size_t f = 0; f < src.size(); ++f) {
    const KpArray& h = src[f];
    KpArray& t = scaled[f];
    t[kKpPelvis] = out.root_scale * (to_robot * h[kKpPelvis]);
    for (int k : kChainOrder) {
      if (k == kKpPelvis) continue;
      const int p = keypoint_parent(k);
      t[k] = out.present[k] ? t[p] + segment_scale[k] * (to_robot * (h[k] - h[p])) : t[p];
    }
  }

  // 5. Resample.
  const double src_dt = bvh.frame_time_s;
  const double duration_s = src_dt * static_cast<double>(src.size() - 1);
  const std::size_t n = static_cast<std::size_t>(std::floor(duration_s * options.rate_hz + 1e-9)) + 1;
  out.frames.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double s = static_cast<double>(i) / options.rate_hz / src_dt;
    const std::size_t a = std::min(static_cast<std::size_t>(std::floor(s)), src.size() - 1);
    const std::size_t b = std::min(a + 1, src.size() - 1);
    const double w = std::clamp(s - static_cast<double>(a), 0.0, 1.0);
    for (int k = 0; k < kNumKeypoints; ++k) out.frames[i].position_m[k] = (1.0 - w) * scaled[a][k] + w * scaled[b][k];
  }

  // 6. Ground and origin.
  const double ankle_h = robot_ankle_height_m(robot), toe_h = robot_toe_height_m(robot);
  std::vector<double> lowest;
  lowest.reserve(n);
  for (const TargetFrame& f : out.frames) {
    double z = std::min(f.position_m[kKpLeftAnkle].z(), f.position_m[kKpRightAnkle].z()) - ankle_h;
    if (out.present[kKpLeftToe]) z = std::min(z, f.position_m[kKpLeftToe].z() - toe_h);
    if (out.present[kKpRightToe]) z = std::min(z, f.position_m[kKpRightToe].z() - toe_h);
    lowest.push_back(z);
  }
  Vec3 shift(-out.frames[0].position_m[kKpPelvis].x(), -out.frames[0].position_m[kKpPelvis].y(),
             -percentile(lowest, 0.05));
  const Mat3 rest_frame = pelvis_frame(robot_rest);
  for (TargetFrame& f : out.frames) {
    for (Vec3& p : f.position_m) p += shift;
    // Feet never aim below the floor: a flat robot foot has its ankle at ankle_h and its toe
    // point on the sole, and neither can go lower without a sole corner going through.
    if (options.feet_above_floor) {
      bool raised = false;
      const auto raise = [&](int k, double floor_z) {
        raised |= f.position_m[k].z() < floor_z - 1e-3;
        f.position_m[k].z() = std::max(f.position_m[k].z(), floor_z);
      };
      for (int k : {kKpLeftAnkle, kKpRightAnkle}) raise(k, ankle_h);
      for (int k : {kKpLeftToe, kKpRightToe, kKpLeftHeel, kKpRightHeel}) raise(k, toe_h);
      out.feet_below_floor_frames += raised;
    }
    f.base_rotation = pelvis_frame(f.position_m) * rest_frame.transpose();
  }
  // A pose whose hips coincide, or whose neck sits on the hip line, has no pelvis frame.
  for (std::size_t i = 0; i < out.frames.size(); ++i) {
    bool finite = out.frames[i].base_rotation.allFinite();
    for (const Vec3& p : out.frames[i].position_m) finite = finite && p.allFinite();
    if (!finite) {
      error = "degenerate pose at output frame " + std::to_string(i) +
              " (hips coincide or the neck lies on the hip line): check the joint mapping";
      out.frames.clear();
      return false;
    }
  }
  return true;
}

}  // namespace kuavo::mocap
