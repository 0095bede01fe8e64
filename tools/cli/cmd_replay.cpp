// kuavo replay RUN.csv [RUN.csv ...] --out DIR [--retarget-report R.json] [--human H.csv] [--title T]
// The HTML report (html_report.h) for logs of `kuavo simulate`: each run's summary JSON beside
// its log (same name, .json) puts the fall on its timeline; the retarget report adds the
// repairs and the human CSV the skeleton, for the runs that dance a motion.
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tools/cli/args.h"
#include "tools/cli/commands.h"
#include "tools/cli/html_report.h"
#include "tools/cli/usage.h"

namespace kuavo::cli {

int run_replay(int argc, char** argv) {
  std::vector<std::string> logs;
  std::string out, retarget_report, human, title = "Kuavo 4Pro replay";
  args::Parser p("kuavo replay");
  p.positionals("RUN.csv", &logs, 64);
  p.text("--out", "DIR", &out);
  p.input_file("--retarget-report", "R.json", &retarget_report);
  p.input_file("--human", "H.csv", &human);
  p.text("--title", "TEXT", &title);
  if (const int code = parse_command_line(p, argc, argv, "replay"); code >= 0) return code;
  if (logs.empty() || out.empty()) {
    std::fprintf(stderr, "kuavo replay: %s\n", logs.empty() ? "no RUN.csv given" : "--out DIR is required");
    print_usage(stderr, "replay");
    return 2;
  }
  std::string error;
  for (const std::string* in : {&retarget_report, &human}) {
    if (!in->empty() && !check_input_file(*in, error)) {
      std::fprintf(stderr, "kuavo replay: %s\n", error.c_str());
      return 2;
    }
  }
  HtmlReport report;
  report.title = title;
  report.subtitle = "Simulator logs replayed (kuavo replay).";
  report.human_csv = human;
  if (!retarget_report.empty() && !read_repairs(retarget_report, report.repairs, error)) {
    std::fprintf(stderr, "kuavo replay: %s\n", error.c_str());
    return 2;
  }
  HtmlTable table{"Runs", {"run", "fell", "simulated [s]", "summary"}, {}, ""};
  for (const std::string& log : logs) {
    if (!check_input_file(log, error)) {
      std::fprintf(stderr, "kuavo replay: %s\n", error.c_str());
      return 2;
    }
    ReplayRun run;
    run.name = std::filesystem::path(log).stem().string();
    run.log_csv = log;
    run.follows_motion = !human.empty() || !retarget_report.empty();
    const std::string summary_path = std::filesystem::path(log).replace_extension(".json").string();
    std::ifstream in(summary_path);
    std::string sim_s = "?";
    if (in) {
      std::stringstream ss;
      ss << in.rdbuf();
      const auto j = nlohmann::json::parse(ss.str(), nullptr, false);
      if (!j.is_discarded() && j.is_object()) {
        run.fell = j.value("fell", false);
        run.fell_at_s = j.value("fell_at_s", -1.0);
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.2f", j.value("sim_time_s", 0.0));
        sim_s = buf;
        run.description = "log " + log + ", summary " + summary_path;
      }
    }
    if (run.description.empty()) run.description = "log " + log + " (no summary: a fall is not marked)";
    table.rows.push_back({run.name, run.fell ? "fell at " + std::to_string(run.fell_at_s).substr(0, 5) + " s" : "no", sim_s,
                          in ? summary_path : "-"});
    report.runs.push_back(run);
  }
  report.tables.push_back(table);
  auto robot = std::make_unique<model::Model>();
  if (model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, *robot) != model::ModelError::kOk) return 1;
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (!write_html_report(*robot, report, out, error)) {
    std::fprintf(stderr, "kuavo replay: %s\n", error.c_str());
    return 1;
  }
  std::printf("report: %s/index.html\n", out.c_str());
  return 0;
}

}  // namespace kuavo::cli
