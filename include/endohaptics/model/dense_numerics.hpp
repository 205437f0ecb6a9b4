//! @file
//! Configuration-time dense numerics on dynamic-size matrices: the eigenvalues of a square
//! matrix (Francis QR, Eigen::EigenSolver), the full-pivoting LU solve (Eigen::FullPivLU), the
//! matrix exponential (scaling and squaring with a Pade approximant) and the principal matrix
//! logarithm (Schur-Parlett; both Eigen's unsupported MatrixFunctions). StateSpace, the
//! discretisations (eqs. 4.1/4.2) and the d2c conversion of `estimation/zoh_resampling.hpp` run
//! on these, so each decomposition is compiled once per Scalar rather than once per model size
//! (a fixed-size EigenSolver costs seconds of compile time for every size).
//!
//! With ENDOHAPTICS_EXTERN_NUMERICS (core/separate_compilation.hpp) the double instantiations
//! are declared `extern` below and compiled once, in `model/impl/dense_numerics.ipp`: this
//! project's unit tests build that way (float models are rare, and `estimation::resample_zoh`
//! converts them in double: a float instantiation compiled once would cost more than it saves).
//! Otherwise they are compiled where they are used. Not on the tick path: these allocate and may
//! throw.
#pragma once

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <complex>
#include <unsupported/Eigen/MatrixFunctions>

namespace endohaptics::model::numerics {

//! Dynamic-size matrix of `Scalar`.
template <typename Scalar>
using Matrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
//! Dynamic-size column of complex `Scalar`.
template <typename Scalar>
using ComplexVector = Eigen::Matrix<std::complex<Scalar>, Eigen::Dynamic, 1>;

//! Eigenvalues of square `A` (Eigen::EigenSolver, no eigenvectors) into `values`. Returns false,
//! leaving `values` unspecified, when the QR iteration did not converge.
template <typename Scalar>
[[nodiscard]] bool eigenvalues(const Matrix<Scalar>& A, ComplexVector<Scalar>& values) {
  const Eigen::EigenSolver<Matrix<Scalar>> solver(A, /*computeEigenvectors=*/false);
  if (solver.info() != Eigen::Success) return false;
  values = solver.eigenvalues();
  return true;
}

//! Result of `lu_solve`.
template <typename Scalar>
struct LuSolution {
  Eigen::Index rank = 0;    //!< numerical rank of M (Eigen's default threshold)
  bool invertible = false;  //!< rank == size: X holds the solution
  Matrix<Scalar> X;         //!< M^-1 R when invertible, empty otherwise
};

//! Solves M X = R for square `M` by LU with full pivoting; reports M's rank, and X only when M is
//! invertible. `R` must have M's row count.
template <typename Scalar>
[[nodiscard]] LuSolution<Scalar> lu_solve(const Matrix<Scalar>& M, const Matrix<Scalar>& R) {
  const Eigen::FullPivLU<Matrix<Scalar>> lu(M);
  LuSolution<Scalar> solution;
  solution.rank = lu.rank();
  solution.invertible = lu.isInvertible();
  if (!solution.invertible) return solution;
  // No right-hand sides: Eigen's solve would bind a reference to a null pointer (UBSan).
  if (R.cols() == 0) {
    solution.X.resize(M.cols(), 0);
  } else {
    solution.X = lu.solve(R);
  }
  return solution;
}

//! Matrix exponential e^M of square `M`.
template <typename Scalar>
[[nodiscard]] Matrix<Scalar> exp(const Matrix<Scalar>& M) {
  return M.exp();
}

//! Principal matrix logarithm of square `M`. Precondition: no eigenvalue of `M` on the closed
//! negative real axis (the caller checks: `estimation::to_continuous_zoh`).
template <typename Scalar>
[[nodiscard]] Matrix<Scalar> log(const Matrix<Scalar>& M) {
  return M.log();
}

#if defined(ENDOHAPTICS_EXTERN_NUMERICS)
// Compiled once, in model/impl/dense_numerics.ipp (file comment).
extern template bool eigenvalues<double>(const Matrix<double>&, ComplexVector<double>&);
extern template LuSolution<double> lu_solve<double>(const Matrix<double>&, const Matrix<double>&);
extern template Matrix<double> exp<double>(const Matrix<double>&);
extern template Matrix<double> log<double>(const Matrix<double>&);
#endif

}  // namespace endohaptics::model::numerics
