//! @file
//! ButterworthBiquad: a second-order Butterworth low-pass, discretised by the bilinear transform
//! with prewarping (unity DC gain), run in direct form II transposed with its two delay values
//! held by the caller (so that a model keeps them in its own state vector), started at the steady
//! state of its first input. Units: cut-off in Hz, sample time in s.
#pragma once

#include <cmath>
#include <numbers>

namespace endohaptics::model {

//! The filter's coefficients (see the file comment); step() and start() are noexcept.
template <typename Scalar = double>
struct ButterworthBiquad {
  // y = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2) u
  Scalar b0{};  //!< numerator, z^0
  Scalar b1{};  //!< numerator, z^-1
  Scalar b2{};  //!< numerator, z^-2
  Scalar a1{};  //!< denominator, z^-1 (the z^0 coefficient is 1)
  Scalar a2{};  //!< denominator, z^-2

  //! The low-pass with `cutoff` Hz at `sample_time` s. Precondition: 0 < cutoff < Nyquist.
  [[nodiscard]] static ButterworthBiquad lowpass(Scalar cutoff, Scalar sample_time) noexcept {
    const Scalar k = std::tan(std::numbers::pi_v<Scalar> * cutoff * sample_time);
    const Scalar root2 = std::numbers::sqrt2_v<Scalar>;
    const Scalar norm = Scalar(1) / (Scalar(1) + root2 * k + k * k);
    ButterworthBiquad b;
    b.b0 = k * k * norm;
    b.b1 = 2 * b.b0;
    b.b2 = b.b0;
    b.a1 = 2 * (k * k - Scalar(1)) * norm;
    b.a2 = (Scalar(1) - root2 * k + k * k) * norm;
    return b;
  }
  //! Delay values of the steady state for the constant input `u` (output u).
  void start(Scalar u, Scalar& z1, Scalar& z2) const noexcept {
    z1 = u * (Scalar(1) - b0);
    z2 = u * (b2 - a2);
  }
  //! One sample `u`: the output, the delay values advanced.
  [[nodiscard]] Scalar step(Scalar u, Scalar& z1, Scalar& z2) const noexcept {
    const Scalar y = b0 * u + z1;
    z1 = b1 * u - a1 * y + z2;
    z2 = b2 * u - a2 * y;
    return y;
  }
};

}  // namespace endohaptics::model
