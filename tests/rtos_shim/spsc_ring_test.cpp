#include "rtos_shim/spsc_ring.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <thread>

#include "tests/support/alloc_trap.h"

namespace kuavo::rtos {
namespace {

// Item with a redundant field, so a slot read while being written (or a stale
// slot) shows up as a mismatch, not just as a wrong sequence number.
struct Item {
  std::uint64_t seq = 0;
  std::uint64_t check = 0;
};
constexpr std::uint64_t kCheckKey = 0x9E3779B97F4A7C15ull;
Item make_item(std::uint64_t seq) { return {seq, ~seq * kCheckKey}; }

TEST(RtosSpscRing, EmptyAndFullBehaviour) {
  SpscRing<int, 8> ring;
  int out = -1;
  EXPECT_FALSE(ring.try_pop_rt(out));
  EXPECT_EQ(out, -1);  // untouched on failure
  for (int i = 0; i < 8; ++i) ASSERT_TRUE(ring.try_push_rt(i)) << i;
  EXPECT_EQ(ring.size_approx(), 8u);
  EXPECT_FALSE(ring.try_push_rt(99)) << "all 8 slots are in use";
  for (int i = 0; i < 8; ++i) {
    ASSERT_TRUE(ring.try_pop_rt(out));
    EXPECT_EQ(out, i);
  }
  EXPECT_FALSE(ring.try_pop_rt(out));
  EXPECT_EQ(ring.size_approx(), 0u);
  // Space freed by pops is usable again.
  EXPECT_TRUE(ring.try_push_rt(42));
  ASSERT_TRUE(ring.try_pop_rt(out));
  EXPECT_EQ(out, 42);
}

TEST(RtosSpscRing, WrapsAroundManyTimesInOrder) {
  SpscRing<std::uint64_t, 4> ring;
  std::uint64_t next_in = 0;
  std::uint64_t next_out = 0;
  for (int round = 0; round < 1000; ++round) {
    const int n = 1 + round % 4;  // uneven batches so the indices wrap at every offset
    for (int i = 0; i < n; ++i) ASSERT_TRUE(ring.try_push_rt(next_in++));
    for (int i = 0; i < n; ++i) {
      std::uint64_t out = 0;
      ASSERT_TRUE(ring.try_pop_rt(out));
      ASSERT_EQ(out, next_out++);
    }
  }
}

// Static storage, as the firmware uses it.
SpscRing<Item, 1024> g_ring;

TEST(RtosSpscRing, ProducerAndConsumerThreadsLoseAndDuplicateNothing) {
  constexpr std::uint64_t kItems = 1u << 20;  // ~1e6
  std::uint64_t producer_allocations = 1;
  std::thread producer([&] {
    kuavo::test::AllocTrap trap;
    for (std::uint64_t seq = 0; seq < kItems;) {
      if (g_ring.try_push_rt(make_item(seq))) {
        ++seq;
      } else {
        std::this_thread::yield();  // two cores shared with compilers: let the consumer run
      }
    }
    producer_allocations = trap.count();
  });

  std::uint64_t expected = 0;
  std::uint64_t bad_order = 0;
  std::uint64_t bad_check = 0;
  std::size_t consumer_allocations = 0;
  {
    kuavo::test::AllocTrap trap;
    Item item;
    while (expected < kItems) {
      if (!g_ring.try_pop_rt(item)) {
        std::this_thread::yield();
        continue;
      }
      if (item.seq != expected) ++bad_order;
      if (item.check != make_item(item.seq).check) ++bad_check;
      expected = item.seq + 1;
    }
    consumer_allocations = trap.count();
  }
  producer.join();

  EXPECT_EQ(bad_order, 0u) << "items lost, duplicated or reordered";
  EXPECT_EQ(bad_check, 0u) << "torn or stale slot contents";
  EXPECT_EQ(expected, kItems);
  Item extra;
  EXPECT_FALSE(g_ring.try_pop_rt(extra)) << "more items than were pushed";
  EXPECT_EQ(producer_allocations, 0u);
  EXPECT_EQ(consumer_allocations, 0u);
}

}  // namespace
}  // namespace kuavo::rtos
