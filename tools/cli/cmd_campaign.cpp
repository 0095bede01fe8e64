// kuavo campaign SPEC.json [--out DIR] [--seeds N] [--jobs N] [--sshloginfile FILE] [--attribute]
// kuavo campaign --example
// A matrix of motions × grounds × perturbation sets × seeds (campaign_spec.h), each run its
// own `kuavo simulate` process with its seed, the job list run by GNU parallel (all cores
// by default; --sshloginfile spreads it over machines that see the same paths). Resumable:
// a run whose DIR/runs/ID.json exists is skipped (a run writes ID.json.part and renames it
// when done, so an interrupted run is redone). Writes DIR/runs.csv (every run, in matrix
// order, no wall-clock figures: the same campaign gives the same table) and
// DIR/summary.json (runs, falls, per motion the fall rate's 95 % Wilson interval). A run
// that produced no summary or whose simulation failed counts as a fall (conservative) and
// is also counted in "sim_failures". --attribute runs each fall that had both a push and
// model errors again with each alone, and once more as it was but with the true base state
// in place of the estimator's (DIR/attribution/, DIR/attribution.csv, and per motion
// "fall_causes" in summary.json): whether the push or the errors topple the robot, and
// whether the state estimate has a part in it.
#include <sys/resource.h>

#include <cmath>
#include <cstdio>
#include <unistd.h>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "controllers/model/model.h"
#include "controllers/motion/load_motion.h"
#include "controllers/planner/motion_plan.h"
#include "sim/motion_loop.h"
#include "tools/cli/args.h"
#include "tools/cli/campaign_spec.h"
#include "tools/cli/commands.h"
#include "tools/cli/usage.h"

namespace kuavo::cli {
namespace {

namespace fs = std::filesystem;

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

struct Motion {
  std::string name;
  std::string path;  // absolute
  double run_length_s = 0.0;
};

struct Run {
  std::string id, motion, motion_path, ground, perturbation, perturbation_arg;
  std::uint64_t seed = 0;
  bool pushed = false;
  PushDraw push;
  std::string command;
};

std::string read_file(const std::string& path, bool& ok) {
  std::ifstream in(path);
  ok = static_cast<bool>(in);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The built-in dance, retargeted once into DIR/motions by this same binary.
bool prepare_builtin_dance(const std::string& self, const fs::path& dir, std::string& path) {
  const fs::path out = dir / "motions" / "dance.motion";
  path = out.string();
  if (fs::exists(out)) return true;
  const fs::path part = dir / "motions" / "dance.motion.part";
  const std::string cmd = quote(self) + " retarget -o " + quote(part.string()) + " --report " +
                          quote((dir / "motions" / "dance.retarget.json").string()) + " > /dev/null 2>&1";
  if (std::system(cmd.c_str()) != 0 || !fs::exists(part)) return false;
  fs::rename(part, out);
  return true;
}

double number_or(const nlohmann::json& j, const char* key, double fallback) {
  return j.contains(key) && j[key].is_number() ? j[key].get<double>() : fallback;
}

// A run's summary as written by `kuavo simulate --summary`: `have` whether the file is there,
// `parsed` whether it holds a JSON object (else an empty one).
nlohmann::json read_summary(const fs::path& summary_path, bool& have, bool& parsed) {
  const std::string text = read_file(summary_path.string(), have);
  nlohmann::json s = have ? nlohmann::json::parse(text, nullptr, false) : nlohmann::json();
  parsed = have && !s.is_discarded() && s.is_object();
  return parsed ? s : nlohmann::json::object();
}

// Whether a run simulated to its end (ok) and whether the robot fell there.
struct Outcome {
  bool ok = false, fell = false;
  double fell_at_s = -1.0;
};
Outcome read_outcome(const fs::path& summary_path) {
  bool have = false, parsed = false;
  const nlohmann::json s = read_summary(summary_path, have, parsed);
  Outcome o;
  o.ok = parsed && s.value("ok", false);
  o.fell = parsed && s.value("fell", false);
  o.fell_at_s = parsed ? number_or(s, "fell_at_s", -1.0) : -1.0;
  return o;
}

}  // namespace

int run_campaign(int argc, char** argv) {
  std::string out_dir = "campaign", sshloginfile, jobs = "100%";
  std::vector<std::string> specs;
  long long seeds_override = 0, jobs_n = 0;
  bool example = false, quiet = false, attribute = false;
  constexpr args::ModeMask kRun = 1, kExample = 2;
  args::Parser p("kuavo campaign");
  p.positionals("SPEC.json", &specs, 1);
  p.flag("--example", &example).modes = kExample;
  p.text("--out", "DIR", &out_dir).modes = kRun;
  p.integer("--seeds", "N", 1, 100000, "seeds", &seeds_override).modes = kRun;
  // GNU parallel's -j: a whole number of jobs (its percentages are not offered here).
  p.integer("--jobs", "N", 1, 4096, "jobs", &jobs_n).modes = kRun;
  p.input_file("--sshloginfile", "FILE", &sshloginfile).modes = kRun;
  p.flag("--quiet", &quiet).modes = kRun;
  p.flag("--attribute", &attribute).modes = kRun;
  if (const int code = parse_command_line(p, argc, argv, "campaign"); code >= 0) return code;
  if (!p.refuse_inapplicable(example ? kExample : kRun, example ? "--example" : "a campaign run")) {
    std::fprintf(stderr, "%s\n", p.error().c_str());
    return usage_error("campaign");
  }
  if (example && !specs.empty()) {
    std::fprintf(stderr, "kuavo campaign: --example prints a spec; it takes no SPEC.json\n");
    return usage_error("campaign");
  }
  if (example) {
    std::fputs(kShowConditionsSpec, stdout);
    return 0;
  }
  if (jobs_n > 0) jobs = std::to_string(jobs_n);
  const std::string spec_path = specs.empty() ? "" : specs[0];
  if (spec_path.empty()) return usage_error("campaign");
  std::string why;
  if (!check_input_file(spec_path, why)) {  // a directory read as a stream threw ("internal error")
    std::fprintf(stderr, "kuavo campaign: %s\n", why.c_str());
    return 2;
  }
  bool ok = false;
  const std::string text = read_file(spec_path, ok);
  if (!ok) {
    std::fprintf(stderr, "kuavo campaign: cannot read %s\n", spec_path.c_str());
    return 2;
  }
  CampaignSpec spec;
  std::string error;
  if (!parse_campaign_spec(text, spec, error)) {
    std::fprintf(stderr, "kuavo campaign: %s: %s\n", spec_path.c_str(), error.c_str());
    return 2;
  }
  if (seeds_override > 0) spec.seeds = static_cast<int>(seeds_override);
  if (std::system("parallel --version > /dev/null 2>&1") != 0) {
    std::fprintf(stderr, "kuavo campaign: GNU parallel is not installed (Debian package 'parallel')\n");
    return 2;
  }

  std::error_code ec;
  const fs::path dir = fs::absolute(out_dir);
  fs::create_directories(dir / "runs", ec);
  fs::create_directories(dir / "motions", ec);
  if (ec) {
    std::fprintf(stderr, "kuavo campaign: cannot create %s: %s\n", dir.c_str(), ec.message().c_str());
    return 2;
  }
  const std::string self = fs::canonical("/proc/self/exe").string();

  // Motions: paths and run lengths (the motion's length plus the settling second, or the spec's duration).
  auto robot = std::make_unique<model::Model>();
  model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, *robot);
  auto plan = std::make_unique<planner::MotionPlan>();
  std::vector<Motion> motions;
  for (const std::string& entry : spec.motions) {
    Motion m;
    m.name = motion_name(entry);
    if (entry == "dance") {
      if (!prepare_builtin_dance(self, dir, m.path)) {
        std::fprintf(stderr, "kuavo campaign: retargeting the built-in dance failed\n");
        return 1;
      }
    } else {
      m.path = fs::absolute(entry).string();
    }
    planner::BalanceFilterReport no_filter;  // loaded as `kuavo simulate` will: refused here first
    if (!motion::load_motion(m.path, *robot, {}, *plan, no_filter, error)) {
      std::fprintf(stderr, "kuavo campaign: %s\n", error.c_str());
      return 2;
    }
    m.run_length_s = spec.duration_s > 0.0 ? spec.duration_s
                                           : planner::motion_plan_duration_s(*plan) + sim::MotionRunConfig{}.settle_s;
    for (const Motion& other : motions) {
      if (other.name == m.name) {
        std::fprintf(stderr, "kuavo campaign: two motions are named '%s'\n", m.name.c_str());
        return 2;
      }
    }
    motions.push_back(m);
  }
  for (std::string& p : spec.perturbations) {
    if (p != "none" && p != "show") p = fs::absolute(p).string();  // remote machines see absolute paths
  }

  // The `kuavo simulate` of a run, its summary to BASE.json (written as .part, renamed when
  // done). Without `errors` the plant is the controller's model (--perturb none, same
  // seed); without `push`, no push: the two halves of a fall's attribution (--attribute).
  // `state`: the third and fourth runs of an attribution. kTrueState: the controller reads
  // the plant's state (--state truth), not the estimator's. kIdealSensors: the estimator reads
  // sensors without the MTi model's noise, bias, tilt and quantization (--sensors ideal; the
  // perturbation set's own sensor errors stay).
  enum class StateSource { kEstimator, kTrueState, kIdealSensors };
  const auto simulate_command = [&](const Run& r, bool errors, bool push, const std::string& base,
                                    StateSource state = StateSource::kEstimator) {
    std::string cmd = quote(self) + " simulate " + quote(r.motion_path) + " --planner " + spec.planner + " --ground " +
                      r.ground + " --perturb " + quote(errors ? r.perturbation_arg : "none") + " --seed " +
                      std::to_string(r.seed);
    if (errors) cmd += " --perturb-seed " + std::to_string(r.seed);
    if (spec.liftoff_hold) cmd += " --liftoff-hold on";
    if (spec.lean_trim) cmd += " --lean-trim " + *spec.lean_trim;
    if (!spec.holdable_soles) cmd += " --holdable-soles off";
    if (spec.plan_anchor) cmd += *spec.plan_anchor ? " --plan-anchor on" : " --plan-anchor off";
    const auto add_number = [&cmd](const char* flag, double value) {
      char text[64];
      std::snprintf(text, sizeof text, " %s %.6g", flag, value);
      cmd += text;
    };
    if (spec.plan_anchor_home) add_number("--plan-anchor-home", *spec.plan_anchor_home);
    if (spec.estimator_unloaded_foot_N) add_number("--estimator-unloaded-foot", *spec.estimator_unloaded_foot_N);
    if (spec.planner_sole_inset_m) add_number("--planner-sole-inset", *spec.planner_sole_inset_m);
    if (spec.recovery_fast_swing_s) add_number("--recovery-fast-swing", *spec.recovery_fast_swing_s);
    const double sink_m = r.ground == "carpet" ? spec.carpet_sink_m : spec.floor_sink_m;
    if (sink_m > 0.0) add_number("--surface-sink", sink_m);
    if (spec.duration_s > 0.0) add_number("--duration", spec.duration_s);
    if (push && r.pushed) {
      char p_arg[128];
      std::snprintf(p_arg, sizeof p_arg, " --push %.3f:%.6f,%.6f,0:%.6g", r.push.start_s,
                    r.push.force_N * std::cos(r.push.direction_rad), r.push.force_N * std::sin(r.push.direction_rad),
                    spec.push.duration_s);
      cmd += p_arg;
    }
    if (state == StateSource::kTrueState) cmd += " --state truth";
    if (state == StateSource::kIdealSensors) cmd += " --sensors ideal";
    return cmd + " --summary " + quote(base + ".json.part") + " > /dev/null 2> " + quote(base + ".err") + "; test -s " +
           quote(base + ".json.part") + " && mv " + quote(base + ".json.part") + " " + quote(base + ".json");
  };
  // GNU parallel over a job file (a failed run shows as a missing or failed summary).
  const auto run_jobs = [&](const fs::path& job_file, const fs::path& joblog) {
    std::string cmd = "parallel --will-cite --halt never -j " + quote(jobs) + " --joblog " + quote(joblog.string());
    if (!sshloginfile.empty()) cmd += " --sshloginfile " + quote(sshloginfile);
    // Progress (GNU parallel's own: done, left, estimated time) on a terminal, not when piped.
    if (!quiet && isatty(STDERR_FILENO)) cmd += " --eta";
    cmd += " < " + quote(job_file.string());
    std::fflush(stderr);
    std::system(cmd.c_str());
  };

  // The matrix, in a fixed order.
  std::vector<Run> runs;
  for (const Motion& m : motions) {
    for (const std::string& g : spec.grounds) {
      for (const std::string& p : spec.perturbations) {
        for (int k = 0; k < spec.seeds; ++k) {
          Run r;
          r.motion = m.name;
          r.ground = g;
          r.perturbation = motion_name(p);
          r.perturbation_arg = p;
          r.seed = spec.first_seed + static_cast<std::uint64_t>(k);
          r.id = r.motion + "__" + g + "__" + r.perturbation + "__" + std::to_string(r.seed);
          if (spec.push.enabled) {
            if (!draw_push(spec.push, r.seed, m.run_length_s, r.push)) {
              std::fprintf(stderr, "kuavo campaign: the push window is empty for motion '%s' (%.3f s)\n", m.name.c_str(),
                           m.run_length_s);
              return 2;
            }
            r.pushed = true;
          }
          r.motion_path = m.path;
          r.command = simulate_command(r, true, true, (dir / "runs" / r.id).string());
          runs.push_back(r);
        }
      }
    }
  }

  // Pending runs through GNU parallel.
  const fs::path job_file = dir / "jobs.txt";
  int pending = 0;
  std::vector<bool> to_do(runs.size(), false);
  {
    std::ofstream jf(job_file);
    for (std::size_t i = 0; i < runs.size(); ++i) {
      if (fs::exists(dir / "runs" / (runs[i].id + ".json"))) continue;
      jf << runs[i].command << "\n";
      to_do[i] = true;
      ++pending;
    }
  }
  std::fprintf(stderr, "kuavo campaign: %zu runs, %d to do, %zu already done\n", runs.size(), pending,
               runs.size() - static_cast<std::size_t>(pending));
  if (pending > 0) run_jobs(job_file, dir / "joblog.txt");
  struct rusage children {};
  getrusage(RUSAGE_CHILDREN, &children);
  const double cpu_s = static_cast<double>(children.ru_utime.tv_sec + children.ru_stime.tv_sec) +
                       1e-6 * static_cast<double>(children.ru_utime.tv_usec + children.ru_stime.tv_usec);

  // Attribution (--attribute): each run that fell with both a push and model errors is run
  // again four times in DIR/attribution/ (resumable like the runs): the push alone on the
  // controller's own model (--perturb none, the same seed: the same sensor noise), and the
  // model errors alone without the push. Its cause: "push" (only the push alone falls),
  // "errors" (only the errors alone), "each" (both halves fall), "together" (neither
  // does: it takes the two), "failed" (one of its runs did not simulate). A third run
  // repeats the fall as it was (push and errors, the same seeds) with the controller reading
  // the plant's true base state instead of the estimator's (--state truth): a fall that it
  // survives is also counted as "state_estimate" (the estimate's errors have a part in it;
  // the controller itself balances that run). Not a cause of its own: it crosses the four.
  // A fourth run repeats it with the estimator reading noise-free sensors (--sensors ideal):
  // a fall that it survives is also counted as "sensor_noise" (the MTi model's errors, its
  // 0.2° orientation error above all, have a part in it; the filter's own lag does not
  // topple that run). Together the two split the estimate's part: a fall counted under
  // state_estimate but not sensor_noise is the filter's (or the show set's sensor errors').
  std::vector<std::string> cause(runs.size());
  std::vector<bool> estimate(runs.size(), false), sensor_noise(runs.size(), false);
  if (attribute) {
    fs::create_directories(dir / "attribution", ec);
    if (ec) {
      std::fprintf(stderr, "kuavo campaign: cannot create %s: %s\n", (dir / "attribution").c_str(), ec.message().c_str());
      return 2;
    }
    const fs::path att_jobs = dir / "attribution" / "jobs.txt";
    std::vector<std::size_t> fallen;
    int att_pending = 0;
    {
      std::ofstream jf(att_jobs);
      for (std::size_t i = 0; i < runs.size(); ++i) {
        const Outcome o = read_outcome(dir / "runs" / (runs[i].id + ".json"));
        if (!(o.ok && o.fell && runs[i].pushed && runs[i].perturbation_arg != "none")) continue;
        fallen.push_back(i);
        for (const bool errors : {false, true}) {
          const fs::path base = dir / "attribution" / (runs[i].id + (errors ? "__errors_alone" : "__push_alone"));
          if (fs::exists(base.string() + ".json")) continue;
          jf << simulate_command(runs[i], errors, !errors, base.string()) << "\n";
          ++att_pending;
        }
        for (const auto& [suffix, state] : {std::pair{"__true_state", StateSource::kTrueState},
                                            std::pair{"__ideal_sensors", StateSource::kIdealSensors}}) {
          const fs::path base = dir / "attribution" / (runs[i].id + suffix);
          if (fs::exists(base.string() + ".json")) continue;
          jf << simulate_command(runs[i], true, true, base.string(), state) << "\n";
          ++att_pending;
        }
      }
    }
    std::fprintf(stderr, "kuavo campaign: attribution of %zu falls, %d runs to do\n", fallen.size(), att_pending);
    if (att_pending > 0) run_jobs(att_jobs, dir / "attribution" / "joblog.txt");
    std::ofstream acsv(dir / "attribution.csv");
    acsv << "run,motion,cause,push_alone_fell_at_s,errors_alone_fell_at_s,true_state_fell_at_s,state_estimate,"
            "ideal_sensors_fell_at_s,sensor_noise\n";
    int failed = 0;
    for (const std::size_t i : fallen) {
      const Outcome p = read_outcome(dir / "attribution" / (runs[i].id + "__push_alone.json"));
      const Outcome e = read_outcome(dir / "attribution" / (runs[i].id + "__errors_alone.json"));
      const Outcome s = read_outcome(dir / "attribution" / (runs[i].id + "__true_state.json"));
      const Outcome n = read_outcome(dir / "attribution" / (runs[i].id + "__ideal_sensors.json"));
      cause[i] = !p.ok || !e.ok || !s.ok || !n.ok ? "failed"
                 : p.fell && e.fell      ? "each"
                 : p.fell                ? "push"
                 : e.fell                ? "errors"
                                         : "together";
      failed += cause[i] == "failed";
      estimate[i] = s.ok && !s.fell;
      sensor_noise[i] = n.ok && !n.fell;
      const auto fell_at = [](const Outcome& o) { return o.ok && o.fell ? o.fell_at_s : -1.0; };
      char times[128];
      std::snprintf(times, sizeof times, "%.3f,%.3f,%.3f,%d,%.3f,%d", fell_at(p), fell_at(e), fell_at(s),
                    estimate[i] ? 1 : 0, fell_at(n), sensor_noise[i] ? 1 : 0);
      acsv << runs[i].id << ',' << runs[i].motion << ',' << cause[i] << ',' << times << '\n';
    }
    if (failed > 0) {
      std::fprintf(stderr,
                   "kuavo campaign: %d attributions failed: one of their runs did not simulate (see %s/*.err)\n",
                   failed, (dir / "attribution").c_str());
    }
  }

  // The table.
  std::ofstream csv(dir / "runs.csv");
  csv << "run,motion,ground,perturbation,seed,push_start_s,push_direction_deg,ok,fell,fell_at_s,sim_time_s,"
         "zmp_margin_m_min,tracking_rms_legs_rad,tracking_rms_arms_rad,com_err_m_max,torque_ratio_max,"
         "torque_saturations,wbc_not_ok_ticks,mpc_failures,recovery_steps,early_touchdowns,liftoff_holds,motion_lag_s_max,anchor_offset_m_max,error,log_sha256\n";
  struct Tally {
    int runs = 0, falls = 0;
    std::map<std::string, int> causes;
  };
  std::map<std::string, Tally> per_motion;
  int total_runs = 0, total_falls = 0, failures = 0;
  double sim_seconds = 0.0;  // of the runs this invocation did
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const Run& r = runs[i];
    bool have = false, parsed = false;
    const nlohmann::json s = read_summary(dir / "runs" / (r.id + ".json"), have, parsed);
    const bool run_ok = parsed && s.value("ok", false);
    const bool fell = parsed && s.value("fell", false);
    std::string err = !have ? "no summary (see runs/" + r.id + ".err)" : !parsed ? "unreadable summary" : s.value("error", "");
    for (char& c : err) c = c == ',' || c == '\n' ? ';' : c;
    char row[1024];
    std::snprintf(row, sizeof row, "%s,%s,%s,%s,%llu,%.3f,%.2f,%d,%d,%.3f,%.3f,%.5f,%.5f,%.5f,%.5f,%.4f,%llu,%llu,%llu,%llu,%llu,%llu,%.3f,%.4f,%s,%s\n",
                  r.id.c_str(), r.motion.c_str(), r.ground.c_str(), r.perturbation.c_str(),
                  static_cast<unsigned long long>(r.seed), r.pushed ? r.push.start_s : -1.0,
                  r.pushed ? r.push.direction_rad * 180.0 / 3.14159265358979323846 : 0.0, run_ok ? 1 : 0, fell ? 1 : 0,
                  parsed ? number_or(s, "fell_at_s", -1.0) : -1.0, parsed ? number_or(s, "sim_time_s", 0.0) : 0.0,
                  parsed ? number_or(s, "zmp_margin_m_min", 0.0) : 0.0,
                  parsed && s.contains("tracking_rms_rad") ? number_or(s["tracking_rms_rad"], "legs", 0.0) : 0.0,
                  parsed && s.contains("tracking_rms_rad") ? number_or(s["tracking_rms_rad"], "arms", 0.0) : 0.0,
                  parsed ? number_or(s, "com_err_m_max", 0.0) : 0.0, parsed ? number_or(s, "torque_ratio_max", 0.0) : 0.0,
                  static_cast<unsigned long long>(parsed ? number_or(s, "torque_saturations", 0.0) : 0.0),
                  static_cast<unsigned long long>(parsed ? number_or(s, "wbc_not_ok_ticks", 0.0) : 0.0),
                  static_cast<unsigned long long>(parsed ? number_or(s, "mpc_failures", 0.0) : 0.0),
                  static_cast<unsigned long long>(parsed ? number_or(s, "recovery_steps", 0.0) : 0.0),
                  static_cast<unsigned long long>(parsed ? number_or(s, "recovery_early_touchdowns", 0.0) : 0.0),
                  static_cast<unsigned long long>(parsed ? number_or(s, "liftoff_holds", 0.0) : 0.0),
                  parsed && s.contains("motion_lag_s") ? number_or(s["motion_lag_s"], "max", 0.0) : 0.0,
                  parsed && s.contains("plan_anchor") ? number_or(s["plan_anchor"], "offset_m_max", 0.0) : 0.0, err.c_str(),
                  parsed ? s.value("log_sha256", "").c_str() : "");
    csv << row;
    const bool counted_fall = fell || !run_ok;
    Tally& t = per_motion[r.motion];
    ++t.runs;
    ++total_runs;
    t.falls += counted_fall;
    total_falls += counted_fall;
    if (!cause[i].empty()) ++t.causes[cause[i]];
    if (estimate[i]) ++t.causes["state_estimate"];
    if (sensor_noise[i]) ++t.causes["sensor_noise"];
    failures += !run_ok;
    if (parsed && to_do[i]) sim_seconds += number_or(s, "sim_time_s", 0.0);
  }
  csv.close();

  nlohmann::ordered_json summary;
  summary["name"] = spec.name;
  summary["runs"] = total_runs;
  summary["falls"] = total_falls;
  summary["sim_failures"] = failures;
  summary["interval"] = "Wilson score, 95 %";
  summary["motions"] = nlohmann::ordered_json::object();
  for (const Motion& m : motions) {
    const Tally& t = per_motion[m.name];
    double lo = 0.0, hi = 1.0;
    wilson_interval_95(t.falls, t.runs, lo, hi);
    // Rounded so the file is the same text on every machine.
    summary["motions"][m.name] = {{"runs", t.runs},
                                  {"falls", t.falls},
                                  {"fall_rate_ci95", {std::round(lo * 1e5) / 1e5, std::round(hi * 1e5) / 1e5}}};
    if (attribute) {  // falls with a push and model errors, by what alone topples the robot
      nlohmann::ordered_json causes = nlohmann::ordered_json::object();
      for (const char* c : {"push", "errors", "each", "together", "failed", "state_estimate", "sensor_noise"}) {
        const auto it = t.causes.find(c);
        causes[c] = it == t.causes.end() ? 0 : it->second;
      }
      summary["motions"][m.name]["fall_causes"] = causes;
    }
  }
  std::ofstream(dir / "summary.json") << summary.dump(2) << "\n";
  std::fputs((summary.dump(2) + "\n").c_str(), stdout);
  if (pending > 0 && cpu_s > 0.0) {
    // Throughput for BENCHMARKS.md: CPU time of every child (parallel, the simulate
    // processes), so other load on the machine does not count.
    std::fprintf(stderr, "kuavo campaign: %d runs, %.1f simulated s in %.1f core-s (children's CPU time): %.3f sim-s per core-s\n",
                 pending, sim_seconds, cpu_s, sim_seconds / cpu_s);
  }
  return 0;
}

}  // namespace kuavo::cli
