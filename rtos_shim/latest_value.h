// Latest-value buffer (triple buffer): hands a large POD -- e.g. the MPC solution,
// tens of KB -- from one writer thread to one reader thread without tearing,
// locks or allocation. Wait-free on both sides; each publish and each read costs
// at most the one copy the writer makes into its back buffer.
//
// Three slots: the writer owns `back`, the reader owns `front`, and `middle` is
// exchanged atomically with a "fresh" bit. publish_rt() swaps back <-> middle
// and sets the bit; update_rt() swaps front <-> middle if the bit is set. The
// exchanges are acq_rel: the writer's filling of a slot happens-before the
// reader sees it, and the reader's use of its old front happens-before the
// writer refills it. A slow reader skips intermediate values (latest wins),
// never sees a half-written one.
//
// Exactly one writer thread and one reader thread. 3 * sizeof(T) of storage,
// inside the object: put big instances in static storage, not on a stack.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <type_traits>

#include "rtos_shim/spsc_ring.h"  // kCacheLineBytes

namespace kuavo::rtos {

template <class T>
class LatestValue {
  static_assert(std::is_nothrow_copy_assignable_v<T> && std::is_nothrow_default_constructible_v<T>,
                "values are copied in the real-time path, which must not throw");

 public:
  // --- Writer side ---

  // The slot the writer fills in place (no extra copy); invisible to the reader
  // until publish_rt(). The reference is valid until the next publish_rt().
  [[nodiscard]] T& back_rt() noexcept { return slots_[back_].value; }

  // Makes the back slot the latest value. Real-time safe.
  void publish_rt() noexcept {
    const std::uint8_t old_middle =
        middle_.exchange(static_cast<std::uint8_t>(back_ | kFreshBit), std::memory_order_acq_rel);
    back_ = old_middle & kIndexMask;
  }

  // Copy-in convenience: back_rt() = value; publish_rt().
  void publish_rt(const T& value) noexcept {
    back_rt() = value;
    publish_rt();
  }

  // --- Reader side ---

  // Takes the latest published value if there is one newer than front_rt().
  // Returns true if front_rt() changed. Real-time safe.
  bool update_rt() noexcept {
    if ((middle_.load(std::memory_order_relaxed) & kFreshBit) == 0) return false;
    const std::uint8_t old_middle = middle_.exchange(front_, std::memory_order_acq_rel);
    front_ = old_middle & kIndexMask;
    ++reads_taken_;
    return true;
  }

  // The value taken by the last successful update_rt(); a default-constructed T
  // before the first one. Valid until the next update_rt().
  [[nodiscard]] const T& front_rt() const noexcept { return slots_[front_].value; }

  // True once the reader has taken at least one published value.
  [[nodiscard]] bool has_value() const noexcept { return reads_taken_ != 0; }

 private:
  static constexpr std::uint8_t kIndexMask = 0x3;
  static constexpr std::uint8_t kFreshBit = 0x4;

  struct alignas(kCacheLineBytes) Slot {
    T value{};
  };

  std::array<Slot, 3> slots_{};
  alignas(kCacheLineBytes) std::uint8_t back_ = 0;       // writer-owned
  alignas(kCacheLineBytes) std::uint8_t front_ = 1;      // reader-owned
  std::uint64_t reads_taken_ = 0;                        // reader-owned
  alignas(kCacheLineBytes) std::atomic<std::uint8_t> middle_{2};  // shared

  static_assert(std::atomic<std::uint8_t>::is_always_lock_free);
};

}  // namespace kuavo::rtos
