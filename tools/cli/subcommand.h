// Running one `kuavo` command from another (kuavo demo and kuavo paper are made of them).
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

namespace kuavo::cli {

// run(argv) with args as argv (args[0] is the command's name).
inline int call_command(int (*run)(int, char**), std::vector<std::string> args) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  return run(static_cast<int>(args.size()), argv.data());
}

// The sub-commands' own lines go to /dev/null for the scope (--quiet, or under a progress
// line); stderr, where errors go, stays.
class MuteStdout {
 public:
  explicit MuteStdout(bool mute) {
    if (!mute) return;
    std::fflush(stdout);
    saved_ = ::dup(STDOUT_FILENO);
    const int null = ::open("/dev/null", O_WRONLY);
    if (saved_ >= 0 && null >= 0) ::dup2(null, STDOUT_FILENO);
    if (null >= 0) ::close(null);
  }
  ~MuteStdout() {
    if (saved_ < 0) return;
    std::fflush(stdout);
    ::dup2(saved_, STDOUT_FILENO);
    ::close(saved_);
  }
  MuteStdout(const MuteStdout&) = delete;
  MuteStdout& operator=(const MuteStdout&) = delete;

 private:
  int saved_ = -1;
};

}  // namespace kuavo::cli
