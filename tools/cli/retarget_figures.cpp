#include "tools/cli/retarget_figures.h"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <limits>
#include <memory>

#include "tools/report/svg_plot.h"

namespace kuavo::cli {
namespace {

using report::Plot;
using report::Series;

constexpr const char* kGeometricColor = "#1f77b4";
constexpr const char* kDynamicColor = "#d62728";
constexpr const char* kLimitColor = "#7f7f7f";
// Wide enough for a title with both motions' numbers (13 px bold, ~7.5 px a character).
constexpr int kFigureWidth_px = 1100;
constexpr int kPanelHeight_px = 260;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Drawing range of the quantities whose geometric values spike where the finite differences
// of a kinematic motion jump (a foot landing, a hop): beyond these the plot would only show
// the spikes. Samples outside are drawn at the bound; every number printed is unclipped.
//  - torques at 2× the joint's limit: twice over is as infeasible as any more;
//  - a foot's lateral force at the robot's weight (μ = 0.5 allows half of it at full load);
//  - the ZMP at 0.25 m outside, beyond a sole's length (0.2 m): "no support" either way.
constexpr double kTorqueDrawLimit = 2.0;
constexpr double kZmpOutsideDraw_m = 0.25;

// Joints the figures show (controller order, FACTS.md §2.1: leg joint 3 hip pitch, 4 knee;
// arm joint 1 shoulder pitch).
constexpr int kLeftHipPitch = model::kLeftLegFirst + 2;
constexpr int kLeftKnee = model::kLeftLegFirst + 3;
constexpr int kRightKnee = model::kRightLegFirst + 3;
constexpr int kLeftShoulderPitch = model::kLeftArmFirst;
// Left sole corners (frame ids 0..3: toe +y, toe −y, heel +y, heel −y).
constexpr int kLeftToeOuter = 0, kLeftToeInner = 1, kLeftCorners = 4;

std::string format(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string format(const char* f, ...) {
  char buf[512];
  va_list args;
  va_start(args, f);
  std::vsnprintf(buf, sizeof buf, f, args);
  va_end(args);
  return buf;
}

struct Stat {
  double max = 0.0, sum = 0.0;
  int count = 0;
  void add(double v) {
    max = std::max(max, v);
    sum += v;
    ++count;
  }
  double mean() const { return count ? sum / count : 0.0; }
};

// Dance clock of a motion whose frame `lead` shows dance frame 0.
std::vector<double> dance_clock(std::size_t n, int lead, double rate_hz) {
  std::vector<double> t(n);
  for (std::size_t i = 0; i < n; ++i) t[i] = (static_cast<double>(i) - lead) / rate_hz;
  return t;
}

Series line(const std::string& name, std::vector<double> x, std::vector<double> y, const char* color,
            bool dashed = false) {
  Series s;
  s.name = name;
  s.x = std::move(x);
  s.y = std::move(y);
  s.color = color;
  s.dashed = dashed;
  return s;
}

Plot panel(const std::string& title, const std::string& y_label) {
  Plot p;
  p.title = title;
  p.x_label = "dance time [s] (dynamic lead-in at t < 0)";
  p.y_label = y_label;
  p.width_px = kFigureWidth_px;
  p.height_px = kPanelHeight_px;
  return p;
}

std::vector<double> clipped(std::vector<double> y, double bound) {
  for (double& v : y) v = std::clamp(v, -bound, bound);  // NaN stays NaN
  return y;
}

// Both motions' curves of one quantity (their legends carry each motion's numbers), and a
// limit drawn as horizontal lines across them.
struct Pair {
  std::vector<double> tg, td;  // dance clocks
  void add(Plot& p, std::vector<double> geometric, std::vector<double> dynamic, const std::string& geometric_numbers,
           const std::string& dynamic_numbers) const {
    p.series.push_back(line("geometric: " + geometric_numbers, tg, std::move(geometric), kGeometricColor));
    p.series.push_back(line("dynamic (TO): " + dynamic_numbers, td, std::move(dynamic), kDynamicColor));
  }
  void limit(Plot& p, const std::string& name, double y) const {
    const double t0 = std::min(tg.front(), td.front()), t1 = std::max(tg.back(), td.back());
    p.series.push_back(line(name, {t0, t1}, {y, y}, kLimitColor, true));
  }
};

template <class Get>
std::vector<double> per_frame(std::size_t n, Get get) {
  std::vector<double> y(n);
  for (std::size_t i = 0; i < n; ++i) y[i] = get(i);
  return y;
}

void knee_panels(const model::Model& robot, const FigureMotion& g, const FigureMotion& d, const Pair& clock, int j,
                 std::vector<Plot>& plots, std::vector<FigureNumber>& numbers) {
  const std::string name = model::joint_name(robot, j);
  const double lo = robot.limits.position_min_rad[j], hi = robot.limits.position_max_rad[j];
  const double limit = robot.limits.torque_Nm[j];
  struct Counts {
    int outside = 0, over = 0;
    double ratio = 0.0;
  };
  const auto counts = [&](const FigureMotion& m) {
    Counts c;
    for (std::size_t i = 0; i < m.q.size(); ++i) {
      const double q = m.q[i][7 + j], tau = std::abs(m.check.tau_Nm[i][j]);
      c.outside += q < lo || q > hi;
      c.over += tau > limit;
      c.ratio = std::max(c.ratio, tau / limit);
    }
    return c;
  };
  const Counts cg = counts(g), cd = counts(d);

  Plot angle = panel(format("Fig. 4: %s (knee) angle and its position limits %.2f..%.2f rad", name.c_str(), lo, hi),
                     "angle [rad]");
  clock.add(angle, per_frame(g.q.size(), [&](std::size_t i) { return g.q[i][7 + j]; }),
            per_frame(d.q.size(), [&](std::size_t i) { return d.q[i][7 + j]; }),
            format("%d frames outside", cg.outside), format("%d frames outside", cd.outside));
  clock.limit(angle, "position limit", lo);
  clock.limit(angle, "", hi);
  plots.push_back(std::move(angle));

  Plot torque = panel(format("Fig. 4: %s (knee) RNEA torque and its limit +-%.0f N m (drawn clipped at +-%.0f N m)",
                             name.c_str(), limit, kTorqueDrawLimit * limit),
                      "torque [N m]");
  const double bound = kTorqueDrawLimit * limit;
  clock.add(torque, clipped(per_frame(g.q.size(), [&](std::size_t i) { return g.check.tau_Nm[i][j]; }), bound),
            clipped(per_frame(d.q.size(), [&](std::size_t i) { return d.check.tau_Nm[i][j]; }), bound),
            format("max |tau|/limit %.2f, %d frames over", cg.ratio, cg.over),
            format("max |tau|/limit %.2f, %d frames over", cd.ratio, cd.over));
  clock.limit(torque, "torque limit", limit);
  clock.limit(torque, "", -limit);
  plots.push_back(std::move(torque));

  numbers.push_back({name + "_torque_ratio_max", cg.ratio, cd.ratio});
  numbers.push_back({name + "_frames_over_torque_limit", double(cg.over), double(cd.over)});
  numbers.push_back({name + "_frames_outside_position_limits", double(cg.outside), double(cd.outside)});
}

// q̇ of joint j per frame, and its |q̇| statistics over all frames and over the frames `take` selects.
template <class Take>
std::vector<double> joint_rate(const FigureMotion& m, double rate_hz, int j, Take take, Stat& all, Stat& taken) {
  std::vector<dynamics::VelocityVector> v, a;
  mocap::frame_rates(m.q, rate_hz, v, a);
  std::vector<double> y(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    y[i] = v[i][6 + j];
    all.add(std::abs(y[i]));
    if (take(m.contacts[i])) taken.add(std::abs(y[i]));
  }
  return y;
}

// The left foot's contact force along its sole's lateral axis while it is down (NaN in swing).
std::vector<double> left_lateral_force(const model::Model& robot, const FigureMotion& m, Stat& stat) {
  auto data = std::make_unique<dynamics::Data>();
  std::vector<double> y(m.q.size(), kNaN);
  for (std::size_t i = 0; i < m.q.size(); ++i) {
    if (!mocap::left_in_contact(m.contacts[i])) continue;
    dynamics::forward_kinematics(robot, *data, m.q[i]);
    dynamics::Vec3 lateral = dynamics::frame_position(robot, *data, kLeftToeOuter) -
                             dynamics::frame_position(robot, *data, kLeftToeInner);
    lateral.z() = 0.0;
    lateral.normalize();
    double f = 0.0;
    for (int c = 0; c < kLeftCorners; ++c) f += m.check.forces_N[i].segment<3>(3 * c).dot(lateral);
    y[i] = f;
    stat.add(std::abs(f));
  }
  return y;
}

void dynamics_panels(const model::Model& robot, const FigureMotion& g, const FigureMotion& d, const Pair& clock,
                     double rate_hz, std::vector<Plot>& plots, std::vector<FigureNumber>& numbers) {
  const auto left_swings = [](mocap::ContactLabel c) { return c == mocap::ContactLabel::kRightSupport; };
  const auto every = [](mocap::ContactLabel) { return true; };
  {
    const std::string name = model::joint_name(robot, kLeftHipPitch);
    Stat ga, gs, da, ds;
    std::vector<double> yg = joint_rate(g, rate_hz, kLeftHipPitch, left_swings, ga, gs);
    std::vector<double> yd = joint_rate(d, rate_hz, kLeftHipPitch, left_swings, da, ds);
    Plot p = panel(format("Fig. 5a: swing leg, %s (hip pitch) velocity; |qd| max, and mean over the left foot's swings",
                          name.c_str()),
                   "velocity [rad/s]");
    clock.add(p, std::move(yg), std::move(yd), format("max %.2f, swing mean %.2f rad/s", ga.max, gs.mean()),
              format("max %.2f, swing mean %.2f rad/s", da.max, ds.mean()));
    plots.push_back(std::move(p));
    numbers.push_back({name + "_speed_rad_s_max", ga.max, da.max});
    numbers.push_back({name + "_swing_speed_rad_s_mean", gs.mean(), ds.mean()});
  }
  {
    const std::string name = model::joint_name(robot, kLeftShoulderPitch);
    Stat ga, gs, da, ds;
    std::vector<double> yg = joint_rate(g, rate_hz, kLeftShoulderPitch, every, ga, gs);
    std::vector<double> yd = joint_rate(d, rate_hz, kLeftShoulderPitch, every, da, ds);
    Plot p = panel(format("Fig. 5b: arm, %s (shoulder pitch) velocity; |qd| max and mean", name.c_str()),
                   "velocity [rad/s]");
    clock.add(p, std::move(yg), std::move(yd), format("max %.2f, mean %.2f rad/s", ga.max, ga.mean()),
              format("max %.2f, mean %.2f rad/s", da.max, da.mean()));
    plots.push_back(std::move(p));
    numbers.push_back({name + "_speed_rad_s_max", ga.max, da.max});
    numbers.push_back({name + "_speed_rad_s_mean", ga.mean(), da.mean()});
  }
  {
    Stat gs, ds;
    std::vector<double> yg = left_lateral_force(robot, g, gs), yd = left_lateral_force(robot, d, ds);
    const double weight_N = robot.total_mass_kg * model::kGravity_m_s2;
    Plot p = panel(format("Fig. 5c: stance foot, left sole's lateral force while down; |F| max and mean (drawn clipped "
                          "at +-%.0f N, the weight)",
                          weight_N),
                   "force [N]");
    clock.add(p, clipped(std::move(yg), weight_N), clipped(std::move(yd), weight_N),
              format("max %.0f, mean %.1f N", gs.max, gs.mean()), format("max %.0f, mean %.1f N", ds.max, ds.mean()));
    plots.push_back(std::move(p));
    numbers.push_back({"left_foot_lateral_force_N_max", gs.max, ds.max});
    numbers.push_back({"left_foot_lateral_force_N_mean", gs.mean(), ds.mean()});
  }
  {
    Stat gs, ds;
    for (double z : g.check.zmp_outside_m) gs.add(z);
    for (double z : d.check.zmp_outside_m) ds.add(z);
    Plot p = panel(format("Fig. 5d: ZMP distance outside the support polygon; max and mean (drawn clipped at %.2f m)",
                          kZmpOutsideDraw_m),
                   "distance [m]");
    clock.add(p, clipped(g.check.zmp_outside_m, kZmpOutsideDraw_m), clipped(d.check.zmp_outside_m, kZmpOutsideDraw_m),
              format("max %.3f, mean %.4f m", gs.max, gs.mean()), format("max %.3f, mean %.4f m", ds.max, ds.mean()));
    plots.push_back(std::move(p));
    numbers.push_back({"zmp_outside_m_max", gs.max, ds.max});
    numbers.push_back({"zmp_outside_m_mean", gs.mean(), ds.mean()});
  }
}

}  // namespace

bool write_retarget_figures(const model::Model& robot, const FigureMotion& geometric, const FigureMotion& dynamic,
                            int lead_frames, double rate_hz, const std::string& dir, RetargetFigures& out,
                            std::string& error) {
  out = RetargetFigures{};
  if (geometric.q.empty() || dynamic.q.empty()) {
    error = "retarget figures: a motion without frames";
    return false;
  }
  const Pair clock{dance_clock(geometric.q.size(), 0, rate_hz), dance_clock(dynamic.q.size(), lead_frames, rate_hz)};
  const std::string prefix = dir.empty() ? std::string() : dir + "/";

  std::vector<Plot> fig4;
  for (int j : {kLeftKnee, kRightKnee}) knee_panels(robot, geometric, dynamic, clock, j, fig4, out.numbers);
  if (!report::write_text_file(prefix + "fig4_knee.svg", report::render_svg_stack(fig4), &error)) return false;
  out.files.push_back("fig4_knee.svg");

  std::vector<Plot> fig5;
  dynamics_panels(robot, geometric, dynamic, clock, rate_hz, fig5, out.numbers);
  if (!report::write_text_file(prefix + "fig5_dynamics.svg", report::render_svg_stack(fig5), &error)) return false;
  out.files.push_back("fig5_dynamics.svg");
  return true;
}

double swing_leg_speed_rad_s(const std::vector<dynamics::ConfigVector>& q,
                             const std::vector<mocap::ContactLabel>& contacts, double rate_hz) {
  std::vector<dynamics::VelocityVector> v, a;
  mocap::frame_rates(q, rate_hz, v, a);
  Stat s;
  for (std::size_t i = 0; i < v.size() && i < contacts.size(); ++i) {
    int first = -1;
    if (contacts[i] == mocap::ContactLabel::kLeftSupport) first = model::kRightLegFirst;
    if (contacts[i] == mocap::ContactLabel::kRightSupport) first = model::kLeftLegFirst;
    if (first >= 0) s.add(v[i].segment<model::kLegJoints>(6 + first).cwiseAbs().mean());
  }
  return s.mean();
}

double com_speed_m_s(const model::Model& robot, const std::vector<dynamics::ConfigVector>& q, double rate_hz,
                     int first, int count) {
  const int begin = std::max(first, 0);
  const int end = std::min(first + count, static_cast<int>(q.size()));
  if (end - begin < 2) return 0.0;
  auto data = std::make_unique<dynamics::Data>();
  double path_m = 0.0;
  dynamics::Vec3 previous = dynamics::Vec3::Zero();
  for (int i = begin; i < end; ++i) {
    dynamics::forward_kinematics(robot, *data, q[i]);
    dynamics::crba(robot, *data);
    if (i > begin) path_m += (data->com_m - previous).norm();
    previous = data->com_m;
  }
  return path_m * rate_hz / (end - begin - 1);
}

}  // namespace kuavo::cli
