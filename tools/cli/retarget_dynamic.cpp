#include "tools/cli/retarget_dynamic.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <thread>
#include <utility>

#include "controllers/motion/load_motion.h"
#include "firmware/sitl/sitl_run.h"
#include "sim/motion_loop.h"
#include "sim/perturbation.h"
#include "tools/cli/campaign_spec.h"
#include "tools/cli/retarget_figures.h"
#include "tools/cli/verify_ladder.h"
#include "tools/mocap/dynamics_check.h"
#include "tools/mocap/motion_file.h"
#include "tools/mocap/motion_metrics.h"
#include "tools/mocap/motion_plan_io.h"

namespace kuavo::cli {
namespace {

std::string push_time(double start_s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f s", start_s);
  return buf;
}

using nlohmann::ordered_json;

ordered_json check_json(const mocap::DynamicsCheck& c, const model::Model& robot) {
  ordered_json j;
  j["torque_violations"] = c.torque_violations;
  j["torque_violation_frames"] = c.torque_violation_frames;
  j["torque_violations_single_support"] = c.torque_violations_single_support;
  // Per slot, those with any; an ankle's pitch and roll slots are its motors A and B.
  ordered_json by_slot = ordered_json::object();
  for (int s = 0; s < model::kNumJoints; ++s) {
    if (c.torque_violations_by_slot[s] == 0) continue;
    std::string name = model::joint_name(robot, s);
    const int in_leg = s >= model::kRightLegFirst ? s - model::kRightLegFirst : s - model::kLeftLegFirst;
    if (c.ankle_slots_are_motors && s < model::kLeftLegFirst + 2 * model::kLegJoints && in_leg >= model::kAnklePitchInLeg) {
      name += in_leg == model::kAnklePitchInLeg ? " (motor A)" : " (motor B)";
    }
    by_slot[name] = c.torque_violations_by_slot[s];
  }
  j["torque_violations_by_slot"] = by_slot;
  j["friction_violations"] = c.friction_violations;
  j["zmp_outside_m_max"] = c.zmp_outside_m_max;
  j["max_torque_ratio"] = c.max_torque_ratio;
  j["max_torque_ratio_joint"] = c.max_torque_ratio_joint >= 0 ? model::joint_name(robot, c.max_torque_ratio_joint) : "";
  j["base_residual"] = {{"force_N_max", c.base_force_residual_N_max},
                        {"force_N_mean", c.base_force_residual_N_mean},
                        {"moment_Nm_max", c.base_moment_residual_Nm_max},
                        {"moment_Nm_mean", c.base_moment_residual_Nm_mean}};
  return j;
}

ordered_json metrics_json(const mocap::MotionMetrics& m) {
  ordered_json j;
  j["keypoint_error_m"] = {{"hands", {{"mean", m.hands_mean_m}, {"max", m.hands_max_m}}},
                           {"feet", {{"mean", m.feet_mean_m}, {"max", m.feet_max_m}}},
                           {"pelvis", {{"mean", m.pelvis_mean_m}, {"max", m.pelvis_max_m}}}};
  j["joint_speed_rad_s_mean"] = {{"legs", m.legs_speed_rad_s}, {"arms", m.arms_speed_rad_s}, {"head", m.head_speed_rad_s}};
  j["com_path_m"] = m.com_path_m;
  j["steps"] = m.steps;
  j["duration_s"] = m.duration_s;
  return j;
}

bool write_csv(const std::string& path, const model::Model& robot, const std::vector<dynamics::ConfigVector>& q,
               const std::vector<mocap::ContactLabel>& contacts, const std::vector<mocap::ForceVector>& forces,
               const mocap::DynamicsCheck& check, double rate_hz) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return false;
  out << "t_s,base_x,base_y,base_z,qx,qy,qz,qw";
  for (int j = 0; j < model::kNumJoints; ++j) out << ',' << model::joint_name(robot, j);
  out << ",p_x,p_y,p_z,L_x,L_y,L_z";
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    for (const char* a : {"x", "y", "z"}) out << ",f_" << model::frame_name(robot, c) << '_' << a;
  }
  for (int j = 0; j < model::kNumJoints; ++j) out << ",tau_" << model::joint_name(robot, j);
  out << ",contact\n";
  std::vector<dynamics::VelocityVector> v, a;
  mocap::frame_rates(q, rate_hz, v, a);
  auto data = std::make_unique<dynamics::Data>();
  char buf[32];
  const auto put = [&](double x) {
    std::snprintf(buf, sizeof buf, ",%.6g", x);
    out << buf;
  };
  for (std::size_t i = 0; i < q.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%.4f", i / rate_hz);
    out << buf;
    for (int k = 0; k < model::kNq; ++k) put(q[i][k]);
    dynamics::forward_kinematics(robot, *data, q[i]);
    dynamics::forward_velocities(robot, *data, v[i]);
    dynamics::crba(robot, *data);
    dynamics::centroidal_dynamics(robot, *data);
    const dynamics::Vec6 h = data->centroidal_matrix * v[i];
    for (int k = 0; k < 6; ++k) put(h[k]);
    for (int k = 0; k < 3 * model::kNumContactPoints; ++k) put(forces[i][k]);
    for (int k = 0; k < model::kNumJoints; ++k) put(check.tau_Nm[i][k]);
    out << ',' << mocap::to_string(contacts[i]) << '\n';
  }
  return static_cast<bool>(out);
}

}  // namespace

bool check_push(std::uint64_t seed, double run_length_s, double impulse_Ns, sim::Push& out) {
  out = sim::Push{};
  PushDraw draw;
  PushSpec spec;
  if (!draw_show_push(seed, run_length_s, impulse_Ns, draw, spec)) return false;
  out.start_s = draw.start_s;
  out.duration_s = spec.duration_s;
  out.force_N = dynamics::Vec3(draw.force_N * std::cos(draw.direction_rad), draw.force_N * std::sin(draw.direction_rad), 0.0);
  return true;
}

std::vector<std::string> dynamic_unsound_reasons(int windows, int windows_at_cap, double zmp_outside_m,
                                                 double max_torque_ratio) {
  std::vector<std::string> why;
  char buf[160];
  if (windows > 0 && static_cast<double>(windows_at_cap) > kUnsoundCapShare * windows) {
    std::snprintf(buf, sizeof buf, "%d of %d optimization windows stopped at the iteration cap", windows_at_cap, windows);
    why.emplace_back(buf);
  }
  if (!(zmp_outside_m <= kUnsoundZmpOutside_m)) {
    std::snprintf(buf, sizeof buf, "its centre of pressure leaves the support by up to %.3g m", zmp_outside_m);
    why.emplace_back(buf);
  }
  if (!(max_torque_ratio <= kUnsoundTorqueRatio)) {
    std::snprintf(buf, sizeof buf, "a joint needs %.3g times its torque limit", max_torque_ratio);
    why.emplace_back(buf);
  }
  return why;
}

int run_dynamic_stage(const model::Model& robot, const mocap::HumanTargets& targets,
                      const mocap::RetargetResult& geometric, const DynamicStageOptions& options,
                      DynamicStageResult& result, ordered_json& report, std::string& error) {
  const double rate = targets.rate_hz;
  std::vector<dynamics::ConfigVector> reference = geometric.q;  // attenuated between rounds
  std::vector<mocap::Repair> attenuations;
  std::vector<mocap::RepairOverride> overrides = options.overrides;  // + the check's calm steps
  double solve_s = 0.0;
  // Repair + TO on `reference`, then the oracle's rounds: 0, or run_dynamic_stage's code.
  const auto optimize = [&]() -> int {
    for (int rounds = 0;; ++rounds) {
      if (!mocap::repair_motion(robot, reference, geometric.contacts, rate, options.repair, overrides, result.repaired,
                                error)) {
        return 2;
      }
      auto plan = std::make_unique<planner::MotionPlan>();
      if (!mocap::motion_plan_from_frames(result.repaired.q, result.repaired.contacts, rate, "repaired motion", *plan,
                                          error)) {
        return 2;
      }
      if (!mocap::dynamic_retarget(robot, *plan, options.dynamic, result.dynamic, error)) return 1;
      solve_s += result.dynamic.stats.solve_s;
      if (rounds >= options.attenuation_rounds) return 0;
      // The oracle on this round's result: leg torques beyond the ratio, as dance-clock ranges.
      mocap::DynamicsCheck check;
      mocap::check_dynamics(robot, result.dynamic.q, result.dynamic.contacts, rate, &result.dynamic.forces_N,
                            options.dynamic.ocp.friction_coefficient, check);
      const int lead = result.repaired.lead_frames, n_dance = result.repaired.dance_frames;
      const int gap = static_cast<int>(std::lround(0.3 * rate));
      std::vector<mocap::AttenuationRange> ranges;
      for (int i = 0; i < static_cast<int>(check.tau_Nm.size()); ++i) {
        const int d = i - lead;
        if (d < 0 || d >= n_dance) continue;
        // Stance legs only: their torques hold the robot up; a swing leg's excess costs tracking.
        double ratio = 0.0;
        const mocap::ContactLabel label = result.dynamic.contacts[i];
        for (int j = 0; j < 2 * model::kLegJoints; ++j) {
          const bool stance = j < model::kLegJoints ? mocap::left_in_contact(label) : mocap::right_in_contact(label);
          if (stance) ratio = std::max(ratio, std::abs(check.tau_Nm[i][j]) / robot.limits.torque_Nm[j]);
        }
        if (!(ratio > options.attenuation_torque_ratio)) continue;
        if (!ranges.empty() && d - ranges.back().b <= gap) {
          ranges.back().b = d + 1;
          ranges.back().torque_ratio = std::max(ranges.back().torque_ratio, ratio);
        } else {
          ranges.push_back({d, d + 1, ratio, {}});
        }
      }
      if (ranges.empty()) return 0;
      for (auto& r : ranges) r.a = std::max(0, r.a - gap), r.b = std::min(n_dance, r.b + gap);
      if (!mocap::attenuate_gestures(reference, rate, ranges, options.attenuation_gain, 0.5, lead / rate,
                                     options.overrides, attenuations)) {
        return 0;
      }
    }
  };
  // The loaders refuse a joint outside the model's limits (mocap::check_motion_frame); the
  // dynamic stage does not bound the arm and head joints it smooths, so its output is put back
  // within the limits here and the report says by how much.
  int clamped_samples = 0, worst_joint = -1;
  double worst_rad = 0.0;
  const auto take_output = [&] {
    result.q = result.dynamic.q;
    result.contacts = result.dynamic.contacts;
    clamped_samples = 0, worst_joint = -1, worst_rad = 0.0;
    for (dynamics::ConfigVector& q : result.q) {
      for (int k = 0; k < model::kNumJoints; ++k) {
        const double lo = robot.limits.position_min_rad[k], hi = robot.limits.position_max_rad[k];
        const double clamped = std::clamp(q[7 + k], lo, hi);
        if (clamped == q[7 + k]) continue;
        ++clamped_samples;
        if (std::abs(clamped - q[7 + k]) > worst_rad) worst_rad = std::abs(clamped - q[7 + k]), worst_joint = k;
        q[7 + k] = clamped;
      }
    }
  };
  if (const int code = optimize(); code != 0) return code;
  take_output();

  // Closed-loop verification: the output danced by the online stack in the simulator, as
  // `kuavo simulate MOTION` dances it (MPC, estimator, MTi model; with --holdable-soles off
  // when verify_holdable_soles is, --recovery-fast-swing S when verify_recovery_fast_swing_s
  // is S, and on carpet --surface-sink M when verify_carpet_sink_m is M), on each ground and
  // then in MuJoCo. Where it falls, the
  // seconds before the fall are repaired (verification_range's ladder) and the motion
  // optimized again, up to verify_rounds times.
  ordered_json verification_runs = ordered_json::array();
  bool danced = true;
  int verify_round = 0;
  double verify_sim_s = 0.0;
  std::vector<std::pair<int, int>> verify_ranges;  // dance-clock frames scaled so far
  bool calm_everywhere = false;
  // Pushed runs the check gave up on: a fall within the ladder's before_s after the push where
  // its next rung is holding both feet down (gives_up_pushed_run). The steps stay; the run is
  // listed and left out of later rounds.
  std::vector<std::pair<std::uint64_t, int>> given_up;  // seed, round
  const VerifyLadder& ladder = options.verify_ladder;
  sim::PerturbationSet show_set;
  sim::perturbation_set_by_name("show", show_set);
  int best_round = -1, best_passed = 0;
  double best_reached = 0.0;
  DynamicStageResult best;
  std::size_t best_attenuations = 0;
  for (; options.verify_rounds > 0; ++verify_round) {
    auto plan = std::make_unique<planner::MotionPlan>();
    planner::BalanceFilterReport filter_report;
    const std::vector<std::uint8_t> bytes = mocap::encode_motion(robot, rate, result.q, result.contacts);
    if (!motion::load_motion_bytes(bytes, "the retargeted motion", robot, motion::MotionOptions{}, *plan,
                                   filter_report, error)) {
      return 2;
    }
    double fell_at_s = -1.0;
    std::string fell_on;
    // The Simbody runs on each ground for each noise seed, then (verify_mujoco) MuJoCo on the
    // floor: Leju's own model and MuJoCo's contact, independent of our tables.
    // Then (verify_firmware) the image users flash, in its firmware loop on each ground.
    struct Check {
      sim::GroundParams ground;
      sim::Engine engine;
      std::uint64_t seed;
      bool firmware = false;
      bool show_errors = false;  // the plant with the show set's model errors drawn from seed
      sim::Push push{};          // and the push check_push draws from seed (duration 0: none)
    };
    std::vector<Check> checks;
    const double run_length_s = planner::motion_plan_duration_s(*plan) + sim::MotionRunConfig{}.settle_s;
    for (const std::uint64_t seed : options.verify_seeds) {
      for (const sim::GroundParams& ground : options.verify_grounds) checks.push_back({ground, sim::Engine::kSimbody, seed});
    }
    if (options.verify_mujoco && !options.verify_seeds.empty()) {
      checks.push_back({sim::kFloor, sim::Engine::kMujoco, options.verify_seeds.front()});
    }
    if (options.verify_firmware && !options.verify_seeds.empty()) {
      for (const sim::GroundParams& ground : options.verify_grounds) {
        checks.push_back({ground, sim::Engine::kSimbody, options.verify_seeds.front(), true});
      }
    }
    for (const std::uint64_t seed : options.verify_show_seeds) {
      if (std::any_of(given_up.begin(), given_up.end(), [&](const auto& g) { return g.first == seed; })) continue;
      Check check{sim::kCarpet, sim::Engine::kSimbody, seed, false, true};
      check_push(seed, run_length_s, options.verify_show_push_Ns, check.push);
      checks.push_back(check);
    }
    std::uint64_t fell_seed = 0;
    int passed = 0;  // runs of this round that danced (read in order, up to the first that fell; one given up is not)
    // The Simbody runs (not MuJoCo's, not the firmware loop's) in batches of consecutive runs,
    // one thread each (a logical CPU each at most): each run is its own plant, controller and
    // workspaces, nothing shared but the read-only plan and model. The firmware loop stays out
    // and runs alone: it has static workspaces and toggles Eigen's process-wide malloc guard.
    // The results are read in the list's order and a round still stops at its first fall (a
    // pushed run given up does not stop it), so the check decides exactly as one run after
    // another does. What a batch wastes: its runs after that fall, danced to their end (in a
    // round that falls, up to a whole run per CPU).
    // An exception in a run is kept and rethrown when the loop reads that run (as it would have
    // surfaced there one run after another), so it reaches the CLI's handler, not terminate.
    std::vector<sim::MotionSummary> runs(checks.size());
    std::vector<std::exception_ptr> failures(checks.size());
    std::size_t simulated_to = 0;  // runs [0, simulated_to) have run (batches go in list order)
    const auto carpet_sink = [&](const sim::GroundParams& ground) {
      return std::strcmp(ground.name, sim::kCarpet.name) == 0 ? options.verify_carpet_sink_m : 0.0;
    };
    const auto parallel = [&](std::size_t i) { return checks[i].engine == sim::Engine::kSimbody && !checks[i].firmware; };
    const auto simulate_one = [&](std::size_t i) {
      try {
        const Check& check = checks[i];
        sim::MotionRunConfig cfg;
        cfg.stack.planner = stack::PlannerKind::kMpc;
        planner::set_holdable_soles(cfg.stack.recovery, options.verify_holdable_soles);
        cfg.stack.recovery.fast_swing_s = options.verify_recovery_fast_swing_s;
        cfg.stack.estimator.stance_sink_m = carpet_sink(check.ground);
        cfg.run.ground = check.ground;
        cfg.run.engine = check.engine;
        cfg.run.seed = check.seed;
        if (check.show_errors) cfg.perturbation = sim::draw_perturbation(robot, show_set, check.seed);
        cfg.run.push = check.push;
        runs[i] = sim::run_motion(robot, *plan, cfg);
      } catch (...) {
        failures[i] = std::current_exception();
      }
    };
    const std::size_t threads = std::max(1u, std::thread::hardware_concurrency());
    const auto simulate_batch = [&](std::size_t first) {
      std::size_t end = first + 1;
      if (parallel(first)) {
        while (end < checks.size() && end - first < threads && parallel(end)) ++end;
      }
      const auto t0 = std::chrono::steady_clock::now();
      {
        std::vector<std::jthread> workers;  // joined on the way out, also if starting one throws
        for (std::size_t i = first + 1; i < end; ++i) workers.emplace_back(simulate_one, i);
        simulate_one(first);
      }
      verify_sim_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      simulated_to = end;
    };
    for (std::size_t index = 0; index < checks.size(); ++index) {
      const auto& [ground, engine, seed, firmware, show_errors, push] = checks[index];
      const bool pushed = push.duration_s > 0.0;
      if (firmware) {
        firmware::sitl::SitlConfig fw;
        fw.loop.legs = firmware::sitl::kImageLegBinding;
        fw.loop.ground = ground;
        fw.loop.seed = seed;
        fw.holdable_soles = options.verify_holdable_soles;
        fw.recovery_fast_swing_s = options.verify_recovery_fast_swing_s;
        fw.surface_sink_m = carpet_sink(ground);
        const auto t0 = std::chrono::steady_clock::now();
        const firmware::sitl::SitlSummary s = firmware::sitl::run_firmware_sim(robot, plan.get(), fw);
        verify_sim_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        ordered_json entry = {{"round", verify_round}, {"engine", "firmware"}, {"ground", ground.name}, {"seed", seed}};
        // The estimator's stance sink as the run's own summary gives it (verify_carpet_sink_m).
        if (s.motion.stance_sink_m > 0.0) entry["surface_sink_m"] = s.motion.stance_sink_m;
        if (!s.motion.run.ok || s.dance_started_at_s < 0.0) {
          // The firmware loop could not run the dance (not the motion's fault, e.g. a bring-up
          // timeout): the check goes on without it, and says so.
          entry["error"] = s.motion.run.ok ? "the firmware did not start the dance" : s.motion.run.error;
          verification_runs.push_back(entry);
          continue;
        }
        // A fault latched or a fall, on the motion's clock (the run's starts on the gantry).
        double end_s = -1.0;
        if (!s.danced_to_end) {
          end_s = s.motion.run.fell ? s.motion.run.fell_at_s : s.motion.motion_duration_s + s.dance_started_at_s;
          if (s.fault_at_s >= 0.0) end_s = std::min(end_s, s.fault_at_s);
          end_s -= s.dance_started_at_s;
        }
        entry["fell"] = !s.danced_to_end;
        entry["fell_at_s"] = end_s;
        if (!s.faults.empty()) entry["fault"] = firmware::to_string(s.faults.front());
        verification_runs.push_back(entry);
        if (!s.danced_to_end) {
          fell_at_s = std::max(0.0, end_s);
          fell_on = std::string(ground.name) + " in the firmware loop";
          fell_seed = seed;
          break;
        }
        ++passed;
        continue;
      }
      if (index >= simulated_to) simulate_batch(index);
      if (failures[index]) std::rethrow_exception(failures[index]);
      const sim::MotionSummary& summary = runs[index];
      ordered_json entry = {{"round", verify_round},
                            {"engine", sim::to_string(engine)},
                            {"ground", ground.name},
                            {"seed", seed}};
      if (summary.stance_sink_m > 0.0) entry["surface_sink_m"] = summary.stance_sink_m;  // as the firmware's
      if (show_errors) entry["perturbation"] = show_set.name;
      if (pushed) {
        entry["push"] = {{"start_s", push.start_s},
                         {"direction_deg", std::atan2(push.force_N.y(), push.force_N.x()) * 180.0 / M_PI},
                         {"impulse_Ns", options.verify_show_push_Ns},
                         {"force_N", {push.force_N.x(), push.force_N.y(), push.force_N.z()}},  // to replay it exactly
                         {"duration_s", push.duration_s}};
      }
      if (!summary.run.ok && engine == sim::Engine::kMujoco) {
        // Leju's MJCF not where the build put it, or MuJoCo refusing it: the check goes on
        // without it, and says so.
        entry["error"] = summary.run.error;
        verification_runs.push_back(entry);
        continue;
      }
      if (!summary.run.ok) {
        error = "the closed-loop check of the retargeted motion failed: " + summary.run.error;
        return 1;
      }
      entry["fell"] = summary.run.fell;
      entry["fell_at_s"] = summary.run.fell ? summary.run.fell_at_s : -1.0;
      if (summary.run.fell && show_errors) {
        // Tipped over by its push (within the range the fall would repair) where two earlier
        // rounds' repairs already lie (the gestures scaled, then taken out): the last rung,
        // both feet down, would buy this push with the dance's steps (cmu_05_20: 3 of its 7
        // for the same show campaign, 1 fall in 60 either way). A standing robot is not the
        // dance; the check gives this run up and goes on. Likewise, pushed or not, a fall
        // over feet an earlier round already held down: the ladder has nothing more there
        // (gives_up_held_run).
        const char* why = nullptr;
        if (pushed && gives_up_pushed_run(push.start_s, summary.run.fell_at_s, result.repaired.lead_frames,
                                          result.repaired.dance_frames, rate, ladder, verify_ranges)) {
          why = "pushed";
        } else if (gives_up_held_run(summary.run.fell_at_s, result.repaired.lead_frames, result.repaired.dance_frames,
                                     rate, ladder, verify_ranges)) {
          why = "held";
        }
        if (why != nullptr) {
          entry["given_up"] = true;
          entry["given_up_because"] = why;
          verification_runs.push_back(entry);
          given_up.emplace_back(seed, verify_round);
          continue;
        }
      }
      verification_runs.push_back(entry);
      if (summary.run.fell) {
        fell_at_s = summary.run.fell_at_s;
        fell_on = std::string(ground.name);
        if (engine == sim::Engine::kMujoco) {
          fell_on += " in MuJoCo";
        } else if (pushed && push.start_s < fell_at_s) {
          fell_on += " with the show set's model errors and a push at " + push_time(push.start_s);
        } else if (pushed) {  // the model errors alone: the push was still to come
          fell_on += " with the show set's model errors, before its push at " + push_time(push.start_s);
        } else if (show_errors) {
          fell_on += " with the show set's model errors";
        }
        fell_seed = seed;
        break;
      }
      ++passed;
    }
    danced = fell_at_s < 0.0;
    // The best round so far: one that danced (every run not given up), else more runs danced,
    // then the later fall. A later round's repair can make things worse elsewhere (cmu_05_07: a
    // round that danced the floor, then carpet's repair fell on the floor at 8.5 s in every later
    // round); the output is the best round's. A round that danced leaves out the runs given up,
    // so it may count fewer passes than one that fell in its last run: it still wins.
    const double reached = danced ? std::numeric_limits<double>::infinity() : fell_at_s;
    if (verify_round == 0 || danced || passed > best_passed || (passed == best_passed && reached > best_reached)) {
      best_round = verify_round, best_passed = passed, best_reached = reached;
      best = result;
      best_attenuations = attenuations.size();
    }
    if (danced || verify_round >= options.verify_rounds) break;
    VerifyRange range;
    if (!verification_range(fell_at_s, result.repaired.lead_frames, result.repaired.dance_frames, rate, ladder,
                            verify_ranges, range)) {
      break;  // a fall in the lead-in or the tail: nothing of the dance to scale
    }
    mocap::AttenuationRange scaled{range.a, range.b, 0.0, {}};
    char why[160];
    std::snprintf(why, sizeof why, "the online stack fell here in the closed-loop simulation (%s, seed %llu, at %.2f s)",
                  fell_on.c_str(), static_cast<unsigned long long>(fell_seed), fell_at_s);
    scaled.why = why;
    if (!mocap::attenuate_gestures(reference, rate, {scaled}, range.gain, 0.5, result.repaired.lead_frames / rate,
                                   options.overrides, attenuations)) {
      break;  // forbidden by an override
    }
    if (range.hold) {
      mocap::RepairOverride hold;
      hold.start_s = range.a / rate;
      hold.end_s = range.b / rate;
      hold.force_double = true;
      hold.square_stance = true;
      overrides.push_back(hold);
      attenuations.back().reason += "; both feet stay down here, side by side";
    }
    // Calm steps over the whole dance, once: each touchdown is placed from the stance foot, so
    // the steps before the fall decide where and how the robot arrives there (calm steps over
    // the fall's range only left cmu_05_20 and cmu_05_07 falling on the floor after 8 rounds;
    // over the whole dance both danced the floor to the end).
    if (range.calm_steps && !calm_everywhere) {
      mocap::RepairOverride calm;
      calm.start_s = 0.0;
      calm.end_s = std::numeric_limits<double>::max();
      calm.calm_steps = true;
      overrides.push_back(calm);
      calm_everywhere = true;
      attenuations.back().reason += "; from now on the whole dance takes calm steps";
    }
    if (const int code = optimize(); code != 0) return code;
    take_output();
  }
  if (best_round >= 0 && best_round != verify_round) {
    result = std::move(best);
    attenuations.resize(best_attenuations);
    take_output();
    danced = false;  // only a last round can have danced
  }
  result.dynamic.stats.solve_s = solve_s;
  result.repaired.repairs.insert(result.repaired.repairs.end(), attenuations.begin(), attenuations.end());

  const double mu = options.dynamic.ocp.friction_coefficient;
  mocap::DynamicsCheck geo_check, dyn_check;
  mocap::check_dynamics(robot, geometric.q, geometric.contacts, rate, nullptr, mu, geo_check);
  mocap::check_dynamics(robot, result.q, result.contacts, rate, &result.dynamic.forces_N, mu, dyn_check);
  mocap::MotionMetrics geo_metrics, dyn_metrics;
  mocap::motion_metrics(robot, targets, geometric.q, geometric.contacts, rate, 0, geo_metrics);
  mocap::motion_metrics(robot, targets, result.q, result.contacts, rate, result.repaired.lead_frames, dyn_metrics);

  const mocap::DynamicStats& s = result.dynamic.stats;
  ordered_json d;
  d["solve_s"] = s.solve_s;
  d["frames"] = static_cast<int>(result.q.size());
  d["windows"] = s.windows;
  d["window_s"] = options.dynamic.ocp.horizon_s;
  d["commit_stages"] = options.dynamic.commit_stages;
  d["sqp_iterations"] = {{"mean", s.sqp_iterations_mean}, {"max", s.sqp_iterations_max}};
  d["windows_at_iteration_cap"] = s.windows_not_converged;
  d["foothold_correction_m_max"] = s.foothold_correction_max_m;
  d["base_drop_m_max"] = s.base_drop_max_m;
  d["foothold_miss_m_max"] = s.foothold_miss_max_m;
  d["foothold_miss_frames"] = s.foothold_miss_frames;
  d["ankle_motor_weight"] = options.dynamic.ankle_motor_weight;
  d["ankle_effort_weight"] = options.dynamic.ankle_effort_weight;
  d["stages_over_ankle_motors"] = s.stages_over_ankle_motors;  // the plan's own, before the frames
  // The forces re-solved for the final frames (mocap/contact_forces.h).
  d["forces"] = {{"frames_over_limit", s.forces.frames_over_limit},
                 {"frames_base_wrench_out_of_cones", s.forces.frames_infeasible},
                 {"max_excess_Nm", s.forces.max_excess_Nm}};
  d["qp_restarts"] = s.qp_failures;
  d["rejected_steps"] = s.rejected_steps;
  d["lead_in_frames"] = result.repaired.lead_frames;
  d["clamped_to_joint_limits"] = {{"samples", clamped_samples},
                                  {"max_rad", worst_rad},
                                  {"worst_joint", worst_joint < 0 ? "" : model::joint_name(robot, worst_joint)}};
  ordered_json geo = check_json(geo_check, robot);
  ordered_json dyn = check_json(dyn_check, robot);
  geo["expressiveness"] = metrics_json(geo_metrics);
  dyn["expressiveness"] = metrics_json(dyn_metrics);
  d["geometric"] = geo;
  d["dynamic"] = dyn;
  // The flat keys of the issue, for the dynamic result.
  d["torque_violations"] = dyn_check.torque_violations;
  d["friction_violations"] = dyn_check.friction_violations;
  d["zmp_outside_m_max"] = dyn_check.zmp_outside_m_max;
  d["max_torque_ratio"] = dyn_check.max_torque_ratio;
  d["unsound"] = dynamic_unsound_reasons(s.windows, s.windows_not_converged, dyn_check.zmp_outside_m_max,
                                         dyn_check.max_torque_ratio);
  // The CoM path each stage keeps, and where it goes: the geometric frames, the reference the
  // repairs hand the optimization (result.repaired.q), the result. Output frame i shows
  // geometric frame i − lead_frames; a repair's range is in the output clock.
  const std::vector<dynamics::Vec3> com_geo = mocap::com_trajectory(robot, geometric.q);
  const std::vector<dynamics::Vec3> com_ref = mocap::com_trajectory(robot, result.repaired.q);
  const std::vector<dynamics::Vec3> com_dyn = mocap::com_trajectory(robot, result.q);
  const int lead = result.repaired.lead_frames;
  const auto paths = [&](int a, int b) {
    return ordered_json{{"geometric", mocap::path_length(com_geo, a - lead, b - lead)},
                        {"reference", mocap::path_length(com_ref, a, b)},
                        {"dynamic", mocap::path_length(com_dyn, a, b)}};
  };
  {
    ordered_json p = paths(0, static_cast<int>(result.q.size()) - 1);
    const double g = p["geometric"].get<double>();
    p["kept"] = g > 0.0 ? p["dynamic"].get<double>() / g : 1.0;
    d["com_path_m"] = p;
  }
  ordered_json repairs = ordered_json::array();
  for (const mocap::Repair& r : result.repaired.repairs) {
    const int a = static_cast<int>(std::lround(r.start_s * rate)), b = static_cast<int>(std::lround(r.end_s * rate));
    repairs.push_back({{"start_s", r.start_s}, {"end_s", r.end_s}, {"kind", mocap::to_string(r.kind)}, {"reason", r.reason},
                       {"com_path_m", paths(a, b)}});
  }
  d["repairs"] = repairs;
  std::vector<std::uint64_t> given_up_seeds;  // those the written round's check left out
  for (const auto& [seed, round] : given_up) {
    if (round <= best_round) given_up_seeds.push_back(seed);
  }
  d["verification"] = {{"rounds", verify_round},
                       {"kept_round", best_round},
                       {"given_up_seeds", given_up_seeds},
                       {"holdable_soles", options.verify_holdable_soles},
                       {"recovery_fast_swing_s", options.verify_recovery_fast_swing_s},
                       {"carpet_sink_m", options.verify_carpet_sink_m},
                       {"danced", verification_runs.empty() ? ordered_json() : ordered_json(danced)},
                       {"sim_s", verify_sim_s},
                       {"runs", verification_runs}};
  d["steps"] = {{"human", result.repaired.human_steps}, {"robot", result.repaired.robot_steps}};
  if (!options.plots_dir.empty()) {
    RetargetFigures figures;
    if (!write_retarget_figures(robot, {geometric.q, geometric.contacts, geo_check},
                                {result.q, result.contacts, dyn_check}, result.repaired.lead_frames, rate,
                                options.plots_dir, figures, error)) {
      return 1;
    }
    d["figures"] = figures.files;
    ordered_json numbers;
    for (const FigureNumber& n : figures.numbers) numbers[n.name] = {{"geometric", n.geometric}, {"dynamic", n.dynamic}};
    d["figure_numbers"] = numbers;
  }
  report["dynamic"] = d;

  if (!options.csv_path.empty() &&
      !write_csv(options.csv_path, robot, result.q, result.contacts, result.dynamic.forces_N, dyn_check, rate)) {
    error = options.csv_path + ": cannot write";
    return 1;
  }
  return 0;
}

}  // namespace kuavo::cli
