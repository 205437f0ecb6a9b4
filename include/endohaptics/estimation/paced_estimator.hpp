//! @file
//! PacedEstimator: runs a fixed-period JointForceEstimator (ForceEstimator: models discretised at
//! a fixed loop period, worksheet 4.4) from a loop whose ticks are not at that period: `--rate
//! max` (faster), lost packets (late). Steps the wrapped estimator once per elapsed period of the
//! clock with the newest signals (sample and hold), bounded catch-up. Times in ns.
#pragma once

#include <chrono>
#include <cstdint>

#include "endohaptics/core/clock.hpp"
#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/joint_force_estimator.hpp"

namespace endohaptics::estimation {

//! What the pacing did so far (for statistics; all monotonic).
struct PacingCounters {
  std::uint64_t calls = 0;     //!< estimate() calls from the loop
  std::uint64_t steps = 0;     //!< steps of the wrapped estimator
  std::uint64_t held = 0;      //!< calls that only returned the held force (period not over)
  std::uint64_t skipped = 0;   //!< periods dropped because the loop was more than max_catch_up late
  std::uint64_t rejected = 0;  //!< steps the wrapped estimator refused
};

//! Satisfies JointForceEstimator. `Estimator` must be stepped every `period` (e.g. a
//! ForceEstimator with settings.loop_period = period). Each call steps it floor(elapsed/period)
//! times (at most `max_catch_up`; older periods are dropped and counted, the model then runs
//! behind real time by that much) with the newest measured state, and returns the newest force.
template <JointForceEstimator Estimator, endohaptics::Clock ClockT = endohaptics::SteadyClock>
class PacedEstimator {
 public:
  //! One value per EndoWrist motor, in motor order.
  using MotorVector = estimation::MotorVector;

  //! Precondition: period > 0, max_catch_up >= 1. `estimator` and `clock` must outlive this.
  PacedEstimator(Estimator& estimator, ClockT& clock, std::chrono::nanoseconds period,
                 int max_catch_up = 20) noexcept
      : estimator_(&estimator), clock_(&clock), period_(period), max_catch_up_(max_catch_up) {
    ENDOHAPTICS_ASSERT(period.count() > 0 && max_catch_up >= 1);
  }

  //! JointForceEstimator: true when `force` holds a finite estimate (fresh or held).
  bool estimate(const MotorState4& measured, const MotorVector& setpoint,
                MotorVector& force) noexcept {
    ++counters_.calls;
    const auto now = clock_->now();
    if (!started_) {  // the first call steps once and starts the period grid here
      started_ = true;
      next_due_ = now;
    }
    std::int64_t due = now >= next_due_ ? (now - next_due_) / period_ + 1 : 0;
    if (due > max_catch_up_) {
      counters_.skipped += static_cast<std::uint64_t>(due - max_catch_up_);
      next_due_ += period_ * (due - max_catch_up_);
      due = max_catch_up_;
    }
    if (due == 0) {
      ++counters_.held;
      force = held_;
      return have_force_;
    }
    for (std::int64_t i = 0; i < due; ++i) {
      MotorVector f;
      ++counters_.steps;
      if (estimator_->estimate(measured, setpoint, f)) {
        held_ = f;
        have_force_ = true;
      } else {
        ++counters_.rejected;
        have_force_ = false;
      }
    }
    next_due_ += period_ * due;
    force = held_;
    return have_force_;
  }

  //! Resets the wrapped estimator and the period grid (TeleopLoop calls this on (re)connection).
  void reset() noexcept {
    estimator_->reset();
    started_ = false;
    have_force_ = false;
    held_.setZero();
  }

  //! What the pacing did since construction.
  [[nodiscard]] const PacingCounters& counters() const noexcept { return counters_; }
  //! The fixed-period estimator being paced.
  [[nodiscard]] Estimator& wrapped() noexcept { return *estimator_; }
  //! The wrapped estimator's step period (ns).
  [[nodiscard]] std::chrono::nanoseconds period() const noexcept { return period_; }

 private:
  Estimator* estimator_;
  ClockT* clock_;
  std::chrono::nanoseconds period_;
  int max_catch_up_;
  bool started_ = false;
  bool have_force_ = false;
  std::chrono::nanoseconds next_due_{0};
  MotorVector held_ = MotorVector::Zero();
  PacingCounters counters_{};
};

}  // namespace endohaptics::estimation
