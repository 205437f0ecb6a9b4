//! @file
//! DirectionalFrontEnd: the signal front end both load observers share (PushLoadObserver,
//! BidirectionalLoadObserver; docs/research_force_models.md K2, K7): second-order Butterworth
//! low-passes of the current and of the encoder difference (velocity), started at the steady state
//! of the first sample; a Dahl-type direction state on the encoder increments (rate-independent,
//! Dahl 1968); the regime from the direction and the filtered velocity. Its six numbers live in
//! the observer's own state vector. Units: A, rad, rad/s, s. noexcept, allocation-free.
#pragma once

#include <cmath>

#include "endohaptics/model/butterworth_biquad.hpp"

namespace endohaptics::estimation {

//! The observers' front end (see the file comment). Configuration: the constructor's values,
//! checked by the observer's parameters (cut-offs below Nyquist, q0 > 0, thresholds in range).
template <typename Scalar = double>
class DirectionalFrontEnd {
 public:
  //! Numbers of its state: current filter z1, z2, velocity filter z1, z2, previous position (rad),
  //! direction h in [-1, 1] (in this order, from the pointer step() is given).
  static constexpr int state_size = 6;

  //! What one sample gives.
  struct Step {
    Scalar delta;     //!< rad, the encoder increment since the previous sample
    Scalar current;   //!< A, filtered
    Scalar velocity;  //!< rad/s, filtered encoder difference
    Scalar regime;    //!< +1 moving the signed way, -1 the other way, 0 at rest or reversing
  };

  DirectionalFrontEnd() = default;  //!< unconfigured (an observer assigns it in its constructor)
  //! Cut-offs in Hz, q0 in rad, |h| threshold, velocity threshold in rad/s, sample time in s.
  DirectionalFrontEnd(Scalar current_cutoff, Scalar velocity_cutoff, Scalar direction_scale,
                      Scalar direction_threshold, Scalar velocity_threshold,
                      Scalar sample_time) noexcept
      : current_(model::ButterworthBiquad<Scalar>::lowpass(current_cutoff, sample_time)),
        velocity_(model::ButterworthBiquad<Scalar>::lowpass(velocity_cutoff, sample_time)),
        direction_scale_(direction_scale),
        direction_threshold_(direction_threshold),
        velocity_threshold_(velocity_threshold),
        sample_time_(sample_time) {}

  //! One sample: `z` the state_size numbers, `started` 0 before the first sample (then set to 1:
  //! the filters start at this sample's steady state, no motion yet). The regime is judged on
  //! sign x direction and sign x velocity (`sign` +1 or -1: which way is "forward"). Precondition:
  //! position and current finite.
  Step step(Scalar* z, Scalar& started, Scalar position, Scalar current,
            Scalar sign = Scalar(1)) const noexcept {
    if (started == Scalar(0)) {
      current_.start(current, z[0], z[1]);
      velocity_.start(Scalar(0), z[2], z[3]);
      z[4] = position;
      started = Scalar(1);
    }
    Step out{};
    out.delta = position - z[4];
    z[4] = position;
    out.current = current_.step(current, z[0], z[1]);
    out.velocity = velocity_.step(out.delta / sample_time_, z[2], z[3]);
    // Direction state: moves towards sign(delta) by |delta| / q0 of the way (at most all of it).
    if (out.delta != Scalar(0)) {
      const Scalar w = std::fmin(Scalar(1), std::fabs(out.delta) / direction_scale_);
      z[5] += w * ((out.delta > 0 ? Scalar(1) : Scalar(-1)) - z[5]);
    }
    const Scalar h = sign * z[5];
    const Scalar v = sign * out.velocity;
    out.regime = h >= direction_threshold_ && v > velocity_threshold_     ? Scalar(1)
                 : h <= -direction_threshold_ && v < -velocity_threshold_ ? Scalar(-1)
                                                                          : Scalar(0);
    return out;
  }

 private:
  model::ButterworthBiquad<Scalar> current_{};
  model::ButterworthBiquad<Scalar> velocity_{};
  Scalar direction_scale_{};
  Scalar direction_threshold_{};
  Scalar velocity_threshold_{};
  Scalar sample_time_{};
};

}  // namespace endohaptics::estimation
