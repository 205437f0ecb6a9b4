//! @file
//! Discrete algebraic Riccati equation of the steady-state Kalman filter (worksheet 4.4.1):
//! P = A P A' - A P C' (C P C' + R)^-1 C P A' + Q, P the one-step prediction (a priori) error
//! covariance, solved by the structured doubling algorithm (SDA). Units: P and Q in state units
//! squared, R in measurement units squared. See docs/models/steady_state_kalman.md.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

#include "endohaptics/core/error.hpp"
#include "endohaptics/model/dense_numerics.hpp"

namespace endohaptics::estimation {

//! Stopping rule of `solve_filter_dare`.
template <typename Scalar = double>
struct DareOptions {
  //! Doubling steps allowed; step k accounts for a horizon of 2^k samples. Must be >= 1.
  int max_iterations = 100;
  //! Converged when ||P_k+1 - P_k||_F <= relative_tolerance * ||P_k+1||_F. Must be > 0.
  Scalar relative_tolerance = Scalar(1000) * std::numeric_limits<Scalar>::epsilon();
};

//! Stabilising solution of the filter DARE and how it was obtained.
template <int Nx, typename Scalar = double>
struct DareSolution {
  Eigen::Matrix<Scalar, Nx, Nx> P;  //!< a priori error covariance, symmetric PSD
  int iterations = 0;               //!< doubling steps taken
  //! ||A P A' - A P C' (C P C' + R)^-1 C P A' + Q - P||_F / ||P||_F (not divided when P = 0).
  Scalar residual = Scalar(0);
};

namespace detail {

using endohaptics::detail::format_number;  // round-trip digits in error messages

inline std::string entry_name(std::string_view what, Eigen::Index i, Eigen::Index j) {
  return std::string(what) + "(" + std::to_string(i) + "," + std::to_string(j) + ")";
}

//! Configuration-time numerics run on dynamic-size matrices in `WorkScalar` (double, or Scalar
//! when wider): each decomposition is then compiled once, not once per size and Scalar (a
//! fixed-size EigenSolver costs about 10 s of compile time per size). Allocation is fine here;
//! the tick path is fixed-size.
template <typename Scalar>
using DynamicMatrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
template <typename Scalar>
using WorkScalar =
    std::conditional_t<(std::numeric_limits<Scalar>::digits > std::numeric_limits<double>::digits),
                       Scalar, double>;

//! Tolerance of the structural checks (symmetry, semidefiniteness) for an n x n matrix whose
//! entries carry a relative rounding error `eps` (that of the caller's Scalar).
template <typename Scalar>
Scalar structure_tolerance(Eigen::Index n, Scalar eps) noexcept {
  return Scalar(100) * static_cast<Scalar>(n) * eps;
}

using endohaptics::detail::require_finite;

//! Checks that square `M` is symmetric to a relative 100 n eps and returns (M + M') / 2.
template <typename Scalar>
DynamicMatrix<Scalar> require_symmetric(const DynamicMatrix<Scalar>& M, std::string_view owner,
                                        std::string_view what, Scalar eps) {
  const Eigen::Index n = M.rows();
  const Scalar scale = M.cwiseAbs().maxCoeff();
  Scalar worst = Scalar(0);
  Eigen::Index wi = 0;
  Eigen::Index wj = 0;
  for (Eigen::Index j = 0; j < n; ++j) {
    for (Eigen::Index i = j + 1; i < n; ++i) {
      const Scalar gap = std::abs(M(i, j) - M(j, i));
      if (gap > worst) {
        worst = gap;
        wi = i;
        wj = j;
      }
    }
  }
  if (worst > structure_tolerance(n, eps) * scale) {
    ENDOHAPTICS_THROW(Error(std::string(owner) + ": " + std::string(what) + " is not symmetric: " +
                            entry_name(what, wi, wj) + " = " + format_number(M(wi, wj)) + " but " +
                            entry_name(what, wj, wi) + " = " + format_number(M(wj, wi))));
  }
  return (M + M.transpose()) / Scalar(2);
}

//! Eigenvalues of a symmetric matrix, ascending. Uses the general EigenSolver (backward stable,
//! so the eigenvalues are accurate to eps ||M||) to compile only one eigen-decomposition.
template <typename Scalar>
Eigen::Matrix<Scalar, Eigen::Dynamic, 1> symmetric_eigenvalues(const DynamicMatrix<Scalar>& M,
                                                               std::string_view owner,
                                                               std::string_view what) {
  model::numerics::ComplexVector<Scalar> eigenvalues;
  if (!model::numerics::eigenvalues<Scalar>(M, eigenvalues)) {
    ENDOHAPTICS_THROW(
        Error(std::string(owner) + ": eigenvalues of " + std::string(what) + " did not converge"));
  }
  Eigen::Matrix<Scalar, Eigen::Dynamic, 1> values = eigenvalues.real();
  std::sort(values.data(), values.data() + values.size());
  return values;
}

//! Symmetrised covariance; throws unless it is positive semidefinite (`definite`: definite).
//! Semidefinite: smallest eigenvalue >= -100 n eps * largest |eigenvalue|.
//! Definite: smallest eigenvalue > n eps * largest eigenvalue (numerically invertible).
template <typename Scalar>
DynamicMatrix<Scalar> require_covariance(const DynamicMatrix<Scalar>& M, std::string_view owner,
                                         std::string_view what, bool definite, Scalar eps) {
  const Eigen::Index n = M.rows();
  DynamicMatrix<Scalar> S = require_symmetric(M, owner, what, eps);
  const auto values = symmetric_eigenvalues(S, owner, what);
  const Scalar smallest = values(0);
  const Scalar largest = values(n - 1);
  const Scalar magnitude = std::max(std::abs(smallest), std::abs(largest));
  if (definite && !(smallest > static_cast<Scalar>(n) * eps * largest && largest > Scalar(0))) {
    ENDOHAPTICS_THROW(Error(std::string(owner) + ": " + std::string(what) +
                            " is not positive definite: smallest eigenvalue " +
                            format_number(smallest) + ", largest " + format_number(largest)));
  }
  if (!definite && smallest < -structure_tolerance(n, eps) * magnitude) {
    ENDOHAPTICS_THROW(Error(std::string(owner) + ": " + std::string(what) +
                            " is not positive semidefinite: smallest eigenvalue " +
                            format_number(smallest)));
  }
  return S;
}

//! PBH test: throws unless every eigenvalue of A with |lambda| >= 1 - sqrt(eps) is observable,
//! i.e. [lambda I - A; C] has full column rank. Rows of C are rescaled to max(||A||_F, 1) (the
//! rank is unchanged); rank-deficient means sigma_min <= 10 sqrt(eps) max(||A||_F, 1), with
//! sigma_min^2 the smallest eigenvalue of M' M. A complex lambda = a + ib is tested through the
//! real embedding [[M_r, -M_i], [M_i, M_r]] of M = M_r + i M_i, whose singular values are those
//! of M, each twice.
template <typename Scalar>
void require_detectable(const DynamicMatrix<Scalar>& A, const DynamicMatrix<Scalar>& C,
                        std::string_view owner, Scalar eps) {
  const Eigen::Index nx = A.rows();
  const Eigen::Index ny = C.rows();
  model::numerics::ComplexVector<Scalar> eigenvalues;
  if (!model::numerics::eigenvalues<Scalar>(A, eigenvalues)) {
    ENDOHAPTICS_THROW(Error(std::string(owner) + ": eigenvalue computation of A did not converge"));
  }
  const Scalar root_eps = std::sqrt(eps);
  const Scalar scale = std::max(A.norm(), Scalar(1));
  DynamicMatrix<Scalar> C_scaled = C;
  for (Eigen::Index i = 0; i < ny; ++i) {
    const Scalar row_norm = C.row(i).norm();
    if (row_norm > Scalar(0)) C_scaled.row(i) *= scale / row_norm;
  }
  for (Eigen::Index k = 0; k < nx; ++k) {
    const std::complex<Scalar> lambda = eigenvalues(k);
    if (std::abs(lambda) < Scalar(1) - root_eps || lambda.imag() < Scalar(0)) continue;
    DynamicMatrix<Scalar> real_part(nx + ny, nx);
    real_part.topRows(nx) = -A;
    real_part.topRows(nx).diagonal().array() += lambda.real();
    real_part.bottomRows(ny) = C_scaled;
    DynamicMatrix<Scalar> pbh = real_part;
    if (lambda.imag() > Scalar(0)) {
      DynamicMatrix<Scalar> imag_part = DynamicMatrix<Scalar>::Zero(nx + ny, nx);
      imag_part.topRows(nx).diagonal().setConstant(lambda.imag());
      pbh.resize(2 * (nx + ny), 2 * nx);
      pbh << real_part, -imag_part, imag_part, real_part;
    }
    const DynamicMatrix<Scalar> gram = pbh.transpose() * pbh;
    const Scalar sigma_min =
        std::sqrt(std::max(symmetric_eigenvalues(gram, owner, "the PBH matrix")(0), Scalar(0)));
    if (sigma_min <= Scalar(10) * root_eps * scale) {
      ENDOHAPTICS_THROW(Error(std::string(owner) + ": (A, C) is not detectable: eigenvalue " +
                              format_number(lambda) +
                              " of A (|lambda| = " + format_number(std::abs(lambda)) +
                              " >= 1) is not observable from C (PBH: smallest singular value of " +
                              "[lambda I - A; C] = " + format_number(sigma_min) + ")"));
    }
  }
}

//! A P A' - A P C' (C P C' + R)^-1 C P A' + Q - P for symmetric P, Q and symmetric PD R.
template <typename Scalar>
DynamicMatrix<Scalar> filter_riccati_defect(const DynamicMatrix<Scalar>& A,
                                            const DynamicMatrix<Scalar>& C,
                                            const DynamicMatrix<Scalar>& Q,
                                            const DynamicMatrix<Scalar>& R,
                                            const DynamicMatrix<Scalar>& P) {
  const DynamicMatrix<Scalar> S = C * P * C.transpose() + R;
  const DynamicMatrix<Scalar> CPA = C * P * A.transpose();
  const DynamicMatrix<Scalar> S_inv_CPA = S.llt().solve(CPA);
  return A * P * A.transpose() - CPA.transpose() * S_inv_CPA + Q - P;
}

//! The solver behind `solve_filter_dare`, on dynamic sizes (A n x n, C m x n, Q n x n, R m x m).
//! `eps`: rounding unit of the caller's Scalar, for the structural tolerances. The residual is
//! left to the caller (it is evaluated for P rounded to the caller's Scalar).
template <typename Scalar>
DareSolution<Eigen::Dynamic, Scalar> solve_filter_dare_dynamic(
    const DynamicMatrix<Scalar>& A, const DynamicMatrix<Scalar>& C, const DynamicMatrix<Scalar>& Q,
    const DynamicMatrix<Scalar>& R, const DareOptions<Scalar>& options, Scalar eps) {
  using Matrix = DynamicMatrix<Scalar>;
  constexpr std::string_view owner = "solve_filter_dare";
  const Eigen::Index n = A.rows();
  require_finite(A, owner, "A");
  require_finite(C, owner, "C");
  require_finite(Q, owner, "Q");
  require_finite(R, owner, "R");
  if (options.max_iterations < 1) {
    ENDOHAPTICS_THROW(Error(std::string(owner) + ": max_iterations must be >= 1, got " +
                            std::to_string(options.max_iterations)));
  }
  if (!std::isfinite(options.relative_tolerance) || !(options.relative_tolerance > Scalar(0))) {
    ENDOHAPTICS_THROW(Error(std::string(owner) +
                            ": relative_tolerance must be finite and > 0, got " +
                            format_number(options.relative_tolerance)));
  }
  const Matrix Q_sym = require_covariance(Q, owner, "Q", /*definite=*/false, eps);
  const Matrix R_sym = require_covariance(R, owner, "R", /*definite=*/true, eps);
  require_detectable(A, C, owner, eps);

  // SDA (Chu, Fan, Lin & Wang 2004) on the dual control DARE, A -> A', B -> C':
  //   W = I + G H,  A+ = A W^-1 A,  G+ = G + A W^-1 G A',  H+ = H + A' H W^-1 A,
  // from A0 = A', G0 = C' R^-1 C, H0 = Q; H converges quadratically to P.
  const Matrix L_inv_C = R_sym.llt().matrixL().solve(C);
  const Matrix I = Matrix::Identity(n, n);
  Matrix Ak = A.transpose();
  Matrix G = L_inv_C.transpose() * L_inv_C;
  Matrix H = Q_sym;
  int iterations = 0;
  Scalar change = std::numeric_limits<Scalar>::infinity();  // relative, of the last step
  for (;;) {
    if (iterations == options.max_iterations) {
      ENDOHAPTICS_THROW(Error(std::string(owner) + ": no convergence after " +
                              std::to_string(iterations) + " doubling steps: relative change " +
                              format_number(change) + " > tolerance " +
                              format_number(options.relative_tolerance)));
    }
    ++iterations;
    const Eigen::PartialPivLU<Matrix> W(I + G * H);
    const Matrix W_inv_A = W.solve(Ak);
    const Matrix W_inv_G = W.solve(G);
    Matrix H_next = H + Ak.transpose() * H * W_inv_A;
    Matrix G_next = G + Ak * W_inv_G * Ak.transpose();
    H_next = (H_next + H_next.transpose()).eval() / Scalar(2);
    G_next = (G_next + G_next.transpose()).eval() / Scalar(2);
    if (!H_next.allFinite() || !G_next.allFinite()) {
      ENDOHAPTICS_THROW(Error(std::string(owner) + ": the doubling iteration overflowed at step " +
                              std::to_string(iterations)));
    }
    const Scalar step = (H_next - H).norm();
    const Scalar size = H_next.norm();
    change = size > Scalar(0) ? step / size : step;
    Ak = (Ak * W_inv_A).eval();
    G = std::move(G_next);
    H = std::move(H_next);
    if (step <= options.relative_tolerance * size) break;
  }

  // A stabilising P makes the prediction error dynamics A - A P C' (C P C' + R)^-1 C stable.
  const Matrix S = C * H * C.transpose() + R_sym;
  const Matrix S_inv_CP = S.llt().solve(C * H);
  const Matrix closed_loop = A - A * S_inv_CP.transpose() * C;
  model::numerics::ComplexVector<Scalar> poles;
  if (!model::numerics::eigenvalues<Scalar>(closed_loop, poles)) {
    ENDOHAPTICS_THROW(
        Error(std::string(owner) + ": eigenvalues of the error dynamics A - L C did not converge"));
  }
  const Scalar radius = poles.cwiseAbs().maxCoeff();
  if (!(radius < Scalar(1) - std::sqrt(eps))) {
    ENDOHAPTICS_THROW(
        Error(std::string(owner) +
              ": no stabilising solution: the error dynamics A - L C have spectral radius " +
              format_number(radius) +
              " (A has a mode on the unit circle that Q does not excite; add process noise)"));
  }

  DareSolution<Eigen::Dynamic, Scalar> solution;
  solution.iterations = iterations;
  solution.P = std::move(H);
  return solution;
}

#if defined(ENDOHAPTICS_EXTERN_NUMERICS)
// The double instantiations (the working precision of float and double models), compiled once in
// estimation/impl/dare.ipp (ENDOHAPTICS_EXTERN_NUMERICS: core/separate_compilation.hpp).
extern template DareSolution<Eigen::Dynamic, double> solve_filter_dare_dynamic<double>(
    const DynamicMatrix<double>&, const DynamicMatrix<double>&, const DynamicMatrix<double>&,
    const DynamicMatrix<double>&, const DareOptions<double>&, double);
extern template DynamicMatrix<double> filter_riccati_defect<double>(const DynamicMatrix<double>&,
                                                                    const DynamicMatrix<double>&,
                                                                    const DynamicMatrix<double>&,
                                                                    const DynamicMatrix<double>&,
                                                                    const DynamicMatrix<double>&);
#endif

}  // namespace detail

//! Solves P = A P A' - A P C' (C P C' + R)^-1 C P A' + Q for its stabilising solution (the
//! steady-state a priori covariance of the Kalman filter for x+ = A x + w, z = C x + v,
//! cov(w) = Q, cov(v) = R). Configuration time. Throws Error when an input is not finite, Q is
//! not symmetric PSD, R is not symmetric PD, (A, C) is not detectable, the options are invalid,
//! the iteration or an eigenvalue computation does not converge, or no stabilising solution
//! exists (a mode on the unit circle that Q does not excite). Same P as
//! scipy.linalg.solve_discrete_are(A.T, C.T, Q, R).
//! Computed in double (or Scalar if wider) and rounded to Scalar; tolerances use Scalar's eps.
template <int Nx, int Ny, typename Scalar>
[[nodiscard]] DareSolution<Nx, Scalar> solve_filter_dare(const Eigen::Matrix<Scalar, Nx, Nx>& A,
                                                         const Eigen::Matrix<Scalar, Ny, Nx>& C,
                                                         const Eigen::Matrix<Scalar, Nx, Nx>& Q,
                                                         const Eigen::Matrix<Scalar, Ny, Ny>& R,
                                                         const DareOptions<Scalar>& options = {}) {
  static_assert(Nx >= 1 && Ny >= 1, "solve_filter_dare needs Nx >= 1 and Ny >= 1 (fixed sizes)");
  static_assert(std::is_floating_point_v<Scalar>, "solve_filter_dare Scalar must be floating");
  using Work = detail::WorkScalar<Scalar>;
  using Dynamic = detail::DynamicMatrix<Work>;
  const Dynamic A_work = A.template cast<Work>();
  const Dynamic C_work = C.template cast<Work>();
  const Dynamic Q_work = Q.template cast<Work>();
  const Dynamic R_work = R.template cast<Work>();
  const DareOptions<Work> work_options{options.max_iterations,
                                       static_cast<Work>(options.relative_tolerance)};
  const auto dynamic = detail::solve_filter_dare_dynamic<Work>(
      A_work, C_work, Q_work, R_work, work_options,
      static_cast<Work>(std::numeric_limits<Scalar>::epsilon()));
  DareSolution<Nx, Scalar> solution;
  solution.P = dynamic.P.template cast<Scalar>();
  solution.iterations = dynamic.iterations;
  // Residual of the P handed out (rounded to Scalar), evaluated in Work precision.
  const Dynamic P_rounded = solution.P.template cast<Work>();
  const Work defect =
      detail::filter_riccati_defect<Work>(A_work, C_work, (Q_work + Q_work.transpose()) / Work(2),
                                          (R_work + R_work.transpose()) / Work(2), P_rounded)
          .norm();
  const Work size = P_rounded.norm();
  solution.residual = static_cast<Scalar>(size > Work(0) ? defect / size : defect);
  return solution;
}

}  // namespace endohaptics::estimation
