// Lock-free single-producer / single-consumer ring of fixed capacity, for log
// records and frames passed between a real-time thread and a non-real-time one.
// Heap-free: the slots live inside the object, so a ring can sit in static storage.
//
// Exactly one thread may push and exactly one thread may pop. Indices run freely
// (wrap at 2^64, i.e. never) and are masked into the slot array; all Capacity
// slots are usable. The producer publishes a slot with a release store of head_,
// the consumer frees it with a release store of tail_; each side reads the
// other's index with acquire. Each side keeps a cached copy of the other's index
// so the shared cache line is only touched when the ring looks full / empty.
#pragma once

#include <array>
#include <atomic>
#include <bit>
#include <cstddef>
#include <new>
#include <type_traits>

namespace kuavo::rtos {

// Typical x86-64 cache line; a named constant because
// std::hardware_destructive_interference_size warns under GCC (-Winterference-size).
inline constexpr std::size_t kCacheLineBytes = 64;

template <class T, std::size_t Capacity>
class SpscRing {
  static_assert(Capacity >= 2 && std::has_single_bit(Capacity), "capacity must be a power of two");
  static_assert(std::is_nothrow_copy_assignable_v<T> && std::is_nothrow_default_constructible_v<T>,
                "slots are copied in and out in the real-time path, which must not throw");

 public:
  static constexpr std::size_t kCapacity = Capacity;

  // Producer side. Returns false (item not stored) when the ring is full; the
  // caller decides whether to drop and count. Real-time safe.
  bool try_push_rt(const T& item) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);  // only we write it
    if (head - tail_cache_ == Capacity) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head - tail_cache_ == Capacity) return false;
    }
    slots_[head & kMask] = item;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  // Consumer side. Returns false (out untouched) when the ring is empty. Real-time safe.
  bool try_pop_rt(T& out) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);  // only we write it
    if (tail == head_cache_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail == head_cache_) return false;
    }
    out = slots_[tail & kMask];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  // Items in the ring as seen at some instant during the call; exact only when
  // neither side is running. For monitoring, not for flow control.
  [[nodiscard]] std::size_t size_approx() const noexcept {
    const std::size_t tail = tail_.load(std::memory_order_acquire);
    const std::size_t head = head_.load(std::memory_order_acquire);
    return head - tail;
  }

  [[nodiscard]] static constexpr std::size_t capacity() noexcept { return Capacity; }

 private:
  static constexpr std::size_t kMask = Capacity - 1;

  // Producer-owned line: head_ is written here, tail_cache_ is private to the producer.
  alignas(kCacheLineBytes) std::atomic<std::size_t> head_{0};
  std::size_t tail_cache_ = 0;
  // Consumer-owned line.
  alignas(kCacheLineBytes) std::atomic<std::size_t> tail_{0};
  std::size_t head_cache_ = 0;
  alignas(kCacheLineBytes) std::array<T, Capacity> slots_{};

  static_assert(std::atomic<std::size_t>::is_always_lock_free);
};

}  // namespace kuavo::rtos
