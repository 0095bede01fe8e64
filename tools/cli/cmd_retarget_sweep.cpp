// kuavo retarget-sweep [IN.bvh] --out DIR [--horizons 0.2,0.4,...] [--variant s45|s42]
//
// The paper's Fig. 6 and the solve-time benchmark: the geometric stage once (automatic
// contacts, built-in skeleton map; the built-in dance without IN.bvh), then the dynamic stage
// (retarget_dynamic.h) at each horizon (default 0.2 … 1.4 s, step 0.2). Writes
//  - DIR/sweep.json: per horizon the TO's solve time (also per 10⁴ output frames), windows,
//    SQP iterations, windows at the iteration cap, the swing leg's mean joint speed over the
//    single-support frames, the mean CoM speed over the dance (lead-in and tail left out:
//    they are the same at every horizon) and the oracle's torque / friction violations; the
//    geometric motion's two speeds as the reference. A horizon whose stage fails keeps its
//    message under "error" and the sweep goes on; one whose result the optimization does not
//    stand behind (retarget_dynamic.h: windows at the cap, the oracle's support and torques)
//    lists why under "unsound", and Fig. 6's titles name it.
//  - DIR/fig6_horizon.svg: the two speeds and the solve time against the horizon.
// Solve times are wall clock on this machine, so the JSON differs from run to run there.
// Exit: 0 when at least one horizon solved, 1 when none did or an output cannot be written,
// 2 bad usage or input.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "rtos_shim/args.h"
#include "tools/cli/commands.h"
#include "tools/cli/usage.h"
#include "tools/cli/progress.h"
#include "tools/cli/retarget_dynamic.h"
#include "tools/cli/retarget_figures.h"
#include "tools/mocap/contacts.h"
#include "tools/mocap/default_dance.h"
#include "tools/mocap/retarget.h"
#include "tools/report/svg_plot.h"

namespace kuavo::cli {
namespace {

using nlohmann::ordered_json;

// The window range the offline OCP accepts (mpc_validate_config without plan output).
constexpr double kMinHorizon_s = 0.2, kMaxHorizon_s = 1.4;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string short_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// "0.2,0.6,1.0": each item a whole number token in the range (rtos_shim/args.h); an empty
// item (",,", a trailing comma) is refused.
bool parse_horizons(const std::string& text, std::vector<double>& out) {
  std::vector<double> h;
  std::size_t pos = 0;
  while (true) {
    const std::size_t comma = text.find(',', pos);
    const std::string item = text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
    double v = 0.0;
    if (!args::parse_number(item.c_str(), kMinHorizon_s, kMaxHorizon_s, v)) return false;
    h.push_back(v);
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  out = std::move(h);
  return true;
}

// One plot of a figure against the horizon, with the geometric motion's value as a dashed line.
report::Plot against_horizon(const std::string& title, const std::string& y_label, const std::vector<double>& h,
                             const std::vector<double>& y, const std::string& name, double geometric) {
  report::Plot p;
  p.title = title;
  p.x_label = "horizon [s]";
  p.y_label = y_label;
  p.height_px = 260;
  report::Series s;
  s.name = name;
  s.x = h;
  s.y = y;
  s.color = "#d62728";
  p.series.push_back(std::move(s));
  if (std::isfinite(geometric)) {
    report::Series g;
    g.name = "geometric";
    g.x = {h.front(), h.back()};
    g.y = {geometric, geometric};
    g.color = "#1f77b4";
    g.dashed = true;
    p.series.push_back(std::move(g));
  }
  return p;
}

int run(int argc, char** argv) {
  std::string out_dir, variant_name = "s45";
  std::vector<std::string> inputs;
  std::vector<double> horizons;
  for (int k = 1; k <= 7; ++k) horizons.push_back(2 * k / 10.0);
  model::Variant variant = model::Variant::kS45;
  args::Parser p("kuavo retarget-sweep");
  p.positionals("INPUT.bvh", &inputs, 1);
  p.text("--out", "DIR", &out_dir);
  p.custom("--horizons", "S,S,... with each S in [0.2, 1.4] s",
           [&](const char* v) { return parse_horizons(v, horizons); });
  p.choice("--variant", {"s45", "s42"}, &variant_name);
  bool quiet = false;
  p.flag("--quiet", &quiet);
  if (const int code = parse_command_line(p, argc, argv, "retarget-sweep"); code >= 0) return code;
  std::sort(horizons.begin(), horizons.end());  // Fig. 6's x axis
  model::parse_variant(variant_name.c_str(), variant);  // one of the two names
  const std::string input = inputs.empty() ? "" : inputs[0];
  if (out_dir.empty()) {
    std::fprintf(stderr, "kuavo retarget-sweep: --out DIR is required\n");
    return usage_error("retarget-sweep");
  }
  if (!input.empty()) {
    std::string why;
    if (!args::check_input_file(input, why)) {
      std::fprintf(stderr, "kuavo retarget-sweep: %s\n", why.c_str());
      return 2;
    }
  }
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (!std::filesystem::is_directory(out_dir)) {
    std::fprintf(stderr, "kuavo retarget-sweep: %s: cannot create directory\n", out_dir.c_str());
    return 1;
  }

  auto robot = std::make_unique<model::Model>();
  if (const auto e = model::build_model(variant, model::kDefaultTotalMass_kg, *robot); e != model::ModelError::kOk) {
    std::fprintf(stderr, "kuavo retarget-sweep: %s\n", model::to_string(e));
    return 1;
  }

  // The geometric stage, once (kuavo retarget's defaults).
  mocap::Bvh bvh;
  std::string error;
  if (input.empty()) {
    bvh = mocap::default_dance_bvh();
  } else if (!mocap::load_bvh_file(input, bvh, error)) {
    std::fprintf(stderr, "kuavo retarget-sweep: %s\n", error.c_str());
    return 2;
  }
  mocap::SkeletonMap map;
  mocap::HumanTargets targets;
  if (!mocap::map_skeleton(bvh, map, error) || !mocap::make_targets(bvh, map, *robot, {}, targets, error)) {
    std::fprintf(stderr, "kuavo retarget-sweep: %s\n", error.c_str());
    return 2;
  }
  const std::vector<mocap::ContactLabel> labels = mocap::detect_contacts(targets, *robot);
  mocap::RetargetResult geometric;
  mocap::retarget_motion(*robot, targets, labels, {}, geometric);
  const double rate = targets.rate_hz;
  const int geo_frames = static_cast<int>(geometric.q.size());
  const double geo_swing = swing_leg_speed_rad_s(geometric.q, geometric.contacts, rate);
  const double geo_com = com_speed_m_s(*robot, geometric.q, rate, 0, geo_frames);

  ordered_json sweep;
  sweep["input"] = input.empty() ? "builtin:default_dance" : input;
  sweep["variant"] = model::to_string(variant);
  sweep["rate_hz"] = rate;
  sweep["geometric"] = {{"frames", geo_frames}, {"swing_leg_speed_rad_s", geo_swing}, {"com_speed_m_s", geo_com}};
  ordered_json rows = ordered_json::array();
  std::vector<double> swing(horizons.size(), kNaN), com(horizons.size(), kNaN), per_frames(horizons.size(), kNaN);
  int solved = 0;
  std::string unsound;  // horizons whose result is not a converged optimum, for Fig. 6's titles
  // A progress line on a terminal: the horizons in turn, each by its TO windows (the longer
  // windows cost more: weighted by the horizon).
  Progress progress(quiet);
  double total = 0.0;
  for (const double h : horizons) total += h;
  progress.set_total(total);
  double done = 0.0;
  for (std::size_t k = 0; k < horizons.size(); ++k) {
    const double h = horizons[k];
    DynamicStageOptions options;
    options.dynamic.set_horizon(h);
    options.verify_rounds = 0;  // Fig. 6 compares the optimization's own results
    if (progress.shown()) {
      options.dynamic.on_progress = [&, h](double f) {
        char what[64];
        std::snprintf(what, sizeof what, "horizon %.1f s", h);
        progress.update(done + f * h, what);
      };
    }
    DynamicStageResult result;
    ordered_json report;
    std::string why;
    ordered_json row;
    row["horizon_s"] = h;
    const int code = run_dynamic_stage(*robot, targets, geometric, options, result, report, why);
    done += h;
    progress.clear();
    if (code != 0) {
      row["error"] = why;
      rows.push_back(row);
      unsound += (unsound.empty() ? "" : ", ") + short_number(h) + " s failed";
      std::printf("kuavo retarget-sweep: horizon %.2f s: failed: %s\n", h, why.c_str());
      continue;
    }
    ++solved;
    const ordered_json& d = report["dynamic"];
    const int frames = d["frames"].get<int>();
    const double solve_s = d["solve_s"].get<double>();
    const mocap::RepairedMotion& rep = result.repaired;
    swing[k] = swing_leg_speed_rad_s(result.q, result.contacts, rate);
    com[k] = com_speed_m_s(*robot, result.q, rate, rep.lead_frames, rep.dance_frames);
    per_frames[k] = solve_s * 1e4 / frames;
    row["solve_s"] = solve_s;
    row["frames"] = frames;
    row["solve_s_per_1e4_frames"] = per_frames[k];
    row["windows"] = d["windows"];
    row["sqp_iterations"] = d["sqp_iterations"];
    row["windows_at_iteration_cap"] = d["windows_at_iteration_cap"];
    row["qp_restarts"] = d["qp_restarts"];
    row["swing_leg_speed_rad_s"] = swing[k];
    row["com_speed_m_s"] = com[k];
    row["torque_violations"] = d["torque_violations"];
    row["friction_violations"] = d["friction_violations"];
    row["max_torque_ratio"] = d["max_torque_ratio"];
    row["zmp_outside_m_max"] = d["zmp_outside_m_max"];
    row["unsound"] = d["unsound"];
    rows.push_back(row);
    const bool sound = d["unsound"].empty();
    if (!sound) {
      unsound += (unsound.empty() ? "" : ", ") + short_number(h) + " s unsound";
    } else if (const int capped = d["windows_at_iteration_cap"].get<int>(); capped > 0) {
      unsound += (unsound.empty() ? "" : ", ") + short_number(h) + " s " + std::to_string(capped) +
                 " windows at the iteration cap";
    }
    std::printf(
        "kuavo retarget-sweep: horizon %.2f s: %.1f s (%.1f s per 1e4 frames), %d windows, %d at the cap, swing leg "
        "%.3f rad/s, CoM %.3f m/s%s\n",
        h, solve_s, per_frames[k], d["windows"].get<int>(), d["windows_at_iteration_cap"].get<int>(), swing[k], com[k],
        sound ? "" : " (unsound: the optimization did not converge)");
    std::fflush(stdout);
  }
  sweep["horizons"] = rows;
  sweep["figure"] = "fig6_horizon.svg";

  const std::string note = unsound.empty() ? "" : " (" + unsound + ")";
  const std::vector<report::Plot> fig6 = {
      against_horizon("Fig. 6: swing leg's mean joint speed in single support vs the TO horizon" + note,
                      "speed [rad/s]", horizons, swing, "dynamic (TO)", geo_swing),
      against_horizon("Fig. 6: mean CoM speed over the dance vs the TO horizon" + note, "speed [m/s]", horizons, com,
                      "dynamic (TO)", geo_com),
      against_horizon("TO solve time per 10^4 output frames (wall clock, this machine)", "solve time [s]", horizons,
                      per_frames, "solve time", kNaN),
  };
  const std::string dir = out_dir + "/";
  if (!report::write_text_file(dir + "sweep.json", sweep.dump(2) + "\n", &error) ||
      !report::write_text_file(dir + "fig6_horizon.svg", report::render_svg_stack(fig6), &error)) {
    std::fprintf(stderr, "kuavo retarget-sweep: %s\n", error.c_str());
    return 1;
  }
  std::printf("kuavo retarget-sweep: %d of %zu horizons solved; %ssweep.json, %sfig6_horizon.svg\n", solved,
              horizons.size(), dir.c_str(), dir.c_str());
  return solved > 0 ? 0 : 1;
}

}  // namespace

int run_retarget_sweep(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "kuavo retarget-sweep: internal error: %s\n", e.what());
    return 1;
  }
}

}  // namespace kuavo::cli
