//! @file
//! Function bodies of identification/subspace.hpp: included at its end (header-only, the default),
//! or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/identification/subspace.hpp"

namespace endohaptics::identification {

ENDOHAPTICS_DECL Weighting weighting_from_string(std::string_view name) {
  for (const Weighting w : {Weighting::moesp, Weighting::n4sid, Weighting::cva}) {
    if (name == to_string(w)) return w;
  }
  ENDOHAPTICS_THROW(Error("identification: unknown weighting \"" + std::string(name) +
                          "\" (expected moesp, n4sid or cva)"));
}
}  // namespace endohaptics::identification

namespace endohaptics::identification {
namespace detail::subspace {

ENDOHAPTICS_DECL std::string idx(Index value) { return std::to_string(value); }

ENDOHAPTICS_DECL void require_finite(const Matrix& m, const std::string& what) {
  endohaptics::detail::require_finite(m, {}, what);
}

ENDOHAPTICS_DECL Matrices matrices_of(const SubspaceModel& m) { return matrices_of(m.state_space); }

ENDOHAPTICS_DECL void check_input(const Matrices& m, const Matrix& u, const char* where) {
  if (u.cols() != m.B.cols()) {
    fail(std::string(where) + ": u has " + idx(u.cols()) + " columns, the model " +
         idx(m.B.cols()) + " inputs");
  }
  require_finite(u, std::string(where) + ": u");
}

ENDOHAPTICS_DECL Matrix simulate(const Matrices& m, const Matrix& u, const Vector& x0) {
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

ENDOHAPTICS_DECL Matrix free_response(const Matrix& A, const Matrix& C, Index samples) {
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

ENDOHAPTICS_DECL Vector scaled_least_squares(Matrix Phi, const Vector& rhs, const char* where) {
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

ENDOHAPTICS_DECL Vector column_rms(std::span<const DataSet> data, Matrix DataSet::*part) {
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

ENDOHAPTICS_DECL TriangularFactor::TriangularFactor(Index cols, Index chunk_rows)
    : cols_(cols),
      work_(Matrix::Zero(cols + (chunk_rows > 0 ? chunk_rows : std::max<Index>(2048, 4 * cols)),
                         cols)) {}

ENDOHAPTICS_DECL void TriangularFactor::flush() {
  if (pending_ == 0) return;
  // [R; pending rows] = Q [R'; 0]: R' overwrites the top rows (the Householder vectors below its
  // diagonal are cleared, the rows below are refilled by the next block).
  Eigen::Ref<Matrix> top(work_.topRows(cols_ + pending_));
  const Eigen::HouseholderQR<Eigen::Ref<Matrix>> qr(top);
  work_.topRows(cols_).triangularView<Eigen::StrictlyLower>().setZero();
  pending_ = 0;
}

ENDOHAPTICS_DECL Eigen::Block<Matrix> TriangularFactor::append(Index wanted) {
  if (cols_ + pending_ == work_.rows()) flush();
  const Index count = std::min(std::max<Index>(wanted, 1), work_.rows() - cols_ - pending_);
  const Index first = cols_ + pending_;
  pending_ += count;
  rows_ += count;
  return work_.middleRows(first, count);
}

ENDOHAPTICS_DECL void TriangularFactor::add(const Eigen::Ref<const Matrix>& rows) {
  for (Index done = 0; done < rows.rows();) {
    auto block = append(rows.rows() - done);
    block = rows.middleRows(done, block.rows());
    done += block.rows();
  }
}

ENDOHAPTICS_DECL Matrix TriangularFactor::R() {
  flush();
  return work_.topRows(cols_);
}

//! Running sum of squares of each column kept as scale^2 * ssq (LAPACK dlassq): no overflow for
//! entries of 1e200 or underflow for 1e-200, like Eigen's stableNorm of the whole column.
struct ColumnNorms {
  Vector scale, ssq;
  explicit ColumnNorms(Index cols) : scale(Vector::Zero(cols)), ssq(Vector::Ones(cols)) {}
  void add(Index j, const Eigen::Ref<const Vector>& values) {
    const double peak = values.cwiseAbs().maxCoeff();
    if (!(peak > 0.0)) return;
    const double sum = (values / peak).squaredNorm();
    if (peak > scale[j]) {
      ssq[j] = ssq[j] * (scale[j] / peak) * (scale[j] / peak) + sum;
      scale[j] = peak;
    } else {
      ssq[j] += sum * (peak / scale[j]) * (peak / scale[j]);
    }
  }
  [[nodiscard]] double norm(Index j) const { return scale[j] * std::sqrt(ssq[j]); }
};

//! The regression rows of one data set, `chunk` samples at a time: columns [x0 (n, if
//! estimated) | vec(B) (n nu) | vec(D) (ny nu, if estimated) | y], ny rows per sample, weighted.
class RegressionRows {
 public:
  RegressionRows(const Matrix& A, const Matrix& C, const DataSet& d, const Matrix* weights,
                 bool estimate_d, bool estimate_x0)
      : A_(A), C_(C), d_(d), w_(weights), estimate_d_(estimate_d), estimate_x0_(estimate_x0) {
    restart();
  }
  [[nodiscard]] Index x0_columns() const { return estimate_x0_ ? A_.rows() : 0; }
  [[nodiscard]] Index columns() const {
    return x0_columns() + A_.rows() * d_.u.cols() + (estimate_d_ ? C_.rows() * d_.u.cols() : 0) + 1;
  }
  [[nodiscard]] bool done() const { return k_ == d_.u.rows(); }
  void restart() {
    const Index n = A_.rows();
    k_ = 0;
    Z_ = Matrix::Identity(n, n);
    X_ = Matrix::Zero(n, n * d_.u.cols());
  }
  //! Fills `out` with the rows of the next samples (at most out.rows() / ny); returns the rows.
  Index next(Matrix& out) {
    const Index n = A_.rows(), ny = C_.rows(), nu = d_.u.cols();
    const Index x0c = x0_columns(), bc = n * nu;
    const Index count = std::min(out.rows() / ny, d_.u.rows() - k_);
    out.topRows(count * ny).setZero();
    for (Index t = 0; t < count; ++t, ++k_) {
      const Index r = t * ny;
      if (estimate_x0_) {
        out.block(r, 0, ny, n).noalias() = C_ * Z_;
        next_z_.noalias() = A_ * Z_;
        Z_.swap(next_z_);
      }
      out.block(r, x0c, ny, bc).noalias() = C_ * X_;
      if (estimate_d_) {
        for (Index j = 0; j < nu; ++j) {
          for (Index i = 0; i < ny; ++i) out(r + i, x0c + bc + j * ny + i) = d_.u(k_, j);
        }
      }
      out.block(r, out.cols() - 1, ny, 1) = d_.y.row(k_).transpose();
      next_x_.noalias() = A_ * X_;
      for (Index j = 0; j < nu; ++j)
        next_x_.block(0, j * n, n, n).diagonal().array() += d_.u(k_, j);
      X_.swap(next_x_);
      if (w_ != nullptr) {
        for (Index i = 0; i < ny; ++i) out.row(r + i) *= (*w_)(k_, i);
      }
    }
    return count * ny;
  }

 private:
  const Matrix& A_;
  const Matrix& C_;
  const DataSet& d_;
  const Matrix* w_;
  bool estimate_d_, estimate_x0_;
  Index k_ = 0;
  Matrix Z_, X_, next_z_, next_x_;  // A^k (free response) and the input-driven states
};

ENDOHAPTICS_DECL Vector estimate_initial_state(const Matrices& m, const Matrix& u, const Matrix& y,
                                               const char* where) {
  check_input(m, u, where);
  if (y.cols() != m.C.rows() || y.rows() != u.rows()) {
    fail(std::string(where) + ": y is " + idx(y.rows()) + " x " + idx(y.cols()) + ", expected " +
         idx(u.rows()) + " x " + idx(m.C.rows()) + " (samples x outputs)");
  }
  require_finite(y, std::string(where) + ": y");
  const Index n = m.A.rows();
  const Index ny = m.C.rows();
  const Matrix residual = y - simulate(m, u, Vector::Zero(n));
  // Least squares over the free response rows C A^k (ny per sample) without forming them whole:
  // column norms first (each column enters scaled to unit norm), then the triangular factor of
  // [free response | residual], a block of samples at a time.
  const Index chunk = std::max<Index>(64, 4096 / std::max<Index>(ny, 1));
  Matrix rows(chunk * ny, n + 1);
  const auto fill = [&](Matrix& Z, Index k0, Index count) {
    Matrix next(n, n);
    for (Index t = 0; t < count; ++t) {
      rows.block(t * ny, 0, ny, n).noalias() = m.C * Z;
      rows.block(t * ny, n, ny, 1) = residual.row(k0 + t).transpose();
      next.noalias() = m.A * Z;
      Z.swap(next);
    }
  };
  ColumnNorms norms(n);
  Matrix Z = Matrix::Identity(n, n);
  for (Index k = 0; k < u.rows(); k += chunk) {
    const Index count = std::min(chunk, u.rows() - k);
    fill(Z, k, count);
    const auto block = rows.topRows(count * ny);
    if (!block.leftCols(n).allFinite()) {
      fail(std::string(where) +
           ": the regression overflowed (the model is too unstable for this many samples)");
    }
    for (Index j = 0; j < n; ++j) norms.add(j, block.col(j));
  }
  Vector scale(n + 1);
  for (Index j = 0; j < n; ++j) {
    const double norm = norms.norm(j);
    scale[j] = norm > 0.0 ? 1.0 / norm : 1.0;
  }
  scale[n] = 1.0;
  TriangularFactor tf(n + 1);
  Z.setIdentity();
  for (Index k = 0; k < u.rows(); k += chunk) {
    const Index count = std::min(chunk, u.rows() - k);
    fill(Z, k, count);
    tf.add(rows.topRows(count * ny) * scale.asDiagonal());
  }
  const Matrix R = tf.R();
  Eigen::ColPivHouseholderQR<Matrix> qr(n, n);
  qr.setThreshold(std::numeric_limits<double>::epsilon() *
                  static_cast<double>(std::min(u.rows() * ny, n)));
  qr.compute(R.topLeftCorner(n, n));
  const Vector x0 = qr.solve(Vector(R.col(n).head(n)));
  return x0.cwiseProduct(scale.head(n));
}

ENDOHAPTICS_DECL Regressed regress_b_d_x0(const Matrix& A, const Matrix& C,
                                          std::span<const DataSet> data, bool estimate_d,
                                          bool estimate_x0,
                                          const std::vector<Matrix>* row_weights) {
  // The least-squares problem min ||Phi theta - y|| over all data sets, Phi with one block of x0
  // columns per set (zero outside its rows) and the B, D columns shared, solved without forming
  // Phi: each set's rows [x0 | B D | y] are reduced to a small triangular factor (two passes:
  // the column norms first, so that every column enters scaled to unit norm as a whole-Phi
  // solve would scale it), its x0 columns eliminated by a pivoting QR, and the remaining rows
  // of all sets stacked for B and D; each x0 then follows by back substitution. Same solution
  // as one pivoting QR of Phi for a full-rank problem.
  const Index n = A.rows();
  const Index ny = C.rows();
  const Index nu = data.front().u.cols();
  const auto sets = static_cast<Index>(data.size());
  const Index x0c = estimate_x0 ? n : 0;
  const Index shared = n * nu + (estimate_d ? ny * nu : 0);  // B, D columns
  const Index chunk_samples = std::max<Index>(64, 4096 / std::max<Index>(ny, 1));
  const auto weights_of = [&](Index e) {
    return row_weights != nullptr ? &(*row_weights)[static_cast<std::size_t>(e)] : nullptr;
  };
  Matrix rows(chunk_samples * ny, x0c + shared + 1);
  // Pass 1: column norms (x0: per set, shared: over all sets) and overflow.
  ColumnNorms shared_norms(shared);
  std::vector<Vector> x0_scale(static_cast<std::size_t>(sets));
  for (Index e = 0; e < sets; ++e) {
    RegressionRows gen(A, C, data[static_cast<std::size_t>(e)], weights_of(e), estimate_d,
                       estimate_x0);
    ColumnNorms x0_norms(x0c);
    while (!gen.done()) {
      const Index count = gen.next(rows);
      const auto block = rows.topRows(count);
      if (!block.leftCols(x0c + shared).allFinite()) {
        fail(
            "identify (B, D, x0): the regression overflowed (the model is too unstable for this "
            "many samples)");
      }
      for (Index j = 0; j < x0c; ++j) x0_norms.add(j, block.col(j));
      for (Index j = 0; j < shared; ++j) shared_norms.add(j, block.col(x0c + j));
    }
    Vector& sc = x0_scale[static_cast<std::size_t>(e)];
    sc.resize(x0c);
    for (Index j = 0; j < x0c; ++j) {
      const double norm = x0_norms.norm(j);
      sc[j] = norm > 0.0 ? 1.0 / norm : 1.0;
    }
  }
  Vector shared_scale(shared);
  for (Index j = 0; j < shared; ++j) {
    const double norm = shared_norms.norm(j);
    shared_scale[j] = norm > 0.0 ? 1.0 / norm : 1.0;
  }
  // Pass 2: per set, R of [x0 | B D | y] scaled; x0 eliminated; the rest stacked. The rank
  // threshold is the one a pivoting QR of the whole Phi would use (relative to its largest pivot,
  // about 1 for unit columns).
  Index total_rows = 0;
  for (const DataSet& d : data) total_rows += d.u.rows() * ny;
  const double threshold = std::numeric_limits<double>::epsilon() *
                           static_cast<double>(std::min(total_rows, x0c * sets + shared));
  TriangularFactor all(shared + 1);
  struct Eliminated {
    Matrix top;                   // the x0 rows of Q1^T [B D | y], rank x (shared + 1)
    Matrix r11;                   // their upper triangular x0 block, rank x rank (pivoted columns)
    Eigen::VectorXi permutation;  // x0 column of each pivoted position
  };
  std::vector<Eliminated> eliminated(static_cast<std::size_t>(sets));
  for (Index e = 0; e < sets; ++e) {
    RegressionRows gen(A, C, data[static_cast<std::size_t>(e)], weights_of(e), estimate_d,
                       estimate_x0);
    TriangularFactor set(x0c + shared + 1);
    Vector column_scale(x0c + shared + 1);
    column_scale << x0_scale[static_cast<std::size_t>(e)], shared_scale, 1.0;
    while (!gen.done()) {
      const Index count = gen.next(rows);
      set.add(rows.topRows(count) * column_scale.asDiagonal());
    }
    const Matrix R = set.R();
    if (x0c == 0) {
      all.add(R);
      continue;
    }
    // Pivoting QR of the x0 block (rank-revealing, like the whole-Phi solve): the rows past its
    // rank carry no x0 and join the shared problem.
    Eigen::ColPivHouseholderQR<Matrix> qr(R.rows(), x0c);
    qr.setThreshold(threshold);
    qr.compute(R.leftCols(x0c));
    const Index rank = qr.rank();
    const Matrix rest = qr.householderQ().transpose() * R.rightCols(shared + 1);
    Eliminated& el = eliminated[static_cast<std::size_t>(e)];
    el.top = rest.topRows(rank);
    el.r11 = qr.matrixR().topLeftCorner(rank, rank).triangularView<Eigen::Upper>();
    el.permutation = qr.colsPermutation().indices();
    all.add(rest.bottomRows(rest.rows() - rank));
  }
  const Matrix Rs = all.R();
  Eigen::ColPivHouseholderQR<Matrix> shared_qr(shared, shared);
  shared_qr.setThreshold(threshold);
  shared_qr.compute(Rs.topLeftCorner(shared, shared));
  const Vector theta_scaled = shared_qr.solve(Vector(Rs.col(shared).head(shared)));
  const Vector theta = theta_scaled.cwiseProduct(shared_scale);
  Regressed out;
  for (Index e = 0; e < sets; ++e) {
    Vector x0 = Vector::Zero(n);
    if (estimate_x0) {
      const Eliminated& el = eliminated[static_cast<std::size_t>(e)];
      const Index rank = el.r11.rows();
      // Basic solution: the x0 components past the rank are 0 (as a pivoting QR solve sets them).
      const Vector rhs = el.top.col(shared) - el.top.leftCols(shared) * theta_scaled;
      const Vector head = el.r11.triangularView<Eigen::Upper>().solve(rhs);
      const Vector& sc = x0_scale[static_cast<std::size_t>(e)];
      for (Index i = 0; i < rank; ++i) {
        const Index col = el.permutation[i];
        x0[col] = head[i] * sc[col];
      }
    }
    out.x0.push_back(std::move(x0));
  }
  out.B = Eigen::Map<const Matrix>(theta.data(), n, nu);
  out.D = estimate_d ? Matrix(Eigen::Map<const Matrix>(theta.data() + n * nu, ny, nu))
                     : Matrix(Matrix::Zero(ny, nu));
  return out;
}
}  // namespace detail::subspace
}  // namespace endohaptics::identification

namespace endohaptics::identification {

ENDOHAPTICS_DECL int select_order(const Eigen::VectorXd& singular_values, int max_order,
                                  double gap_ratio) {
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

ENDOHAPTICS_DECL int default_block_rows(Eigen::Index total_samples, int data_sets, int nu, int ny,
                                        int max_order) {
  const int minimum = std::max(2, (max_order + ny - 1) / ny + 1);
  int s = std::max(15, minimum);
  auto fits = [&](int rows) {
    return total_samples - static_cast<Eigen::Index>(data_sets) * (2 * rows - 1) >=
           static_cast<Eigen::Index>(2 * rows * (nu + ny));
  };
  while (s > minimum && !fits(s)) --s;
  return fits(s) ? s : 0;
}

ENDOHAPTICS_DECL HankelFactor hankel_factor(std::span<const DataSet> data, int block_rows,
                                            const Eigen::VectorXd& input_scale,
                                            const Eigen::VectorXd& output_scale) {
  namespace ds = detail::subspace;
  using ds::fail;
  using ds::idx;
  using ds::Index;
  if (data.empty()) fail("hankel_factor: no data sets");
  const Index nu = data.front().u.cols();
  const Index ny = data.front().y.cols();
  const Index s = block_rows;
  if (s < 1) fail("hankel_factor: block_rows must be >= 1, got " + std::to_string(block_rows));
  if (input_scale.size() != nu || output_scale.size() != ny) {
    fail("hankel_factor: " + idx(input_scale.size()) + " input and " + idx(output_scale.size()) +
         " output scales for " + idx(nu) + " inputs and " + idx(ny) + " outputs");
  }
  const Index a = s * nu;         // Uf rows
  const Index p = s * (nu + ny);  // Wp = [Up; Yp] rows
  const Index r = a + p + s * ny;
  const Eigen::VectorXd u_inverse = input_scale.cwiseInverse();
  const Eigen::VectorXd y_inverse = output_scale.cwiseInverse();
  HankelFactor out;
  out.block_rows = block_rows;
  out.data_sets = static_cast<int>(data.size());
  out.input_scale = input_scale;
  out.output_scale = output_scale;
  ds::TriangularFactor tf(r);
  for (std::size_t e = 0; e < data.size(); ++e) {
    const DataSet& d = data[e];
    if (d.u.cols() != nu || d.y.cols() != ny || d.u.rows() != d.y.rows()) {
      fail("hankel_factor: data set " + std::to_string(e) + " does not match data set 0");
    }
    if (d.u.rows() < 2 * s) {
      fail("hankel_factor: data set " + std::to_string(e) + " has " + idx(d.u.rows()) +
           " samples, fewer than 2 x " + std::to_string(s) + " block rows");
    }
    const Index jn = d.u.rows() - 2 * s + 1;
    out.samples += d.u.rows();
    out.columns += jn;
    // Hankel columns j0.. as rows of H^T, a block at a time, scaled as the data would be.
    for (Index j0 = 0; j0 < jn;) {
      auto rows = tf.append(jn - j0);
      const Index c = rows.rows();
      for (Index i = 0; i < s; ++i) {
        for (Index m = 0; m < nu; ++m) {
          rows.col(i * nu + m) = d.u.block(s + i + j0, m, c, 1) * u_inverse[m];  // Uf
          rows.col(a + i * nu + m) = d.u.block(i + j0, m, c, 1) * u_inverse[m];  // Up
        }
        for (Index m = 0; m < ny; ++m) {
          rows.col(a + a + i * ny + m) = d.y.block(i + j0, m, c, 1) * y_inverse[m];      // Yp
          rows.col(a + p + i * ny + m) = d.y.block(s + i + j0, m, c, 1) * y_inverse[m];  // Yf
        }
      }
      if (!rows.allFinite()) {
        fail("hankel_factor: data set " + std::to_string(e) + " is not finite after scaling");
      }
      j0 += c;
    }
  }
  out.R = tf.R();
  return out;
}

ENDOHAPTICS_DECL HankelFactor rescaled(const HankelFactor& factor,
                                       const Eigen::VectorXd& input_scale,
                                       const Eigen::VectorXd& output_scale) {
  namespace ds = detail::subspace;
  const ds::Index nu = factor.input_scale.size();
  const ds::Index ny = factor.output_scale.size();
  if (input_scale.size() != nu || output_scale.size() != ny) {
    ds::fail("rescaled: the scales do not match the factor's " + ds::idx(nu) + " inputs and " +
             ds::idx(ny) + " outputs");
  }
  const ds::Index s = factor.block_rows;
  // Ratio old / new of each Hankel row's signal, in the order [Uf | Up | Yp | Yf].
  const Eigen::VectorXd u_ratio = factor.input_scale.cwiseQuotient(input_scale);
  const Eigen::VectorXd y_ratio = factor.output_scale.cwiseQuotient(output_scale);
  Eigen::VectorXd ratio(2 * s * (nu + ny));
  ds::Index k = 0;
  for (int block = 0; block < 2; ++block) {
    for (ds::Index i = 0; i < s; ++i) ratio.segment(k + i * nu, nu) = u_ratio;
    k += s * nu;
  }
  for (int block = 0; block < 2; ++block) {
    for (ds::Index i = 0; i < s; ++i) ratio.segment(k + i * ny, ny) = y_ratio;
    k += s * ny;
  }
  HankelFactor out = factor;
  out.R = factor.R * ratio.asDiagonal();
  out.input_scale = input_scale;
  out.output_scale = output_scale;
  return out;
}

ENDOHAPTICS_DECL HankelFactor combine(std::span<const HankelFactor> parts) {
  namespace ds = detail::subspace;
  if (parts.empty()) ds::fail("combine: no Hankel factors");
  const HankelFactor& first = parts.front();
  ds::TriangularFactor tf(first.R.cols());
  HankelFactor out;
  out.block_rows = first.block_rows;
  out.input_scale = first.input_scale;
  out.output_scale = first.output_scale;
  for (const HankelFactor& part : parts) {
    if (part.block_rows != first.block_rows || part.R.rows() != first.R.rows() ||
        part.R.cols() != first.R.cols() || part.input_scale.size() != first.input_scale.size() ||
        part.output_scale.size() != first.output_scale.size()) {
      ds::fail("combine: the Hankel factors differ in block rows or signals");
    }
    if (part.input_scale == first.input_scale && part.output_scale == first.output_scale) {
      tf.add(part.R);
    } else {
      tf.add(rescaled(part, first.input_scale, first.output_scale).R);
    }
    out.columns += part.columns;
    out.samples += part.samples;
    out.data_sets += part.data_sets;
  }
  out.R = tf.R();
  return out;
}

namespace detail::subspace {

//! Whether `factor` can stand for the factor of data with these sizes and horizon.
ENDOHAPTICS_DECL bool matches(const HankelFactor& factor, int block_rows, Index samples,
                              int data_sets, Index rows) {
  return factor.R.rows() == rows && factor.R.cols() == rows && factor.block_rows == block_rows &&
         factor.samples == samples && factor.data_sets == data_sets;
}

//! `identify` with an optional factor to reuse or fill.
ENDOHAPTICS_DECL SubspaceModel identify_with(std::span<const DataSet> data,
                                             const SubspaceOptions& options, HankelFactor* factor) {
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
  // A scaled copy of the data only when it is scaled (the B, D, x0 regression reads it).
  std::vector<DataSet> scaled_data;
  if (scale) {
    scaled_data.reserve(data.size());
    for (const DataSet& d : data) {
      scaled_data.push_back(
          {d.u * u_scale.cwiseInverse().asDiagonal(), d.y * y_scale.cwiseInverse().asDiagonal()});
      ds::require_finite(scaled_data.back().u, "identify: u scaled to unit RMS");
      ds::require_finite(scaled_data.back().y, "identify: y scaled to unit RMS");
    }
  }
  const std::span<const DataSet> scaled = scale ? std::span<const DataSet>(scaled_data) : data;
  HankelFactor factor_storage;
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

  // R of the QR of H^T (one row per Hankel column, blocks [Uf | Up | Yp | Yf]) is L^T of the LQ
  // factorisation [Uf; Wp; Yf] = L Q: reused from `factor` when it was computed from these data
  // with this horizon, else computed a block of columns at a time.
  if (factor == nullptr || !matches(*factor, s, total, sets, r)) {
    HankelFactor computed = hankel_factor(data, s, u_scale, y_scale);
    if (factor == nullptr) {
      factor_storage = std::move(computed);
      factor = &factor_storage;
    } else {
      *factor = std::move(computed);
    }
  }
  const Matrix L = (factor->input_scale == u_scale && factor->output_scale == y_scale
                        ? factor->R
                        : rescaled(*factor, u_scale, y_scale).R)
                       .transpose();
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

}  // namespace detail::subspace

ENDOHAPTICS_DECL SubspaceModel identify(std::span<const DataSet> data,
                                        const SubspaceOptions& options) {
  return detail::subspace::identify_with(data, options, nullptr);
}

ENDOHAPTICS_DECL SubspaceModel identify(std::span<const DataSet> data,
                                        const SubspaceOptions& options, HankelFactor& factor) {
  return detail::subspace::identify_with(data, options, &factor);
}

ENDOHAPTICS_DECL SubspaceModel identify(const Eigen::MatrixXd& u, const Eigen::MatrixXd& y,
                                        const SubspaceOptions& options) {
  const std::array<DataSet, 1> data{DataSet{u, y}};
  return identify(std::span<const DataSet>(data), options);
}

}  // namespace endohaptics::identification
