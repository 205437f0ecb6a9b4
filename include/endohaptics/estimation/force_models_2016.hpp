//! @file
//! The 2016 per-joint force models as the estimator runs them (worksheet chapter 4, appendix C):
//! roll static gain 0.070 N m/A, linear pitch model (eqs. C.4-C.6, gram-force) and the yaw
//! Hammerstein-Wiener model (eqs. C.1-C.3, N) for both clamps, with table 5.2 dead zones in A.
#pragma once

#include "endohaptics/estimation/joint_force_model.hpp"
#include "endohaptics/estimation/open_loop.hpp"
#include "endohaptics/model/presets_2016.hpp"
#include "endohaptics/model/state_space.hpp"

namespace endohaptics::estimation {

//! The appendix C / 2016 per-joint models, wrapped for the estimator.
template <typename Scalar = double>
using RollModel2016 = OpenLoop<model::StateSpace<1, 1, 1, Scalar>>;  //!< static roll gain
template <typename Scalar = double>
using PitchModel2016 = OpenLoop<model::StateSpace<6, 2, 1, Scalar>>;  //!< linear pitch C.4-C.6
template <typename Scalar = double>
using ClampModel2016 = OpenLoop<model::YawForceHW2016<Scalar>>;  //!< yaw HW model C.1-C.3

//! The 2016 defaults: roll static gain (0.070 N m/A), pitch linear preset, and the yaw
//! Hammerstein-Wiener preset for each clamp with the table 5.2 dead zone of its row (clamp 1:
//! "yaw" 0.21 A, clamp 2: "clamp" 0.20 A).
template <typename Scalar = double>
[[nodiscard]] ForceModels<RollModel2016<Scalar>, PitchModel2016<Scalar>, ClampModel2016<Scalar>>
models_2016() {
  return {RollModel2016<Scalar>(model::roll_torque_2016<Scalar>()),
          PitchModel2016<Scalar>(model::pitch_force_2016<Scalar>()),
          ClampModel2016<Scalar>(model::yaw_force_2016_hw<Scalar>(
              static_cast<Scalar>(model::yaw_static_friction_2016))),
          ClampModel2016<Scalar>(model::yaw_force_2016_hw<Scalar>(
              static_cast<Scalar>(model::clamp_static_friction_2016)))};
}

}  // namespace endohaptics::estimation
