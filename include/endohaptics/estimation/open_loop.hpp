//! @file
//! OpenLoop: a JointForceModel that runs a StateSpace or Hammerstein-Wiener model (eqs. 4.1/4.2,
//! appendix C) open loop on u = [current A] or [current A; velocity rad/s]; output 0 is the
//! force in the model's unit. The default, uncorrected per-joint model of ForceEstimator.
#pragma once

#include <concepts>
#include <utility>

#include "endohaptics/estimation/joint_force_model.hpp"
#include "endohaptics/estimation/zoh_resampling.hpp"
#include "endohaptics/model/hammerstein_wiener.hpp"
#include "endohaptics/model/state_space.hpp"

namespace endohaptics::estimation {

namespace detail::force {

//! The linear block of a model: itself, or `linear()` of a Hammerstein-Wiener model.
template <typename M>
const auto& linear_block(const M& m) noexcept {
  if constexpr (requires { m.linear(); }) {
    return m.linear();
  } else {
    return m;
  }
}

}  // namespace detail::force

//! A model the estimator can drive open loop: a model::StateSpace or model::HammersteinWiener
//! (anything with their interface and a `sample_time()`/`C()`, directly or via `linear()`) with
//! u = [current A] or u = [current A; velocity rad/s] and the force as output 0.
template <typename Model>
concept CurrentVelocityModel =
    model::LinearBlock<Model> &&(Model::inputs == 1 || Model::inputs == 2) && Model::outputs >= 1 &&
    requires(const Model& m) {
  { detail::force::linear_block(m).sample_time() } -> std::same_as<typename Model::ScalarType>;
  detail::force::linear_block(m).C();
};

//! No correction (the default): the model runs open loop on u = [current; velocity] (or
//! [current]) and its output 0 is the force, in the model's units and sign.
template <CurrentVelocityModel Model>
class OpenLoop {
 public:
  using ModelType = Model;                        //!< the wrapped model type
  using ScalarType = typename Model::ScalarType;  //!< floating-point type of the model
  using State = typename Model::State;            //!< model state x
  using Input = typename Model::Input;       //!< u = [current A] or [current A; velocity rad/s]
  using Signals = JointSignals<ScalarType>;  //!< one joint's signals for one tick

  //! Takes a copy of `model`, starting from its current state.
  explicit OpenLoop(Model model)
      : model_(std::move(model)),
        memoryless_(detail::force::linear_block(model_).C().isZero(ScalarType(0))) {}

  [[nodiscard]] const Model& model() const noexcept { return model_; }  //!< the wrapped model
  //! Sample time of the model, s.
  [[nodiscard]] ScalarType sample_time() const noexcept {
    return detail::force::linear_block(model_).sample_time();
  }
  //! True when C == 0: the output is D u only and the sample time does not matter.
  [[nodiscard]] bool memoryless() const noexcept { return memoryless_; }

  //! u = [current] or [current; velocity].
  [[nodiscard]] static Input input(const Signals& s) noexcept {
    Input u;
    u[0] = s.current;
    if constexpr (Model::inputs == 2) u[1] = s.velocity;
    return u;
  }
  //! Force (output 0) at the current state with feedthrough from `s`; does not advance.
  [[nodiscard]] ScalarType force(const Signals& s) const noexcept {
    return model_.output(input(s))[0];
  }
  //! One model period with input from `s`; all-or-nothing (model::NumericStatus).
  [[nodiscard]] model::NumericStatus advance(const Signals& s) noexcept {
    typename Model::Output y;
    return model_.update(input(s), y);
  }
  [[nodiscard]] const State& state() const noexcept { return model_.state(); }  //!< x(k)
  void reset(const State& x = State::Zero()) noexcept { model_.reset(x); }      //!< sets x(k)

  //! The model resampled at `period` s (`resample_zoh`). Throws Error as `resample_zoh` does.
  [[nodiscard]] OpenLoop resampled(ScalarType period) const requires
      requires(const Model& m, ScalarType t) {
    resample_zoh(m, t);
  }
  { return OpenLoop(resample_zoh(model_, period)); }

 private:
  Model model_;
  bool memoryless_;
};

}  // namespace endohaptics::estimation
