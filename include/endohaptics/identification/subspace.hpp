//! @file
//! Subspace identification of discrete MIMO state-space models x(k+1) = A x(k) + B u(k),
//! y(k) = C x(k) + D u(k) (eq. 4.2, worksheet 4.2): MOESP, N4SID and CVA weightings of the
//! projected block-Hankel data (Van Overschee & De Moor 1996, theorem 2; MATLAB n4sid N4Weight),
//! A, C by shift invariance, B, D, x0 by least squares. Configuration time: dynamic Eigen sizes,
//! throws Error. Signals in the data's units, sample time in s. See docs/models/subspace.md.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/model/state_space.hpp"

namespace endohaptics::identification {

//! Weighting of the oblique projection O = Yf /_Uf Wp before the SVD (W1 O W2).
enum class Weighting : std::uint8_t {
  moesp = 0,  //!< W1 = I, W2 = projection onto the complement of Uf (PO-MOESP, SLICOT 'M')
  n4sid,      //!< W1 = I, W2 = I (unit weights, SLICOT 'N')
  cva,        //!< W1 = (Yf/Uf-perp Yf/Uf-perp^T)^-1/2, W2 as MOESP (canonical variates)
};

//! Lower-case name of a weighting ("moesp", "n4sid", "cva").
[[nodiscard]] constexpr std::string_view to_string(Weighting weighting) noexcept {
  switch (weighting) {
    case Weighting::moesp:
      return "moesp";
    case Weighting::n4sid:
      return "n4sid";
    case Weighting::cva:
      return "cva";
  }
  return "unknown";
}

//! Weighting named `name` (as `to_string` writes it, case-sensitive). Throws Error otherwise.
[[nodiscard]] inline Weighting weighting_from_string(std::string_view name) {
  for (const Weighting w : {Weighting::moesp, Weighting::n4sid, Weighting::cva}) {
    if (name == to_string(w)) return w;
  }
  ENDOHAPTICS_THROW(Error("identification: unknown weighting \"" + std::string(name) +
                          "\" (expected moesp, n4sid or cva)"));
}

//! One experiment: u is N x nu (one row per sample), y is N x ny, same N.
struct DataSet {
  Eigen::MatrixXd u;  //!< inputs, one row per sample
  Eigen::MatrixXd y;  //!< outputs, one row per sample
};

//! Options of `identify`. Defaults: MOESP, automatic order in 1..10, automatic block rows.
struct SubspaceOptions {
  Weighting weighting = Weighting::moesp;  //!< projection weighting
  int order = 0;                           //!< model order n >= 1; 0: automatic (select_order)
  int max_order = 10;                      //!< largest order the automatic choice considers
  int block_rows = 0;                      //!< horizon s (block rows); 0: default_block_rows
  bool estimate_d = true;                  //!< false: D = 0 (strictly proper model)
  bool estimate_x0 = true;                 //!< false: x0 = 0 in the B, D regression
  double gap_ratio = 0.5;                  //!< order rule: keep gaps >= ratio x largest, (0, 1]
  double sample_time = 1.0;                //!< s, stored in the result (the data has none)
  //! N4SID only: the largest ||O|| / ||Yf|| (Frobenius) of the oblique projection accepted, > 0.
  //! Above it the future inputs and the past data are nearly collinear (e.g. an input low-pass
  //! filtered far below the Nyquist frequency) and O is mostly amplified noise: `identify` throws
  //! Error instead of returning that model. Infinity: no check. See docs/models/subspace.md.
  double max_projection_gain = 1e3;
  //! Scale each input and output column to unit RMS before the fit (the model is scaled back):
  //! automatic does it when a column's RMS lies outside [1e-6, 1e6], where the sums of squares
  //! of the LQ factorisation lose precision or overflow, and otherwise leaves the data as given
  //! (results and singular values then match SLICOT and MATLAB, which do not scale).
  enum class Scaling : std::uint8_t { automatic, unit_rms, none };
  Scaling scaling = Scaling::automatic;  //!< see Scaling
};

//! An identified model and what identification adds to it. The model itself is the library's
//! one linear-model type, `model::DynamicStateSpace<>` (A, B, C, D, sample time; its state is
//! the initial state of the first data set): convert it to a fixed size for real time with
//! StateSpace's converting constructor, `model::StateSpace<Nx, Nu, Ny>(m.state_space)`. An
//! aggregate without a default constructor (a StateSpace has no empty state): `identify`, or
//! `SubspaceModel{.state_space = ..., ...}`, builds it complete.
struct SubspaceModel {
  model::DynamicStateSpace<> state_space;         //!< the model; state() = x0 of data set 0
  std::vector<Eigen::VectorXd> initial_states{};  //!< initial state of every data set
  //! Singular values of the weighted projection, descending (MATLAB's order plot); for CVA the
  //! canonical correlations.
  Eigen::VectorXd singular_values{};
  //! Singular values the automatic order rule used: MOESP's (L32), whatever the weighting.
  Eigen::VectorXd order_singular_values{};
  int order = 0;                           //!< n
  int block_rows = 0;                      //!< horizon s used (0: not a subspace result)
  Weighting weighting = Weighting::moesp;  //!< weighting used
  //! What `identify` divided each input column by before the fit (its RMS, units of u; all 1
  //! when it did not scale: SubspaceOptions::scaling).
  Eigen::VectorXd input_scale{};
  Eigen::VectorXd output_scale{};  //!< the same for each output column (units of y)
};

namespace detail::subspace {

using Matrix = Eigen::MatrixXd;
using Vector = Eigen::VectorXd;
using Index = Eigen::Index;

using endohaptics::detail::fail;

using endohaptics::detail::format_number;

inline std::string idx(Index value) { return std::to_string(value); }

//! Throws Error naming `what`, its (row, col) and the value when an entry is NaN or +-Inf.
inline void require_finite(const Matrix& m, const std::string& what) {
  endohaptics::detail::require_finite(m, {}, what);
}

//! The matrices of a linear model, whatever type held them.
struct Matrices {
  Matrix A, B, C, D;
};

template <int Nx, int Nu, int Ny, typename Scalar>
Matrices matrices_of(const model::StateSpace<Nx, Nu, Ny, Scalar>& m) {
  return {m.A().template cast<double>(), m.B().template cast<double>(),
          m.C().template cast<double>(), m.D().template cast<double>()};
}

inline Matrices matrices_of(const SubspaceModel& m) { return matrices_of(m.state_space); }

//! Checks u (N x nu) against a model with nu inputs; `where` names the caller.
inline void check_input(const Matrices& m, const Matrix& u, const char* where) {
  if (u.cols() != m.B.cols()) {
    fail(std::string(where) + ": u has " + idx(u.cols()) + " columns, the model " +
         idx(m.B.cols()) + " inputs");
  }
  require_finite(u, std::string(where) + ": u");
}

//! y (N x ny) from x0 (n); plain loop over the samples with preallocated vectors.
inline Matrix simulate(const Matrices& m, const Matrix& u, const Vector& x0) {
  const Index n = m.A.rows();
  Matrix y(u.rows(), m.C.rows());
  Vector x = x0;
  Vector next(n);
  for (Index k = 0; k < u.rows(); ++k) {
    y.row(k).noalias() = (m.C * x).transpose();
    y.row(k).noalias() += u.row(k) * m.D.transpose();
    next.noalias() = m.A * x;
    next.noalias() += m.B * u.row(k).transpose();
    x.swap(next);
  }
  return y;
}

//! O (N ny x n): row block k is C A^k, the free response to each unit initial state.
inline Matrix free_response(const Matrix& A, const Matrix& C, Index samples) {
  const Index n = A.rows();
  const Index ny = C.rows();
  Matrix O(samples * ny, n);
  Matrix Z = Matrix::Identity(n, n);
  Matrix next(n, n);
  for (Index k = 0; k < samples; ++k) {
    O.middleRows(k * ny, ny).noalias() = C * Z;
    next.noalias() = A * Z;
    Z.swap(next);
  }
  return O;
}

//! Least squares solution of Phi theta = rhs with columns scaled to unit norm first
//! (the x0 columns of a slow or unstable model can be orders of magnitude larger).
inline Vector scaled_least_squares(Matrix Phi, const Vector& rhs, const char* where) {
  if (!Phi.allFinite()) {
    fail(std::string(where) +
         ": the regression overflowed (the model is too unstable for this many samples)");
  }
  Vector scale(Phi.cols());
  for (Index j = 0; j < Phi.cols(); ++j) {
    const double norm = Phi.col(j).stableNorm();  // no overflow for columns of 1e150
    scale[j] = norm > 0.0 ? 1.0 / norm : 1.0;
    Phi.col(j) *= scale[j];
  }
  const Eigen::ColPivHouseholderQR<Matrix> qr(Phi);
  Vector theta = qr.solve(rhs);
  return theta.cwiseProduct(scale);
}

//! x0 minimising ||y - simulate(m, u, x0)|| (MATLAB findstates / compare 'InitialCondition' e).
inline Vector estimate_initial_state(const Matrices& m, const Matrix& u, const Matrix& y,
                                     const char* where) {
  check_input(m, u, where);
  if (y.cols() != m.C.rows() || y.rows() != u.rows()) {
    fail(std::string(where) + ": y is " + idx(y.rows()) + " x " + idx(y.cols()) + ", expected " +
         idx(u.rows()) + " x " + idx(m.C.rows()) + " (samples x outputs)");
  }
  require_finite(y, std::string(where) + ": y");
  const Index n = m.A.rows();
  const Matrix residual = y - simulate(m, u, Vector::Zero(n));
  const Matrix residual_t = residual.transpose();  // sample-major, like free_response's rows
  const Eigen::Map<const Vector> rhs(residual_t.data(), residual_t.size());
  return scaled_least_squares(free_response(m.A, m.C, u.rows()), rhs, where);
}

//! RMS of every column of `part` (&DataSet::u or &DataSet::y) over all data sets, computed
//! without overflow or underflow (each column divided by its largest magnitude first); 1 for an
//! all-zero column.
inline Vector column_rms(std::span<const DataSet> data, Matrix DataSet::*part) {
  const Index cols = (data.front().*part).cols();
  Vector peak = Vector::Zero(cols);
  Index rows = 0;
  for (const DataSet& d : data) {
    const Matrix& m = d.*part;
    for (Index j = 0; j < cols && m.rows() > 0; ++j) {
      peak[j] = std::max(peak[j], m.col(j).cwiseAbs().maxCoeff());
    }
    rows += m.rows();
  }
  Vector sum = Vector::Zero(cols);
  for (const DataSet& d : data) {
    for (Index j = 0; j < cols; ++j) {
      if (peak[j] > 0.0) sum[j] += ((d.*part).col(j) / peak[j]).squaredNorm();
    }
  }
  Vector rms = Vector::Ones(cols);
  for (Index j = 0; j < cols; ++j) {
    if (peak[j] > 0.0 && rows > 0) {
      rms[j] = peak[j] * std::sqrt(sum[j] / static_cast<double>(rows));
    }
  }
  return rms;
}

//! Least-squares B, D and one x0 per data set for given A, C: the output is linear in them
//! (y(k) = C A^k x0 + sum_t C A^(k-1-t) B u(t) + D u(k)); SLICOT IB01CD's approach.
struct Regressed {
  Matrix B, D;
  std::vector<Vector> x0;
};

//! `row_weights` (optional, one N x ny matrix per data set) weights each equation, e.g. 0 for
//! samples a later output saturation clipped.
inline Regressed regress_b_d_x0(const Matrix& A, const Matrix& C, std::span<const DataSet> data,
                                bool estimate_d, bool estimate_x0,
                                const std::vector<Matrix>* row_weights = nullptr) {
  const Index n = A.rows();
  const Index ny = C.rows();
  const Index nu = data.front().u.cols();
  const auto sets = static_cast<Index>(data.size());
  Index rows = 0;
  for (const DataSet& d : data) rows += d.u.rows() * ny;
  const Index x0_columns = estimate_x0 ? n * sets : 0;
  const Index b_columns = n * nu;
  const Index d_columns = estimate_d ? ny * nu : 0;
  Matrix Phi = Matrix::Zero(rows, x0_columns + b_columns + d_columns);
  Vector rhs(rows);
  Index row = 0;
  Matrix X(n, n * nu);  // column j*n + i: state driven by input j through B = e_i
  Matrix next(n, n * nu);
  for (Index e = 0; e < sets; ++e) {
    const DataSet& d = data[static_cast<std::size_t>(e)];
    const Index N = d.u.rows();
    if (estimate_x0) Phi.block(row, e * n, N * ny, n) = free_response(A, C, N);
    X.setZero();
    for (Index k = 0; k < N; ++k) {
      const Index r = row + k * ny;
      Phi.block(r, x0_columns, ny, b_columns).noalias() = C * X;
      if (estimate_d) {
        for (Index j = 0; j < nu; ++j) {
          for (Index i = 0; i < ny; ++i)
            Phi(r + i, x0_columns + b_columns + j * ny + i) = d.u(k, j);
        }
      }
      rhs.segment(r, ny) = d.y.row(k).transpose();
      next.noalias() = A * X;
      for (Index j = 0; j < nu; ++j) next.block(0, j * n, n, n).diagonal().array() += d.u(k, j);
      X.swap(next);
    }
    if (row_weights != nullptr) {
      const Matrix& w = (*row_weights)[static_cast<std::size_t>(e)];
      for (Index k = 0; k < N; ++k) {
        for (Index i = 0; i < ny; ++i) {
          Phi.row(row + k * ny + i) *= w(k, i);
          rhs[row + k * ny + i] *= w(k, i);
        }
      }
    }
    row += N * ny;
  }
  const Vector theta = scaled_least_squares(std::move(Phi), rhs, "identify (B, D, x0)");
  Regressed out;
  for (Index e = 0; e < sets; ++e) {
    out.x0.push_back(estimate_x0 ? Vector(theta.segment(e * n, n)) : Vector(Vector::Zero(n)));
  }
  out.B = Eigen::Map<const Matrix>(theta.data() + x0_columns, n, nu);
  out.D = estimate_d
              ? Matrix(Eigen::Map<const Matrix>(theta.data() + x0_columns + b_columns, ny, nu))
              : Matrix(Matrix::Zero(ny, nu));
  return out;
}

}  // namespace detail::subspace

//! The automatic order rule (documented in docs/models/subspace.md): with log gaps
//! g_n = ln(sv_n / max(sv_(n+1), 1e-10 sv_1)) for n = 1..min(max_order, size - 1), the order is
//! the largest n whose gap is at least `gap_ratio` x the largest gap (gap_ratio = 1: SLICOT's
//! largest gap). Precondition: `singular_values` descending. Throws Error on fewer than 2
//! values, max_order < 1 or gap_ratio outside (0, 1].
[[nodiscard]] inline int select_order(const Eigen::VectorXd& singular_values, int max_order,
                                      double gap_ratio = 0.5) {
  using detail::subspace::fail;
  using endohaptics::detail::format_number;
  if (singular_values.size() < 2) {
    fail("select_order: needs at least 2 singular values, got " +
         std::to_string(singular_values.size()));
  }
  if (max_order < 1) fail("select_order: max_order must be >= 1, got " + std::to_string(max_order));
  if (!(gap_ratio > 0.0 && gap_ratio <= 1.0)) {
    fail("select_order: gap_ratio must be in (0, 1], got " + format_number(gap_ratio));
  }
  if (!(singular_values[0] > 0.0)) return 1;  // no signal at all
  const auto count =
      std::min<Eigen::Index>(max_order, singular_values.size() - 1);  // candidate orders 1..count
  const double floor = 1e-10 * singular_values[0];
  std::vector<double> gap(static_cast<std::size_t>(count));
  double largest = -std::numeric_limits<double>::infinity();
  for (Eigen::Index n = 1; n <= count; ++n) {
    const double g =
        std::log(std::max(singular_values[n - 1], floor) / std::max(singular_values[n], floor));
    gap[static_cast<std::size_t>(n - 1)] = g;
    largest = std::max(largest, g);
  }
  int order = 1;
  for (Eigen::Index n = 1; n <= count; ++n) {
    if (gap[static_cast<std::size_t>(n - 1)] >= gap_ratio * largest) order = static_cast<int>(n);
  }
  return order;
}

//! Default horizon s: max(15, ceil(max_order / ny) + 1, order + 1) (SLICOT's dryer example
//! uses 15), reduced to what the data allows (sum of N_e - 2s + 1 >= 2s(nu + ny) columns).
//! Returns 0 when even the minimum does not fit (`identify` then throws).
[[nodiscard]] inline int default_block_rows(Eigen::Index total_samples, int data_sets, int nu,
                                            int ny, int max_order) {
  const int minimum = std::max(2, (max_order + ny - 1) / ny + 1);
  int s = std::max(15, minimum);
  auto fits = [&](int rows) {
    return total_samples - static_cast<Eigen::Index>(data_sets) * (2 * rows - 1) >=
           static_cast<Eigen::Index>(2 * rows * (nu + ny));
  };
  while (s > minimum && !fits(s)) --s;
  return fits(s) ? s : 0;
}

//! Largest block-Hankel matrix `identify` builds, entries (2^28 doubles: 2 GB).
inline constexpr double max_hankel_entries = 268'435'456.0;

//! Identifies one model from one or several experiments (Hankel columns of all experiments are
//! concatenated; B, D are shared, one x0 per experiment). Data of extreme magnitude (or all data,
//! SubspaceOptions::scaling) is scaled to unit RMS per column internally and the model scaled
//! back, so the result does not depend on the units (the singular values are then those of the
//! scaled data). Throws Error on empty or mismatched
//! data, non-finite samples, too few samples for the horizon, an order the horizon cannot
//! carry (n <= (s - 1) ny), a block-Hankel matrix above max_hankel_entries, or (N4SID) an
//! oblique projection larger than `max_projection_gain` x the future outputs.
[[nodiscard]] inline SubspaceModel identify(std::span<const DataSet> data,
                                            const SubspaceOptions& options = {}) {
  namespace ds = detail::subspace;
  using ds::fail;
  using ds::idx;
  using ds::Index;
  using ds::Matrix;
  using ds::Vector;
  if (data.empty()) fail("identify: no data sets");
  const Index nu = data.front().u.cols();
  const Index ny = data.front().y.cols();
  if (nu < 1) fail("identify: needs at least one input column, got 0");
  if (ny < 1) fail("identify: needs at least one output column, got 0");
  Index total = 0;
  for (std::size_t e = 0; e < data.size(); ++e) {
    const DataSet& d = data[e];
    const std::string where = "identify: data set " + std::to_string(e);
    if (d.u.cols() != nu || d.y.cols() != ny) {
      fail(where + " has " + idx(d.u.cols()) + " inputs and " + idx(d.y.cols()) +
           " outputs, data set 0 has " + idx(nu) + " and " + idx(ny));
    }
    if (d.u.rows() != d.y.rows()) {
      fail(where + ": u has " + idx(d.u.rows()) + " samples, y " + idx(d.y.rows()));
    }
    ds::require_finite(d.u, where + ": u");
    ds::require_finite(d.y, where + ": y");
    total += d.u.rows();
  }
  if (options.order < 0)
    fail("identify: order must be >= 0 (0: automatic), got " + std::to_string(options.order));
  if (options.order == 0 && options.max_order < 1) {
    fail("identify: max_order must be >= 1, got " + std::to_string(options.max_order));
  }
  if (!std::isfinite(options.sample_time) || !(options.sample_time > 0.0)) {
    fail("identify: sample time must be finite and > 0 s, got " +
         ds::format_number(options.sample_time));
  }
  if (!(options.max_projection_gain > 0.0)) {
    fail("identify: max_projection_gain must be > 0, got " +
         ds::format_number(options.max_projection_gain));
  }
  // Every input and output column scaled to unit RMS over all data sets (options.scaling): the LQ
  // factorisation, the SVD and the B, D, x0 regression then see columns of one size whatever the
  // units (1e150 next to 1), and the model is scaled back at the end (same x, so the same x0).
  Vector u_scale = ds::column_rms(data, &DataSet::u);
  Vector y_scale = ds::column_rms(data, &DataSet::y);
  const auto extreme = [](const Vector& rms) {
    return (rms.array() < 1e-6).any() || (rms.array() > 1e6).any();
  };
  const bool scale = options.scaling == SubspaceOptions::Scaling::unit_rms ||
                     (options.scaling == SubspaceOptions::Scaling::automatic &&
                      (extreme(u_scale) || extreme(y_scale)));
  if (!scale) {
    u_scale.setOnes();
    y_scale.setOnes();
  }
  std::vector<DataSet> scaled_data;
  scaled_data.reserve(data.size());
  for (const DataSet& d : data) {
    scaled_data.push_back(
        {d.u * u_scale.cwiseInverse().asDiagonal(), d.y * y_scale.cwiseInverse().asDiagonal()});
    ds::require_finite(scaled_data.back().u, "identify: u scaled to unit RMS");
    ds::require_finite(scaled_data.back().y, "identify: y scaled to unit RMS");
  }
  const std::span<const DataSet> scaled(scaled_data);
  const int wanted = options.order > 0 ? options.order : options.max_order;
  const auto sets = static_cast<int>(data.size());
  const int s = options.block_rows > 0 ? options.block_rows
                                       : default_block_rows(total, sets, static_cast<int>(nu),
                                                            static_cast<int>(ny), wanted);
  if (options.block_rows < 0) {
    fail("identify: block_rows must be >= 0 (0: automatic), got " +
         std::to_string(options.block_rows));
  }
  if (s == 0) {
    fail("identify: " + idx(total) + " samples are too few for order " + std::to_string(wanted) +
         " with " + idx(nu) + " inputs and " + idx(ny) + " outputs");
  }
  // Columns of the block-Hankel matrices, all experiments side by side.
  Index columns = 0;
  for (std::size_t e = 0; e < data.size(); ++e) {
    const Index N = data[e].u.rows();
    if (N < 2 * s) {
      fail("identify: data set " + std::to_string(e) + " has " + idx(N) +
           " samples, fewer than 2 x " + std::to_string(s) + " block rows");
    }
    columns += N - 2 * s + 1;
  }
  const Index a = s * nu;         // Uf rows
  const Index p = s * (nu + ny);  // Wp = [Up; Yp] rows
  const Index f = s * ny;         // Yf rows
  const Index r = a + p + f;
  if (columns < r) {
    fail("identify: " + idx(columns) + " Hankel columns are fewer than the " + idx(r) +
         " rows of [Uf; Up; Yp; Yf] for " + std::to_string(s) + " block rows (more samples or " +
         "fewer block_rows needed)");
  }
  if (options.order > 0 && options.order > f - ny) {
    fail("identify: order " + std::to_string(options.order) + " needs more than " +
         std::to_string(s) + " block rows for " + idx(ny) +
         " outputs (order <= (s - 1) ny = " + idx(f - ny) + ")");
  }

  // H^T, one row per Hankel column, blocks [Uf | Up | Yp | Yf]; R of its QR is L^T of the LQ
  // factorisation [Uf; Wp; Yf] = L Q.
  if (static_cast<double>(columns) * static_cast<double>(r) > max_hankel_entries) {
    fail("identify: the block-Hankel matrix would have " + idx(columns) + " x " + idx(r) +
         " entries, more than the limit of " + ds::format_number(max_hankel_entries) +
         " (2 GB): use fewer samples (a larger sample time) or a lower max_order");
  }
  Matrix Ht(columns, r);
  Index c = 0;
  for (const DataSet& d : scaled) {
    const Index jn = d.u.rows() - 2 * s + 1;
    for (Index i = 0; i < s; ++i) {
      for (Index m = 0; m < nu; ++m) {
        Ht.block(c, i * nu + m, jn, 1) = d.u.block(s + i, m, jn, 1);  // Uf
        Ht.block(c, a + i * nu + m, jn, 1) = d.u.block(i, m, jn, 1);  // Up
      }
      for (Index m = 0; m < ny; ++m) {
        Ht.block(c, a + a + i * ny + m, jn, 1) = d.y.block(i, m, jn, 1);      // Yp
        Ht.block(c, a + p + i * ny + m, jn, 1) = d.y.block(s + i, m, jn, 1);  // Yf
      }
    }
    c += jn;
  }
  Eigen::HouseholderQR<Eigen::Ref<Matrix>> qr(Ht);  // in place
  const Matrix L = qr.matrixQR().topRows(r).triangularView<Eigen::Upper>().transpose();
  const Matrix L21 = L.block(a, 0, p, a);
  const Matrix L22 = L.block(a, a, p, p);
  const Matrix L32 = L.block(a + p, a, f, p);
  const Matrix L33 = L.block(a + p, a + p, f, f);

  // Weighted projection W1 O W2 (up to a right orthogonal factor, which the SVD ignores).
  Matrix weighted;
  Matrix W1_inverse;  // empty: W1 = I
  switch (options.weighting) {
    case Weighting::moesp:
      weighted = L32;
      break;
    case Weighting::n4sid: {
      // O = L32 L22^+ [L21 L22] [Q1; Q2] (oblique projection of Yf along Uf onto Wp).
      // L22 is lower triangular and invertible for persistently exciting data; the pivoting
      // QR still gives a least-squares solution when it is not.
      const Matrix X = L22.transpose().colPivHouseholderQr().solve(L32.transpose()).transpose();
      weighted.resize(f, a + p);
      weighted.leftCols(a).noalias() = X * L21;
      weighted.rightCols(p).noalias() = X * L22;
      // Yf = O + (its part along Uf) + (the rest), and ||Yf|| = ||[L31 L32 L33]|| (Q is
      // orthonormal). An O far larger than Yf cancels against the Uf part: Uf and Wp are nearly
      // collinear and X amplifies the noise in the directions where L22 is nearly singular.
      const double yf = L.bottomRows(f).norm();
      const double gain = yf > 0.0 ? weighted.norm() / yf : 0.0;
      if (!(gain <= options.max_projection_gain)) {
        fail("identify: N4SID weighting: the oblique projection is " + ds::format_number(gain) +
             " times the future outputs (max_projection_gain " +
             ds::format_number(options.max_projection_gain) +
             "): the future inputs and the past data are nearly collinear (e.g. a low-pass "
             "filtered input) and the projection is amplified noise; use moesp or cva");
      }
      break;
    }
    case Weighting::cva: {
      // Yf projected onto the complement of Uf is [L32 L33] Q; its covariance is Lc Lc^T
      // (Cholesky). W1 = Lc^-1 gives the same singular values (canonical correlations) and
      // Gamma as the symmetric root (Yf/Uf-perp Yf/Uf-perp^T)^-1/2: they differ by a rotation.
      Matrix covariance = L32 * L32.transpose();
      covariance.noalias() += L33 * L33.transpose();
      const double ridge = std::numeric_limits<double>::epsilon() * static_cast<double>(f) *
                           std::max(covariance.trace(), std::numeric_limits<double>::min());
      covariance.diagonal().array() += ridge;  // keeps Cholesky defined for exact data
      const Eigen::LLT<Matrix> llt(covariance);
      if (llt.info() != Eigen::Success) fail("identify: CVA weighting: Yf covariance not positive");
      W1_inverse = llt.matrixL();
      weighted = llt.matrixL().solve(L32);
      break;
    }
  }
  const Eigen::JacobiSVD<Matrix> svd(weighted, Eigen::ComputeThinU);
  const Vector moesp_values =
      options.weighting == Weighting::moesp
          ? Vector(svd.singularValues())
          : Vector(Eigen::JacobiSVD<Matrix>(L32, Eigen::ComputeThinU).singularValues());

  const int n =
      options.order > 0
          ? options.order
          : select_order(moesp_values, std::min<int>(options.max_order, static_cast<int>(f - ny)),
                         options.gap_ratio);
  // Extended observability matrix Gamma = W1^-1 U1 S1^(1/2); C = first block row; A from the
  // shift invariance Gamma_up A = Gamma_down (least squares).
  Matrix Gamma = svd.matrixU().leftCols(n) * svd.singularValues().head(n).cwiseSqrt().asDiagonal();
  if (W1_inverse.size() > 0) Gamma = W1_inverse * Gamma;
  const Matrix C = Gamma.topRows(ny);
  const Matrix A = Gamma.topRows(f - ny).colPivHouseholderQr().solve(Gamma.bottomRows(f - ny));
  ds::require_finite(A, "identify: A");

  const ds::Regressed bd =
      ds::regress_b_d_x0(A, C, scaled, options.estimate_d, options.estimate_x0);
  // Back to the data's units: u = Su u', y = Sy y' give B = B' Su^-1, C = Sy C', D = Sy D' Su^-1.
  const Matrix B = bd.B * u_scale.cwiseInverse().asDiagonal();
  const Matrix C_unscaled = y_scale.asDiagonal() * C;
  const Matrix D = y_scale.asDiagonal() * bd.D * u_scale.cwiseInverse().asDiagonal();
  ds::require_finite(B, "identify: B in the data's units");
  ds::require_finite(C_unscaled, "identify: C in the data's units");
  ds::require_finite(D, "identify: D in the data's units");
  model::DynamicStateSpace<> state_space(A, B, C_unscaled, D, options.sample_time);
  state_space.reset(bd.x0.front());
  return SubspaceModel{.state_space = std::move(state_space),
                       .initial_states = std::move(bd.x0),
                       .singular_values = svd.singularValues(),
                       .order_singular_values = moesp_values,
                       .order = n,
                       .block_rows = s,
                       .weighting = options.weighting,
                       .input_scale = u_scale,
                       .output_scale = y_scale};
}

//! One experiment: u is N x nu, y is N x ny. Throws Error as the multi-experiment overload.
[[nodiscard]] inline SubspaceModel identify(const Eigen::MatrixXd& u, const Eigen::MatrixXd& y,
                                            const SubspaceOptions& options = {}) {
  const std::array<DataSet, 1> data{DataSet{u, y}};
  return identify(std::span<const DataSet>(data), options);
}

//! Something `simulate`, `estimate_initial_state` and `compare` accept: a model::StateSpace of
//! any sizes (fixed or dynamic) or a SubspaceModel (its state_space).
template <typename M>
concept IdentifiableModel = requires(const M& m) {
  { detail::subspace::matrices_of(m) } -> std::same_as<detail::subspace::Matrices>;
};

//! Output (N x ny) of the model from initial state x0 for inputs u (N x nu), like
//! scipy.signal.dlsim / MATLAB sim. Throws Error on mismatched sizes or non-finite input.
template <IdentifiableModel M>
[[nodiscard]] Eigen::MatrixXd simulate(const M& model, const Eigen::MatrixXd& u,
                                       const Eigen::VectorXd& x0) {
  const auto m = detail::subspace::matrices_of(model);
  detail::subspace::check_input(m, u, "simulate");
  if (x0.size() != m.A.rows()) {
    detail::subspace::fail("simulate: x0 has " + std::to_string(x0.size()) +
                           " entries, the model " + std::to_string(m.A.rows()) + " states");
  }
  return detail::subspace::simulate(m, u, x0);
}

//! Least-squares initial state: argmin_x0 ||y - simulate(model, u, x0)|| (MATLAB findstates).
//! Throws Error on mismatched sizes, non-finite data or a regression that overflows.
template <IdentifiableModel M>
[[nodiscard]] Eigen::VectorXd estimate_initial_state(const M& model, const Eigen::MatrixXd& u,
                                                     const Eigen::MatrixXd& y) {
  return detail::subspace::estimate_initial_state(detail::subspace::matrices_of(model), u, y,
                                                  "estimate_initial_state");
}

}  // namespace endohaptics::identification
