//! @file
//! Memoryless input/output nonlinearities of a Hammerstein-Wiener model (worksheet 4.1.1,
//! figure 4.1): dead zone (like MATLAB idDeadZone), saturation, piecewise linear, identity,
//! and PerChannel, which applies one of them per vector element. Units pass through unchanged.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <type_traits>
#include <utility>

#include "endohaptics/core/error.hpp"

namespace endohaptics::model {

//! A memoryless scalar map y = f(u) that a tick may call: `apply` is const and noexcept.
//! Contract (checked by tests/model/static_nonlinearity_test.cpp for every implementation):
//! NaN in gives NaN out, finite in gives finite out.
template <typename NL>
concept StaticNonlinearity = requires(const NL& nl, typename NL::ScalarType u) {
  requires std::is_floating_point_v<typename NL::ScalarType>;
  { nl.apply(u) }
  noexcept->std::same_as<typename NL::ScalarType>;
};

namespace detail::nl {

using endohaptics::detail::require_finite;

//! Returns `value` if finite and >= 0, throws Error otherwise.
template <typename Scalar>
Scalar non_negative(Scalar value, const char* owner, const char* what) {
  require_finite(value, owner, what);
  if (value < Scalar(0)) {
    ENDOHAPTICS_THROW(Error(std::string(owner) + ": " + what + " must be >= 0, got " +
                            endohaptics::detail::format_number(value)));
  }
  return value;
}

template <typename Scalar>
void require_ordered(Scalar lower, Scalar upper, const char* owner) {
  require_finite(lower, owner, "lower breakpoint");
  require_finite(upper, owner, "upper breakpoint");
  if (!(lower <= upper)) {
    ENDOHAPTICS_THROW(Error(
        std::string(owner) + ": lower breakpoint " + endohaptics::detail::format_number(lower) +
        " is greater than upper breakpoint " + endohaptics::detail::format_number(upper)));
  }
}

}  // namespace detail::nl

//! y = u: no nonlinearity.
template <typename Scalar = double>
struct Identity {
  static_assert(std::is_floating_point_v<Scalar>, "Identity Scalar must be floating point");
  using ScalarType = Scalar;  //!< scalar type of u and y
  //! Returns u unchanged.
  [[nodiscard]] constexpr Scalar apply(Scalar u) const noexcept { return u; }
};

//! Dead zone with breakpoints lower <= upper (MATLAB idDeadZone ZeroInterval [lower, upper]):
//! y = 0 for lower <= u <= upper, u - upper above, u - lower below. NaN in gives NaN out.
template <typename Scalar = double>
class Deadzone {
  static_assert(std::is_floating_point_v<Scalar>, "Deadzone Scalar must be floating point");

 public:
  using ScalarType = Scalar;  //!< scalar type of u and y

  //! Symmetric zero interval [-half_width, half_width]. Throws Error unless finite and >= 0.
  explicit Deadzone(Scalar half_width)
      : Deadzone(-detail::nl::non_negative(half_width, "Deadzone", "half width"), half_width) {}

  //! Asymmetric zero interval [lower, upper]. Throws Error unless finite and lower <= upper.
  Deadzone(Scalar lower, Scalar upper) : lower_(lower), upper_(upper) {
    detail::nl::require_ordered(lower_, upper_, "Deadzone");
  }

  [[nodiscard]] Scalar lower() const noexcept { return lower_; }  //!< lower breakpoint
  [[nodiscard]] Scalar upper() const noexcept { return upper_; }  //!< upper breakpoint

  //! 0 inside [lower, upper], u - upper above, u - lower below; NaN stays NaN.
  [[nodiscard]] Scalar apply(Scalar u) const noexcept {
    if (u > upper_) return u - upper_;
    if (u < lower_) return u - lower_;
    return std::isnan(u) ? u : Scalar(0);
  }

 private:
  Scalar lower_;
  Scalar upper_;
};

//! Saturation: y = clamp(u, lower, upper) with lower <= upper. NaN in gives NaN out.
template <typename Scalar = double>
class Saturation {
  static_assert(std::is_floating_point_v<Scalar>, "Saturation Scalar must be floating point");

 public:
  using ScalarType = Scalar;  //!< scalar type of u and y

  //! Symmetric limits [-limit, limit]. Throws Error unless finite and >= 0.
  explicit Saturation(Scalar limit)
      : Saturation(-detail::nl::non_negative(limit, "Saturation", "limit"), limit) {}

  //! Limits [lower, upper]. Throws Error unless finite and lower <= upper.
  Saturation(Scalar lower, Scalar upper) : lower_(lower), upper_(upper) {
    detail::nl::require_ordered(lower_, upper_, "Saturation");
  }

  [[nodiscard]] Scalar lower() const noexcept { return lower_; }  //!< lower limit
  [[nodiscard]] Scalar upper() const noexcept { return upper_; }  //!< upper limit

  //! lower below lower, upper above upper, u in between; NaN stays NaN.
  [[nodiscard]] Scalar apply(Scalar u) const noexcept {
    if (u > upper_) return upper_;
    if (u < lower_) return lower_;
    return u;
  }

 private:
  Scalar lower_;
  Scalar upper_;
};

//! Free-motion threshold: an estimate whose magnitude is at most `threshold` reads 0 (what a
//! force model gives when nothing touches), between `threshold` and twice it the output rises
//! linearly from 0 to the estimate (continuous: no step the operator feels), beyond twice it is
//! the estimate unchanged. y = 0 for |u| <= t, sign(u) 2 (|u| - t) for t < |u| < 2 t, u for
//! |u| >= 2 t. A threshold of 0 is the identity. NaN in gives NaN out.
template <typename Scalar = double>
class FreeMotionThreshold {
  static_assert(std::is_floating_point_v<Scalar>, "FreeMotionThreshold Scalar must be floating");

 public:
  using ScalarType = Scalar;  //!< scalar type of u and y

  //! The identity (threshold 0).
  FreeMotionThreshold() = default;
  //! Throws Error unless `threshold` is finite and >= 0.
  explicit FreeMotionThreshold(Scalar threshold)
      : threshold_(detail::nl::non_negative(threshold, "FreeMotionThreshold", "threshold")) {}

  [[nodiscard]] Scalar threshold() const noexcept { return threshold_; }  //!< t, >= 0

  //! See the class; NaN stays NaN.
  [[nodiscard]] Scalar apply(Scalar u) const noexcept {
    const Scalar m = std::fabs(u);
    if (!(m < 2 * threshold_)) return u;  // beyond twice the threshold, or NaN
    if (m <= threshold_) return Scalar(0);
    return std::copysign(2 * (m - threshold_), u);
  }

 private:
  Scalar threshold_ = Scalar(0);
};

//! What a PiecewiseLinear map does outside its first and last breakpoints.
enum class Extrapolation : std::uint8_t {
  linear,  //!< continue the first/last segment (MATLAB idPiecewiseLinear); default
  clamp,   //!< hold the first/last value
};

//! Piecewise-linear map through 2..MaxPoints points (x_i, y_i) with strictly increasing x_i;
//! linear interpolation between them, `Extrapolation` outside. NaN in gives NaN out.
template <int MaxPoints, typename Scalar = double>
class PiecewiseLinear {
  static_assert(MaxPoints >= 2, "PiecewiseLinear needs room for at least two points");
  static_assert(std::is_floating_point_v<Scalar>, "PiecewiseLinear Scalar must be floating point");

 public:
  using ScalarType = Scalar;                    //!< scalar type of u, y and the points
  static constexpr int max_points = MaxPoints;  //!< capacity (points)

  //! Throws Error when the sizes differ, the count is outside [2, MaxPoints], a value is not
  //! finite or the breakpoints are not strictly increasing (the message names index and value).
  PiecewiseLinear(std::span<const Scalar> x, std::span<const Scalar> y,
                  Extrapolation extrapolation = Extrapolation::linear)
      : extrapolation_(extrapolation) {
    if (x.size() != y.size()) {
      ENDOHAPTICS_THROW(Error("PiecewiseLinear: " + std::to_string(x.size()) + " breakpoints but " +
                              std::to_string(y.size()) + " values"));
    }
    if (x.size() < 2 || x.size() > static_cast<std::size_t>(MaxPoints)) {
      ENDOHAPTICS_THROW(Error("PiecewiseLinear: needs 2 to " + std::to_string(MaxPoints) +
                              " points, got " + std::to_string(x.size())));
    }
    count_ = static_cast<int>(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (!std::isfinite(x[i]) || !std::isfinite(y[i])) {
        ENDOHAPTICS_THROW(Error("PiecewiseLinear: point " + std::to_string(i) + " is not finite (" +
                                endohaptics::detail::format_number(x[i]) + ", " +
                                endohaptics::detail::format_number(y[i]) + ")"));
      }
      if (i > 0 && !(x[i] > x[i - 1])) {
        ENDOHAPTICS_THROW(
            Error("PiecewiseLinear: breakpoints must increase strictly, x[" + std::to_string(i) +
                  "] = " + endohaptics::detail::format_number(x[i]) + " <= x[" +
                  std::to_string(i - 1) + "] = " + endohaptics::detail::format_number(x[i - 1])));
      }
      x_[i] = x[i];
      y_[i] = y[i];
    }
  }

  [[nodiscard]] int size() const noexcept { return count_; }  //!< number of points in use
  //! Breakpoints in use (strictly increasing).
  [[nodiscard]] std::span<const Scalar> breakpoints() const noexcept {
    return {x_.data(), static_cast<std::size_t>(count_)};
  }
  //! Values at the breakpoints.
  [[nodiscard]] std::span<const Scalar> values() const noexcept {
    return {y_.data(), static_cast<std::size_t>(count_)};
  }
  //! What the map does outside the first and last breakpoints.
  [[nodiscard]] Extrapolation extrapolation() const noexcept { return extrapolation_; }

  //! Interpolates (O(log n), no allocation); NaN stays NaN.
  [[nodiscard]] Scalar apply(Scalar u) const noexcept {
    if (std::isnan(u)) return u;
    const auto n = static_cast<std::size_t>(count_);
    if (extrapolation_ == Extrapolation::clamp) {
      if (u <= x_[0]) return y_[0];
      if (u >= x_[n - 1]) return y_[n - 1];
    }
    // Segment [x_i, x_{i+1}] with i in [0, n - 2]: the first and last also extrapolate.
    const auto* it = std::upper_bound(x_.data() + 1, x_.data() + (n - 1), u);
    const auto i = static_cast<std::size_t>(it - x_.data()) - 1;
    const Scalar rise = y_[i + 1] - y_[i];
    if (rise == Scalar(0)) return y_[i];  // flat segment: also keeps +-Inf from giving NaN
    return y_[i] + rise / (x_[i + 1] - x_[i]) * (u - x_[i]);
  }

 private:
  std::array<Scalar, static_cast<std::size_t>(MaxPoints)> x_{};
  std::array<Scalar, static_cast<std::size_t>(MaxPoints)> y_{};
  int count_ = 0;
  Extrapolation extrapolation_;
};

//! Applies one scalar nonlinearity per element of an N-vector (N >= 0): y_i = f_i(u_i).
template <StaticNonlinearity NL, int N>
class PerChannel {
  static_assert(N >= 0, "PerChannel channel count must be >= 0");

 public:
  using ScalarType = typename NL::ScalarType;      //!< scalar type of every channel
  using Channel = NL;                              //!< the nonlinearity of one channel
  using Vector = Eigen::Matrix<ScalarType, N, 1>;  //!< one value per channel
  static constexpr int size = N;                   //!< number of channels

  //! Default: every channel default-constructed (only for default-constructible NL).
  PerChannel() requires std::default_initializable<NL> : channels_{} {}
  //! The same nonlinearity on every channel.
  explicit PerChannel(const NL& every_channel)
      : channels_([&]<std::size_t... I>(std::index_sequence<I...>) {
          return std::array<NL, sizeof...(I)>{((void)I, every_channel)...};
        }(std::make_index_sequence<static_cast<std::size_t>(N)>{})) {}
  //! One nonlinearity per channel, channel i for element i.
  explicit PerChannel(const std::array<NL, static_cast<std::size_t>(N)>& channels)
      : channels_(channels) {}

  //! The nonlinearity of channel i. Precondition: 0 <= i < N.
  [[nodiscard]] const NL& channel(int i) const noexcept {
    ENDOHAPTICS_ASSERT(i >= 0 && i < N);
    return channels_[static_cast<std::size_t>(i)];
  }

  //! y_i = f_i(u_i) for every element.
  [[nodiscard]] Vector apply(const Vector& u) const noexcept {
    Vector y;
    for (int i = 0; i < N; ++i) y[i] = channels_[static_cast<std::size_t>(i)].apply(u[i]);
    return y;
  }

 private:
  std::array<NL, static_cast<std::size_t>(N)> channels_;
};

}  // namespace endohaptics::model
