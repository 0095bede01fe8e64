#include "tools/cli/motion_report.h"

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

}  // namespace kuavo::cli
