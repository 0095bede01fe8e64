// Subcommands of the `kuavo` CLI. Each returns the process exit code:
// 0 success, 1 failure while running, 2 bad usage or bad input.
#pragma once

namespace kuavo::cli {

int run_model(int argc, char** argv);  // kuavo model [--variant s45|s42] [--mass KG] --json
int run_demo(int argc, char** argv);   // kuavo demo: the main job
int run_simulate(int argc, char** argv);  // kuavo simulate --stand SECONDS ...
int run_retarget(int argc, char** argv);  // kuavo retarget [IN.bvh] -o OUT.motion ... --report R.json
int run_retarget_sweep(int argc, char** argv);  // kuavo retarget-sweep [IN.bvh] --out DIR [--horizons S,...]
int run_campaign(int argc, char** argv);
int run_replay(int argc, char** argv);    // kuavo replay RUN.csv ... --out DIR: HTML replay of simulator logs
int run_paper(int argc, char** argv);     // kuavo paper [--out DIR]: the paper's experiments in one page  // kuavo campaign SPEC.json [--out DIR] [--seeds N] | --example

}  // namespace kuavo::cli
