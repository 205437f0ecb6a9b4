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
#include "endohaptics/core/separate_compilation.hpp"

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
[[nodiscard]] ENDOHAPTICS_DECL Weighting weighting_from_string(std::string_view name);

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

ENDOHAPTICS_DECL std::string idx(Index value);

//! Throws Error naming `what`, its (row, col) and the value when an entry is NaN or +-Inf.
ENDOHAPTICS_DECL void require_finite(const Matrix& m, const std::string& what);

//! The matrices of a linear model, whatever type held them.
struct Matrices {
  Matrix A, B, C, D;
};

template <int Nx, int Nu, int Ny, typename Scalar>
Matrices matrices_of(const model::StateSpace<Nx, Nu, Ny, Scalar>& m) {
  return {m.A().template cast<double>(), m.B().template cast<double>(),
          m.C().template cast<double>(), m.D().template cast<double>()};
}

ENDOHAPTICS_DECL Matrices matrices_of(const SubspaceModel& m);

//! Checks u (N x nu) against a model with nu inputs; `where` names the caller.
ENDOHAPTICS_DECL void check_input(const Matrices& m, const Matrix& u, const char* where);

//! y (N x ny) from x0 (n); plain loop over the samples with preallocated vectors.
ENDOHAPTICS_DECL Matrix simulate(const Matrices& m, const Matrix& u, const Vector& x0);

//! O (N ny x n): row block k is C A^k, the free response to each unit initial state.
ENDOHAPTICS_DECL Matrix free_response(const Matrix& A, const Matrix& C, Index samples);

//! Least squares solution of Phi theta = rhs with columns scaled to unit norm first
//! (the x0 columns of a slow or unstable model can be orders of magnitude larger).
ENDOHAPTICS_DECL Vector scaled_least_squares(Matrix Phi, const Vector& rhs, const char* where);

//! x0 minimising ||y - simulate(m, u, x0)|| (MATLAB findstates / compare 'InitialCondition' e).
ENDOHAPTICS_DECL Vector estimate_initial_state(const Matrices& m, const Matrix& u, const Matrix& y,
                                               const char* where);

//! RMS of every column of `part` (&DataSet::u or &DataSet::y) over all data sets, computed
//! without overflow or underflow (each column divided by its largest magnitude first); 1 for an
//! all-zero column.
ENDOHAPTICS_DECL Vector column_rms(std::span<const DataSet> data, Matrix DataSet::*part);

//! Least-squares B, D and one x0 per data set for given A, C: the output is linear in them
//! (y(k) = C A^k x0 + sum_t C A^(k-1-t) B u(t) + D u(k)); SLICOT IB01CD's approach.
struct Regressed {
  Matrix B, D;
  std::vector<Vector> x0;
};

//! R of the QR factorisation of a tall matrix handed over a block of rows at a time: each block is
//! stacked under the R so far and [R; block] factorised again (Householder), so memory is
//! (cols + chunk_rows) x cols whatever the number of rows. R^T R = M^T M for all rows M given;
//! R is that of one QR of M up to the signs of its rows.
class TriangularFactor {
 public:
  //! `cols` columns; rows are factorised in groups of `chunk_rows` (0: max(2048, 4 cols): 2048
  //! factorised 1.4 M rows of 90 columns in 1.53 s here, 512 in 1.73 s, 128 in 2.53 s).
  ENDOHAPTICS_DECL explicit TriangularFactor(Index cols, Index chunk_rows = 0);
  //! The next rows to fill, at most `wanted` and at least 1 (fewer when the buffer is nearly
  //! full); the caller fills every row of the block before the next call.
  ENDOHAPTICS_DECL Eigen::Block<Matrix> append(Index wanted);
  //! Appends all rows of `rows` (cols columns).
  ENDOHAPTICS_DECL void add(const Eigen::Ref<const Matrix>& rows);
  //! The cols x cols upper triangular R of every row appended so far.
  [[nodiscard]] ENDOHAPTICS_DECL Matrix R();
  [[nodiscard]] Index rows_added() const noexcept { return rows_; }  //!< rows appended so far

 private:
  void flush();
  Index cols_;
  Index pending_ = 0;  // rows appended below the R and not yet factorised
  Index rows_ = 0;
  Matrix work_;  // top cols_ rows: R so far; below: pending rows
};

//! `row_weights` (optional, one N x ny matrix per data set) weights each equation, e.g. 0 for
//! samples a later output saturation clipped. The regression is never formed whole: each data
//! set's rows are reduced to a small triangular factor as they are generated, its x0 eliminated,
//! and the rest stacked for B and D (memory independent of the number of samples).
ENDOHAPTICS_DECL Regressed regress_b_d_x0(const Matrix& A, const Matrix& C,
                                          std::span<const DataSet> data, bool estimate_d,
                                          bool estimate_x0,
                                          const std::vector<Matrix>* row_weights = nullptr);

}  // namespace detail::subspace

//! The automatic order rule (documented in docs/models/subspace.md): with log gaps
//! g_n = ln(sv_n / max(sv_(n+1), 1e-10 sv_1)) for n = 1..min(max_order, size - 1), the order is
//! the largest n whose gap is at least `gap_ratio` x the largest gap (gap_ratio = 1: SLICOT's
//! largest gap). Precondition: `singular_values` descending. Throws Error on fewer than 2
//! values, max_order < 1 or gap_ratio outside (0, 1].
[[nodiscard]] ENDOHAPTICS_DECL int select_order(const Eigen::VectorXd& singular_values,
                                                int max_order, double gap_ratio = 0.5);

//! Default horizon s: max(15, ceil(max_order / ny) + 1, order + 1) (SLICOT's dryer example
//! uses 15), reduced to what the data allows (sum of N_e - 2s + 1 >= 2s(nu + ny) columns).
//! Returns 0 when even the minimum does not fit (`identify` then throws).
[[nodiscard]] ENDOHAPTICS_DECL int default_block_rows(Eigen::Index total_samples, int data_sets,
                                                      int nu, int ny, int max_order);

//! The order- and weighting-independent part of a subspace fit: R = L^T of the LQ factorisation
//! [Uf; Up; Yp; Yf] = L Q of the data's block-Hankel matrices (Q is never needed), with what it
//! was computed from. `identify` computes it from the data a block of Hankel columns at a time
//! (memory O(rows^2), not O(samples)); a fit of the same data at another order or weighting, or
//! of a union of data sets whose factors are known (`combine`), can reuse it.
struct HankelFactor {
  Eigen::MatrixXd R{};             //!< 2 s (nu + ny) square, upper triangular; empty: none yet
  int block_rows = 0;              //!< s
  Eigen::Index columns = 0;        //!< Hankel columns (sum over data sets of N - 2 s + 1)
  Eigen::Index samples = 0;        //!< samples of the data sets it was computed from
  int data_sets = 0;               //!< how many data sets
  Eigen::VectorXd input_scale{};   //!< what each input column was divided by first
  Eigen::VectorXd output_scale{};  //!< what each output column was divided by first
};

//! The factor of `data` with s = `block_rows`, each input column divided by input_scale (nu
//! entries) and each output column by output_scale (ny entries). Throws Error on mismatched
//! data or scales, a data set shorter than 2 s, or non-finite scaled samples.
[[nodiscard]] ENDOHAPTICS_DECL HankelFactor hankel_factor(std::span<const DataSet> data,
                                                          int block_rows,
                                                          const Eigen::VectorXd& input_scale,
                                                          const Eigen::VectorXd& output_scale);

//! The factor of the union of the data sets of `parts` (same block rows and signal counts; each
//! part rescaled to the first one's scales): the QR of their stacked R factors. Throws Error on
//! an empty list or parts that do not match.
[[nodiscard]] ENDOHAPTICS_DECL HankelFactor combine(std::span<const HankelFactor> parts);

//! `factor` for data divided by input_scale and output_scale instead of its own scales
//! (R D_old D_new^-1: each Hankel row keeps its signal's scale).
[[nodiscard]] ENDOHAPTICS_DECL HankelFactor rescaled(const HankelFactor& factor,
                                                     const Eigen::VectorXd& input_scale,
                                                     const Eigen::VectorXd& output_scale);

//! Identifies one model from one or several experiments (Hankel columns of all experiments are
//! concatenated; B, D are shared, one x0 per experiment). Data of extreme magnitude (or all data,
//! SubspaceOptions::scaling) is scaled to unit RMS per column internally and the model scaled
//! back, so the result does not depend on the units (the singular values are then those of the
//! scaled data). Throws Error on empty or mismatched
//! data, non-finite samples, too few samples for the horizon, an order the horizon cannot
//! carry (n <= (s - 1) ny), or (N4SID) an oblique projection larger than `max_projection_gain`
//! x the future outputs. Memory does not grow with the number of samples beyond the data itself
//! (the block-Hankel matrices and the B, D, x0 regression are reduced a block at a time).
[[nodiscard]] ENDOHAPTICS_DECL SubspaceModel identify(std::span<const DataSet> data,
                                                      const SubspaceOptions& options = {});

//! `identify` reusing `factor` when it is the factor of these same data sets with the horizon
//! and the number of samples and data sets this fit uses (its scales may differ: it is
//! rescaled); otherwise the factor is computed and stored in `factor` for the next call. The
//! caller keeps one `factor` per data: the order search and refits of the same data then skip
//! the block-Hankel pass. Throws Error as the overload above.
[[nodiscard]] ENDOHAPTICS_DECL SubspaceModel identify(std::span<const DataSet> data,
                                                      const SubspaceOptions& options,
                                                      HankelFactor& factor);

//! One experiment: u is N x nu, y is N x ny. Throws Error as the multi-experiment overload.
[[nodiscard]] ENDOHAPTICS_DECL SubspaceModel identify(const Eigen::MatrixXd& u,
                                                      const Eigen::MatrixXd& y,
                                                      const SubspaceOptions& options = {});

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

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/identification/impl/subspace.ipp"
#endif
