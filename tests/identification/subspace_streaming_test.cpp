// The streaming parts of subspace identification (identification/subspace.hpp): the triangular
// factor built a block of rows at a time, the block-Hankel factor of several data sets and its
// reuse, and the B, D, x0 regression solved without forming its matrix -- each against the
// dense computation it replaces.
#include <doctest/doctest.h>

#include <Eigen/QR>
#include <random>
#include <vector>

#include "endohaptics/identification/subspace.hpp"

namespace identification_subspace_streaming_test {

namespace {

namespace id = endohaptics::identification;
namespace ds = endohaptics::identification::detail::subspace;
using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

MatrixXd noise(Index rows, Index cols, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  MatrixXd m(rows, cols);
  for (Index i = 0; i < m.size(); ++i) m.data()[i] = normal(rng);
  return m;
}

// A stable 3rd-order system with 2 inputs and 2 outputs.
struct System {
  MatrixXd A{{0.8, 0.3, 0.0}, {-0.3, 0.8, 0.1}, {0.0, 0.0, 0.5}};
  MatrixXd B{{1.0, 0.2}, {0.0, -0.7}, {0.5, 0.5}};
  MatrixXd C{{1.0, 0.0, 0.4}, {0.2, -1.0, 0.0}};
  MatrixXd D{{0.1, 0.0}, {0.0, -0.2}};
};

// Data set of `n` samples: white inputs, the system's output from x0 plus `sigma` noise.
id::DataSet data_set(const System& s, Index n, unsigned seed, double sigma) {
  id::DataSet d{noise(n, 2, seed), MatrixXd()};
  const endohaptics::model::DynamicStateSpace<> model(s.A, s.B, s.C, s.D, 1.0);
  d.y = id::simulate(model, d.u, noise(3, 1, seed + 1).col(0)) + sigma * noise(n, 2, seed + 2);
  return d;
}

// The block-Hankel matrix H^T (one row per column, blocks [Uf | Up | Yp | Yf]) formed whole.
MatrixXd hankel_transposed(const std::vector<id::DataSet>& data, Index s) {
  const Index nu = data.front().u.cols(), ny = data.front().y.cols();
  Index columns = 0;
  for (const auto& d : data) columns += d.u.rows() - 2 * s + 1;
  MatrixXd H(columns, 2 * s * (nu + ny));
  Index c = 0;
  for (const auto& d : data) {
    for (Index j = 0; j < d.u.rows() - 2 * s + 1; ++j, ++c) {
      for (Index i = 0; i < s; ++i) {
        H.row(c).segment(i * nu, nu) = d.u.row(s + i + j);
        H.row(c).segment(s * nu + i * nu, nu) = d.u.row(i + j);
        H.row(c).segment(2 * s * nu + i * ny, ny) = d.y.row(i + j);
        H.row(c).segment(2 * s * nu + s * ny + i * ny, ny) = d.y.row(s + i + j);
      }
    }
  }
  return H;
}

// The B, D, x0 regression formed whole, columns scaled to unit norm, one pivoting QR: the
// computation regress_b_d_x0 did before it streamed.
ds::Regressed dense_regression(const MatrixXd& A, const MatrixXd& C,
                               const std::vector<id::DataSet>& data,
                               const std::vector<MatrixXd>* weights) {
  const Index n = A.rows(), ny = C.rows(), nu = data.front().u.cols();
  const auto sets = static_cast<Index>(data.size());
  Index rows = 0;
  for (const auto& d : data) rows += d.u.rows() * ny;
  const Index cols = n * sets + n * nu + ny * nu;
  MatrixXd Phi = MatrixXd::Zero(rows, cols);
  VectorXd rhs(rows);
  Index row = 0;
  for (Index e = 0; e < sets; ++e) {
    const auto& d = data[static_cast<std::size_t>(e)];
    MatrixXd Z = MatrixXd::Identity(n, n);
    MatrixXd X = MatrixXd::Zero(n, n * nu);
    for (Index k = 0; k < d.u.rows(); ++k) {
      const Index r = row + k * ny;
      Phi.block(r, e * n, ny, n) = C * Z;
      Phi.block(r, n * sets, ny, n * nu) = C * X;
      for (Index j = 0; j < nu; ++j) {
        for (Index i = 0; i < ny; ++i) Phi(r + i, n * sets + n * nu + j * ny + i) = d.u(k, j);
      }
      rhs.segment(r, ny) = d.y.row(k).transpose();
      if (weights != nullptr) {
        for (Index i = 0; i < ny; ++i) {
          const double w = (*weights)[static_cast<std::size_t>(e)](k, i);
          Phi.row(r + i) *= w;
          rhs[r + i] *= w;
        }
      }
      Z = A * Z;
      MatrixXd next = A * X;
      for (Index j = 0; j < nu; ++j) next.block(0, j * n, n, n).diagonal().array() += d.u(k, j);
      X = next;
    }
    row += d.u.rows() * ny;
  }
  VectorXd scale(cols);
  for (Index j = 0; j < cols; ++j) {
    scale[j] = 1.0 / Phi.col(j).norm();
    Phi.col(j) *= scale[j];
  }
  const VectorXd theta = Phi.colPivHouseholderQr().solve(rhs).cwiseProduct(scale);
  ds::Regressed out;
  for (Index e = 0; e < sets; ++e) out.x0.emplace_back(theta.segment(e * n, n));
  out.B = Eigen::Map<const MatrixXd>(theta.data() + n * sets, n, nu);
  out.D = Eigen::Map<const MatrixXd>(theta.data() + n * sets + n * nu, ny, nu);
  return out;
}

double relative(const MatrixXd& a, const MatrixXd& b) { return (a - b).norm() / b.norm(); }

}  // namespace

TEST_CASE("TriangularFactor: rows given in pieces give the R of one QR, up to row signs") {
  const MatrixXd M = noise(1000, 7, 1);
  ds::TriangularFactor tf(7, 16);  // a small buffer: 63 refactorisations
  Index done = 0;
  for (const Index piece : {1, 5, 40, 3, 200, 751}) {
    tf.add(M.middleRows(done, piece));
    done += piece;
  }
  REQUIRE(done == M.rows());
  CHECK(tf.rows_added() == 1000);
  const MatrixXd R = tf.R();
  CHECK(R.triangularView<Eigen::StrictlyLower>().toDenseMatrix().norm() == 0.0);
  CHECK(relative(R.transpose() * R, M.transpose() * M) < 1e-13);
  const MatrixXd dense =
      MatrixXd(M.householderQr().matrixQR().topRows(7)).triangularView<Eigen::Upper>();
  CHECK(relative(R.cwiseAbs(), dense.cwiseAbs()) < 1e-12);
  // Fewer rows than columns: the missing rows of R are zero (to rounding).
  ds::TriangularFactor small(7);
  small.add(M.topRows(3));
  const MatrixXd Rs = small.R();
  CHECK(Rs.bottomRows(4).norm() < 1e-12 * Rs.norm());
  CHECK(relative(Rs.transpose() * Rs, M.topRows(3).transpose() * M.topRows(3)) < 1e-13);
}

TEST_CASE("hankel_factor is R of the whole block-Hankel matrix and combine joins data sets") {
  const System sys;
  const std::vector<id::DataSet> data{data_set(sys, 300, 10, 0.05), data_set(sys, 217, 20, 0.05)};
  const Index s = 5;
  const VectorXd ones2 = VectorXd::Ones(2);
  const id::HankelFactor whole = id::hankel_factor(data, s, ones2, ones2);
  const MatrixXd H = hankel_transposed(data, s);
  CHECK(whole.columns == H.rows());
  CHECK(whole.samples == 517);
  CHECK(whole.data_sets == 2);
  CHECK(relative(whole.R.transpose() * whole.R, H.transpose() * H) < 1e-13);

  const std::vector<id::HankelFactor> parts{
      id::hankel_factor(std::span<const id::DataSet>(&data[0], 1), s, ones2, ones2),
      id::hankel_factor(std::span<const id::DataSet>(&data[1], 1), s, ones2, ones2)};
  const id::HankelFactor joined = id::combine(parts);
  CHECK(joined.columns == whole.columns);
  CHECK(joined.samples == whole.samples);
  CHECK(joined.data_sets == 2);
  CHECK(relative(joined.R.cwiseAbs(), whole.R.cwiseAbs()) < 1e-12);

  // Scaling: the factor of data divided by (2, 4) and (0.5, 8) is the unscaled one rescaled.
  const VectorXd us{{2.0, 4.0}}, ys{{0.5, 8.0}};
  const id::HankelFactor scaled = id::hankel_factor(data, s, us, ys);
  const id::HankelFactor converted = id::rescaled(whole, us, ys);
  CHECK(relative(converted.R.transpose() * converted.R, scaled.R.transpose() * scaled.R) < 1e-13);
  // combine rescales parts to the first part's scales.
  const std::vector<id::HankelFactor> mixed{
      parts[0], id::hankel_factor(std::span<const id::DataSet>(&data[1], 1), s, us, ys)};
  CHECK(relative(id::combine(mixed).R.cwiseAbs(), whole.R.cwiseAbs()) < 1e-12);

  CHECK_THROWS_AS((void)id::hankel_factor(data, 200, ones2, ones2), endohaptics::Error);
  CHECK_THROWS_AS((void)id::hankel_factor(data, s, VectorXd::Ones(3), ones2), endohaptics::Error);
  CHECK_THROWS_AS((void)id::combine(std::span<const id::HankelFactor>()), endohaptics::Error);
  const std::vector<id::HankelFactor> other_s{
      parts[0], id::hankel_factor(std::span<const id::DataSet>(&data[1], 1), 4, ones2, ones2)};
  CHECK_THROWS_AS((void)id::combine(other_s), endohaptics::Error);
}

TEST_CASE("identify reuses a matching Hankel factor and recomputes one of other data") {
  const System sys;
  const std::vector<id::DataSet> data{data_set(sys, 2000, 30, 0.05), data_set(sys, 900, 40, 0.05)};
  id::SubspaceOptions options;
  options.order = 3;
  const id::SubspaceModel fresh = id::identify(data, options);
  id::HankelFactor factor;
  const id::SubspaceModel first = id::identify(data, options, factor);
  REQUIRE(factor.R.rows() == 2 * fresh.block_rows * 4);
  CHECK(factor.samples == 2900);
  CHECK((first.singular_values - fresh.singular_values).norm() == 0.0);
  // Another order and weighting on the same data: the stored factor, the same model as fresh.
  options.order = 2;
  options.weighting = id::Weighting::cva;
  const id::SubspaceModel reused = id::identify(data, options, factor);
  const id::SubspaceModel direct = id::identify(data, options);
  CHECK(relative(reused.singular_values, direct.singular_values) < 1e-12);
  CHECK(relative(id::simulate(reused, data[0].u, reused.initial_states[0]),
                 id::simulate(direct, data[0].u, direct.initial_states[0])) < 1e-9);
  // The factor really is what is used: a factor of other data with the same sizes gives another
  // model; one of a different length is not used.
  id::HankelFactor foreign = id::hankel_factor(
      std::vector<id::DataSet>{data_set(sys, 2000, 50, 0.5), data_set(sys, 900, 60, 0.5)},
      direct.block_rows, VectorXd::Ones(2), VectorXd::Ones(2));
  CHECK(relative(id::identify(data, options, foreign).singular_values, direct.singular_values) >
        1e-3);
  id::HankelFactor shorter = id::hankel_factor(
      std::vector<id::DataSet>{data_set(sys, 1999, 50, 0.5), data_set(sys, 900, 60, 0.5)},
      direct.block_rows, VectorXd::Ones(2), VectorXd::Ones(2));
  CHECK(relative(id::identify(data, options, shorter).singular_values, direct.singular_values) <
        1e-12);
  CHECK(shorter.samples == 2900);  // replaced by the factor of `data`
}

TEST_CASE("regress_b_d_x0 without its matrix: the dense pivoting solution to rounding") {
  const System sys;
  const std::vector<id::DataSet> data{data_set(sys, 700, 70, 0.1), data_set(sys, 45, 80, 0.1),
                                      data_set(sys, 300, 90, 0.1)};
  // A, C a little off the truth (as identify's are), so the residual is not noise only.
  const MatrixXd A = sys.A + 0.01 * noise(3, 3, 5);
  const MatrixXd C = sys.C + 0.01 * noise(2, 3, 6);
  std::vector<MatrixXd> weights;
  for (const auto& d : data)
    weights.push_back((noise(d.u.rows(), 2, 7).array() > -1.0).cast<double>());
  for (const bool weighted : {false, true}) {
    CAPTURE(weighted);
    const auto* w = weighted ? &weights : nullptr;
    const ds::Regressed streamed = ds::regress_b_d_x0(A, C, data, true, true, w);
    const ds::Regressed dense = dense_regression(A, C, data, w);
    CHECK(relative(streamed.B, dense.B) < 1e-10);
    CHECK(relative(streamed.D, dense.D) < 1e-10);
    for (std::size_t e = 0; e < data.size(); ++e) {
      CHECK(relative(streamed.x0[e], dense.x0[e]) < 1e-9);
    }
  }
  // Without D and x0: B alone, against the truth of noise-free data.
  std::vector<id::DataSet> exact;
  for (const auto& d : data) {
    const endohaptics::model::DynamicStateSpace<> model(sys.A, sys.B, sys.C, MatrixXd::Zero(2, 2),
                                                        1.0);
    exact.push_back({d.u, id::simulate(model, d.u, VectorXd::Zero(3))});
  }
  const ds::Regressed b_only = ds::regress_b_d_x0(sys.A, sys.C, exact, false, false);
  CHECK(relative(b_only.B, sys.B) < 1e-12);
  CHECK(b_only.D.norm() == 0.0);
  CHECK(b_only.x0[1].norm() == 0.0);
  // An unobservable state: its x0 component is not determined and is set to 0, the rest fits.
  MatrixXd C_blind = sys.C;
  C_blind.col(2).setZero();
  MatrixXd A_blind = sys.A;
  A_blind(1, 2) = 0.0;  // state 3 no longer reaches the observed states
  const ds::Regressed blind = ds::regress_b_d_x0(A_blind, C_blind, data, true, true);
  for (const auto& x0 : blind.x0) CHECK(x0[2] == 0.0);
  CHECK(blind.B.allFinite());
}

TEST_CASE("estimate_initial_state without the free-response matrix: the dense solution") {
  const System sys;
  const id::DataSet d = data_set(sys, 5000, 110, 0.2);  // 5000 samples: 3 blocks of rows
  const endohaptics::model::DynamicStateSpace<> model(sys.A + 0.02 * noise(3, 3, 8), sys.B, sys.C,
                                                      sys.D, 1.0);
  const ds::Matrices m = ds::matrices_of(model);
  const MatrixXd residual = d.y - id::simulate(model, d.u, VectorXd::Zero(3));
  const MatrixXd residual_t = residual.transpose();
  const VectorXd dense = ds::scaled_least_squares(
      ds::free_response(m.A, m.C, d.u.rows()),
      Eigen::Map<const VectorXd>(residual_t.data(), residual_t.size()), "test");
  CHECK(relative(id::estimate_initial_state(model, d.u, d.y), dense) < 1e-10);
}

TEST_CASE("regress_b_d_x0: a regression that overflows is refused with a message") {
  const System sys;
  const std::vector<id::DataSet> data{data_set(sys, 3000, 100, 0.0)};
  const MatrixXd unstable = 1.5 * MatrixXd::Identity(3, 3);  // 1.5^3000 overflows
  const auto attempt = [&] { (void)ds::regress_b_d_x0(unstable, sys.C, data, true, true); };
  CHECK_THROWS_WITH_AS(attempt(), doctest::Contains("overflowed"), endohaptics::Error);
}

}  // namespace identification_subspace_streaming_test
