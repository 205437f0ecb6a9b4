//! @file
//! Rate policies of ForceEstimator: how a model identified at Ts (appendix C: 0.02 s) runs in a
//! loop of period T (1 ms): rate::SameRate, rate::Decimate (window means, R = Ts / T) or
//! rate::Resample (ZOH resampling of eqs. 4.1/4.2 at T), and the RatePolicyFor concept. Times in s.
#pragma once

#include <algorithm>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/joint_force_model.hpp"
#include "endohaptics/model/state_space.hpp"

namespace endohaptics::estimation {

namespace detail::force {

//! Tolerance for "ratio of sample times is an integer": 1e-9, or a few ulps of Scalar when that
//! is coarser (0.02f / 0.001f = 19.9999986).
template <typename Scalar>
double ratio_tolerance(double ratio) noexcept {
  return std::max(1e-9, 16.0 * static_cast<double>(std::numeric_limits<Scalar>::epsilon()) *
                            std::max(1.0, std::abs(ratio)));
}

enum class RateMode : std::uint8_t { same, decimate, resample };

template <typename Scalar>
JointSignals<Scalar> operator+(const JointSignals<Scalar>& a, const JointSignals<Scalar>& b) {
  return {a.position + b.position, a.velocity + b.velocity, a.current + b.current,
          a.setpoint + b.setpoint};
}

//! Runs one joint model at the loop period according to the rate mode.
template <JointForceModel M, RateMode Mode>
requires(Mode != RateMode::resample || ResamplableJointForceModel<M>) class RateStepper {
 public:
  using Scalar = typename M::ScalarType;
  using Signals = JointSignals<Scalar>;
  //! Everything a tick may change.
  struct Snapshot {
    typename M::State state;
    Signals sum;
    int count;
  };

  //! Throws Error when the model cannot run at `loop_period` under this mode; `joint` names it.
  RateStepper(const M& model, Scalar loop_period, std::string_view joint)
      : model_(prepare(model, loop_period, joint)),
        ratio_(ticks_per_step(model, loop_period, joint)),
        memoryless_(model.memoryless()) {}

  [[nodiscard]] const M& model() const noexcept { return model_; }
  //! Loop ticks per model step (1 unless decimating).
  [[nodiscard]] int ratio() const noexcept { return ratio_; }

  //! Writes the force at the current state (feedthrough from `s`), then advances the model if a
  //! model period ends with this tick (decimation: with the mean of the window's signals).
  //! A memoryless model is never advanced (its state cannot reach the output). On anything but
  //! ok the caller restores a snapshot.
  [[nodiscard]] model::NumericStatus tick(const Signals& s, Scalar& force) noexcept {
    force = model_.force(s);
    if (memoryless_) return model::NumericStatus::ok;
    if constexpr (Mode == RateMode::decimate) {
      if (ratio_ > 1) {
        sum_ = sum_ + s;
        // Huge finite signals can overflow the window sum: refuse the tick, never keep an Inf.
        if (!std::isfinite(sum_.position) || !std::isfinite(sum_.velocity) ||
            !std::isfinite(sum_.current) || !std::isfinite(sum_.setpoint)) {
          return model::NumericStatus::non_finite_result;
        }
        if (++count_ < ratio_) return model::NumericStatus::ok;
        const Scalar inv = Scalar(1) / static_cast<Scalar>(ratio_);
        const Signals mean{sum_.position * inv, sum_.velocity * inv, sum_.current * inv,
                           sum_.setpoint * inv};
        sum_ = Signals{};
        count_ = 0;
        return model_.advance(mean);
      }
    }
    return model_.advance(s);
  }

  [[nodiscard]] Snapshot snapshot() const noexcept { return {model_.state(), sum_, count_}; }
  void restore(const Snapshot& saved) noexcept {
    model_.reset(saved.state);
    sum_ = saved.sum;
    count_ = saved.count;
  }
  //! The model's start state, empty decimation window. The start state is the model's own
  //! `reset()` when it has one (PushLoadObserver starts from its initial load and variance,
  //! not from zero), else the zero state.
  void reset() noexcept {
    if constexpr (requires(M & m) {
                    { m.reset() }
                    noexcept;
                  }) {
      model_.reset();
    } else {
      model_.reset(typename M::State(M::State::Zero()));
    }
    sum_ = Signals{};
    count_ = 0;
  }

 private:
  static M prepare(const M& model, Scalar loop_period, std::string_view joint) {
    model::detail::require_sample_time(loop_period, "ForceEstimator loop period");
    (void)joint;
    if constexpr (Mode == RateMode::resample) {
      const double ratio = static_cast<double>(model.sample_time()) / loop_period;
      if (model.memoryless() || std::abs(ratio - 1.0) <= ratio_tolerance<Scalar>(ratio)) {
        return model;
      }
#if defined(__cpp_exceptions)
      try {
        return model.resampled(loop_period);
      } catch (const Error& error) {
        ENDOHAPTICS_THROW(Error("ForceEstimator (rate::Resample): the " + std::string(joint) +
                                " model cannot be resampled at " +
                                endohaptics::detail::format_number(loop_period) +
                                " s: " + error.what()));
      }
#else
      return model.resampled(loop_period);
#endif
    } else {
      return model;
    }
  }

  static int ticks_per_step(const M& model, Scalar loop_period, std::string_view joint) {
    if (model.memoryless() || Mode == RateMode::resample) return 1;
    const double ratio = static_cast<double>(model.sample_time()) / loop_period;
    const auto nearest = static_cast<long long>(std::llround(ratio));
    // At most a million ticks per model step (keeps the count an int).
    const bool integer =
        nearest >= 1 && nearest <= 1000000 &&
        std::abs(ratio - static_cast<double>(nearest)) <= ratio_tolerance<Scalar>(ratio);
    const std::string where = "ForceEstimator: the " + std::string(joint) +
                              " model's sample time " +
                              endohaptics::detail::format_number(model.sample_time()) + " s";
    if constexpr (Mode == RateMode::same) {
      if (!integer || nearest != 1) {
        ENDOHAPTICS_THROW(Error(where + " differs from the loop period " +
                                endohaptics::detail::format_number(loop_period) + " s (ratio " +
                                endohaptics::detail::format_number(ratio) +
                                "); choose a rate policy: rate::Decimate or rate::Resample"));
      }
    } else {
      if (!integer) {
        ENDOHAPTICS_THROW(Error(where + " is not an integer multiple of the loop period " +
                                endohaptics::detail::format_number(loop_period) + " s (ratio " +
                                endohaptics::detail::format_number(ratio) +
                                ", tolerance 1e-9); rate::Decimate needs one, use "
                                "rate::Resample or change the loop period"));
      }
    }
    return static_cast<int>(nearest);
  }

  M model_;
  int ratio_;
  bool memoryless_;
  Signals sum_{};
  int count_ = 0;
};

}  // namespace detail::force

//! Rate policies for ForceEstimator.
namespace rate {

//! No conversion: every dynamic model's sample time must equal the loop period (ratio 1 within
//! 1e-9), else the constructor throws Error. Memoryless models (y = D u) run at any period.
struct SameRate {
  //! Runs `M` at its own sample time, one step per loop tick.
  template <JointForceModel M>
  using Stepper = detail::force::RateStepper<M, detail::force::RateMode::same>;
};

//! Decimation: model Ts must be an integer multiple R of the loop period (within 1e-9, else
//! Error). The signals are averaged over R ticks and the model is stepped once per window; the
//! output between steps uses the held state (added latency: 0 to R - 1 ticks, see docs).
struct Decimate {
  //! Runs `M` once per R loop ticks on the window's mean signals.
  template <JointForceModel M>
  using Stepper = detail::force::RateStepper<M, detail::force::RateMode::decimate>;
};

//! Resampling: each model is converted to continuous time (matrix logarithm) and rediscretised
//! with ZOH at the loop period, then stepped every tick. Error if a model's A is singular or has
//! an eigenvalue on the closed negative real axis (the appendix C pitch model has -0.095).
struct Resample {
  //! Runs `M` resampled (ZOH) at the loop period, one step per tick.
  template <JointForceModel M>
  requires ResamplableJointForceModel<M>
  using Stepper = detail::force::RateStepper<M, detail::force::RateMode::resample>;
};

}  // namespace rate

//! `Rate` can run the joint model `M`: `Rate::Stepper<M>` exists and ticks without throwing.
template <typename Rate, typename M>
concept RatePolicyFor = JointForceModel<M> &&
    requires(typename Rate::template Stepper<M>& stepper,
             const JointSignals<typename M::ScalarType>& s, typename M::ScalarType& force) {
  { stepper.tick(s, force) }
  noexcept->std::same_as<model::NumericStatus>;
  { stepper.snapshot() }
  noexcept;
  { stepper.reset() }
  noexcept;
  { stepper.ratio() }
  noexcept->std::same_as<int>;
};

}  // namespace endohaptics::estimation
