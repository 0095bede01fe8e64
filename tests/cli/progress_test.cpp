// The progress line: drawn on a terminal (a pseudo-terminal here) with percent and time left,
// nothing on a pipe, nothing with --quiet.
#include "tools/cli/progress.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <pty.h>
#include <unistd.h>

#include <string>

namespace kuavo::cli {
namespace {

// stderr pointed at `fd` for the scope (and back after).
class StderrTo {
 public:
  explicit StderrTo(int fd) : saved_(::dup(STDERR_FILENO)) { ::dup2(fd, STDERR_FILENO); }
  ~StderrTo() {
    std::fflush(stderr);
    ::dup2(saved_, STDERR_FILENO);
    ::close(saved_);
  }

 private:
  int saved_;
};

std::string drain(int fd) {
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
  std::string s;
  char buf[4096];
  for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) s.append(buf, static_cast<std::size_t>(n));
  return s;
}

// Enough work that the estimate shows, with a measurable elapsed time before it.
void run_some(Progress& p) {
  p.set_total(10.0);
  p.update(0.0, "starting");
  ::usleep(20'000);
  p.update(5.0, "half way");
}

TEST(Progress, DrawsPercentAndTimeLeftOnATerminal) {
  int master = -1, slave = -1;
  ASSERT_EQ(::openpty(&master, &slave, nullptr, nullptr, nullptr), 0);
  std::string text;
  {
    StderrTo redirect(slave);
    Progress p(false);
    EXPECT_TRUE(p.shown());
    run_some(p);
    p.clear();
  }
  text = drain(master);
  ::close(master);
  ::close(slave);
  EXPECT_NE(text.find("[ 50%] half way"), std::string::npos) << text;
  EXPECT_NE(text.find("left"), std::string::npos) << text;
  EXPECT_NE(text.find("[  0%] starting"), std::string::npos) << text;
}

TEST(Progress, SilentOnAPipeAndWhenQuiet) {
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  {
    StderrTo redirect(fds[1]);
    Progress piped(false);
    EXPECT_FALSE(piped.shown());
    run_some(piped);
  }
  EXPECT_EQ(drain(fds[0]), "");
  ::close(fds[0]);
  ::close(fds[1]);
  int master = -1, slave = -1;
  ASSERT_EQ(::openpty(&master, &slave, nullptr, nullptr, nullptr), 0);
  {
    StderrTo redirect(slave);
    Progress quiet(true);
    EXPECT_FALSE(quiet.shown());
    run_some(quiet);
  }
  EXPECT_EQ(drain(master), "");
  ::close(master);
  ::close(slave);
}

TEST(Progress, FormatsDurations) {
  EXPECT_EQ(format_duration(0.4), "0 s");
  EXPECT_EQ(format_duration(59.4), "59 s");
  EXPECT_EQ(format_duration(65.0), "1 min 05 s");
  EXPECT_EQ(format_duration(-3.0), "0 s");
}

}  // namespace
}  // namespace kuavo::cli
