// kuavo retarget: a BVH dance (or the built-in default dance) → robot motion file + report.
//
//   kuavo retarget [INPUT.bvh] -o OUT.motion [--variant s45|s42] [--contacts auto|none|FILE]
//                  [--map MAPPING.txt] [--csv OUT.csv] [--dance-bvh OUT.bvh] --report REPORT.json
//                  [--stage geometric|dynamic] [--horizon S] [--repairs FILE] [--dynamic-csv OUT.csv]
//                  [--torque-weight W] [--attenuate ROUNDS] [--verify ROUNDS] [--figures DIR|none]
//                  [--support-margin M] [--stage-smoothing PASSES] [--human-csv OUT.csv] [--duration S]
//                  [--force-reference static|motion] [--ankle-motor-weight W] [--stance-lean M]
//                  [--ankle-effort-weight W]
//
// The whole offline stage by default: geometric retargeting, contact schedule, feasibility
// repair, dynamic retargeting (retarget_dynamic.h). --stage geometric stops after the
// geometric stage (what the human did, kinematically on the robot; for those motions
// `kuavo simulate` and `kuavo_fw` offer --balance-filter on).
// --ankle-motor-weight W (0…1000, (N·m)⁻² s⁻¹): the TO's hinge on each stance ankle's two motor
// torques (DynamicRetargetConfig::ankle_motor_weight). --ankle-effort-weight W (0…10, default
// 0: off; measured at 0.1): the TO's cost on the stance ankles' torques beyond what standing
// asks of them, the pitch only forward (DynamicRetargetConfig::ankle_effort_weight).
// --stance-lean M (0…0.08 m, default 0: off): the repair's stance lean (RepairConfig::
// max_stance_lean_m, feasibility_repair.h).
// --torque-weight W turns on the TO's joint-torque hinge (off by default, see
// dynamic_retarget.h). --support-margin M (0…0.04 m, default 0) plans the TO's centre of
// pressure M inside the soles (DynamicRetargetConfig::support_margin_m). --stage-smoothing
// PASSES (0…8, default 2): low-pass passes over the TO's stages before they become frames
// (DynamicRetargetConfig::stage_smoothing_passes). --force-reference static|motion (default
// static): the TO's reference forces carry the weight alone, or the reference motion's own
// centroidal wrench, the nearest within the friction pyramids
// (mpc::MpcConfig::reference_forces_from_motion). --attenuate ROUNDS (0…5, default 0): rounds of the oracle's second
// pass (retarget_dynamic.h: gestures scaled down where the result still asks a stance leg for
// more than 1.5× its torque limits, then repair and TO again). --verify ROUNDS (0…16, default
// 12): the result is danced in the closed-loop simulation on floor and carpet (Simbody) and on
// the floor in MuJoCo (--verify-mujoco on|off, default on), then in the firmware loop on floor
// and carpet (--verify-firmware on|off, default on: kuavo_fw_sim's run), then on carpet with
// the show set's model errors (--verify-show SEEDS, 0…48, default 24: seeds 1001…), each with one
// push of the show campaign's kind (--verify-show-push NS, 0…40 N·s, default 10; 0: none); every
// run with the recovery step's trigger on the holdable soles as online (--verify-holdable-soles
// on|off, default on; off: on the soles; retarget_dynamic.h), and its carpet runs on a stage
// that sinks M under the standing robot (--verify-carpet-sink M, 0…0.05 m, default 0: the
// estimator's stance sink, kuavo simulate's --surface-sink); where it falls,
// the gestures before the fall are scaled down (a second fall there: taken out, and calm steps;
// a third: both feet held down there, side by side) and the motion optimized again (0: no check).
// The dynamic stage draws the paper's Fig. 4 and 5 (retarget_figures.h)
// into the report's directory, or into --figures DIR (none: no figures).
// --contacts FILE: lines "start_s end_s flight|left|right|double" replace the automatic labels
// over those ranges. --repairs FILE: "start_s end_s forbid KIND" / "start_s end_s force double|square"
// (feasibility_repair.h). --horizon: the optimization window [s], 0.2…1.4. --map: "keypoint =
// joint" lines for skeletons the built-in tables miss. --dance-bvh writes the built-in dance as
// BVH (to inspect it in a viewer). --duration S: the built-in dance's length, a whole number
// of its 30 s cycles up to 300 s (default 30 s; 240 s makes the 4-minute motion). --human-csv
// writes the human keypoints scaled to the robot
// (the targets) in the output motion's clock (after the lead-in), one row per frame: the
// HTML report's skeleton.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "controllers/estimator/estimator.h"
#include "tools/cli/args.h"
#include "tools/cli/commands.h"
#include "tools/cli/usage.h"
#include "tools/cli/progress.h"
#include "tools/cli/retarget_dynamic.h"
#include "tools/mocap/contacts.h"
#include "tools/mocap/default_dance.h"
#include "tools/mocap/motion_file.h"
#include "tools/mocap/retarget.h"

namespace kuavo::cli {
namespace {


// A side input (mapping, contacts, repairs): a regular file (a directory read as empty text
// and was accepted), or false with "PATH: why" in error.
bool read_text(const std::string& path, std::string& out, std::string& error) {
  if (!check_input_file(path, error)) return false;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error = path + ": cannot open";
    return false;
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  out = ss.str();
  return true;
}

bool write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  return static_cast<bool>(out);
}

// The targets (robot-proportioned human keypoints), in the output motion's clock.
std::string human_csv(const mocap::HumanTargets& targets, int lead_frames) {
  std::string s = "time_s";
  for (int k = 0; k < mocap::kNumKeypoints; ++k) {
    if (!targets.present[k]) continue;
    for (const char* a : {"_x", "_y", "_z"}) s += std::string(",") + mocap::keypoint_name(k) + a;
  }
  s += "\n";
  char buf[64];
  for (std::size_t f = 0; f < targets.frames.size(); ++f) {
    std::snprintf(buf, sizeof buf, "%.4f", (static_cast<double>(f) + lead_frames) / targets.rate_hz);
    s += buf;
    for (int k = 0; k < mocap::kNumKeypoints; ++k) {
      if (!targets.present[k]) continue;
      const auto& p = targets.frames[f].position_m[k];
      std::snprintf(buf, sizeof buf, ",%.5f,%.5f,%.5f", p.x(), p.y(), p.z());
      s += buf;
    }
    s += "\n";
  }
  return s;
}

// The stages: an option of the dynamic stage given with --stage geometric is refused.
constexpr args::ModeMask kGeometric = 1, kDynamic = 2;

int run(int argc, char** argv) {
  std::string output, report_path, contacts = "auto", map_path, csv_path, dance_path;
  std::string stage = "dynamic", repairs_path, figures_dir, variant_name = "s45";
  std::vector<std::string> inputs;
  std::string human_path;
  bool quiet = false;
  double verify_show_push_Ns = DynamicStageOptions{}.verify_show_push_Ns;
  double horizon_s = 0.0, torque_weight = 0.0, support_margin_m = 0.0, stance_lean_m = 0.0, ankle_motor_weight = 0.0,
         ankle_effort_weight = 0.0, dance_duration_s = mocap::kDefaultDanceDuration_s;
  long long attenuate_rounds = 0, smoothing_passes = 0, verify_rounds = DynamicStageOptions{}.verify_rounds,
            verify_show = static_cast<long long>(DynamicStageOptions{}.verify_show_seeds.size());
  std::string verify_mujoco = "on", verify_firmware = "on", verify_holdable = "on", force_reference = "static";
  DynamicStageOptions dyn_options;
  model::Variant variant = model::Variant::kS45;
  args::Parser p("kuavo retarget");
  p.positionals("INPUT.bvh", &inputs, 1);
  p.output_file("--out", "OUT.motion", &output).alias = "-o";
  p.output_file("--report", "REPORT.json", &report_path);
  p.text("--contacts", "auto|none|FILE", &contacts);
  p.input_file("--map", "MAPPING.txt", &map_path);
  p.output_file("--csv", "OUT.csv", &csv_path);
  p.output_file("--dance-bvh", "OUT.bvh", &dance_path);
  p.choice("--stage", {"geometric", "dynamic"}, &stage);
  // The offline OCP's window range (mpc_validate_config without plan output).
  p.number("--horizon", "SECONDS", 0.2, 1.4, "s", &horizon_s).modes = kDynamic;
  p.input_file("--repairs", "FILE", &repairs_path).modes = kDynamic;
  p.output_file("--dynamic-csv", "OUT.csv", &dyn_options.csv_path).modes = kDynamic;
  p.number("--torque-weight", "W", 0.0, 1e4, "", &torque_weight).modes = kDynamic;
  p.number("--support-margin", "M", 0.0, 0.04, "m", &support_margin_m).modes = kDynamic;
  p.number("--stance-lean", "M", 0.0, 0.08, "m", &stance_lean_m).modes = kDynamic;
  p.number("--ankle-motor-weight", "W", 0.0, 1e3, "", &ankle_motor_weight).modes = kDynamic;
  p.number("--ankle-effort-weight", "W", 0.0, 10.0, "", &ankle_effort_weight).modes = kDynamic;
  p.integer("--stage-smoothing", "PASSES", 0, 8, "passes", &smoothing_passes).modes = kDynamic;
  p.choice("--force-reference", {"static", "motion"}, &force_reference).modes = kDynamic;
  p.integer("--attenuate", "ROUNDS", 0, 5, "rounds", &attenuate_rounds).modes = kDynamic;
  p.integer("--verify", "ROUNDS", 0, 16, "rounds", &verify_rounds).modes = kDynamic;
  p.choice("--verify-mujoco", {"on", "off"}, &verify_mujoco).modes = kDynamic;
  p.choice("--verify-firmware", {"on", "off"}, &verify_firmware).modes = kDynamic;
  p.integer("--verify-show", "SEEDS", 0, 48, "seeds", &verify_show).modes = kDynamic;
  p.number("--verify-show-push", "NS", 0.0, 40.0, "N·s", &verify_show_push_Ns).modes = kDynamic;
  p.choice("--verify-holdable-soles", {"on", "off"}, &verify_holdable).modes = kDynamic;
  // Opt-in: the check's recovery step with the fast swing as kuavo simulate's
  // --recovery-fast-swing (retarget_dynamic.h); absent: off.
  p.number("--verify-recovery-fast-swing", "SECONDS", 0.2, 0.4, "s", &dyn_options.verify_recovery_fast_swing_s).modes =
      kDynamic;
  // The check's carpet runs on a stage surface that sinks M under the standing robot, as
  // kuavo simulate --surface-sink M (retarget_dynamic.h); absent: 0, a hard floor.
  p.number("--verify-carpet-sink", "M", 0.0, estimator::kMaxStanceSink_m, "m", &dyn_options.verify_carpet_sink_m).modes =
      kDynamic;
  p.text("--figures", "DIR|none", &figures_dir).modes = kDynamic;
  p.output_file("--human-csv", "OUT.csv", &human_path);
  p.number("--duration", "SECONDS", mocap::kDefaultDanceDuration_s,
           mocap::kDefaultDanceDuration_s * mocap::kDefaultDanceMaxCycles, "s", &dance_duration_s);
  p.flag("--quiet", &quiet);
  p.choice("--variant", {"s45", "s42"}, &variant_name);
  if (const int code = parse_command_line(p, argc, argv, "retarget"); code >= 0) return code;
  if (!p.refuse_inapplicable(stage == "geometric" ? kGeometric : kDynamic, "--stage " + stage)) {
    std::fprintf(stderr, "%s\n", p.error().c_str());
    return 2;
  }
  const std::string input = inputs.empty() ? "" : inputs[0];
  if (!input.empty() && !dance_path.empty()) {
    std::fprintf(stderr, "kuavo retarget: --dance-bvh writes the built-in dance; it does not apply with INPUT.bvh\n");
    return 2;
  }
  const int dance_cycles = mocap::default_dance_cycles(dance_duration_s);
  if (!input.empty() && p.given("--duration")) {
    std::fprintf(stderr, "kuavo retarget: --duration sets the built-in dance's length; it does not apply with INPUT.bvh\n");
    return 2;
  }
  if (dance_cycles == 0) {
    std::fprintf(stderr, "kuavo retarget: --duration %g s: the built-in dance repeats its %g s cycle; give a multiple of it\n",
                 dance_duration_s, mocap::kDefaultDanceDuration_s);
    return 2;
  }
  if (!input.empty()) {
    std::string why;
    if (!check_input_file(input, why)) {
      std::fprintf(stderr, "kuavo retarget: %s\n", why.c_str());
      return 2;
    }
  }
  model::parse_variant(variant_name.c_str(), variant);  // one of the two names
  if (p.given("--horizon")) dyn_options.dynamic.set_horizon(horizon_s);
  if (p.given("--torque-weight")) dyn_options.dynamic.torque_penalty_weight = torque_weight;
  if (p.given("--support-margin")) dyn_options.dynamic.support_margin_m = support_margin_m;
  if (p.given("--stance-lean")) dyn_options.repair.max_stance_lean_m = stance_lean_m;
  if (p.given("--ankle-motor-weight")) dyn_options.dynamic.ankle_motor_weight = ankle_motor_weight;
  if (p.given("--ankle-effort-weight")) dyn_options.dynamic.ankle_effort_weight = ankle_effort_weight;
  if (p.given("--stage-smoothing")) dyn_options.dynamic.stage_smoothing_passes = static_cast<int>(smoothing_passes);
  dyn_options.dynamic.ocp.reference_forces_from_motion = force_reference == "motion";
  dyn_options.attenuation_rounds = static_cast<int>(attenuate_rounds);
  dyn_options.verify_rounds = static_cast<int>(verify_rounds);
  dyn_options.verify_mujoco = verify_mujoco == "on";
  dyn_options.verify_firmware = verify_firmware == "on";
  dyn_options.verify_show_push_Ns = verify_show_push_Ns;
  dyn_options.verify_holdable_soles = verify_holdable == "on";
  if (p.given("--verify-show")) {
    dyn_options.verify_show_seeds.clear();
    for (long long k = 0; k < verify_show; ++k) dyn_options.verify_show_seeds.push_back(1001 + static_cast<std::uint64_t>(k));
  }
  // Figures next to the report unless told otherwise (none without a report).
  if (figures_dir.empty() && !report_path.empty()) {
    figures_dir = std::filesystem::path(report_path).parent_path().string();
    if (figures_dir.empty()) figures_dir = ".";
  }
  if (figures_dir != "none") dyn_options.plots_dir = figures_dir;
  if (stage == "dynamic" && !dyn_options.plots_dir.empty() && !std::filesystem::is_directory(dyn_options.plots_dir)) {
    std::fprintf(stderr, "kuavo retarget: --figures %s: not a directory\n", dyn_options.plots_dir.c_str());
    return 2;
  }
  if (!repairs_path.empty()) {
    std::string text, why;
    if (!read_text(repairs_path, text, why)) {
      std::fprintf(stderr, "kuavo retarget: --repairs %s\n", why.c_str());
      return 2;
    }
    if (!mocap::parse_repair_overrides(text, dyn_options.overrides, why)) {
      std::fprintf(stderr, "kuavo retarget: %s: %s\n", repairs_path.c_str(), why.c_str());
      return 2;
    }
  }
  if (output.empty() && dance_path.empty()) {
    std::fprintf(stderr, "kuavo retarget: -o OUT.motion is required\n");
    return usage_error("retarget");
  }

  // Every file named is checked before the (long) run: the parser checked the other inputs
  // (regular files) and the outputs (writable); --contacts names a file unless auto or none.
  if (contacts != "auto" && contacts != "none") {
    std::string why;
    if (!check_input_file(contacts, why)) {
      std::fprintf(stderr, "kuavo retarget: --contacts %s\n", why.c_str());
      return 2;
    }
  }
  auto robot = std::make_unique<model::Model>();
  if (const auto e = model::build_model(variant, model::kDefaultTotalMass_kg, *robot); e != model::ModelError::kOk) {
    std::fprintf(stderr, "kuavo retarget: %s\n", model::to_string(e));
    return 1;
  }

  // 1. The dance.
  mocap::Bvh bvh;
  std::string error;
  if (input.empty()) {
    bvh = mocap::default_dance_bvh(dance_cycles);
    if (!dance_path.empty() && !write_text(dance_path, mocap::write_bvh(bvh))) {
      std::fprintf(stderr, "kuavo retarget: %s: cannot write\n", dance_path.c_str());
      return 1;
    }
    if (output.empty()) return 0;
  } else if (!mocap::load_bvh_file(input, bvh, error)) {
    std::fprintf(stderr, "kuavo retarget: %s\n", error.c_str());
    return 2;
  }

  // The controller holds at most planner::kMaxMotionFrames frames; a longer motion (a legal
  // but absurd Frame Time such as 10 s) is refused before it is resampled, not written as a
  // file every other command refuses.
  {
    const double duration_s = std::max(bvh.frame_count - 1, 0) * bvh.frame_time_s;
    const double frames = duration_s * mocap::ImportOptions{}.rate_hz + 1.0;
    if (!(frames <= planner::kMaxMotionFrames)) {
      std::fprintf(stderr,
                   "kuavo retarget: %s: the motion lasts %.6g s (%d frames of %.6g s): %.0f frames at %.0f Hz, more "
                   "than the %d a robot motion holds\n",
                   input.c_str(), duration_s, bvh.frame_count, bvh.frame_time_s, frames,
                   mocap::ImportOptions{}.rate_hz, planner::kMaxMotionFrames);
      return 2;
    }
  }

  // 2. Correspondence and robot-proportioned targets.
  mocap::SkeletonMap map;
  if (!map_path.empty()) {
    std::string text;
    if (!read_text(map_path, text, error)) {
      std::fprintf(stderr, "kuavo retarget: --map %s\n", error.c_str());
      return 2;
    }
    if (!mocap::map_skeleton_with_file(bvh, text, map, error)) {
      std::fprintf(stderr, "kuavo retarget: %s: %s\n", map_path.c_str(), error.c_str());
      return 2;
    }
  } else if (!mocap::map_skeleton(bvh, map, error)) {
    std::fprintf(stderr, "kuavo retarget: %s\n", error.c_str());
    return 2;
  }
  mocap::HumanTargets targets;
  if (!mocap::make_targets(bvh, map, *robot, {}, targets, error)) {
    std::fprintf(stderr, "kuavo retarget: %s\n", error.c_str());
    return 2;
  }
  // The skeleton's scale to the robot (robot leg / human leg): a positive finite number, or
  // every target would be NaN or at the origin.
  if (!(std::isfinite(targets.root_scale) && targets.root_scale > 0.0)) {
    std::fprintf(stderr, "kuavo retarget: root scale %g is not a positive finite number\n", targets.root_scale);
    return 2;
  }

  // 3. Contact schedule.
  mocap::RetargetOptions options;
  std::vector<mocap::ContactLabel> labels;
  if (contacts == "none") {
    labels.assign(targets.frames.size(), mocap::ContactLabel::kFlight);
    options.pin_stance_feet = false;
  } else {
    labels = mocap::detect_contacts(targets, *robot);
    if (contacts != "auto") {
      std::string text;
      if (!read_text(contacts, text, error)) {
        std::fprintf(stderr, "kuavo retarget: --contacts %s\n", error.c_str());
        return 2;
      }
      if (!mocap::apply_contact_overrides(text, targets.rate_hz, labels, error)) {
        std::fprintf(stderr, "kuavo retarget: %s: %s\n", contacts.c_str(), error.c_str());
        return 2;
      }
    }
  }

  // 4. Retarget (timed: processing speed is part of the report).
  mocap::RetargetResult result;
  const auto t0 = std::chrono::steady_clock::now();
  mocap::retarget_motion(*robot, targets, labels, options, result);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const mocap::RetargetReport& r = result.report;

  // 5. Feasibility repair and dynamic retargeting.
  nlohmann::ordered_json j;
  DynamicStageResult dynamic;
  const std::vector<dynamics::ConfigVector>* out_q = &result.q;
  const std::vector<mocap::ContactLabel>* out_contacts = &result.contacts;
  if (stage == "dynamic") {
    // A progress line on a terminal (the TO reports after each window; --attenuate rounds
    // start it again), nothing when piped or with --quiet.
    Progress progress(quiet);
    progress.set_total(1.0);
    if (progress.shown()) {
      dyn_options.dynamic.on_progress = [&](double done) { progress.update(done, "dynamic retargeting"); };
    }
    const int code = run_dynamic_stage(*robot, targets, result, dyn_options, dynamic, j, error);
    progress.clear();
    dyn_options.dynamic.on_progress = nullptr;
    if (code != 0) {
      std::fprintf(stderr, "kuavo retarget: %s\n", error.c_str());
      return code;
    }
    out_q = &dynamic.q;
    out_contacts = &dynamic.contacts;
    // The optimization did not converge to a motion it stands behind (retarget_dynamic.h).
    if (const auto& unsound = j["dynamic"]["unsound"]; !unsound.empty()) {
      std::string why;
      for (const auto& r : unsound) why += (why.empty() ? "" : "; ") + r.get<std::string>();
      std::fprintf(stderr,
                   "kuavo retarget: warning: the dynamic optimization did not converge on this dance with %.2f s "
                   "windows: %s; no robot dances such a motion. A longer window sees each single support to its "
                   "end (the default, 1.0 s, converges on every dance we have)\n",
                   j["dynamic"]["window_s"].get<double>(), why.c_str());
    }
    // The closed-loop check still saw a fall: the motion is written (a user may edit its
    // repairs, or dance it on the other ground), and the message says where it falls.
    const auto& v = j["dynamic"]["verification"];
    if (v["danced"].is_boolean() && !v["danced"].get<bool>()) {
      nlohmann::ordered_json last = v["runs"].back();  // the kept round's fall
      for (const auto& run : v["runs"]) {
        if (run["round"] == v["kept_round"] && run.value("fell", false) && !run.value("given_up", false)) last = run;
      }
      std::fprintf(stderr,
                   "kuavo retarget: warning: the motion still falls in the closed-loop simulation after %d round(s) "
                   "of repair; the one written, round %d's, falls on %s (seed %llu) at %.2f s; the report's "
                   "\"verification\" lists every run\n",
                   v["rounds"].get<int>(), v["kept_round"].get<int>(), last["ground"].get<std::string>().c_str(),
                   static_cast<unsigned long long>(last["seed"].get<std::uint64_t>()), last["fell_at_s"].get<double>());
    }
    if (!quiet && !v["given_up_seeds"].empty()) {
      std::string seeds;
      for (const auto& seed : v["given_up_seeds"]) {
        seeds += (seeds.empty() ? "" : ", ") + std::to_string(seed.get<std::uint64_t>());
      }
      std::fprintf(stderr,
                   "kuavo retarget: note: the closed-loop check gave up %zu pushed run(s) (seed(s) %s): each fell after "
                   "its push where the only repair left was holding both feet down over the dance's steps\n",
                   v["given_up_seeds"].size(), seeds.c_str());
    }
  }

  // 6. Outputs: never a file the loaders refuse. Every frame meets the loader's rules
  // (mocap::check_motion_frame: finite, plausible base, joints within limits), else exit 2.
  if (out_q->size() < 2 || out_q->size() > static_cast<std::size_t>(planner::kMaxMotionFrames)) {
    std::fprintf(stderr, "kuavo retarget: the retargeted motion has %zu frames, outside 2..%d\n", out_q->size(),
                 planner::kMaxMotionFrames);
    return 2;
  }
  for (std::size_t f = 0; f < out_q->size(); ++f) {
    int joint = -1;
    if (const mocap::MotionError e = mocap::check_motion_frame(*robot, (*out_q)[f], joint); e != mocap::MotionError::kOk) {
      std::fprintf(stderr, "kuavo retarget: %s: the retargeted motion is not one the robot can load: frame %zu: %s%s%s\n",
                   input.empty() ? "default dance" : input.c_str(), f, mocap::to_string(e), joint >= 0 ? ": " : "",
                   joint >= 0 ? model::joint_name(*robot, joint) : "");
      return 2;
    }
  }
  if (!mocap::write_motion_file(output, mocap::encode_motion(*robot, targets.rate_hz, *out_q, *out_contacts),
                                error)) {
    std::fprintf(stderr, "kuavo retarget: %s\n", error.c_str());
    return 1;
  }
  if (!csv_path.empty() &&
      !write_text(csv_path, mocap::motion_csv(*robot, targets.rate_hz, *out_q, *out_contacts))) {
    std::fprintf(stderr, "kuavo retarget: %s: cannot write\n", csv_path.c_str());
    return 1;
  }
  if (!human_path.empty()) {
    const int lead_frames = stage == "dynamic" ? j["dynamic"].value("lead_in_frames", 0) : 0;
    if (!write_text(human_path, human_csv(targets, lead_frames))) {
      std::fprintf(stderr, "kuavo retarget: %s: cannot write\n", human_path.c_str());
      return 1;
    }
  }
  j["input"] = input.empty() ? "builtin:default_dance" : input;
  j["variant"] = model::to_string(variant);
  j["frames"] = r.frames;
  j["duration_s"] = r.duration_s;
  j["rate_hz"] = targets.rate_hz;
  j["keypoint_pos_err_m"] = {{"mean", r.keypoint_error_mean_m}, {"max", r.keypoint_error_max_m}};
  j["foot_slide_m_per_s_max"] = r.foot_slide_max_m_s;
  j["penetration_m_max"] = r.penetration_max_m;
  j["stance_float_m_max"] = r.float_max_m;
  j["joint_limit_violations"] = r.joint_limit_violations;
  j["velocity_limit_violations"] = r.velocity_limit_violations;
  j["contact_phases"] = r.contact_phases;
  j["schedule_contact_phases"] = r.schedule_phases;
  j["frames_per_s"] = seconds > 0.0 ? r.frames / seconds : 0.0;
  nlohmann::ordered_json limited = nlohmann::ordered_json::object();
  for (int k = 0; k < model::kNumJoints; ++k) {
    if (r.position_bound_active_per_joint[k] == 0 && r.velocity_bound_active_per_joint[k] == 0) continue;
    limited[model::joint_name(*robot, k)] = {{"position_frames", r.position_bound_active_per_joint[k]},
                                             {"velocity_frames", r.velocity_bound_active_per_joint[k]}};
  }
  j["limited"] = {{"position_bound_active_samples", r.position_bound_active_samples},
                  {"velocity_bound_active_samples", r.velocity_bound_active_samples},
                  {"stance_yaw_clamped_phases", r.stance_yaw_clamped_phases},
                  {"feet_below_floor_frames", targets.feet_below_floor_frames},
                  {"joints", limited}};
  j["import"] = {{"family", targets.family},
                 {"unit", targets.unit},
                 {"human_height_m", targets.human_height_m},
                 {"up_axis", targets.up_axis},
                 {"dropped_reference_frames", targets.dropped_frames},
                 {"source_frames", targets.source_frames},
                 {"source_rate_hz", targets.source_rate_hz},
                 {"root_scale", targets.root_scale}};
  j["contacts"] = contacts;
  j["stage"] = stage;
  if (!report_path.empty() && !write_text(report_path, j.dump(2) + "\n")) {
    std::fprintf(stderr, "kuavo retarget: %s: cannot write\n", report_path.c_str());
    return 1;
  }
  if (quiet) return 0;
  std::printf(
      "kuavo retarget: %s -> %s: %d frames (%.2f s), keypoint error mean %.3f m max %.3f m, "
      "stance slide max %.4f m/s, penetration max %.4f m, limit violations %d/%d, %d contact phases, "
      "%.0f frames/s\n",
      input.empty() ? "default dance" : input.c_str(), output.c_str(), r.frames, r.duration_s, r.keypoint_error_mean_m,
      r.keypoint_error_max_m, r.foot_slide_max_m_s, r.penetration_max_m, r.joint_limit_violations,
      r.velocity_limit_violations, r.contact_phases, j["frames_per_s"].get<double>());
  if (stage == "dynamic") {
    const auto& d = j["dynamic"];
    std::printf(
        "kuavo retarget: dynamic: %d frames, %zu repairs, %d windows, SQP iterations mean %.1f max %d, %.1f s; "
        "torque ratio max %.2f (geometric %.2f), torque violations %d (geometric %d), friction violations %d, "
        "ZMP outside max %.3f m (geometric %.3f)\n",
        d["frames"].get<int>(), dynamic.repaired.repairs.size(), d["windows"].get<int>(),
        d["sqp_iterations"]["mean"].get<double>(), d["sqp_iterations"]["max"].get<int>(), d["solve_s"].get<double>(),
        d["dynamic"]["max_torque_ratio"].get<double>(), d["geometric"]["max_torque_ratio"].get<double>(),
        d["dynamic"]["torque_violations"].get<int>(), d["geometric"]["torque_violations"].get<int>(),
        d["dynamic"]["friction_violations"].get<int>(), d["dynamic"]["zmp_outside_m_max"].get<double>(),
        d["geometric"]["zmp_outside_m_max"].get<double>());
    if (d["dynamic"]["torque_violations"].get<int>() > 0) {
      // Where the oracle's torque violations are: the four slots with the most.
      std::vector<std::pair<int, std::string>> slots;
      for (const auto& [name, count] : d["dynamic"]["torque_violations_by_slot"].items()) {
        slots.emplace_back(count.get<int>(), name);
      }
      std::stable_sort(slots.begin(), slots.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
      std::printf("kuavo retarget: dynamic: torque violations in %d frames, %d of the samples on one foot; most at",
                  d["dynamic"]["torque_violation_frames"].get<int>(),
                  d["dynamic"]["torque_violations_single_support"].get<int>());
      for (std::size_t k = 0; k < slots.size() && k < 4; ++k) {
        std::printf("%s %s %d", k == 0 ? "" : ",", slots[k].second.c_str(), slots[k].first);
      }
      std::printf("\n");
    }
    {
      // What the repairs and the optimization keep of the CoM path (per repair: the report).
      const auto& p = d["com_path_m"];
      std::printf("kuavo retarget: dynamic: CoM path geometric %.2f m, after the repairs %.2f m, dynamic %.2f m (%.0f %% kept)\n",
                  p["geometric"].get<double>(), p["reference"].get<double>(), p["dynamic"].get<double>(),
                  100.0 * p["kept"].get<double>());
    }
    const auto& c = d["clamped_to_joint_limits"];
    if (c["samples"].get<int>() > 0) {
      std::printf("kuavo retarget: dynamic: %d joint samples put back within the position limits, up to %.4f rad (%s)\n",
                  c["samples"].get<int>(), c["max_rad"].get<double>(), c["worst_joint"].get<std::string>().c_str());
    }
    if (d.contains("figures")) {
      std::printf("kuavo retarget: figures in %s:", dyn_options.plots_dir.c_str());
      for (const auto& f : d["figures"]) std::printf(" %s", f.get<std::string>().c_str());
      std::printf("\n");
    }
  }
  return 0;
}

}  // namespace

int run_retarget(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "kuavo retarget: internal error: %s\n", e.what());
    return 1;
  }
}

}  // namespace kuavo::cli
