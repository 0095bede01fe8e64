// kuavo_fuzz: the hostile-input campaign of issue 22.
//
//   kuavo_fuzz [--seed N] [--parser-cases N] [--e2e-cases N] [--first-case N]
//              [--timeout-s S] [--memory-mb MB (0: no limit)] [--bvh-frames N] [--findings DIR]
//
// 1. In-process (--parser-cases): seeded mutations through the parsers themselves -- BVH
//    (parse_bvh), motion files (the reader and the frame rules, checksums recomputed after the
//    mutation), drivers configurations (apply_drivers_json + validate_drivers_config) and the
//    strict argument parser (rtos_shim/args.h). A finding: an exception, a refusal without a
//    message, or an accepted input holding a non-finite or out-of-limit value.
// 2. End to end (--e2e-cases): the same mutations and mutated command lines through the built
//    programs -- kuavo_fw --check (--dance, --config), kuavo retarget --stage geometric,
//    kuavo simulate (runs bounded by a fixed short --duration/--stand), kuavo model, campaign,
//    demo and retarget-sweep (their parsing; a fixed unwritable --out ends them before work),
//    kuavo_fw_sim (--stand 0.01) -- each under a time and an address-space limit. A finding: a
//    crash (signal), a hang (killed at --timeout-s), an exit code outside {0, 1, 2}, or an exit 0
//    whose output holds nan/inf/null, a motion file the loaders refuse or a value out of limits.
// Case i is drawn from case_seed(seed, i) alone: --first-case i --e2e-cases 1 replays it.
// Findings are written to DIR/<kind>_<case>/ (input, command line, stdout, stderr).
// Exit: 0 nothing found, 1 findings, 2 bad usage or the corpus cannot be read.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "rtos_shim/args.h"
#include "rtos_shim/clock.h"
#include "tests/fuzz/fuzz_inputs.h"
#include "tests/fuzz/run_limited.h"

namespace fs = std::filesystem;
using namespace kuavo::fuzz;

namespace {

struct Tally {
  long cases = 0, exit0 = 0, exit1 = 0, exit2 = 0, findings = 0;
  double seconds = 0.0;  // wall clock spent (printed, never judged)
};

struct Harness {
  Corpus corpus;
  std::string bin, work, findings_dir;
  RunLimits limits;
  int bvh_frames = 40;
  std::map<std::string, Tally> tally;
  long findings = 0;

  void write(const std::string& path, const std::string& text) const { std::ofstream(path, std::ios::binary) << text; }

  void finding(const std::string& kind, std::uint64_t index, const std::string& why, const std::vector<std::string>& argv,
               const RunResult* r, const std::string& input_name) {
    ++findings;
    ++tally[kind].findings;
    const fs::path dir = fs::path(findings_dir) / (kind + "_" + std::to_string(index));
    std::error_code ec;
    fs::create_directories(dir, ec);
    std::string cmd;
    for (const std::string& a : argv) cmd += "'" + a + "' ";
    write((dir / "why.txt").string(), why + "\n" + cmd + "\n");
    if (r != nullptr) {
      write((dir / "stdout.txt").string(), r->out);
      write((dir / "stderr.txt").string(), r->err);
    }
    if (!input_name.empty()) fs::copy_file(fs::path(work) / input_name, dir / input_name, fs::copy_options::overwrite_existing, ec);
    std::printf("FINDING %s case %llu: %s\n  %s\n", kind.c_str(), static_cast<unsigned long long>(index), why.c_str(), cmd.c_str());
    std::fflush(stdout);
  }

  // Runs one program, judges its end and (after exit 0) its outputs with `check_outputs`.
  template <typename Check>
  void run_case(const std::string& kind, std::uint64_t index, const std::vector<std::string>& argv,
                const std::string& input_name, Check check_outputs) {
    // Every case starts from the same files: whatever an earlier command line wrote (an output
    // named "1e308", say) is removed, and the fixed inputs are written again.
    std::error_code ec;
    for (const fs::directory_entry& e : fs::directory_iterator(work, ec)) {
      const std::string name = e.path().filename().string();
      if (name != input_name && name != "in.motion" && name != "in.json" && name != "in.bvh") fs::remove_all(e.path(), ec);
    }
    fs::create_directories(work + "/dir", ec);
    write_fixed_files();
    const kuavo::rtos::TimeNs t0 = kuavo::rtos::now_ns();
    const RunResult r = run_limited(argv, work, limits);
    Tally& t = tally[kind];
    t.seconds += static_cast<double>(kuavo::rtos::now_ns() - t0) * 1e-9;
    ++t.cases;
    std::string why = judge_end(r, limits);
    if (why.empty()) {
      (r.code == 0 ? t.exit0 : r.code == 1 ? t.exit1 : t.exit2)++;
      if (r.code == 0) why = check_outputs(r);
      if (r.code != 0 && r.err.empty()) why = "exit " + std::to_string(r.code) + " without a message";
      // An exception that reached main (bad input must be refused where it is read).
      if (why.empty() && r.err.find("internal error") != std::string::npos) why = "an exception reached main: " + r.err.substr(0, 200);
    }
    if (!why.empty()) finding(kind, index, why, argv, &r, input_name);
  }

  std::string fw() const { return bin + "/firmware/kuavo_fw"; }
  std::string kuavo() const { return bin + "/kuavo"; }

  void e2e_case(std::uint64_t index, std::uint64_t seed) {
    Rng rng(case_seed(seed, index));
    const std::string w = work + "/";
    const auto motion_ok = [&](const std::string& name) {
      return [this, name](const RunResult& r) {
        if (std::string why = check_output_text(r.out); !why.empty()) return why;
        return name.empty() ? std::string() : check_motion_file(work + "/" + name, corpus.robot);
      };
    };
    switch (rng() % 8) {
      case 0:
      case 1: {  // a mutated motion through the robot image's --check
        const std::vector<std::uint8_t> b = mutate_motion(corpus.motion, rng);
        write(w + "in.motion", std::string(b.begin(), b.end()));
        std::vector<std::string> argv = {fw(), "--check", "--dance", "in.motion"};
        if (rng() % 4 == 0) argv.insert(argv.end(), {"--balance-filter", "on"});
        run_case("motion", index, argv, "in.motion", motion_ok("in.motion"));
        break;
      }
      case 2: {  // a mutated drivers configuration through --check
        write(w + "in.json", mutate_config(corpus.config_json, rng));
        run_case("config", index, {fw(), "--check", "--config", "in.json"}, "in.json",
                 [](const RunResult& r) { return check_output_text(r.out); });
        break;
      }
      case 3:
      case 4: {  // a mutated shared clip through kuavo retarget's geometric stage
        const std::size_t clip = rng() % corpus.bvh_clips.size();
        write(w + "in.bvh", mutate_bvh(corpus.bvh_clips[clip], bvh_frames, rng));
        run_case("bvh", index, {kuavo(), "retarget", "in.bvh", "-o", "out.motion", "--stage", "geometric", "--report", "r.json"},
                 "in.bvh", [&](const RunResult& r) {
                   std::string why = motion_ok("out.motion")(r);
                   if (why.empty()) {
                     std::ifstream in(w + "r.json");
                     std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
                     why = check_output_json(text);
                   }
                   return why;
                 });
        break;
      }
      default:
        command_line_case(index, rng);
        break;
    }
  }

  // Mutated command lines; the fixed tokens bound every run (a short simulation, --check, an
  // --out that cannot be created) so a valid line never runs long.
  void command_line_case(std::uint64_t index, Rng& rng) {
    const std::vector<std::string> values = {
        "m.motion", "c.json", "small.bvh", "spec.json", "dir", "/dev/zero", "/dev/null", "/nonexistent/x", "out.motion",
        "s.json", "run.csv", "dir/x.json", "csp", "cst", "on", "off", "floor", "carpet", "ice", "s45", "s42", "mpc",
        "kinematic", "truth", "estimator", "ideal", "mti", "measured", "cvode", "rkm", "euler", "show", "none", "auto",
        "geometric", "dynamic", "0.02", "0.6", "1.2", "3", "1:10,0,0:0.1", "0:1e9,0,0:0.1", "1:10,0,0:inf", "1:10,0:0.1",
        "0.2,0.4", "0.2,", "-", "--", "-o", "--json", "--check", "--help"};
    const std::vector<std::string> strangers = {"--bogus", "-x", "--stand", "--dance", "--timing", "--evict-cache",
                                                "--require-rt", "--seed", "--out", "--stage", "--horizon", "--duration"};
    auto with = [&](std::vector<std::string> own) {
      own.insert(own.end(), strangers.begin(), strangers.end());
      return own;
    };
    const auto text_ok = [](const RunResult& r) { return check_output_text(r.out); };
    // A summary on stdout is JSON; --help prints the usage instead (exit 0, not a finding).
    const auto json_ok = [](const RunResult& r) {
      return r.out.rfind("usage:", 0) == 0 ? check_output_text(r.out) : check_output_json(r.out);
    };
    const std::string nowhere = "/proc/kuavo_fuzz_no_such_dir/out";  // cannot be created: ends a run before its work
    switch (rng() % 10) {
      case 0:
      case 1:
        run_case("args:kuavo_fw", index,
                 mutate_command_line({fw(), "--check"}, {"--legs", "csp", "--dance", "m.motion", "--config", "c.json"},
                                     with({"--legs", "--config", "--balance-filter", "--check", "--stand"}), values, rng),
                 "", text_ok);
        break;
      case 2:
        run_case("args:model", index,
                 mutate_command_line({kuavo(), "model"}, {"--variant", "s45", "--mass", "55", "--json"},
                                     with({"--variant", "--mass", "--json"}), values, rng),
                 "", [](const RunResult& r) { return r.out.rfind("{", 0) == 0 ? check_output_json(r.out) : check_output_text(r.out); });
        break;
      case 3:
        run_case("args:simulate", index,
                 mutate_command_line({kuavo(), "simulate", "--duration", "0.02"},
                                     {"m.motion", "--ground", "carpet", "--seed", "3", "--horizon", "1.2", "--summary", "s.json"},
                                     with({"--planner", "--state", "--sensors", "--plan-latency-ms", "--balance-filter",
                                           "--perturb", "--perturb-seed", "--latency-ticks", "--rtol", "--mass", "--variant",
                                           "--step-in-place", "--push", "--log", "--summary"}),
                                     values, rng),
                 "", json_ok);
        break;
      case 4:
        run_case("args:simulate", index,
                 mutate_command_line({kuavo(), "simulate", "--stand", "0.02"},
                                     {"--ground", "floor", "--push", "0.01:10,0,0:0.01", "--seed", "1", "--integrator", "cvode"},
                                     with({"--latency-ticks", "--integrator", "--rtol", "--push", "--log", "--summary", "--mass"}),
                                     values, rng),
                 "", json_ok);
        break;
      case 5:
      case 6: {
        const std::vector<std::string> argv =
            mutate_command_line({kuavo(), "retarget", "--stage", "geometric"},
                                {"small.bvh", "-o", "out.motion", "--report", "r.json", "--contacts", "auto", "--csv", "c.csv"},
                                with({"--map", "--contacts", "--dance-bvh", "--variant", "--repairs", "--figures",
                                      "--dynamic-csv", "--torque-weight", "--report", "--csv"}),
                                values, rng);
        // out.motion is judged when the motion output (-o/--out) is the only option naming it.
        const long names = std::count(argv.begin(), argv.end(), std::string("out.motion"));
        bool motion_out = false;
        for (std::size_t k = 0; k + 1 < argv.size(); ++k)
          if ((argv[k] == "-o" || argv[k] == "--out") && argv[k + 1] == "out.motion") motion_out = names == 1;
        for (const std::string& a : argv)
          if (a == "--help" || a == "-h") motion_out = false;  // exit 0 with the usage, nothing written
        run_case("args:retarget", index, argv, "", [&, motion_out](const RunResult& r) {
          std::string why = check_output_text(r.out);
          if (why.empty() && motion_out) why = check_motion_file(work + "/out.motion", corpus.robot);
          return why;
        });
        break;
      }
      case 7: {
        const std::size_t which = rng() % 3;
        const std::vector<std::string> fixed[] = {{kuavo(), "retarget-sweep", "--out", nowhere},
                                                  {kuavo(), "demo", "--out", nowhere},
                                                  {kuavo(), "campaign", "--out", nowhere}};
        const std::vector<std::string> base[] = {{"small.bvh", "--horizons", "0.2,0.4", "--variant", "s45"},
                                                 {"--planner", "mpc"},
                                                 {"spec.json", "--seeds", "2", "--jobs", "1"}};
        run_case("args:" + fixed[which][1], index,
                 mutate_command_line(fixed[which], base[which],
                                     with({"--horizons", "--variant", "--planner", "--seeds", "--jobs", "--sshloginfile", "--example"}),
                                     values, rng),
                 "", text_ok);
        break;
      }
      default:
        run_case("args:kuavo_fw_sim", index,
                 mutate_command_line({bin + "/firmware/sitl/kuavo_fw_sim", "--stand", "0.01"},
                                     {"--ground", "carpet", "--seed", "2", "--legs", "csp", "--plan-latency-ms", "4", "--summary", "s.json"},
                                     with({"--config", "--legs", "--ground", "--push", "--plan-latency-ms", "--log", "--summary",
                                           "--balance-filter"}),
                                     values, rng),
                 "", json_ok);
        break;
    }
  }

  std::string small_bvh;
  void write_fixed_files() const {
    write(work + "/m.motion", std::string(corpus.motion.begin(), corpus.motion.end()));
    write(work + "/c.json", corpus.config_json);
    write(work + "/small.bvh", small_bvh);
    write(work + "/spec.json", R"({"motions": ["m.motion"], "grounds": ["floor"], "perturbations": ["none"], "seeds": 1})");
  }

  // The fixed files command lines name.
  bool prepare_work(std::string& error) {
    std::error_code ec;
    fs::create_directories(work + "/dir", ec);
    const std::string clip = corpus.bvh_clips[0];
    // A small valid clip: the first 120 frames of cmu_05_20_mb (mutate_bvh cuts, then damages; here only cut).
    const std::size_t t = clip.find("Frame Time:");
    std::size_t end = clip.find('\n', t) + 1;
    for (int k = 0; k < 120 && end < clip.size(); ++k) end = clip.find('\n', end) + 1;
    std::string small = clip.substr(0, end);
    const std::size_t f = small.find("Frames:");
    small.replace(f, small.find('\n', f) - f, "Frames: 120");
    small_bvh = small;
    write_fixed_files();
    if (!check_bvh_text(small).empty()) {
      error = "the small clip does not parse";
      return false;
    }
    return true;
  }
};

void print_tally(const std::map<std::string, Tally>& tally) {
  std::printf("%-22s %9s %8s %8s %8s %8s %9s\n", "kind", "cases", "exit 0", "exit 1", "exit 2", "findings", "ms/case");
  for (const auto& [kind, t] : tally) {
    std::printf("%-22s %9ld %8ld %8ld %8ld %8ld %9.2f\n", kind.c_str(), t.cases, t.exit0, t.exit1, t.exit2, t.findings,
                t.cases ? 1e3 * t.seconds / static_cast<double>(t.cases) : 0.0);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::uint64_t seed = 1, first = 0;
  long long parser_cases = 20000, e2e_cases = 200, bvh_frames = 40;
  double timeout_s = 20.0, memory_mb = 512.0;
  std::string findings_dir = "fuzz_findings";
  kuavo::args::Parser p("kuavo_fuzz");
  p.uint64("--seed", "N", &seed);
  p.uint64("--first-case", "N", &first);
  p.integer("--parser-cases", "N", 0, 100'000'000, "cases", &parser_cases);
  p.integer("--e2e-cases", "N", 0, 10'000'000, "cases", &e2e_cases);
  p.integer("--bvh-frames", "N", 1, 100'000, "frames", &bvh_frames);
  p.number("--timeout-s", "S", 0.1, 3600.0, "s", &timeout_s);
  p.number("--memory-mb", "MB", 0.0, 65536.0, "MB", &memory_mb);  // 0: no limit (sanitized builds)
  p.text("--findings", "DIR", &findings_dir);
  switch (p.parse(argc, argv)) {
    case kuavo::args::Parser::Result::kHelp:
      std::puts("usage: kuavo_fuzz [--seed N] [--parser-cases N] [--e2e-cases N] [--first-case N] [--timeout-s S]\n"
                "                  [--memory-mb MB] [--bvh-frames N] [--findings DIR]   (see tests/fuzz/README.md)");
      return 0;
    case kuavo::args::Parser::Result::kError:
      std::fprintf(stderr, "%s\n", p.error().c_str());
      return 2;
    case kuavo::args::Parser::Result::kOk:
      break;
  }
  Harness h;
  std::string error;
  if (!load_corpus(KUAVO_SHARED_DIR, h.corpus, error)) {
    std::fprintf(stderr, "kuavo_fuzz: %s\n", error.c_str());
    return 2;
  }
  h.bin = KUAVO_BINARY_DIR;
  h.findings_dir = fs::absolute(findings_dir).string();
  h.work = (fs::path(KUAVO_BINARY_DIR) / ("fuzz_work_" + std::to_string(seed))).string();
  h.limits.timeout_s = timeout_s;
  h.limits.memory_bytes = static_cast<long>(memory_mb * 1024 * 1024);
  h.bvh_frames = static_cast<int>(bvh_frames);
  std::error_code ec;
  fs::create_directories(h.work, ec);
  if (!h.prepare_work(error)) {
    std::fprintf(stderr, "kuavo_fuzz: %s\n", error.c_str());
    return 2;
  }

  const kuavo::rtos::TimeNs t0 = kuavo::rtos::now_ns();
  // 1. In process.
  const std::vector<std::string> arg_values = {"5", "0.02", "600", "floor", "carpet", "m.motion", "x", "--stand"};
  for (std::uint64_t i = first; i < first + static_cast<std::uint64_t>(parser_cases); ++i) {
    const kuavo::rtos::TimeNs case_t0 = kuavo::rtos::now_ns();
    Rng rng(case_seed(seed, i));
    std::string why, kind, input;
    switch (i % 4) {
      case 0:
        kind = "parse:bvh";
        input = mutate_bvh(h.corpus.bvh_clips[rng() % h.corpus.bvh_clips.size()], h.bvh_frames, rng);
        why = check_bvh_text(input);
        break;
      case 1: {
        kind = "parse:motion";
        const std::vector<std::uint8_t> b = mutate_motion(h.corpus.motion, rng);
        input.assign(b.begin(), b.end());
        why = check_motion_bytes(b, h.corpus.robot);
        break;
      }
      case 2:
        kind = "parse:config";
        input = mutate_config(h.corpus.config_json, rng);
        why = check_config_text(input, h.corpus.robot);
        break;
      default: {
        kind = "parse:args";
        const std::vector<std::string> tokens = mutate_command_line(
            {}, {"m.motion", "--stand", "5", "--seed", "3", "--ground", "floor"},
            {"--stand", "--plan-latency-ms", "--step-in-place", "--seed", "--ground", "--config", "--check", "--push", "--x", "-h"},
            arg_values, rng);
        for (const std::string& t : tokens) input += t + "\n";
        why = check_argument_tokens(tokens);
        break;
      }
    }
    Tally& t = h.tally[kind];
    ++t.cases;
    t.seconds += static_cast<double>(kuavo::rtos::now_ns() - case_t0) * 1e-9;
    if (!why.empty()) {
      h.write(h.work + "/input", input);
      h.finding(kind, i, why, {}, nullptr, "input");
    }
  }
  const double parser_s = static_cast<double>(kuavo::rtos::now_ns() - t0) * 1e-9;
  // 2. End to end.
  for (std::uint64_t i = first; i < first + static_cast<std::uint64_t>(e2e_cases); ++i) h.e2e_case(i, seed);
  const double total_s = static_cast<double>(kuavo::rtos::now_ns() - t0) * 1e-9;

  print_tally(h.tally);
  std::printf("kuavo_fuzz: seed %llu, cases %llu..%llu: %lld in process (%.1f s), %lld end to end (%.1f s), %ld findings%s\n",
              static_cast<unsigned long long>(seed), static_cast<unsigned long long>(first),
              static_cast<unsigned long long>(first + std::max(parser_cases, e2e_cases)), parser_cases, parser_s, e2e_cases,
              total_s - parser_s, h.findings, h.findings ? (" (in " + h.findings_dir + ")").c_str() : "");
  return h.findings == 0 ? 0 : 1;
}
