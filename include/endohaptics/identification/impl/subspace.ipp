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

ENDOHAPTICS_DECL Vector estimate_initial_state(const Matrices& m, const Matrix& u, const Matrix& y,
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

ENDOHAPTICS_DECL Regressed regress_b_d_x0(const Matrix& A, const Matrix& C,
                                          std::span<const DataSet> data, bool estimate_d,
                                          bool estimate_x0,
                                          const std::vector<Matrix>* row_weights) {
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

ENDOHAPTICS_DECL SubspaceModel identify(std::span<const DataSet> data,
                                        const SubspaceOptions& options) {
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

ENDOHAPTICS_DECL SubspaceModel identify(const Eigen::MatrixXd& u, const Eigen::MatrixXd& y,
                                        const SubspaceOptions& options) {
  const std::array<DataSet, 1> data{DataSet{u, y}};
  return identify(std::span<const DataSet>(data), options);
}

}  // namespace endohaptics::identification
