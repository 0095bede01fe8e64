#include "tools/cli/motion_report.h"

#include <array>
#include <cmath>

#include "tools/report/svg_plot.h"

namespace kuavo::cli {
namespace {

using report::Plot;
using report::Series;

template <class Rows, class Get>
Series column(const std::string& name, const std::vector<double>& t, const Rows& rows, Get get, const std::string& color,
              bool dashed = false) {
  Series s;
  s.name = name;
  s.x = t;
  s.y.reserve(rows.size());
  for (const auto& r : rows) s.y.push_back(get(r));
  s.color = color;
  s.dashed = dashed;
  return s;
}

Plot time_plot(const std::string& title, const std::string& y_label) {
  Plot p;
  p.title = title;
  p.x_label = "time [s]";
  p.y_label = y_label;
  return p;
}

}  // namespace

bool write_motion_plots(const model::Model& robot, const sim::MotionTrace& trace, const std::string& stem,
                        const std::string& title, std::string& error) {
  const auto& t = trace.time_s;
  // Joint tracking: hip pitch, knee and ankle pitch of the left leg, two left-arm joints.
  std::vector<Plot> joints;
  const char* colors[] = {"#1f77b4", "#d62728"};
  for (int j : {model::kLeftLegFirst + 2, model::kLeftLegFirst + 3, model::kLeftLegFirst + 4, model::kLeftArmFirst,
                model::kLeftArmFirst + 3}) {
    Plot p = time_plot(title + ": " + model::joint_name(robot, j), "angle [rad]");
    p.height_px = 240;
    p.series.push_back(column("plan", t, trace.q_ref, [j](const auto& r) { return r[j]; }, colors[0], true));
    p.series.push_back(column("simulated", t, trace.q, [j](const auto& r) { return r[j]; }, colors[1]));
    joints.push_back(std::move(p));
  }
  // CoM against the plan, per axis.
  std::vector<Plot> com;
  const char* axis[] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    Plot p = time_plot(title + ": centre of mass " + axis[a], std::string(axis[a]) + " [m]");
    p.height_px = 240;
    p.series.push_back(column("plan", t, trace.com_ref, [a](const auto& r) { return r[a]; }, colors[0], true));
    p.series.push_back(column("simulated", t, trace.com, [a](const auto& r) { return r[a]; }, colors[1]));
    com.push_back(std::move(p));
  }
  // ZMP against the support polygon (its bounding box per axis), and the margin.
  std::vector<Plot> zmp;
  for (int a = 0; a < 2; ++a) {
    Plot p = time_plot(title + ": ZMP " + axis[a] + " and the support polygon's extent", std::string(axis[a]) + " [m]");
    p.height_px = 260;
    p.series.push_back(column("support min", t, trace.support_lo, [a](const auto& r) { return r[a]; }, "#7f7f7f", true));
    p.series.push_back(column("support max", t, trace.support_hi, [a](const auto& r) { return r[a]; }, "#7f7f7f", true));
    p.series.push_back(column("CoM", t, trace.com, [a](const auto& r) { return r[a]; }, "#2ca02c"));
    p.series.push_back(column("ZMP (centre of pressure)", t, trace.zmp, [a](const auto& r) { return r[a]; }, "#d62728"));
    zmp.push_back(std::move(p));
  }
  Plot margin = time_plot(title + ": ZMP margin to the support polygon's edge", "margin [m]");
  margin.height_px = 220;
  margin.series.push_back(column("margin", t, trace.zmp_margin_m, [](double v) { return v; }, "#9467bd"));
  zmp.push_back(std::move(margin));
  // Top-down: CoM and ZMP paths over the ground.
  Plot top;
  top.title = title + ": top view, CoM and ZMP paths";
  top.x_label = "x [m]";
  top.y_label = "y [m]";
  top.equal_axes = true;
  top.height_px = 420;
  Series zx = column("ZMP", trace.time_s, trace.zmp, [](const auto& r) { return r[1]; }, "#d62728");
  zx.x.clear();
  for (const auto& r : trace.zmp) zx.x.push_back(r[0]);
  Series cx = column("CoM", trace.time_s, trace.com, [](const auto& r) { return r[1]; }, "#2ca02c");
  cx.x.clear();
  for (const auto& r : trace.com) cx.x.push_back(r[0]);
  top.series = {zx, cx};
  zmp.push_back(std::move(top));

  return report::write_text_file(stem + "_tracking.svg", report::render_svg_stack(joints), &error) &&
         report::write_text_file(stem + "_com.svg", report::render_svg_stack(com), &error) &&
         report::write_text_file(stem + "_zmp.svg", report::render_svg_stack(zmp), &error);
}

namespace {

// Sole-centre positions at each touchdown, as dots: one point between NaN separators.
report::Series touchdowns(const std::string& name, const sim::MotionTrace& t, const std::string& color) {
  report::Series s;
  s.name = name;
  s.color = color;
  const double nan = std::nan("");
  std::array<bool, 2> up{false, false};
  for (std::size_t i = 0; i < t.foot_force_z_N.size(); ++i) {
    for (int foot = 0; foot < 2; ++foot) {
      const double f = t.foot_force_z_N[i][foot];
      if (f < 5.0) up[foot] = true;
      if (up[foot] && f > 100.0) {
        up[foot] = false;
        s.x.insert(s.x.end(), {nan, t.foot_xy_m[i][2 * foot]});
        s.y.insert(s.y.end(), {nan, t.foot_xy_m[i][2 * foot + 1]});
      }
    }
  }
  return s;
}

report::Series knee_series(const std::string& name, const sim::MotionTrace& t, bool plan, const std::string& color) {
  report::Series s;
  s.name = name;
  s.color = color;
  s.dashed = plan;
  s.x = t.time_s;
  for (std::size_t i = 0; i < t.q.size(); ++i) s.y.push_back((plan ? t.q_ref[i] : t.q[i])[model::kLeftLegFirst + 3]);
  return s;
}

}  // namespace

bool write_horizon_plots(const sim::MotionTrace& long_horizon, const sim::MotionTrace& short_horizon,
                         const std::string& stem, std::string& error) {
  report::Plot knee;
  knee.title = "carpet: left knee, MPC horizon 1.2 s vs 0.6 s";
  knee.x_label = "time [s]";
  knee.y_label = "knee [rad]";
  knee.series = {knee_series("plan", long_horizon, true, "#7f7f7f"), knee_series("horizon 1.2 s", long_horizon, false, "#1f77b4"),
                 knee_series("horizon 0.6 s", short_horizon, false, "#d62728")};
  report::Plot feet;
  feet.title = "carpet: touchdown positions (sole centres), top view";
  feet.x_label = "x [m]";
  feet.y_label = "y [m]";
  feet.equal_axes = true;
  feet.height_px = 420;
  feet.series = {touchdowns("horizon 1.2 s", long_horizon, "#1f77b4"), touchdowns("horizon 0.6 s", short_horizon, "#d62728")};
  return report::write_text_file(stem + "_knee.svg", report::render_svg(knee), &error) &&
         report::write_text_file(stem + "_feet.svg", report::render_svg(feet), &error);
}

}  // namespace kuavo::cli
