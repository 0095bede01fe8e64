#include "rtos_shim/latest_value.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <thread>

#include "tests/support/alloc_trap.h"

namespace kuavo::rtos {
namespace {

// 32 KiB, like an MPC solution: sequence number, body derived from it, checksum.
struct Payload {
  static constexpr int kWords = 4094;
  std::uint64_t seq = 0;
  std::uint64_t words[kWords] = {};
  std::uint64_t checksum = 0;
};
static_assert(sizeof(Payload) == 32 * 1024);

constexpr std::uint64_t word_for(std::uint64_t seq, int i) {
  return (seq + 1) * 0x9E3779B97F4A7C15ull ^ static_cast<std::uint64_t>(i) * 0xBF58476D1CE4E5B9ull;
}

void fill(Payload& p, std::uint64_t seq) {
  p.seq = seq;
  std::uint64_t sum = seq;
  for (int i = 0; i < Payload::kWords; ++i) {
    p.words[i] = word_for(seq, i);
    sum += p.words[i];
  }
  p.checksum = sum;
}

// True if every word belongs to the same write: a torn read mixes two sequences.
bool consistent(const Payload& p) {
  std::uint64_t sum = p.seq;
  for (int i = 0; i < Payload::kWords; ++i) {
    if (p.words[i] != word_for(p.seq, i)) return false;
    sum += p.words[i];
  }
  return sum == p.checksum;
}

TEST(RtosLatestValue, ChecksumDetectsAMixedPayload) {
  // Guards the tearing test below: the checker must reject a half-updated value.
  static Payload p;
  fill(p, 7);
  EXPECT_TRUE(consistent(p));
  p.words[100] = word_for(8, 100);
  EXPECT_FALSE(consistent(p));
}

TEST(RtosLatestValue, ReaderSeesOnlyTheLatestPublishedValue) {
  static LatestValue<Payload> buffer;
  EXPECT_FALSE(buffer.update_rt());
  EXPECT_FALSE(buffer.has_value());
  EXPECT_EQ(buffer.front_rt().seq, 0u);

  fill(buffer.back_rt(), 1);
  buffer.publish_rt();
  ASSERT_TRUE(buffer.update_rt());
  EXPECT_TRUE(buffer.has_value());
  EXPECT_EQ(buffer.front_rt().seq, 1u);
  EXPECT_FALSE(buffer.update_rt()) << "nothing new was published";
  EXPECT_EQ(buffer.front_rt().seq, 1u) << "front stays valid without a new value";

  for (std::uint64_t seq = 2; seq <= 5; ++seq) {
    fill(buffer.back_rt(), seq);
    buffer.publish_rt();
  }
  ASSERT_TRUE(buffer.update_rt());
  EXPECT_EQ(buffer.front_rt().seq, 5u) << "latest wins, intermediate values are skipped";
  EXPECT_TRUE(consistent(buffer.front_rt()));
}

TEST(RtosLatestValue, CopyInPublish) {
  static LatestValue<Payload> buffer;
  static Payload p;
  fill(p, 3);
  buffer.publish_rt(p);
  ASSERT_TRUE(buffer.update_rt());
  EXPECT_EQ(buffer.front_rt().seq, 3u);
  EXPECT_TRUE(consistent(buffer.front_rt()));
}

LatestValue<Payload> g_buffer;  // static storage: 3 x 32 KiB is too big for a stack

TEST(RtosLatestValue, NeverTearsUnderConcurrentWriterAndReader) {
  constexpr std::uint64_t kPublishes = 20'000;
  std::atomic<bool> writer_done{false};
  std::size_t writer_allocations = 1;
  std::thread writer([&] {
    kuavo::test::AllocTrap trap;
    for (std::uint64_t seq = 1; seq <= kPublishes; ++seq) {
      fill(g_buffer.back_rt(), seq);
      g_buffer.publish_rt();
      if (seq % 64 == 0) std::this_thread::yield();  // interleave on a busy 2-core box
    }
    writer_allocations = trap.count();
    writer_done.store(true, std::memory_order_release);
  });

  std::uint64_t reads = 0;
  std::uint64_t torn = 0;
  std::uint64_t went_back = 0;
  std::uint64_t last_seq = 0;
  std::size_t reader_allocations = 0;
  {
    kuavo::test::AllocTrap trap;
    for (;;) {
      const bool done = writer_done.load(std::memory_order_acquire);
      if (g_buffer.update_rt()) {
        const Payload& p = g_buffer.front_rt();
        ++reads;
        if (!consistent(p)) ++torn;
        if (p.seq <= last_seq) ++went_back;
        last_seq = p.seq;
      }
      // Once the writer is done, the update above must have delivered its last value.
      if (done) break;
    }
    reader_allocations = trap.count();
  }
  writer.join();

  EXPECT_EQ(torn, 0u) << "reader saw a mixed payload";
  EXPECT_EQ(went_back, 0u) << "a fresh read returned an older or repeated value";
  EXPECT_GE(reads, 1u);
  EXPECT_EQ(last_seq, kPublishes);
  EXPECT_EQ(writer_allocations, 0u);
  EXPECT_EQ(reader_allocations, 0u);
  RecordProperty("fresh_reads", static_cast<int>(reads));
}

}  // namespace
}  // namespace kuavo::rtos
