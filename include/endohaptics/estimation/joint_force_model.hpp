//! @file
//! The per-joint force model as ForceEstimator drives it (worksheet 4.1/4.2 models, chapter 4 and
//! appendix C): one joint's signals per tick, the JointForceModel concept (force output, advance
//! one model period), and ForceModels, one model per tool joint. Signals in rad, rad/s, A.
#pragma once

#include <concepts>
#include <limits>
#include <type_traits>

#include "endohaptics/core/parameter.hpp"
#include "endohaptics/model/joint_model_bounds.hpp"
#include "endohaptics/model/state_space.hpp"

namespace endohaptics::estimation {

// The parameter bounds of the joint models (model/joint_model_bounds.hpp), under the names the
// estimation types use.
using model::max_joint_model_parameter;
using model::min_current_per_load;

//! The sample time of a joint model: finite and > 0 s.
inline constexpr Bound sample_time_bound =
    Bound::above(0, std::numeric_limits<double>::infinity(), "s");

//! A low-pass cut-off of a joint model sampled every `sample_time` s: in (0, Nyquist) Hz.
[[nodiscard]] constexpr Bound cutoff_bound(double sample_time) {
  return Bound::between(0, 0.5 / sample_time, "Hz")
      .described("in (0, Nyquist = 0.5 / sample_time) Hz");
}

//! The signals of one joint (one motor) for one tick.
template <typename Scalar = double>
struct JointSignals {
  Scalar position{};  //!< rad
  Scalar velocity{};  //!< rad/s
  Scalar current{};   //!< A
  Scalar setpoint{};  //!< rad
  //! Position error setpoint - position, rad (what the sbRIO's P controller acts on).
  [[nodiscard]] constexpr Scalar position_error() const noexcept { return setpoint - position; }
};

//! A per-joint force model as the estimator drives it: `force(s)` is the model's force output
//! at its current state (feedthrough from the signals `s`), `advance(s)` steps the model one
//! model period with `s` (all-or-nothing), `memoryless()` is true when the state never reaches
//! the output (the sample time then does not matter). Implementations: OpenLoop, KalmanCorrected,
//! StallHold, PushLoadObserver, BidirectionalLoadObserver.
template <typename M>
concept JointForceModel = requires(M& m, const M& cm,
                                   const JointSignals<typename M::ScalarType>& signals,
                                   const typename M::State& x) {
  typename M::ScalarType;
  typename M::State;
  requires std::is_floating_point_v<typename M::ScalarType>;
  { cm.sample_time() }
  noexcept->std::same_as<typename M::ScalarType>;
  { cm.memoryless() }
  noexcept->std::same_as<bool>;
  { cm.force(signals) }
  noexcept->std::same_as<typename M::ScalarType>;
  { m.advance(signals) }
  noexcept->std::same_as<model::NumericStatus>;
  { cm.state() }
  noexcept->std::convertible_to<const typename M::State&>;
  { m.reset(x) }
  noexcept;
};

//! A JointForceModel that rate::Resample can convert: `M resampled(Scalar period) const`
//! (configuration time, may throw Error).
template <typename M>
concept ResamplableJointForceModel = JointForceModel<M> &&
    requires(const M& cm, typename M::ScalarType period) {
  { cm.resampled(period) } -> std::same_as<M>;
};

//! One model per tool joint; both clamps use the same model type.
template <JointForceModel Roll, JointForceModel Pitch, JointForceModel Clamp>
struct ForceModels {
  Roll roll;     //!< roll torque model
  Pitch pitch;   //!< pitch force model
  Clamp clamp1;  //!< clamp 1 force model
  Clamp clamp2;  //!< clamp 2 force model
};

}  // namespace endohaptics::estimation
