#include "tools/mocap/default_dance.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace kuavo::mocap {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRadToDeg = 180.0 / kPi;
constexpr double kUnitsPerM = 100.0;  // the clip is written in centimetres

// Skeleton [m], rest pose: T-pose, Y up, facing +Z, left = +X.
constexpr double kHipHalfWidth = 0.09, kHipDrop = 0.06;  // hip joints below/beside the root
constexpr double kThigh = 0.44, kShin = 0.42, kAnkleHeight = 0.08;
constexpr double kStandingHipHeight = 0.90;  // hip joints above ground: knees slightly bent
constexpr double kStanceHalfWidth = 0.09;    // feet ±9 cm from the centre line
constexpr double kSwingLift = 0.06, kSwingTime = 0.4;

enum Joint {
  kHips,
  kLUpLeg,
  kLLeg,
  kLFoot,
  kLToe,
  kLToeEnd,
  kRUpLeg,
  kRLeg,
  kRFoot,
  kRToe,
  kRToeEnd,
  kSpine,
  kSpine1,
  kNeck,
  kHead,
  kHeadEnd,
  kLShoulder,
  kLArm,
  kLForeArm,
  kLHand,
  kLHandEnd,
  kRShoulder,
  kRArm,
  kRForeArm,
  kRHand,
  kRHandEnd,
  kJointCount
};

struct JointDef {
  const char* name;
  int parent;
  double x, y, z;  // offset [m]
};
constexpr JointDef kSkeleton[kJointCount] = {
    {"Hips", -1, 0, 0, 0},
    {"LeftUpLeg", kHips, kHipHalfWidth, -kHipDrop, 0},
    {"LeftLeg", kLUpLeg, 0, -kThigh, 0},
    {"LeftFoot", kLLeg, 0, -kShin, 0},
    {"LeftToeBase", kLFoot, 0, -0.06, 0.13},
    {"", kLToe, 0, 0, 0.05},
    {"RightUpLeg", kHips, -kHipHalfWidth, -kHipDrop, 0},
    {"RightLeg", kRUpLeg, 0, -kThigh, 0},
    {"RightFoot", kRLeg, 0, -kShin, 0},
    {"RightToeBase", kRFoot, 0, -0.06, 0.13},
    {"", kRToe, 0, 0, 0.05},
    {"Spine", kHips, 0, 0.10, 0},
    {"Spine1", kSpine, 0, 0.15, 0},
    {"Neck", kSpine1, 0, 0.22, 0},
    {"Head", kNeck, 0, 0.10, 0.01},
    {"", kHead, 0, 0.18, 0},
    {"LeftShoulder", kSpine1, 0.04, 0.18, 0},
    {"LeftArm", kLShoulder, 0.14, 0, 0},
    {"LeftForeArm", kLArm, 0.28, 0, 0},
    {"LeftHand", kLForeArm, 0.25, 0, 0},
    {"", kLHand, 0.15, 0, 0},
    {"RightShoulder", kSpine1, -0.04, 0.18, 0},
    {"RightArm", kRShoulder, -0.14, 0, 0},
    {"RightForeArm", kRArm, -0.28, 0, 0},
    {"RightHand", kRForeArm, -0.25, 0, 0},
    {"", kRHand, -0.15, 0, 0},
};

// Ground-plane pose of a foot: forward, left [m] and heading [rad] in the dance frame.
struct FootPose {
  double fwd = 0.0, left = 0.0, yaw = 0.0;
};
struct Step {
  double t0;
  int foot;  // 0 left, 1 right
  FootPose to;
};

double smooth(double s) {
  return 0.5 - 0.5 * std::cos(kPi * std::clamp(s, 0.0, 1.0));
}
double bump(double s) {
  return s <= 0.0 || s >= 1.0 ? 0.0 : std::sin(kPi * s);
}

// Footstep plan (see the header for the phases).
std::vector<Step> plan_steps() {
  std::vector<Step> steps;
  std::array<FootPose, 2> feet = {FootPose{0, kStanceHalfWidth, 0}, FootPose{0, -kStanceHalfWidth, 0}};
  const auto step = [&](double t0, int foot, double dfwd, double dleft) {
    feet[foot].fwd += dfwd;
    feet[foot].left += dleft;
    steps.push_back({t0, foot, feet[foot]});
  };
  const auto side_steps = [&](double t0) {  // two steps left, two right, back to start
    step(t0 + 0.0, 0, 0, 0.25), step(t0 + 0.5, 1, 0, 0.25), step(t0 + 1.0, 0, 0, 0.25), step(t0 + 1.5, 1, 0, 0.25);
    step(t0 + 2.0, 1, 0, -0.25), step(t0 + 2.5, 0, 0, -0.25), step(t0 + 3.0, 1, 0, -0.25), step(t0 + 3.5, 0, 0, -0.25);
  };
  side_steps(2.0);
  step(6.0, 0, 0, 0.2), step(6.5, 1, 0, 0.2), step(7.0, 1, 0, -0.2), step(7.5, 0, 0, -0.2);
  // Strides forward and back.
  step(8.0, 0, 0.3, 0), step(8.5, 1, 0.3, 0), step(9.0, 0, 0.3, 0), step(9.5, 1, 0.3, 0);
  step(10.0, 0, -0.3, 0), step(10.5, 1, -0.3, 0), step(11.0, 0, -0.3, 0), step(11.5, 1, -0.3, 0);
  step(12.0, 1, 0.25, 0), step(12.5, 0, 0.25, 0), step(13.0, 1, -0.25, 0), step(13.5, 0, -0.25, 0);
  // Stepping turn: 8 steps of 45° about the body centre, left foot first (turning left).
  const double cf = 0.5 * (feet[0].fwd + feet[1].fwd), cl = 0.5 * (feet[0].left + feet[1].left);
  // A ninth step brings the left foot (last at 315°) alongside the right at 360°.
  for (int k = 1; k <= 9; ++k) {
    const int foot = (k - 1) % 2;
    const double yaw = kPi / 4.0 * std::min(k, 8);
    const double side = foot == 0 ? kStanceHalfWidth : -kStanceHalfWidth;
    feet[foot] = {cf - std::sin(yaw) * side, cl + std::cos(yaw) * side, yaw};
    steps.push_back({18.0 + 0.5 * (k - 1), foot, feet[foot]});
  }
  // After the turn both feet face 360° = 0 again (keep the heading continuous).
  side_steps(22.5);
  std::stable_sort(steps.begin(), steps.end(), [](const Step& a, const Step& b) { return a.t0 < b.t0; });
  return steps;
}

// Foot pose and lift at time t.
void foot_at(const std::vector<Step>& steps, int foot, double t, FootPose& pose, double& lift, double& swing) {
  FootPose from{0, foot == 0 ? kStanceHalfWidth : -kStanceHalfWidth, 0};
  lift = 0.0;
  swing = -1.0;  // progress of the current swing, -1 in stance
  for (const Step& s : steps) {
    if (s.foot != foot) continue;
    if (t >= s.t0 + kSwingTime) {
      from = s.to;
      continue;
    }
    if (t > s.t0) {
      const double u = (t - s.t0) / kSwingTime, w = smooth(u);
      pose = {from.fwd + w * (s.to.fwd - from.fwd), from.left + w * (s.to.left - from.left),
              from.yaw + w * (s.to.yaw - from.yaw)};
      lift = kSwingLift * bump(u);
      swing = u;
      return;
    }
    break;
  }
  pose = from;
}

// Trapezoid weight of a phase [a, b) with 0.4 s ramps.
double phase_weight(double t, double a, double b) {
  constexpr double r = 0.4;
  return std::clamp(std::min((t - a) / r + 0.5, (b - t) / r + 0.5), 0.0, 1.0);
}

struct ArmParams {
  double abduction, swing, elbow;  // [rad]: 0 = arm down; swing > 0 forward; elbow flexion
};

// Arm choreography for one arm (side +1 left, -1 right). Always inlined, as when one_cycle
// was its only caller: the 30 s dance keeps its bits (see one_cycle).
[[gnu::always_inline]] inline ArmParams arm_at(double t, double side) {
  const double w = 2.0 * kPi;
  struct Phase {
    double a, b;
    ArmParams p;
  };
  const Phase phases[] = {
      {-1.0, 2.0, {0.15, 0.35 * side * std::sin(w * t), 0.4}},
      {2.0, 8.0, {0.2 + 1.0 * smooth(0.5 - 0.5 * std::cos(w * t)), 0.1, 0.3}},
      {8.0, 14.0, {0.15, 0.6 * side * std::sin(w * t), 0.8}},
      {14.0, 18.0, {2.4 + 0.25 * std::sin(w * t + (side > 0 ? 0.0 : kPi)), 0.2, 0.3}},
      {18.0, 22.0, {1.2, 0.0, 0.5}},
      {22.0, 28.0, {0.4, 0.8 + 0.4 * std::sin(2.0 * w * t), 1.2 + 0.5 * std::sin(2.0 * w * t)}},
      {28.0, 40.0, {0.1, 0.0, 0.3}},
  };
  ArmParams out{0, 0, 0};
  double total = 0.0;
  for (const Phase& ph : phases) {
    const double k = phase_weight(t, ph.a, ph.b);
    out.abduction += k * ph.p.abduction;
    out.swing += k * ph.p.swing;
    out.elbow += k * ph.p.elbow;
    total += k;
  }
  out.abduction /= total;
  out.swing /= total;
  out.elbow = std::max(0.15, out.elbow / total);  // a bent elbow keeps the bend plane defined
  return out;
}

// The arms d_s from a seam (negative: before it): the earlier cycle's settle cross-fades into
// the later cycle's intro linearly over kSeamFade_s centred on the seam, as the cycle's own
// phases fade (phase_weight's 0.4 s ramps).
constexpr double kSeamFade_s = 0.4;
ArmParams arm_across_seam(double d_s, double side) {
  const ArmParams before = arm_at(kDefaultDanceDuration_s + d_s, side), after = arm_at(d_s, side);
  const double w = std::clamp(d_s / kSeamFade_s + 0.5, 0.0, 1.0);
  return {(1.0 - w) * before.abduction + w * after.abduction, (1.0 - w) * before.swing + w * after.swing,
          (1.0 - w) * before.elbow + w * after.elbow};
}

Mat3 yaw_matrix(double yaw) {
  return Eigen::AngleAxisd(yaw, Vec3::UnitY()).toRotationMatrix();
}

Vec3 ground_point(const FootPose& f, double height) {
  return {f.left, height, f.fwd};
}

// Two-link IK: thigh and shin world rotations for hip H, ankle A, knee bending toward fwd.
void leg_ik(const Vec3& hip, const Vec3& ankle, const Vec3& fwd, Mat3& thigh, Mat3& shin) {
  Vec3 d = ankle - hip;
  const double reach = std::min(d.norm(), 0.999 * (kThigh + kShin));
  const Vec3 u = d.normalized();
  Vec3 wdir = fwd - fwd.dot(u) * u;
  wdir.normalize();
  const double cos_alpha = (kThigh * kThigh + reach * reach - kShin * kShin) / (2.0 * kThigh * reach);
  const double alpha = std::acos(std::clamp(cos_alpha, -1.0, 1.0));
  const Vec3 d1 = std::cos(alpha) * u + std::sin(alpha) * wdir;
  const Vec3 knee = hip + kThigh * d1;
  const Vec3 d2 = (hip + reach * u - knee).normalized();
  const Vec3 lateral = wdir.cross(u).normalized();
  thigh.col(0) = lateral;
  thigh.col(1) = -d1;
  thigh.col(2) = lateral.cross(-d1);
  shin.col(0) = lateral;
  shin.col(1) = -d2;
  shin.col(2) = lateral.cross(-d2);
}

// Upper-arm and forearm rotations in the chest frame.
void arm_rotations(const ArmParams& p, double side, Mat3& upper, Mat3& fore) {
  const Vec3 x = Vec3::UnitX(), y = Vec3::UnitY(), z = Vec3::UnitZ();
  const Vec3 d =
      (std::cos(p.swing) * (side * std::sin(p.abduction) * x - std::cos(p.abduction) * y) + std::sin(p.swing) * z)
          .normalized();
  Vec3 bend = z - z.dot(d) * d;
  if (bend.norm() < 1e-3) bend = y - y.dot(d) * d;
  bend.normalize();
  const Vec3 dfa = std::cos(p.elbow) * d + std::sin(p.elbow) * bend;
  const Vec3 yb = (-side * d.cross(dfa)).normalized();
  const Vec3 xu = side * d, xf = side * dfa;
  upper.col(0) = xu;
  upper.col(1) = yb;
  upper.col(2) = xu.cross(yb);
  fore.col(0) = xf;
  fore.col(1) = yb;
  fore.col(2) = xf.cross(yb);
}

void put_rotation(Bvh& b, int joint, double* row, const Mat3& local) {
  const Vec3 e = local.eulerAngles(2, 0, 1);  // channels Z X Y, after the root's 3 positions
  const int c = b.joints[joint].first_column + (joint == kHips ? 3 : 0);
  row[c] = e[0] * kRadToDeg;
  row[c + 1] = e[1] * kRadToDeg;
  row[c + 2] = e[2] * kRadToDeg;
}

// One cycle: kDefaultDanceDuration_s, both end frames. Not inlined: compiled as its own
// function the 30 s dance keeps its bits (the build contracts a·b + c into FMAs, so where a
// body is inlined decides the last bits; checked by comparing `kuavo retarget --dance-bvh`
// before and after).
[[gnu::noinline]] Bvh one_cycle() {
  Bvh b;
  for (int i = 0; i < kJointCount; ++i) {
    const JointDef& d = kSkeleton[i];
    BvhJoint j;
    j.parent = d.parent;
    j.offset = kUnitsPerM * Vec3(d.x, d.y, d.z);
    j.end_site = d.name[0] == '\0';
    j.name = j.end_site ? b.joints[d.parent].name + "_End" : d.name;
    if (i == kHips)
      j.channels = {BvhChannel::kXposition, BvhChannel::kYposition, BvhChannel::kZposition,
                    BvhChannel::kZrotation, BvhChannel::kXrotation, BvhChannel::kYrotation};
    else if (!j.end_site)
      j.channels = {BvhChannel::kZrotation, BvhChannel::kXrotation, BvhChannel::kYrotation};
    j.first_column = b.channel_count;
    b.channel_count += static_cast<int>(j.channels.size());
    b.joints.push_back(j);
  }
  b.frame_time_s = 1.0 / kDefaultDanceRate_hz;
  b.frame_count = static_cast<int>(std::lround(kDefaultDanceDuration_s * kDefaultDanceRate_hz)) + 1;
  b.motion.assign(static_cast<std::size_t>(b.frame_count) * b.channel_count, 0.0);
  const std::vector<Step> steps = plan_steps();

  for (int f = 0; f < b.frame_count; ++f) {
    const double t = f * b.frame_time_s;
    double* row = b.motion.data() + static_cast<std::size_t>(f) * b.channel_count;
    std::array<FootPose, 2> feet;
    std::array<double, 2> lift{}, swing{};
    for (int s = 0; s < 2; ++s) foot_at(steps, s, t, feet[s], lift[s], swing[s]);
    // Weight shift toward the stance foot around each swing, plus a sway in the intro,
    // the hip-sway section and the final settle.
    double shift = 0.0;  // +: toward the left foot
    for (const Step& s : steps) {
      const double u = (t - (s.t0 - 0.15)) / (kSwingTime + 0.3);
      shift += (s.foot == 1 ? 0.35 : -0.35) * bump(u);
    }
    const double sway = phase_weight(t, -1.0, 2.0) + phase_weight(t, 14.0, 18.0) + phase_weight(t, 26.0, 31.0);
    shift += 0.3 * sway * std::sin(kPi * t);
    const double bounce = phase_weight(t, 14.0, 18.0) + phase_weight(t, 22.0, 28.0);
    const double yaw = 0.5 * (feet[0].yaw + feet[1].yaw);
    const double mid_fwd = 0.5 * (feet[0].fwd + feet[1].fwd), mid_left = 0.5 * (feet[0].left + feet[1].left);
    const double pelvis_fwd = mid_fwd + shift * (feet[0].fwd - feet[1].fwd);
    const double pelvis_left = mid_left + shift * (feet[0].left - feet[1].left);
    const double hip_height = kStandingHipHeight - 0.035 * bounce * (0.5 - 0.5 * std::cos(4.0 * kPi * t));
    const double roll = -0.06 * sway * std::sin(kPi * t);
    const Mat3 pelvis = yaw_matrix(yaw) * Eigen::AngleAxisd(roll, Vec3::UnitZ()).toRotationMatrix();
    const Vec3 hip_centre(pelvis_left, hip_height, pelvis_fwd);
    const Vec3 root = hip_centre + pelvis * Vec3(0, kHipDrop, 0);
    row[0] = kUnitsPerM * root.x();
    row[1] = kUnitsPerM * root.y();
    row[2] = kUnitsPerM * root.z();
    put_rotation(b, kHips, row, pelvis);

    for (int s = 0; s < 2; ++s) {
      const double side = s == 0 ? 1.0 : -1.0;
      const Vec3 hip = root + pelvis * Vec3(side * kHipHalfWidth, -kHipDrop, 0);
      const Vec3 ankle = ground_point(feet[s], kAnkleHeight + lift[s]);
      const Mat3 foot = yaw_matrix(feet[s].yaw);
      Mat3 thigh, shin;
      leg_ik(hip, ankle, foot.col(2), thigh, shin);
      const int up = s == 0 ? kLUpLeg : kRUpLeg;
      put_rotation(b, up, row, pelvis.transpose() * thigh);
      put_rotation(b, up + 1, row, thigh.transpose() * shin);
      put_rotation(b, up + 2, row, shin.transpose() * foot);
    }
    // Torso: a little forward lean, a twist against the arm swing, a nod.
    const Mat3 spine = Eigen::AngleAxisd(0.15 * std::sin(kPi * t) * phase_weight(t, 8.0, 14.0), Vec3::UnitY()) *
                       Eigen::AngleAxisd(0.06, Vec3::UnitX()).toRotationMatrix();
    put_rotation(b, kSpine, row, spine);
    put_rotation(b, kHead, row, Eigen::AngleAxisd(0.1 * std::sin(2.0 * kPi * t), Vec3::UnitX()).toRotationMatrix());
    for (int s = 0; s < 2; ++s) {
      const double side = s == 0 ? 1.0 : -1.0;
      Mat3 upper, fore;
      arm_rotations(arm_at(t, side), side, upper, fore);
      const int arm = s == 0 ? kLArm : kRArm;
      put_rotation(b, arm, row, upper);
      put_rotation(b, arm + 1, row, upper.transpose() * fore);
    }
  }
  return b;
}

}  // namespace

int default_dance_cycles(double duration_s) {
  const double cycles = std::round(duration_s / kDefaultDanceDuration_s);
  if (!(std::abs(duration_s - cycles * kDefaultDanceDuration_s) <= 1e-3) || cycles < 1 || cycles > kDefaultDanceMaxCycles)
    return 0;
  return static_cast<int>(cycles);
}

Bvh default_dance_bvh(int cycles) {
  Bvh b = one_cycle();
  cycles = std::clamp(cycles, 1, kDefaultDanceMaxCycles);
  if (cycles == 1) return b;
  // Every cycle's frames are the first's (a seam frame is the first of the later cycle; the
  // last frame is the first cycle's last), but for the arms within half a fade of a seam.
  const int per_cycle = b.frame_count - 1;
  const std::vector<double> first = b.motion;
  const auto width = static_cast<std::size_t>(b.channel_count);
  b.frame_count = cycles * per_cycle + 1;
  b.motion.resize(static_cast<std::size_t>(b.frame_count) * width);
  for (int f = per_cycle + 1; f < b.frame_count; ++f) {
    const int local = f - std::min(f / per_cycle, cycles - 1) * per_cycle;
    std::copy_n(first.begin() + static_cast<std::ptrdiff_t>(local * width), width,
                b.motion.begin() + static_cast<std::ptrdiff_t>(f * width));
  }
  const int half_fade = static_cast<int>(std::lround(0.5 * kSeamFade_s / b.frame_time_s));
  for (int c = 1; c < cycles; ++c) {
    for (int f = c * per_cycle - half_fade + 1; f < c * per_cycle + half_fade; ++f) {
      double* row = b.motion.data() + static_cast<std::size_t>(f) * width;
      for (int s = 0; s < 2; ++s) {
        const double side = s == 0 ? 1.0 : -1.0;
        Mat3 upper, fore;
        arm_rotations(arm_across_seam((f - c * per_cycle) * b.frame_time_s, side), side, upper, fore);
        const int arm = s == 0 ? kLArm : kRArm;
        put_rotation(b, arm, row, upper);
        put_rotation(b, arm + 1, row, upper.transpose() * fore);
      }
    }
  }
  return b;
}

std::string default_dance_bvh_text() {
  return write_bvh(default_dance_bvh());
}

}  // namespace kuavo::mocap
