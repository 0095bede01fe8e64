#include "tools/cli/usage.h"

#include <cstring>

namespace kuavo::cli {
namespace {

constexpr CommandHelp kHelp[] = {
    {"demo", "the main job: a BVH (or the built-in dance) through the whole pipeline into a report",
     "usage: kuavo demo [IN.bvh] [--out DIR] [--planner mpc|kinematic] [--quiet]\n"
     "  IN.bvh through import, geometric and dynamic retargeting with repairs, then danced by the\n"
     "  online stack in the simulator: floor, carpet with a 10 N·s push (MPC horizon 1.2 s and 0.6 s),\n"
     "  20 steps in place, standing with a push. Without IN.bvh: the built-in 30 s dance.\n"
     "  --out DIR       report folder (default demo_report); open DIR/index.html in a browser\n"
     "  --planner P     mpc (default) or kinematic (geometric motion + balance filter)\n"
     "  --quiet         no progress and no stage lines (errors and the report's path only)\n"},
    {"paper", "the paper's experiments (Figs. 4-7, Table I) beside its numbers, in one page",
     "usage: kuavo paper [--out DIR] [--quiet]\n"
     "  Figs. 4/5 (dynamic retargeting of the built-in dance), Fig. 6 (TO horizon sweep 0.2..1.4 s),\n"
     "  Fig. 7 (carpet, 10 N·s push, MPC horizon 0.6 s vs 1.2 s: knees, foot placement, falls) and\n"
     "  Table I (MPC solve time against horizon, this machine beside the paper's i9-13900H).\n"
     "  --out DIR       output folder (default paper_report); open DIR/index.html\n"
     "  --quiet         no progress and no stage lines\n"},
    {"replay", "an HTML replay report from simulator logs",
     "usage: kuavo replay RUN.csv [RUN.csv ...] --out DIR [--retarget-report R.json] [--human H.csv] [--title T]\n"
     "  RUN.csv: a log of `kuavo simulate --log` (its summary RUN.json beside it is read when present:\n"
     "  the fall goes on the timeline). --retarget-report: the repairs of `kuavo retarget --report`;\n"
     "  --human: `kuavo retarget --human-csv` (the skeleton beside the robot). Writes DIR/index.html.\n"},
    {"retarget", "a BVH dance (or the built-in dance) -> robot motion file + report",
     "usage: kuavo retarget [INPUT.bvh] -o OUT.motion [--variant s45|s42] [--contacts auto|none|FILE]\n"
     "                      [--map MAPPING.txt] [--csv OUT.csv] [--dance-bvh OUT.bvh] --report REPORT.json\n"
     "                      [--stage geometric|dynamic] [--horizon S] [--repairs FILE] [--dynamic-csv OUT.csv]\n"
     "                      [--torque-weight W] [--attenuate ROUNDS] [--verify ROUNDS] [--figures DIR|none]\n"
     "                      [--verify-mujoco on|off] [--verify-firmware on|off] [--support-margin M]\n"
     "                      [--verify-show SEEDS] [--human-csv OUT.csv] [--force-reference static|motion]\n"
     "                      [--ankle-motor-weight W]   (the TO's hinge on the stance ankles' motor torques; 0: off)\n"
     "                      [--ankle-effort-weight W]   (the TO's cost on the stance ankles' torques beyond standing's,\n"
     "                      the pitch only forward: a held lean moves back over the ankles; 0..10; default 0: off)\n"
     "                      (--support-margin: the TO's centre of pressure M m inside the soles, 0..0.04, default 0)\n"
     "                      [--stance-lean M]   (the repair moves the pelvis up to M m back or ahead where a double\n"
     "                      support holds the CoM off its standing place over the ankles, 0..0.08; default 0: off)\n"
     "                      (--verify: closed-loop check rounds, 0..16, default 12; 0: none)\n"
     "                      (--verify-show: carpet runs with the show set's model errors, 0..48 seeds, default 24)\n"
     "                      [--verify-show-push NS]   (each of those runs pushed once as in the show campaign; 0..40, default 10; 0: none)\n"
     "                      [--verify-holdable-soles on|off]   (the check's recovery step on the holdable soles, as online; default on)\n"
     "                      [--verify-recovery-fast-swing S]   (the check's recovery step with simulate's --recovery-fast-swing S,\n"
     "                      0.2..0.4; default off, as online)\n"
     "                      [--verify-carpet-sink M]   (the check's carpet runs with simulate's --surface-sink M, 0..0.05;\n"
     "                      default 0)\n"
     "                      [--duration S]   (the built-in dance: whole 30 s cycles, 30..300 s; default 30)\n"
     "                      [--quiet]   (a progress line on a terminal; --quiet: none, and no summary lines)\n"},
    {"retarget-sweep", "the dynamic stage per TO horizon (Fig. 6)",
     "usage: kuavo retarget-sweep [INPUT.bvh] --out DIR [--horizons S,S,...] [--variant s45|s42] [--quiet]\n"
     "       horizons in [0.2, 1.4] s; default 0.2,0.4,0.6,0.8,1.0,1.2,1.4\n"},
    {"simulate", "one run in the simulator: standing, a motion, or stepping in place",
     "usage: kuavo simulate --stand SECONDS | MOTION | --step-in-place STEPS\n"
     "               [--ground floor|carpet] [--push T:FX,FY,FZ:DURATION] [--seed N]\n"
     "               [--latency-ticks N] [--integrator cvode|rkm|euler] [--variant s45|s42] [--mass KG]\n"
     "               [--engine simbody|mujoco|both]   (mujoco: Leju's MJCF and MuJoCo's contact; floor only;\n"
     "               both: a run on each, one summary saying where they disagree; MuJoCo's log NAME.mujoco.csv)\n"
     "               [--planner kinematic|mpc] [--state estimator|truth] [--sensors mti|ideal]\n"
     "               [--estimator-unloaded-foot N]   (opt-in: a foot the WBC loads below N leaves the estimator's stance set)\n"
     "               [--surface-sink M]   (the stage surface's sink under the standing robot, 0..0.05; default 0:\n"
     "               a hard floor)\n"
     "               [--planner-sole-inset M]   (opt-in: the MPC planner plans on soles M m narrower each side, 0..0.04)\n"
     "               [--recovery-fast-swing SECONDS]   (opt-in: a recovery step no 0.40 s swing captures is planned\n"
     "               again with this swing, 0.2..0.4)\n"
     "               [--lean-trim on|off]   (opt-in: the base tilt trimmed until the WBC's forces move the CoM as planned)\n"
     "               [--horizon SECONDS] [--plan-latency-ms MS|measured] [--recovery-step on|off]\n"
     "               [--early-touchdown on|off] [--liftoff-hold on|off] [--plan-anchor on|off]\n"
     "               [--holdable-soles on|off]   (default on: the recovery step's trigger on the part of the soles the ankles hold)\n"
     "               [--plan-anchor-home SHARE]\n"
     "               [--duration SECONDS] [--balance-filter on|off] [--perturb none|show|FILE.json [--perturb-seed N]]\n"
     "               --log run.csv --summary run.json [--quiet]\n"},
    {"campaign", "runs over seeds, grounds and perturbations under GNU parallel",
     "usage: kuavo campaign SPEC.json [--out DIR] [--seeds N] [--jobs N] [--sshloginfile FILE] [--quiet]\n"
     "                      [--attribute]   (each fall with a push and model errors run again with each alone,\n"
     "                                       with the true base state for the estimate's, and with\n"
     "                                       noise-free sensors (--sensors ideal) for the sensors':\n"
     "                                       DIR/attribution.csv, summary.json \"fall_causes\")\n"
     "       kuavo campaign --example      print the \"show conditions\" spec\n"},
    {"model", "robot model summary",
     "usage: kuavo model [--variant s45|s42] [--mass KG] --json\n"},
};

}  // namespace

const CommandHelp* command_help(const char* name) {
  for (const CommandHelp& h : kHelp) {
    if (name != nullptr && !std::strcmp(name, h.name)) return &h;
  }
  return nullptr;
}

const CommandHelp* commands_help(int& count) {
  count = static_cast<int>(sizeof kHelp / sizeof kHelp[0]);
  return kHelp;
}

void print_overview(std::FILE* out) {
  std::fprintf(out, "usage: kuavo <command> [options]      (kuavo help <command>, kuavo <command> --help)\n\ncommands:\n");
  for (const CommandHelp& h : kHelp) std::fprintf(out, "  %-15s %s\n", h.name, h.summary);
}

void print_usage(std::FILE* out, const char* name) {
  const CommandHelp* h = command_help(name);
  if (h == nullptr) return print_overview(out);
  std::fputs(h->usage, out);
}

int usage_error(const char* name) {
  print_usage(stderr, name);
  return 2;
}

int parse_command_line(args::Parser& parser, int argc, char** argv, const char* name) {
  switch (parser.parse(argc, argv)) {
    case args::Parser::Result::kHelp:
      print_usage(stdout, name);
      return 0;
    case args::Parser::Result::kError:
      std::fprintf(stderr, "%s\n", parser.error().c_str());
      return usage_error(name);
    case args::Parser::Result::kOk:
      break;
  }
  return -1;
}

}  // namespace kuavo::cli
