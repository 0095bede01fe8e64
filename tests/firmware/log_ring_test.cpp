// The log path: records pushed from the cycle, formatted by the writer
// thread; a full ring drops and counts instead of blocking.
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <string>

#include "firmware/log_ring.h"

namespace kuavo::firmware {
namespace {

std::string read_all(std::FILE* f) {
  std::rewind(f);
  std::string s;
  char buf[256];
  while (std::fgets(buf, sizeof buf, f) != nullptr) s += buf;
  return s;
}

TEST(LogRing, WriterThreadFormatsRecords) {
  auto sink = std::make_unique<LogSink>();
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  LogWriter writer;
  writer.start(*sink, f);
  log_rt(*sink, LogRecord{1'500'000'000, LogKind::kFault, Mode::kReady, Fault::kBusOff, -1, 0.0});
  log_rt(*sink, LogRecord{1'500'000'000, LogKind::kModeChange, Mode::kDamping, Fault::kBusOff, -1, 0.0});
  writer.stop();  // drains what is left
  const std::string text = read_all(f);
  std::fclose(f);
  EXPECT_NE(text.find("1.5000 FAULT 13: CAN bus-off (joint -1) in ready"), std::string::npos) << text;
  EXPECT_NE(text.find("1.5000 mode damping (fault 13: CAN bus-off)"), std::string::npos) << text;
}

TEST(LogRing, FullRingDropsAndCounts) {
  auto sink = std::make_unique<LogSink>();
  for (std::size_t i = 0; i < LogRing::capacity() + 10; ++i) log_rt(*sink, LogRecord{});
  EXPECT_EQ(sink->dropped.load(), 10u);
  EXPECT_EQ(LogWriter::drain(*sink, nullptr), static_cast<int>(LogRing::capacity()));
}

}  // namespace
}  // namespace kuavo::firmware
