#include "tests/fuzz/run_limited.h"

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <csignal>
#include <cstring>
#include <fstream>
#include <sstream>

#include "rtos_shim/clock.h"

namespace kuavo::fuzz {
namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

RunResult run_limited(const std::vector<std::string>& argv, const std::string& workdir, const RunLimits& limits) {
  RunResult r;
  const std::string out_path = workdir + "/.stdout", err_path = workdir + "/.stderr";
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return r;
  if (pid == 0) {
    // Child: only async-signal-safe calls until exec. Its own process group (a timeout kills
    // whatever it started too), and killed with the harness (no orphan spins on after it).
    setpgid(0, 0);
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (chdir(workdir.c_str()) != 0) _exit(125);
    const int in = open("/dev/null", O_RDONLY);
    const int out = open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err = open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (in < 0 || out < 0 || err < 0) _exit(125);
    dup2(in, 0);
    dup2(out, 1);
    dup2(err, 2);
    if (limits.memory_bytes > 0) {
      rlimit as{static_cast<rlim_t>(limits.memory_bytes), static_cast<rlim_t>(limits.memory_bytes)};
      setrlimit(RLIMIT_AS, &as);
    }
    rlimit core{0, 0};
    setrlimit(RLIMIT_CORE, &core);
    execv(args[0], args.data());
    _exit(126);
  }
  // Parent: poll for the end; past the timeout the child is killed (a hang).
  const rtos::TimeNs deadline = rtos::now_ns() + static_cast<rtos::TimeNs>(limits.timeout_s * 1e9);
  int status = 0;
  rtos::TimeNs wait_ns = 20'000;
  while (true) {
    const pid_t done = waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    if (rtos::now_ns() > deadline) {
      kill(-pid, SIGKILL);
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      r.end = RunResult::End::kTimeout;
      break;
    }
    rtos::sleep_until_ns_rt(rtos::now_ns() + wait_ns);
    wait_ns = std::min<rtos::TimeNs>(wait_ns * 2, 2'000'000);  // 20 µs .. 2 ms: short runs end early
  }
  if (r.end != RunResult::End::kTimeout) {
    if (WIFEXITED(status)) {
      r.end = RunResult::End::kExited;
      r.code = WEXITSTATUS(status);
    } else if (WIFSIGNALED(status)) {
      r.end = RunResult::End::kSignal;
      r.code = WTERMSIG(status);
    }
  }
  r.out = slurp(out_path);
  r.err = slurp(err_path);
  return r;
}

std::string judge_end(const RunResult& r, const RunLimits& limits) {
  switch (r.end) {
    case RunResult::End::kExited:
      if (r.code == 0 || r.code == 1 || r.code == 2) return "";
      if (r.code == 125 || r.code == 126) return "not started (exit " + std::to_string(r.code) + ")";
      return "exit " + std::to_string(r.code);
    case RunResult::End::kSignal:
      return "crash: signal " + std::to_string(r.code) + " (" + strsignal(r.code) + ")";
    case RunResult::End::kTimeout: {
      char buf[64];
      std::snprintf(buf, sizeof buf, "hang: killed after %g s", limits.timeout_s);
      return buf;
    }
    case RunResult::End::kNotStarted:
      break;
  }
  return "not started (fork failed)";
}

}  // namespace kuavo::fuzz
