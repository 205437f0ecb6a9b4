//! @file
//! LatestValue<T>: a lock-free, allocation-free single-producer / single-consumer hand-off of the
//! newest value (a triple buffer). The producer never waits for the consumer and the consumer
//! never waits for the producer; the consumer always reads a whole value written by one `publish`.
//! Used to hand a middleware's newest stylus sample to the real-time tick (docs/ros.md).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <type_traits>

namespace endohaptics::teleop {

//! Newest-value hand-off between exactly one producer thread and one consumer thread. `T` is
//! copied whole by assignment, which must not throw or allocate (fixed-size values: numbers,
//! fixed-size Eigen vectors, arrays).
template <typename T>
class LatestValue {
  // Eigen's fixed-size types are not noexcept-assignable by declaration, though they never throw.
  static_assert(std::is_copy_assignable_v<T> && std::is_default_constructible_v<T>,
                "LatestValue<T>: T must be default-constructible and copy-assignable");

 public:
  //! Producer side: makes `value` the newest. Wait-free, noexcept, no allocation.
  void publish(const T& value) noexcept {
    slots_[back_] = value;
    // Swap the written slot into the middle, marking it fresh; take the old middle as our next
    // back slot (the consumer never touches it until it swaps it out again).
    const std::uint8_t previous =
        middle_.exchange(static_cast<std::uint8_t>(back_ | fresh_bit), std::memory_order_acq_rel);
    back_ = static_cast<std::uint8_t>(previous & index_mask);
    published_.fetch_add(1, std::memory_order_relaxed);
  }

  //! Consumer side: copies the newest value into `out`. Returns false (and leaves `out` alone)
  //! when nothing was ever published. `fresh` (optional) is set to whether it was published since
  //! the previous successful read. Wait-free, noexcept, no allocation.
  [[nodiscard]] bool read(T& out, bool* fresh = nullptr) noexcept {
    const bool is_fresh = (middle_.load(std::memory_order_relaxed) & fresh_bit) != 0;
    if (is_fresh) {
      const std::uint8_t previous = middle_.exchange(front_, std::memory_order_acq_rel);
      front_ = static_cast<std::uint8_t>(previous & index_mask);
      have_ = true;
    }
    if (fresh != nullptr) *fresh = is_fresh;
    if (!have_) return false;
    out = slots_[front_];
    return true;
  }

  //! Values published so far (any thread may read it).
  [[nodiscard]] std::uint64_t published() const noexcept {
    return published_.load(std::memory_order_relaxed);
  }

 private:
  static constexpr std::uint8_t fresh_bit = 0x4;
  static constexpr std::uint8_t index_mask = 0x3;

  std::array<T, 3> slots_{};
  // Slot indices: back_ is the producer's, front_ the consumer's, middle_ the one in between
  // (with fresh_bit when the producer put it there after the consumer's last swap).
  alignas(64) std::uint8_t back_ = 0;
  alignas(64) std::atomic<std::uint8_t> middle_{1};
  alignas(64) std::uint8_t front_ = 2;
  bool have_ = false;
  std::atomic<std::uint64_t> published_{0};
};

}  // namespace endohaptics::teleop
