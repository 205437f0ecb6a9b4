//! @file
//! LTI state-space models: continuous eq. 4.1 (x' = A x + B u, y = C x + D u), discrete eq. 4.2
//! (x(k+1) = A x(k) + B u(k), y(k) = C x(k) + D u(k)), ZOH/Tustin discretisation, parallel and
//! series composition (4.3). Signal units are the model's; sample times in s. Sizes are fixed
//! (real time: no allocation) or Eigen::Dynamic (`DynamicStateSpace`: identification, model
//! files, configuration; see docs/architecture.md, "One linear-model type").
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/numeric_status.hpp"
#include "endohaptics/model/dense_numerics.hpp"

namespace endohaptics::model {

namespace detail {

using endohaptics::detail::format_number;  // round-trip digits in error messages

//! Configuration-time numerics (eigenvalues, LU, the matrix exponential) run on dynamic-size
//! matrices (model/dense_numerics.hpp): each decomposition is then compiled once per Scalar, not
//! once per model size. Not on the tick path.
template <typename Scalar>
using DynamicMatrix = numerics::Matrix<Scalar>;

using endohaptics::detail::require_finite;

//! Throws Error unless `sample_time` is finite and > 0.
template <typename Scalar>
void require_sample_time(Scalar sample_time, std::string_view owner) {
  if (!std::isfinite(sample_time) || !(sample_time > Scalar(0))) {
    ENDOHAPTICS_THROW(Error(std::string(owner) + ": sample time must be finite and > 0 s, got " +
                            format_number(sample_time)));
  }
}

//! True when every entry is finite (also for zero-size vectors). Branch-free: x * 0 is 0 for
//! finite x and NaN for NaN or +-Inf, so the sum is 0 exactly when all entries are finite.
template <typename Derived>
bool all_finite(const Eigen::MatrixBase<Derived>& m) noexcept {
  using Scalar = typename Derived::Scalar;
  Scalar zero_if_finite(0);
  for (Eigen::Index i = 0; i < m.size(); ++i) zero_if_finite += m.coeff(i) * Scalar(0);
  return zero_if_finite == Scalar(0);
}

//! True when two sample times agree to a few ulps (they are usually computed the same way).
template <typename Scalar>
bool same_sample_time(Scalar a, Scalar b) noexcept {
  return std::abs(a - b) <=
         Scalar(8) * std::numeric_limits<Scalar>::epsilon() * std::max(std::abs(a), std::abs(b));
}

}  // namespace detail

//! A checked tick (`update`) returns `NumericStatus` (core/numeric_status.hpp); on anything but
//! `ok` state and output are untouched.
using endohaptics::NumericStatus;

namespace detail {

//! True when a size `from` may be converted to a size `to` (equal, or either is dynamic).
constexpr bool convertible_size(int from, int to) noexcept {
  return from == to || from == Eigen::Dynamic || to == Eigen::Dynamic;
}

//! True when a model of sizes (Mx, Mu, My) may convert to (Nx, Nu, Ny), size by size.
template <int Mx, int Mu, int My, int Nx, int Nu, int Ny>
inline constexpr bool convertible_sizes = convertible_size(Mx, Nx) && convertible_size(Mu, Nu) &&
                                          convertible_size(My, Ny);

//! "2" for a fixed size, "Dynamic" for Eigen::Dynamic (error messages).
inline std::string size_name(int size) {
  return size == Eigen::Dynamic ? std::string("Dynamic") : std::to_string(size);
}

//! "r x c" of a matrix (error messages).
template <typename Derived>
std::string shape_of(const Eigen::EigenBase<Derived>& m) {
  return std::to_string(m.rows()) + " x " + std::to_string(m.cols());
}

}  // namespace detail

//! Discrete-time LTI model (eq. 4.2): x(k+1) = A x(k) + B u(k), y(k) = C x(k) + D u(k).
//! Nx >= 1 states, Nu >= 0 inputs (Nu == 0: autonomous), Ny >= 1 outputs, each fixed or
//! Eigen::Dynamic (sizes then set by the matrices at construction). Fixed sizes: the tick
//! (`step`, `update`, `output`) allocates nothing. Any dynamic size: the same arithmetic on
//! heap-allocated vectors, so every tick allocates; that form is for identification, model
//! files and configuration, converted to fixed sizes (the converting constructor) for real time.
template <int Nx, int Nu, int Ny, typename Scalar = double>
class StateSpace {
  static_assert(Nx >= 1 || Nx == Eigen::Dynamic,
                "StateSpace needs at least one state (Nx >= 1) or Eigen::Dynamic");
  static_assert(Nu >= 0 || Nu == Eigen::Dynamic,
                "StateSpace input count must be >= 0 or Eigen::Dynamic");
  static_assert(Ny >= 1 || Ny == Eigen::Dynamic,
                "StateSpace needs at least one output (Ny >= 1) or Eigen::Dynamic");
  static_assert(std::is_floating_point_v<Scalar>, "StateSpace Scalar must be floating point");

 public:
  //! State dimension, or Eigen::Dynamic (then `state_size()` gives it).
  static constexpr int states = Nx;
  //! Input dimension, or Eigen::Dynamic (then `input_size()` gives it).
  static constexpr int inputs = Nu;
  //! Output dimension, or Eigen::Dynamic (then `output_size()` gives it).
  static constexpr int outputs = Ny;
  //! True when all three sizes are fixed: the allocation-free real-time form.
  static constexpr bool fixed_size =
      Nx != Eigen::Dynamic && Nu != Eigen::Dynamic && Ny != Eigen::Dynamic;
  using ScalarType = Scalar;                                       //!< scalar type
  using State = Eigen::Matrix<Scalar, Nx, 1>;                      //!< state vector x
  using Input = Eigen::Matrix<Scalar, Nu, 1>;                      //!< input vector u
  using Output = Eigen::Matrix<Scalar, Ny, 1>;                     //!< output vector y
  using MatrixA = Eigen::Matrix<Scalar, Nx, Nx>;                   //!< state matrix A
  using MatrixB = Eigen::Matrix<Scalar, Nx, Nu>;                   //!< input matrix B
  using MatrixC = Eigen::Matrix<Scalar, Ny, Nx>;                   //!< output matrix C
  using MatrixD = Eigen::Matrix<Scalar, Ny, Nu>;                   //!< feedthrough matrix D
  using Eigenvalues = Eigen::Matrix<std::complex<Scalar>, Nx, 1>;  //!< eigenvalues of A

  //! Builds the model with zero initial state. Throws Error on a non-finite matrix entry or a
  //! sample time that is not finite and > 0 (the message names the entry and the value), and,
  //! with a dynamic size, when the sizes disagree: A must be n x n (n >= 1), B n x nu, C ny x n
  //! (ny >= 1), D ny x nu (the message gives the sizes found and expected).
  StateSpace(const MatrixA& A, const MatrixB& B, const MatrixC& C, const MatrixD& D,
             Scalar sample_time)
      : A_(A), B_(B), C_(C), D_(D), sample_time_(sample_time), x_(State::Zero(A.rows())) {
    validate();
  }

  //! The same model in other sizes (e.g. Eigen::Dynamic -> fixed) and/or another Scalar (e.g.
  //! double -> float), starting from `other`'s current state (cast). Throws Error when `other`'s
  //! sizes do not fit Nx, Nu, Ny (the message gives both), or as the main constructor (e.g. an
  //! entry that overflows in Scalar). Two different fixed sizes do not compile.
  template <int Mx, int Mu, int My, typename OtherScalar>
  requires detail::convertible_sizes<Mx, Mu, My, Nx, Nu, Ny>
  explicit StateSpace(const StateSpace<Mx, Mu, My, OtherScalar>& other)
      : A_((require_sizes_fit(other), other.A().template cast<Scalar>())),
        B_(other.B().template cast<Scalar>()),
        C_(other.C().template cast<Scalar>()),
        D_(other.D().template cast<Scalar>()),
        sample_time_(static_cast<Scalar>(other.sample_time())),
        x_(other.state().template cast<Scalar>()) {
    validate();
  }

  [[nodiscard]] const MatrixA& A() const noexcept { return A_; }  //!< state matrix
  [[nodiscard]] const MatrixB& B() const noexcept { return B_; }  //!< input matrix
  [[nodiscard]] const MatrixC& C() const noexcept { return C_; }  //!< output matrix
  [[nodiscard]] const MatrixD& D() const noexcept { return D_; }  //!< feedthrough matrix
  //! Number of states n (Nx when fixed).
  [[nodiscard]] int state_size() const noexcept { return static_cast<int>(A_.rows()); }
  //! Number of inputs nu (Nu when fixed).
  [[nodiscard]] int input_size() const noexcept { return static_cast<int>(B_.cols()); }
  //! Number of outputs ny (Ny when fixed).
  [[nodiscard]] int output_size() const noexcept { return static_cast<int>(C_.rows()); }
  //! Sample time the model was identified or discretised at, s.
  [[nodiscard]] Scalar sample_time() const noexcept { return sample_time_; }
  //! Current state x(k).
  [[nodiscard]] const State& state() const noexcept { return x_; }

  //! Sets the state to zero.
  void reset() noexcept { x_.setZero(); }

  //! Sets the state to `x0`. With a dynamic state size, throws Error unless x0 has
  //! `state_size()` entries (the state is then unchanged).
  void reset(const State& x0) noexcept(Nx != Eigen::Dynamic) {
    if constexpr (Nx == Eigen::Dynamic) {
      if (x0.size() != x_.size()) {
        ENDOHAPTICS_THROW(Error("StateSpace::reset: x0 has " + std::to_string(x0.size()) +
                                " entries, the model " + std::to_string(x_.size()) + " states"));
      }
    }
    x_ = x0;
  }

  //! y(k) = C x(k) + D u(k) at the current state; does not advance.
  //! Precondition: u has `input_size()` entries (checked by the type when fixed).
  [[nodiscard]] Output output(const Input& u) const noexcept {
    ENDOHAPTICS_ASSERT(u.size() == B_.cols());
    Output y = C_ * x_;
    if constexpr (Nu != 0) y.noalias() += D_ * u;
    return y;
  }

  //! One tick: returns y(k) = C x(k) + D u(k), then advances x(k+1) = A x(k) + B u(k).
  //! A NaN/Inf input propagates into the state (no UB); `reset` recovers.
  //! Precondition: u has `input_size()` entries.
  Output step(const Input& u) noexcept {
    const Output y = output(u);
    State next = A_ * x_;
    if constexpr (Nu != 0) next.noalias() += B_ * u;
    x_ = next;
    return y;
  }

  //! Checked tick: like `step`, but refuses a non-finite input or result. Writes y(k) into `y`
  //! and advances only on `ok`; otherwise state and `y` are untouched.
  //! Precondition: u has `input_size()` entries.
  [[nodiscard]] NumericStatus update(const Input& u, Output& y) noexcept {
    if (!detail::all_finite(u)) return NumericStatus::non_finite_input;
    const Output y_now = output(u);
    State next = A_ * x_;
    if constexpr (Nu != 0) next.noalias() += B_ * u;
    if (!detail::all_finite(y_now) || !detail::all_finite(next)) {
      return NumericStatus::non_finite_result;
    }
    y = y_now;
    x_ = next;
    return NumericStatus::ok;
  }

  //! Steps once per input column from the current state (like scipy.signal.dlsim) and returns
  //! one output column per sample; the state is left at x(k + N).
  template <int N>
  [[nodiscard]] Eigen::Matrix<Scalar, Ny, N> simulate(
      const Eigen::Matrix<Scalar, Nu, N>& inputs_per_sample) noexcept {
    static_assert(N >= 1, "simulate needs a fixed number N >= 1 of samples");
    Eigen::Matrix<Scalar, Ny, N> y;
    if constexpr (Ny == Eigen::Dynamic) y.resize(C_.rows(), N);
    for (int k = 0; k < N; ++k) y.col(k) = step(inputs_per_sample.col(k));
    return y;
  }

  //! Eigenvalues (poles) of A. Configuration time: throws Error if the QR iteration fails.
  [[nodiscard]] Eigenvalues eigenvalues() const {
    numerics::ComplexVector<Scalar> values;
    if (!numerics::eigenvalues<Scalar>(detail::DynamicMatrix<Scalar>(A_), values)) {
      ENDOHAPTICS_THROW(Error("StateSpace: eigenvalue computation of A did not converge"));
    }
    return values;
  }

  //! max |lambda_i(A)|: the model is asymptotically stable when this is < 1.
  [[nodiscard]] Scalar spectral_radius() const { return eigenvalues().cwiseAbs().maxCoeff(); }

  //! True when every pole lies strictly inside the unit circle.
  [[nodiscard]] bool is_stable() const { return spectral_radius() < Scalar(1); }

  //! Steady-state gain C (I - A)^-1 B + D (ny x nu). Throws Error if I - A is singular
  //! (a pole at z = 1, e.g. an integrator).
  [[nodiscard]] MatrixD dc_gain() const {
    const auto lu = numerics::lu_solve<Scalar>(
        detail::DynamicMatrix<Scalar>(MatrixA::Identity(A_.rows(), A_.cols()) - A_),
        detail::DynamicMatrix<Scalar>(B_));
    if (!lu.invertible) {
      ENDOHAPTICS_THROW(Error("StateSpace: DC gain undefined, I - A is singular (rank " +
                              std::to_string(lu.rank) + " of " + std::to_string(A_.rows()) +
                              "; A has a pole at z = 1)"));
    }
    if constexpr (Nu == 0) {
      return MatrixD{};
    } else {
      const MatrixB X = lu.X;
      return C_ * X + D_;
    }
  }

 private:
  //! Throws Error unless `other`'s sizes fit Nx, Nu, Ny (a dynamic size takes any).
  template <typename Other>
  static void require_sizes_fit(const Other& other) {
    const auto fits = [](int wanted, int size) {
      return wanted == Eigen::Dynamic || wanted == size;
    };
    if (!fits(Nx, other.state_size()) || !fits(Nu, other.input_size()) ||
        !fits(Ny, other.output_size())) {
      ENDOHAPTICS_THROW(Error("StateSpace: cannot convert a model with " +
                              std::to_string(other.state_size()) + " states, " +
                              std::to_string(other.input_size()) + " inputs, " +
                              std::to_string(other.output_size()) + " outputs into StateSpace<" +
                              detail::size_name(Nx) + ", " + detail::size_name(Nu) + ", " +
                              detail::size_name(Ny) + ">"));
    }
  }

  //! The constructors' checks: sizes (dynamic only), finite entries, sample time.
  void validate() const {
    if constexpr (!fixed_size) {
      const Eigen::Index n = A_.rows();
      if (n < 1 || A_.cols() != n) {
        ENDOHAPTICS_THROW(Error("StateSpace: A is " + detail::shape_of(A_) +
                                ", expected n x n with n >= 1 states"));
      }
      const std::string n_text = std::to_string(n);
      if (B_.rows() != n) {
        ENDOHAPTICS_THROW(Error("StateSpace: B is " + detail::shape_of(B_) + ", expected " +
                                n_text + " x nu (A has " + n_text + " states)"));
      }
      if (C_.rows() < 1 || C_.cols() != n) {
        ENDOHAPTICS_THROW(Error("StateSpace: C is " + detail::shape_of(C_) + ", expected ny x " +
                                n_text + " with ny >= 1 outputs (A has " + n_text + " states)"));
      }
      if (D_.rows() != C_.rows() || D_.cols() != B_.cols()) {
        ENDOHAPTICS_THROW(Error("StateSpace: D is " + detail::shape_of(D_) + ", expected " +
                                std::to_string(C_.rows()) + " x " + std::to_string(B_.cols()) +
                                " (outputs of C x inputs of B)"));
      }
    }
    detail::require_finite(A_, "StateSpace", "A");
    detail::require_finite(B_, "StateSpace", "B");
    detail::require_finite(C_, "StateSpace", "C");
    detail::require_finite(D_, "StateSpace", "D");
    detail::require_sample_time(sample_time_, "StateSpace");
  }

  MatrixA A_;
  MatrixB B_;
  MatrixC C_;
  MatrixD D_;
  Scalar sample_time_;
  State x_;
};

//! The configuration-time form: every size set at run time by the matrices (see StateSpace).
template <typename Scalar = double>
using DynamicStateSpace = StateSpace<Eigen::Dynamic, Eigen::Dynamic, Eigen::Dynamic, Scalar>;

//! `m` realised with `states` >= m.state_size() states, so that a lower-order model runs in a
//! fixed-size type of that many states (e.g. the bridge's 6-state clamp model). The added states
//! are decoupled and stay zero: A = diag(A_m, 0), B = [B_m; 0], C = [C_m 0], x = [x_m; 0]. The
//! input-output behaviour is exactly m's, from any initial state of m; the spectral radius is
//! m's. Throws Error when `states` is smaller than m's order.
template <typename Scalar>
[[nodiscard]] DynamicStateSpace<Scalar> embed_states(const DynamicStateSpace<Scalar>& m,
                                                     int states) {
  const int n = m.state_size();
  if (states < n) {
    ENDOHAPTICS_THROW(Error("embed_states: a model of order " + std::to_string(n) +
                            " does not fit in " + std::to_string(states) + " states"));
  }
  using Matrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  Matrix A = Matrix::Zero(states, states);
  Matrix B = Matrix::Zero(states, m.input_size());
  Matrix C = Matrix::Zero(m.output_size(), states);
  A.topLeftCorner(n, n) = m.A();
  B.topRows(n) = m.B();
  C.leftCols(n) = m.C();
  DynamicStateSpace<Scalar> out(A, B, C, m.D(), m.sample_time());
  Eigen::Matrix<Scalar, Eigen::Dynamic, 1> x =
      Eigen::Matrix<Scalar, Eigen::Dynamic, 1>::Zero(states);
  x.head(n) = m.state();
  out.reset(x);
  return out;
}

//! Continuous-time LTI model (eq. 4.1): x' = A x + B u, y = C x + D u. Only a description to
//! be discretised with `discretize_zoh` or `discretize_tustin`; it has no state.
template <int Nx, int Nu, int Ny, typename Scalar = double>
class ContinuousStateSpace {
  static_assert(Nx >= 1, "ContinuousStateSpace needs at least one state (Nx >= 1)");
  static_assert(Nu >= 0, "ContinuousStateSpace input count must be >= 0");
  static_assert(Ny >= 1, "ContinuousStateSpace needs at least one output (Ny >= 1)");
  static_assert(std::is_floating_point_v<Scalar>,
                "ContinuousStateSpace Scalar must be floating point");

 public:
  static constexpr int states = Nx;               //!< state dimension
  static constexpr int inputs = Nu;               //!< input dimension
  static constexpr int outputs = Ny;              //!< output dimension
  using ScalarType = Scalar;                      //!< scalar type
  using State = Eigen::Matrix<Scalar, Nx, 1>;     //!< state vector x
  using Input = Eigen::Matrix<Scalar, Nu, 1>;     //!< input vector u
  using Output = Eigen::Matrix<Scalar, Ny, 1>;    //!< output vector y
  using MatrixA = Eigen::Matrix<Scalar, Nx, Nx>;  //!< state matrix A
  using MatrixB = Eigen::Matrix<Scalar, Nx, Nu>;  //!< input matrix B
  using MatrixC = Eigen::Matrix<Scalar, Ny, Nx>;  //!< output matrix C
  using MatrixD = Eigen::Matrix<Scalar, Ny, Nu>;  //!< feedthrough matrix D

  //! Throws Error on a non-finite matrix entry (the message names the entry and the value).
  ContinuousStateSpace(const MatrixA& A, const MatrixB& B, const MatrixC& C, const MatrixD& D)
      : A_(A), B_(B), C_(C), D_(D) {
    detail::require_finite(A_, "ContinuousStateSpace", "A");
    detail::require_finite(B_, "ContinuousStateSpace", "B");
    detail::require_finite(C_, "ContinuousStateSpace", "C");
    detail::require_finite(D_, "ContinuousStateSpace", "D");
  }

  [[nodiscard]] const MatrixA& A() const noexcept { return A_; }  //!< state matrix, 1/s
  [[nodiscard]] const MatrixB& B() const noexcept { return B_; }  //!< input matrix
  [[nodiscard]] const MatrixC& C() const noexcept { return C_; }  //!< output matrix
  [[nodiscard]] const MatrixD& D() const noexcept { return D_; }  //!< feedthrough matrix

 private:
  MatrixA A_;
  MatrixB B_;
  MatrixC C_;
  MatrixD D_;
};

//! Zero-order-hold discretisation (scipy cont2discrete 'zoh'): Van Loan's block exponential
//! expm([[A, B], [0, 0]] Ts) = [[Ad, Bd], [0, I]]; Cd = C, Dd = D. Throws Error on a bad Ts.
template <int Nx, int Nu, int Ny, typename Scalar>
[[nodiscard]] StateSpace<Nx, Nu, Ny, Scalar> discretize_zoh(
    const ContinuousStateSpace<Nx, Nu, Ny, Scalar>& continuous, Scalar sample_time) {
  detail::require_sample_time(sample_time, "discretize_zoh");
  constexpr int n = Nx + Nu;
  detail::DynamicMatrix<Scalar> M = detail::DynamicMatrix<Scalar>::Zero(n, n);
  M.template topLeftCorner<Nx, Nx>() = continuous.A() * sample_time;
  if constexpr (Nu > 0) M.template topRightCorner<Nx, Nu>() = continuous.B() * sample_time;
  const detail::DynamicMatrix<Scalar> E = numerics::exp<Scalar>(M);
  typename StateSpace<Nx, Nu, Ny, Scalar>::MatrixB Bd;
  if constexpr (Nu > 0) Bd = E.template topRightCorner<Nx, Nu>();
  return StateSpace<Nx, Nu, Ny, Scalar>(E.template topLeftCorner<Nx, Nx>(), Bd, continuous.C(),
                                        continuous.D(), sample_time);
}

//! Tustin (bilinear) discretisation, as scipy cont2discrete 'bilinear' (gbt, alpha = 1/2):
//! M = I - A Ts/2, Ad = M^-1 (I + A Ts/2), Bd = M^-1 B Ts, Cd = C M^-1, Dd = D + C Bd / 2.
//! Throws Error on a bad Ts or when I - A Ts/2 is singular (a pole at s = 2/Ts).
template <int Nx, int Nu, int Ny, typename Scalar>
[[nodiscard]] StateSpace<Nx, Nu, Ny, Scalar> discretize_tustin(
    const ContinuousStateSpace<Nx, Nu, Ny, Scalar>& continuous, Scalar sample_time) {
  detail::require_sample_time(sample_time, "discretize_tustin");
  using SS = StateSpace<Nx, Nu, Ny, Scalar>;
  const Scalar half = sample_time / Scalar(2);
  const typename SS::MatrixA I = SS::MatrixA::Identity();
  const detail::DynamicMatrix<Scalar> M = I - continuous.A() * half;
  // [Ad, Bd, M^-1] = M^-1 [I + A Ts/2, B Ts, I] in one solve.
  detail::DynamicMatrix<Scalar> R(Nx, Nx + Nu + Nx);
  R.leftCols(Nx) = I + continuous.A() * half;
  if constexpr (Nu > 0) R.middleCols(Nx, Nu) = continuous.B() * sample_time;
  R.rightCols(Nx) = I;
  const auto solved = numerics::lu_solve<Scalar>(M, R);
  if (!solved.invertible) {
    ENDOHAPTICS_THROW(Error(
        "discretize_tustin: I - A Ts/2 is singular for Ts = " + detail::format_number(sample_time) +
        " s (A has an eigenvalue at 2/Ts)"));
  }
  const typename SS::MatrixA Ad = solved.X.leftCols(Nx);
  typename SS::MatrixB Bd;
  typename SS::MatrixD Dd = continuous.D();
  if constexpr (Nu > 0) {
    Bd = solved.X.middleCols(Nx, Nu);
    Dd += continuous.C() * Bd / Scalar(2);
  }
  const typename SS::MatrixC Cd = continuous.C() * solved.X.rightCols(Nx);  // C M^-1
  return SS(Ad, Bd, Cd, Dd, sample_time);
}

//! Parallel (block-diagonal) composition, worksheet eq. 4.3: states, inputs and outputs are
//! stacked [first; second]. The result starts from the stacked current states. Fixed sizes
//! only. Throws Error when the sample times differ.
template <int Nx1, int Nu1, int Ny1, int Nx2, int Nu2, int Ny2, typename Scalar>
requires(
    StateSpace<Nx1, Nu1, Ny1, Scalar>::fixed_size&& StateSpace<Nx2, Nu2, Ny2, Scalar>::fixed_size)
    [[nodiscard]] StateSpace<Nx1 + Nx2, Nu1 + Nu2, Ny1 + Ny2, Scalar> parallel(
        const StateSpace<Nx1, Nu1, Ny1, Scalar>& first,
        const StateSpace<Nx2, Nu2, Ny2, Scalar>& second) {
  if (!detail::same_sample_time(first.sample_time(), second.sample_time())) {
    ENDOHAPTICS_THROW(Error("parallel: sample times differ (" +
                            detail::format_number(first.sample_time()) + " s and " +
                            detail::format_number(second.sample_time()) + " s)"));
  }
  using SS = StateSpace<Nx1 + Nx2, Nu1 + Nu2, Ny1 + Ny2, Scalar>;
  typename SS::MatrixA A = SS::MatrixA::Zero();
  typename SS::MatrixB B = SS::MatrixB::Zero();
  typename SS::MatrixC C = SS::MatrixC::Zero();
  typename SS::MatrixD D = SS::MatrixD::Zero();
  A.template topLeftCorner<Nx1, Nx1>() = first.A();
  A.template bottomRightCorner<Nx2, Nx2>() = second.A();
  if constexpr (Nu1 > 0) {
    B.template topLeftCorner<Nx1, Nu1>() = first.B();
    D.template topLeftCorner<Ny1, Nu1>() = first.D();
  }
  if constexpr (Nu2 > 0) {
    B.template bottomRightCorner<Nx2, Nu2>() = second.B();
    D.template bottomRightCorner<Ny2, Nu2>() = second.D();
  }
  C.template topLeftCorner<Ny1, Nx1>() = first.C();
  C.template bottomRightCorner<Ny2, Nx2>() = second.C();
  SS result(A, B, C, D, first.sample_time());
  typename SS::State x0;
  x0 << first.state(), second.state();
  result.reset(x0);
  return result;
}

//! Series composition: the output of `first` feeds the input of `second` (y = G2 G1 u). State
//! [x1; x2]; A = [[A1, 0], [B2 C1, A2]], B = [B1; B2 D1], C = [D2 C1, C2], D = D2 D1.
//! Requires Ny1 == Nu2 and fixed sizes. The result starts from the stacked current states.
//! Throws Error when the sample times differ.
template <int Nx1, int Nu1, int Ny1, int Nx2, int Nu2, int Ny2, typename Scalar>
requires(Ny1 == Nu2 && StateSpace<Nx1, Nu1, Ny1, Scalar>::fixed_size &&
         StateSpace<Nx2, Nu2, Ny2, Scalar>::fixed_size)
    [[nodiscard]] StateSpace<Nx1 + Nx2, Nu1, Ny2, Scalar> series(
        const StateSpace<Nx1, Nu1, Ny1, Scalar>& first,
        const StateSpace<Nx2, Nu2, Ny2, Scalar>& second) {
  if (!detail::same_sample_time(first.sample_time(), second.sample_time())) {
    ENDOHAPTICS_THROW(Error("series: sample times differ (" +
                            detail::format_number(first.sample_time()) + " s and " +
                            detail::format_number(second.sample_time()) + " s)"));
  }
  using SS = StateSpace<Nx1 + Nx2, Nu1, Ny2, Scalar>;
  typename SS::MatrixA A = SS::MatrixA::Zero();
  typename SS::MatrixB B = SS::MatrixB::Zero();
  typename SS::MatrixC C;
  typename SS::MatrixD D = SS::MatrixD::Zero();
  A.template topLeftCorner<Nx1, Nx1>() = first.A();
  A.template bottomLeftCorner<Nx2, Nx1>() = second.B() * first.C();
  A.template bottomRightCorner<Nx2, Nx2>() = second.A();
  C.template leftCols<Nx1>() = second.D() * first.C();
  C.template rightCols<Nx2>() = second.C();
  if constexpr (Nu1 > 0) {
    B.template topRows<Nx1>() = first.B();
    B.template bottomRows<Nx2>() = second.B() * first.D();
    D = second.D() * first.D();
  }
  SS result(A, B, C, D, first.sample_time());
  typename SS::State x0;
  x0 << first.state(), second.state();
  result.reset(x0);
  return result;
}

}  // namespace endohaptics::model
