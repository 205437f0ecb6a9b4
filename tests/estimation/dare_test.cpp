#include "endohaptics/estimation/dare.hpp"
#include "endohaptics/model/dense_numerics.hpp"

#include <doctest/doctest.h>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <random>

namespace estimation_dare_test {

namespace {

using endohaptics::Error;
using endohaptics::estimation::DareOptions;
using endohaptics::estimation::solve_filter_dare;

template <int R, int C, typename Scalar = double>
using Mat = Eigen::Matrix<Scalar, R, C>;

// Largest |entry| of the difference, relative to the largest |entry| of the reference.
template <typename A, typename B>
double relative_gap(const A& actual, const B& expected) {
  return (actual.template cast<double>() - expected).cwiseAbs().maxCoeff() /
         expected.cwiseAbs().maxCoeff();
}

// The filter DARE right-hand side, written out plainly (independent of the solver's helpers).
template <int Nx, int Ny>
Mat<Nx, Nx> riccati_map(const Mat<Nx, Nx>& A, const Mat<Ny, Nx>& C, const Mat<Nx, Nx>& Q,
                        const Mat<Ny, Ny>& R, const Mat<Nx, Nx>& P) {
  const Mat<Ny, Ny> S = C * P * C.transpose() + R;
  return A * P * A.transpose() - A * P * C.transpose() * S.inverse() * C * P * A.transpose() + Q;
}

// Dynamic-size decompositions: one instantiation for all sizes keeps this file quick to compile.
double spectral_radius(const Eigen::MatrixXd& M) {
  Eigen::VectorXcd values;
  REQUIRE(endohaptics::model::numerics::eigenvalues<double>(M, values));
  return values.cwiseAbs().maxCoeff();
}

double smallest_eigenvalue(const Eigen::MatrixXd& symmetric) {
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(symmetric, Eigen::EigenvaluesOnly)
      .eigenvalues()
      .minCoeff();
}

// Reference solutions below were printed by /usr/bin/python3 (scipy 1.10.1, numpy 1.24.2):
//   from scipy.linalg import solve_discrete_are
//   P = solve_discrete_are(A.T, C.T, Q, R)   # transposes: scipy solves the control form
//   for row in P: print(", ".join(repr(float(v)) for v in row))
// with the A, C, Q, R written in each test case.

}  // namespace

TEST_CASE("scipy reference: double integrator (Jordan block at z = 1), position measured") {
  Mat<2, 2> A;
  A << 1.0, 0.1, 0.0, 1.0;
  const Mat<1, 2> C(1.0, 0.0);
  Mat<2, 2> Q;
  Q << 2.6e-5, 5e-4, 5e-4, 1.0001e-2;
  const Mat<1, 1> R(0.01);
  Mat<2, 2> scipy_P;
  scipy_P << 0.00562691389750081, 0.012501390558210083,  //
      0.012501390558210083, 0.0500158050545846;

  const auto solution = solve_filter_dare(A, C, Q, R);
  CHECK(relative_gap(solution.P, scipy_P) < 1e-10);
  CHECK(solution.residual < 1e-13);
  CHECK(solution.iterations >= 2);
  CHECK(solution.iterations <= 12);
  CHECK((solution.P - solution.P.transpose()).norm() == 0.0);
}

TEST_CASE("scipy reference: unstable but detectable 3-state system, 2 correlated measurements") {
  Mat<3, 3> A;
  A << 1.05, 0.2, 0.0, 0.0, 0.9, 0.3, 0.1, 0.0, 0.5;
  Mat<2, 3> C;
  C << 1.0, 0.0, 0.0, 0.0, 0.0, 1.0;
  Mat<3, 3> Q;
  Q << 0.02, 0.005, 0.0, 0.005, 0.01, 0.002, 0.0, 0.002, 0.03;
  Mat<2, 2> R;
  R << 0.04, 0.01, 0.01, 0.09;
  Mat<3, 3> scipy_P;
  scipy_P << 0.051278839868586515, 0.025463958289032973, 0.004952183360508286,  //
      0.025463958289032973, 0.053702078947310654, 0.010249499737774346,         //
      0.004952183360508286, 0.010249499737774346, 0.03710898874212334;

  const auto solution = solve_filter_dare(A, C, Q, R);
  CHECK(relative_gap(solution.P, scipy_P) < 1e-10);
  CHECK(solution.residual < 1e-13);
  CHECK((riccati_map(A, C, Q, R, solution.P) - solution.P).norm() < 1e-14);

  SUBCASE("float solves the same equation to float accuracy") {
    const auto single = solve_filter_dare<3, 2, float>(A.cast<float>(), C.cast<float>(),
                                                       Q.cast<float>(), R.cast<float>());
    CHECK(relative_gap(single.P, scipy_P) < 1e-5);
    CHECK(single.residual < 1e-5f);
  }
}

TEST_CASE("scipy reference: worksheet appendix C yaw model, A = (C.1), C = (C.3)") {
  // Worksheet appendix C, current and velocity to yaw force model, rows of (C.1) and (C.3).
  Mat<6, 6> A;
  A << 0.9745, -0.3699, -0.0620, 0.2917, 0.5007, -5.5391,   //
      -0.0002, 1.0135, 0.8285, -0.3743, -1.4557, -2.0967,   //
      -0.0002, -0.0123, 0.9149, -1.1440, -0.9316, -2.7853,  //
      -0.0001, -0.0002, 0.0275, 0.7842, 1.6365, 1.8560,     //
      0.0000, -0.0001, -0.0019, -0.0809, 0.8869, 2.4092,    //
      0.0000, -0.0000, 0.0001, 0.0080, -0.0583, 0.8887;
  Mat<1, 6> C;
  C << -0.3687, -0.4929, 0.5447, 0.4463, -0.2808, 0.1893;
  const Mat<6, 6> Q = Mat<6, 1>(1e-3, 1e-3, 1e-3, 1e-4, 1e-4, 1e-5).asDiagonal();
  const Mat<1, 1> R(0.05);
  Mat<6, 6> scipy_P;
  scipy_P << 30.656653015576705, -23.433352585337843, -3.1260117571673707, 0.12403447366579572,
      0.061340717232572686, 0.008289248667132511,  //
      -23.433352585337843, 18.706526301711165, 2.832919613293929, -0.14118581698982877,
      -0.04357476571548326, -0.007941713245507302,  //
      -3.1260117571673707, 2.832919613293929, 0.6244652961913619, -0.06424069875142777,
      -0.0051716830939469455, -0.001582667450237518,  //
      0.12403447366579572, -0.14118581698982877, -0.06424069875142777, 0.021101792167865924,
      0.00265198645101781, 7.21689263645926e-05,  //
      0.061340717232572686, -0.04357476571548326, -0.0051716830939469455, 0.00265198645101781,
      0.0013294331820479636, 6.604574005127659e-05,  //
      0.008289248667132511, -0.007941713245507302, -0.001582667450237518, 7.21689263645926e-05,
      6.604574005127659e-05, 3.353149365820933e-05;

  const auto solution = solve_filter_dare(A, C, Q, R);
  CHECK(relative_gap(solution.P, scipy_P) < 1e-9);
  CHECK(solution.residual < 1e-12);
  // The eigenvalues of (C.1) reach |lambda| = 0.9946: slow modes, yet doubling needs few steps.
  CHECK(solution.iterations <= 16);
}

TEST_CASE("closed form: scalar DARE") {
  // P = a^2 P - a^2 c^2 P^2 / (c^2 P + r) + q  <=>  c^2 P^2 + (r (1 - a^2) - q c^2) P - q r = 0,
  // whose positive root is P = (-b + sqrt(b^2 + 4 c^2 q r)) / (2 c^2), b = r (1 - a^2) - q c^2.
  for (const double a : {0.5, 1.0, 1.3, -2.0}) {
    const double c = 0.7;
    const double q = 0.3;
    const double r = 0.2;
    const double b = r * (1.0 - a * a) - q * c * c;
    const double expected = (-b + std::sqrt(b * b + 4.0 * c * c * q * r)) / (2.0 * c * c);
    const auto solution = solve_filter_dare(Mat<1, 1>(a), Mat<1, 1>(c), Mat<1, 1>(q), Mat<1, 1>(r));
    CAPTURE(a);
    CHECK(solution.P(0, 0) == doctest::Approx(expected).epsilon(1e-13));
  }
}

TEST_CASE("Q = 0 with stable A: P = 0 after one step") {
  const auto solution =
      solve_filter_dare(Mat<2, 2>(Mat<2, 1>(0.5, -0.3).asDiagonal()), Mat<1, 2>(1.0, 1.0),
                        Mat<2, 2>::Zero().eval(), Mat<1, 1>(1.0));
  CHECK(solution.P.norm() == 0.0);
  CHECK(solution.iterations == 1);
  CHECK(solution.residual == 0.0);
}

TEST_CASE("detectability: PBH test on eigenvalues with |lambda| >= 1") {
  Mat<2, 2> A;
  A << 1.2, 0.0, 0.0, 0.5;
  const Mat<2, 2> Q = Mat<2, 2>::Identity();
  const Mat<1, 1> R(1.0);

  SUBCASE("an unstable mode the measurement does not see: undetectable, throws") {
    CHECK_THROWS_WITH_AS(
        (void)solve_filter_dare(A, Mat<1, 2>(0.0, 1.0), Q, R),
        doctest::Contains("(A, C) is not detectable: eigenvalue 1.2 + 0i of A (|lambda| = 1.2"),
        Error);
  }
  SUBCASE("a marginal mode (integrator) the measurement does not see: throws") {
    Mat<2, 2> integrator;
    integrator << 1.0, 0.0, 0.0, 0.5;
    CHECK_THROWS_WITH_AS((void)solve_filter_dare(integrator, Mat<1, 2>(0.0, 1.0), Q, R),
                         doctest::Contains("not detectable"), Error);
  }
  SUBCASE("a complex unstable pair hidden from C: throws") {
    Mat<3, 3> rotation = Mat<3, 3>::Zero();
    rotation << 1.01 * std::cos(0.3), -1.01 * std::sin(0.3), 0.0,  //
        1.01 * std::sin(0.3), 1.01 * std::cos(0.3), 0.0,           //
        0.0, 0.0, 0.2;
    CHECK_THROWS_WITH_AS((void)solve_filter_dare(rotation, Mat<1, 3>(0.0, 0.0, 1.0),
                                                 Mat<3, 3>::Identity().eval(), R),
                         doctest::Contains("not detectable"), Error);
  }
  SUBCASE("an unobservable but stable mode is fine (detectable, not observable)") {
    const auto solution = solve_filter_dare(A, Mat<1, 2>(1.0, 0.0), Q, R);
    // The hidden mode 0.5 keeps its open-loop variance q / (1 - 0.25).
    CHECK(solution.P(1, 1) == doctest::Approx(1.0 / 0.75).epsilon(1e-12));
    CHECK(solution.P(0, 1) == 0.0);
  }
  SUBCASE("a weakly but really coupled measurement (1e-3) is detectable") {
    const auto solution = solve_filter_dare(A, Mat<1, 2>(1e-3, 1.0), Q, R);
    CHECK((riccati_map<2, 1>(A, Mat<1, 2>(1e-3, 1.0), Q, R, solution.P) - solution.P).norm() <
          1e-9 * solution.P.norm());
  }
}

TEST_CASE("invalid Q and R throw Error naming the matrix and the value") {
  const Mat<2, 2> A = Mat<2, 1>(0.9, 0.8).asDiagonal();
  const Mat<1, 2> C(1.0, 1.0);
  const Mat<2, 2> Q = Mat<2, 2>::Identity();
  const Mat<1, 1> R(1.0);

  Mat<2, 2> asymmetric = Q;
  asymmetric(0, 1) = 0.5;
  CHECK_THROWS_WITH_AS((void)solve_filter_dare(A, C, asymmetric, R),
                       "solve_filter_dare: Q is not symmetric: Q(1,0) = 0 but Q(0,1) = 0.5", Error);
  Mat<2, 2> indefinite;
  indefinite << 1.0, 0.0, 0.0, -0.25;
  CHECK_THROWS_WITH_AS((void)solve_filter_dare(A, C, indefinite, R),
                       "solve_filter_dare: Q is not positive semidefinite: smallest eigenvalue "
                       "-0.25",
                       Error);
  CHECK_THROWS_WITH_AS((void)solve_filter_dare(A, C, Q, Mat<1, 1>(0.0)),
                       doctest::Contains("R is not positive definite: smallest eigenvalue 0"),
                       Error);
  CHECK_THROWS_WITH_AS((void)solve_filter_dare(A, C, Q, Mat<1, 1>(-1.0)),
                       doctest::Contains("R is not positive definite"), Error);
  Mat<2, 2> R2;
  R2 << 1.0, 0.2, 0.1, 1.0;
  CHECK_THROWS_WITH_AS((void)solve_filter_dare(A, Mat<2, 2>::Identity().eval(), Q, R2),
                       doctest::Contains("R is not symmetric"), Error);
  Mat<2, 2> singular_R;
  singular_R << 1.0, 1.0, 1.0, 1.0;  // PSD but not PD
  CHECK_THROWS_WITH_AS((void)solve_filter_dare(A, Mat<2, 2>::Identity().eval(), Q, singular_R),
                       doctest::Contains("R is not positive definite"), Error);

  // Round-off asymmetry and round-off negative eigenvalues are accepted.
  Mat<2, 2> nearly = Q;
  nearly(0, 1) = 1e-17;
  CHECK_NOTHROW((void)solve_filter_dare(A, C, nearly, R));
  const Mat<2, 1> g(0.3, 0.7);
  CHECK_NOTHROW((void)solve_filter_dare(A, C, (g * g.transpose()).eval(), R));  // rank 1
}

TEST_CASE("non-finite input throws Error naming the entry") {
  const Mat<2, 2> A = Mat<2, 1>(0.9, 0.8).asDiagonal();
  const Mat<1, 2> C(1.0, 1.0);
  const Mat<2, 2> Q = Mat<2, 2>::Identity();
  const Mat<1, 1> R(1.0);
  Mat<2, 2> bad = A;
  bad(1, 0) = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH_AS((void)solve_filter_dare(bad, C, Q, R),
                       "solve_filter_dare: A(1,0) is not finite (nan)", Error);
  CHECK_THROWS_WITH_AS(
      (void)solve_filter_dare(A, Mat<1, 2>(1.0, std::numeric_limits<double>::infinity()), Q, R),
      "solve_filter_dare: C(0,1) is not finite (inf)", Error);
  Mat<2, 2> bad_Q = Q;
  bad_Q(0, 0) = -std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH_AS((void)solve_filter_dare(A, C, bad_Q, R),
                       "solve_filter_dare: Q(0,0) is not finite (-inf)", Error);
  CHECK_THROWS_WITH_AS(
      (void)solve_filter_dare(A, C, Q, Mat<1, 1>(std::numeric_limits<double>::quiet_NaN())),
      doctest::Contains("R(0,0) is not finite"), Error);
}

TEST_CASE("no convergence, invalid options and no stabilising solution throw") {
  Mat<3, 3> A;
  A << 1.05, 0.2, 0.0, 0.0, 0.9, 0.3, 0.1, 0.0, 0.5;
  Mat<2, 3> C;
  C << 1.0, 0.0, 0.0, 0.0, 0.0, 1.0;
  const Mat<3, 3> Q = Mat<3, 3>::Identity() * 0.01;
  const Mat<2, 2> R = Mat<2, 2>::Identity() * 0.04;

  CHECK_THROWS_WITH_AS((void)solve_filter_dare(A, C, Q, R, DareOptions<double>{2, 1e-13}),
                       doctest::Contains("no convergence after 2 doubling steps: relative change"),
                       Error);
  const auto converged = solve_filter_dare(A, C, Q, R);
  CHECK(converged.iterations > 2);
  // Exactly the converged number of steps is enough.
  CHECK_NOTHROW((void)solve_filter_dare(A, C, Q, R, DareOptions<double>{converged.iterations}));

  CHECK_THROWS_WITH_AS((void)solve_filter_dare(A, C, Q, R, DareOptions<double>{0}),
                       "solve_filter_dare: max_iterations must be >= 1, got 0", Error);
  CHECK_THROWS_WITH_AS((void)solve_filter_dare(A, C, Q, R, DareOptions<double>{10, 0.0}),
                       "solve_filter_dare: relative_tolerance must be finite and > 0, got 0",
                       Error);

  // x+ = x exactly, no process noise: P = 0 solves the equation but the error dynamics keep the
  // eigenvalue 1, so there is no stabilising solution.
  CHECK_THROWS_WITH_AS(
      (void)solve_filter_dare(Mat<1, 1>(1.0), Mat<1, 1>(1.0), Mat<1, 1>(0.0), Mat<1, 1>(1.0)),
      doctest::Contains("no stabilising solution"), Error);
}

namespace {
template <int X, int Y>
struct Sizes {
  static constexpr int nx = X;
  static constexpr int ny = Y;
};
}  // namespace

TEST_CASE_TEMPLATE("random systems: SDA agrees with iterating the Riccati recursion", S,
                   Sizes<1, 1>, Sizes<2, 1>, Sizes<3, 2>, Sizes<6, 2>, Sizes<5, 5>) {
  constexpr int Nx = S::nx;
  constexpr int Ny = S::ny;
  std::mt19937_64 rng(4401);
  std::normal_distribution<double> normal;
  auto random = [&]<int Rows, int Cols>() {
    Mat<Rows, Cols> m;
    for (int j = 0; j < Cols; ++j) {
      for (int i = 0; i < Rows; ++i) m(i, j) = normal(rng);
    }
    return m;
  };
  for (int trial = 0; trial < 20; ++trial) {
    // Spectral radius 0.3 to 1.2: stable and unstable systems, observable almost surely.
    Mat<Nx, Nx> A = random.template operator()<Nx, Nx>();
    A *= (0.3 + 0.045 * trial) / spectral_radius(A);
    const Mat<Ny, Nx> C = random.template operator()<Ny, Nx>();
    const Mat<Nx, Nx> G = random.template operator()<Nx, Nx>();
    const Mat<Nx, Nx> Q = G * G.transpose() * 0.1;
    const Mat<Ny, Ny> H = random.template operator()<Ny, Ny>();
    const Mat<Ny, Ny> R = H * H.transpose() + Mat<Ny, Ny>::Identity();

    const auto solution = solve_filter_dare(A, C, Q, R);
    // The Riccati difference equation from P0 = Q converges to the stabilising solution.
    Mat<Nx, Nx> P = Q;
    for (int k = 0; k < 5000; ++k) P = riccati_map(A, C, Q, R, P);
    CAPTURE(trial);
    CHECK(relative_gap(solution.P, P) < 1e-9);
    CHECK(solution.residual < 1e-11);
    const Mat<Ny, Ny> Sinn = C * solution.P * C.transpose() + R;
    const Mat<Nx, Ny> L = A * solution.P * C.transpose() * Sinn.inverse();
    CHECK(spectral_radius(A - L * C) < 1.0);
    CHECK(smallest_eigenvalue(solution.P) > -1e-12 * solution.P.norm());
  }
}

}  // namespace estimation_dare_test
