//! @file
//! The `Clock` concept the TeleopLoop paces itself with, injectable so tests are deterministic:
//! `SteadyClock` (std::chrono::steady_clock, absolute-deadline sleeps) and `ManualClock`
//! (simulated time that advances only when told or when "sleeping"). Times in nanoseconds.
#pragma once

#include <time.h>

#include <cerrno>
#include <chrono>
#include <concepts>

namespace endohaptics {

//! now() is monotonic; sleep_until(t) returns at or after t (never early, except on a stop).
template <typename C>
concept Clock = requires(C& clock, std::chrono::nanoseconds t) {
  { clock.now() }
  noexcept->std::same_as<std::chrono::nanoseconds>;
  { clock.sleep_until(t) }
  noexcept;
};

//! The monotonic system clock; sleeps with clock_nanosleep(TIMER_ABSTIME), so pacing uses
//! absolute deadlines and never accumulates drift.
struct SteadyClock {
  //! Current CLOCK_MONOTONIC time (ns since an unspecified epoch).
  std::chrono::nanoseconds now() const noexcept {
    timespec ts{};
    ::clock_gettime(CLOCK_MONOTONIC, &ts);
    return std::chrono::seconds(ts.tv_sec) + std::chrono::nanoseconds(ts.tv_nsec);
  }
  //! Sleeps until the absolute monotonic time `t` (ns); retries when interrupted by a signal.
  void sleep_until(std::chrono::nanoseconds t) const noexcept {
    const auto s = std::chrono::duration_cast<std::chrono::seconds>(t);
    timespec ts{static_cast<time_t>(s.count()), static_cast<long>((t - s).count())};
    while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
  }
};

//! Simulated time for tests: starts at `start`, moves only by advance() or sleep_until().
class ManualClock {
 public:
  //! Starts the simulated time at `start` (ns).
  explicit ManualClock(std::chrono::nanoseconds start = std::chrono::nanoseconds(0)) noexcept
      : now_(start) {}
  //! Current simulated time (ns).
  std::chrono::nanoseconds now() const noexcept { return now_; }
  //! Jumps to `t` (ns) if that is later than now; never moves backwards.
  void sleep_until(std::chrono::nanoseconds t) noexcept {
    if (t > now_) now_ = t;
  }
  //! Moves the simulated time forward by `d` (ns).
  void advance(std::chrono::nanoseconds d) noexcept { now_ += d; }

 private:
  std::chrono::nanoseconds now_;
};

static_assert(Clock<SteadyClock>);
static_assert(Clock<ManualClock>);

}  // namespace endohaptics
