//! @file
//! Zero-order-hold conversion between sample times (eqs. 4.1/4.2): to_continuous_zoh (d2c by the
//! matrix logarithm, scipy's 'zoh') and resample_zoh (the same model at another period, for
//! rate::Resample), for StateSpace and Hammerstein-Wiener models. Times in s. Configuration time.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <type_traits>

#include "endohaptics/core/error.hpp"
#include "endohaptics/model/dense_numerics.hpp"
#include "endohaptics/model/hammerstein_wiener.hpp"
#include "endohaptics/model/state_space.hpp"

namespace endohaptics::estimation {

//! Continuous-time model whose ZOH discretisation at `discrete.sample_time()` is `discrete`
//! (scipy-style d2c 'zoh'): logm([[A, B], [0, I]]) / Ts = [[Ac, Bc], [0, 0]], Cc = C, Dc = D.
//! Throws Error if A is singular or has an eigenvalue on the closed negative real axis (no real
//! matrix logarithm: the message names the eigenvalue), or if the result is not finite.
template <int Nx, int Nu, int Ny, typename Scalar>
[[nodiscard]] model::ContinuousStateSpace<Nx, Nu, Ny, Scalar> to_continuous_zoh(
    const model::StateSpace<Nx, Nu, Ny, Scalar>& discrete) {
  const Scalar eps = std::numeric_limits<Scalar>::epsilon();
  // Dynamic size on purpose: configuration time only, and one instantiation of Eigen's
  // eigenvalue solver and matrix logarithm per Scalar instead of one per model size
  // (model/dense_numerics.hpp).
  using Dynamic = model::numerics::Matrix<Scalar>;
  const Dynamic A = discrete.A();
  const Scalar norm = std::max(Scalar(1), A.norm());
  model::numerics::ComplexVector<Scalar> eigenvalues;
  if (!model::numerics::eigenvalues<Scalar>(A, eigenvalues)) {
    ENDOHAPTICS_THROW(Error("to_continuous_zoh: eigenvalues of A did not converge"));
  }
  for (Eigen::Index i = 0; i < eigenvalues.size(); ++i) {
    const std::complex<Scalar> lambda = eigenvalues[i];
    if (std::abs(lambda) <= Scalar(100) * eps * norm) {
      ENDOHAPTICS_THROW(Error("to_continuous_zoh: A is singular (eigenvalue " +
                              endohaptics::detail::format_number(lambda) +
                              "), no matrix logarithm"));
    }
    if (lambda.real() < Scalar(0) && std::abs(lambda.imag()) <= std::sqrt(eps) * std::abs(lambda)) {
      ENDOHAPTICS_THROW(Error("to_continuous_zoh: A has the eigenvalue " +
                              endohaptics::detail::format_number(lambda) +
                              " on the negative real axis, no real matrix logarithm "
                              "(no continuous-time model has this discretisation)"));
    }
  }
  Dynamic M = Dynamic::Identity(Nx + Nu, Nx + Nu);
  M.topLeftCorner(Nx, Nx) = discrete.A();
  if constexpr (Nu > 0) M.topRightCorner(Nx, Nu) = discrete.B();
  const Dynamic L = model::numerics::log<Scalar>(M) / discrete.sample_time();
  if (!L.allFinite()) {
    ENDOHAPTICS_THROW(Error("to_continuous_zoh: the matrix logarithm is not finite"));
  }
  typename model::ContinuousStateSpace<Nx, Nu, Ny, Scalar>::MatrixB Bc;
  if constexpr (Nu > 0) Bc = L.topRightCorner(Nx, Nu);
  return model::ContinuousStateSpace<Nx, Nu, Ny, Scalar>(L.topLeftCorner(Nx, Nx), Bc, discrete.C(),
                                                         discrete.D());
}

//! The same system sampled at `period` s instead (ZOH both ways), keeping the current state.
//! A memoryless model (C == 0: y = D u) only gets the new sample time; float models are
//! converted in double. Throws Error as `to_continuous_zoh` and `discretize_zoh` do.
template <int Nx, int Nu, int Ny, typename Scalar>
[[nodiscard]] model::StateSpace<Nx, Nu, Ny, Scalar> resample_zoh(
    const model::StateSpace<Nx, Nu, Ny, Scalar>& discrete, Scalar period) {
  model::detail::require_sample_time(period, "resample_zoh");
  if (discrete.C().isZero(Scalar(0))) {
    model::StateSpace<Nx, Nu, Ny, Scalar> same(discrete.A(), discrete.B(), discrete.C(),
                                               discrete.D(), period);
    same.reset(discrete.state());
    return same;
  }
  // float models are converted in double and rounded once at the end: the float matrix
  // logarithm of the nearly defective yaw model is off by several percent.
  using Wide = std::conditional_t<(sizeof(Scalar) < sizeof(double)), double, Scalar>;
  if constexpr (std::is_same_v<Wide, Scalar>) {
    auto resampled = model::discretize_zoh(to_continuous_zoh(discrete), period);
    resampled.reset(discrete.state());
    return resampled;
  } else {
    const model::StateSpace<Nx, Nu, Ny, Wide> wide(
        discrete.A().template cast<Wide>(), discrete.B().template cast<Wide>(),
        discrete.C().template cast<Wide>(), discrete.D().template cast<Wide>(),
        static_cast<Wide>(discrete.sample_time()));
    const auto fine = model::discretize_zoh(to_continuous_zoh(wide), static_cast<Wide>(period));
    model::StateSpace<Nx, Nu, Ny, Scalar> resampled(
        fine.A().template cast<Scalar>(), fine.B().template cast<Scalar>(),
        fine.C().template cast<Scalar>(), fine.D().template cast<Scalar>(), period);
    resampled.reset(discrete.state());
    return resampled;
  }
}

//! Hammerstein-Wiener model with its linear block resampled; the static nonlinearities are kept.
template <typename Linear, typename InputNL, typename OutputNL>
[[nodiscard]] model::HammersteinWiener<Linear, InputNL, OutputNL> resample_zoh(
    const model::HammersteinWiener<Linear, InputNL, OutputNL>& hw,
    typename Linear::ScalarType period) {
  return model::HammersteinWiener<Linear, InputNL, OutputNL>(
      resample_zoh(hw.linear(), period), hw.input_nonlinearity(), hw.output_nonlinearity());
}

}  // namespace endohaptics::estimation
