#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include "endohaptics/estimation/steady_state_kalman.hpp"
#include "endohaptics/model/dense_numerics.hpp"

#include <doctest/doctest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>
#include <random>
#include <type_traits>

#include "endohaptics/model/state_space.hpp"

namespace estimation_steady_state_kalman_test {

namespace {

using endohaptics::Error;
using endohaptics::estimation::DiscreteLinearModel;
using endohaptics::estimation::NumericStatus;
using endohaptics::estimation::SteadyStateKalman;
using endohaptics::model::StateSpace;
using endohaptics::test::allocations_during;

template <int R, int C, typename Scalar = double>
using Mat = Eigen::Matrix<Scalar, R, C>;

template <typename A, typename B>
double relative_gap(const A& actual, const B& expected) {
  return (actual.template cast<double>() - expected).cwiseAbs().maxCoeff() /
         expected.cwiseAbs().maxCoeff();
}

double spectral_radius(const Eigen::MatrixXd& M) {
  Eigen::VectorXcd values;
  REQUIRE(endohaptics::model::numerics::eigenvalues<double>(M, values));
  return values.cwiseAbs().maxCoeff();
}

// The 3-state test system: an oscillatory pair (0.95 +- 0.2i) and a first-order lag (0.6).
// Model outputs y = [force; position error] = C x; measured z = [position error; velocity]
// = Cm x + Dm u (the velocity row has feedthrough 0.2 to exercise Dm).
struct TestSystem {
  using Model = StateSpace<3, 1, 2>;
  using Filter = SteadyStateKalman<Model, 2>;
  Mat<3, 3> A;
  Mat<3, 1> B;
  Mat<2, 3> C;
  Mat<2, 1> D = Mat<2, 1>::Zero();
  Mat<2, 3> Cm;
  Mat<2, 1> Dm;
  Mat<3, 3> Q;
  Mat<2, 2> R;
  TestSystem() {
    A << 0.95, 0.2, 0.0, -0.2, 0.95, 0.1, 0.0, 0.0, 0.6;
    B << 0.0, 0.1, 0.5;
    C << 1.0, 0.0, 0.5, 0.0, 1.0, 0.0;
    Cm << 0.0, 1.0, 0.0, 0.0, 0.0, 1.0;
    Dm << 0.0, 0.2;
    Q << 0.01, 0.002, 0.0, 0.002, 0.02, 0.001, 0.0, 0.001, 0.005;
    R << 0.04, 0.005, 0.005, 0.01;
  }
  [[nodiscard]] Model model() const { return Model(A, B, C, D, 0.001); }
  [[nodiscard]] Filter filter(double r_scale = 1.0) const {
    return Filter(model(), Cm, Dm, Q, (R * r_scale).eval());
  }
};

// References printed by /usr/bin/python3 (scipy 1.10.1, numpy 1.24.2) for TestSystem:
//   P  = scipy.linalg.solve_discrete_are(A.T, Cm.T, Q, R)
//   M  = P @ Cm.T @ np.linalg.inv(Cm @ P @ Cm.T + R);  Pf = P - M @ Cm @ P
//   Sx = scipy.linalg.solve_discrete_lyapunov(A, Q)   # open-loop error covariance
//   force MSE, open loop: C[0] @ Sx @ C[0].T;  Kalman: C[0] @ Pf @ C[0].T
//   R * 100 gain M100 on the true system: Lyapunov of F = (I - M100 Cm) A with noise
//   (I - M100 Cm) Q (I - M100 Cm)' + M100 R M100'; trace of that covariance.
Mat<3, 3> scipy_P() {
  Mat<3, 3> P;
  P << 0.07176531317085535, -0.012176664835886145, 0.00022226759558453151,  //
      -0.012176664835886145, 0.04408466068570488, 0.0021749654033889083,    //
      0.00022226759558453151, 0.0021749654033889083, 0.006403619681353561;
  return P;
}
Mat<3, 2> scipy_M() {
  Mat<3, 2> M;
  M << -0.15162992970391997, 0.07987304758216246,  //
      0.5328633504255534, -0.10048457186080811,    //
      -0.007733353230347982, 0.39376103254672107;
  return M;
}
Mat<3, 3> scipy_Pf() {
  Mat<3, 3> Pf;
  Pf << 0.06990121314752365, -0.005665831950245989, 4.0580827302024597e-05,  //
      -0.005665831950245989, 0.020812111157718107, 0.0016594710335196864,    //
      4.058082730202457e-05, 0.0016594710335196866, 0.003898943559315471;
  return Pf;
}
constexpr double scipy_force_mse_open_loop = 0.26982981105448933;
constexpr double scipy_force_mse_kalman = 0.07091652986465453;
constexpr double scipy_trace_r100 = 0.29586762356119406;

// Seeded simulation of TestSystem with process and measurement noise; runs the filter tuned
// with R * r_scale and the open-loop model side by side and returns the empirical statistics.
struct MonteCarlo {
  Mat<3, 3> predicted = Mat<3, 3>::Zero();  // E[e e'] of x(k+1|k)
  Mat<3, 3> filtered = Mat<3, 3>::Zero();   // E[e e'] of x(k|k)
  double force_mse_kalman = 0.0;
  double force_mse_open_loop = 0.0;
  int bad_status = 0;
};

MonteCarlo run_monte_carlo(double r_scale, int steps) {
  const TestSystem sys;
  auto filter = sys.filter(r_scale);
  auto open_loop = sys.model();
  const Mat<3, 3> Lq = sys.Q.llt().matrixL();
  const Mat<2, 2> Lr = sys.R.llt().matrixL();
  std::mt19937_64 rng(20160620);
  std::normal_distribution<double> normal;
  const int burn_in = 1000;
  MonteCarlo out;
  Mat<3, 1> x = Mat<3, 1>::Zero();
  for (int k = 0; k < steps + burn_in; ++k) {
    const Mat<1, 1> u(std::sin(0.01 * k));
    const Mat<2, 1> v = Lr * Mat<2, 1>(normal(rng), normal(rng));
    const Mat<3, 1> w = Lq * Mat<3, 1>(normal(rng), normal(rng), normal(rng));
    const Mat<2, 1> z = sys.Cm * x + sys.Dm * u + v;
    out.bad_status += filter.update(z, u) != NumericStatus::ok;
    const Mat<3, 1> e_filtered = x - filter.state();
    const double force = (sys.C.row(0) * x).value();
    const double force_kalman = filter.estimate_output(u)[0];
    const double force_open_loop = open_loop.step(u)[0];
    out.bad_status += filter.predict(u) != NumericStatus::ok;
    x = sys.A * x + sys.B * u + w;
    const Mat<3, 1> e_predicted = x - filter.state();
    if (k < burn_in) continue;
    out.filtered += e_filtered * e_filtered.transpose();
    out.predicted += e_predicted * e_predicted.transpose();
    out.force_mse_kalman += (force - force_kalman) * (force - force_kalman);
    out.force_mse_open_loop += (force - force_open_loop) * (force - force_open_loop);
  }
  out.filtered /= steps;
  out.predicted /= steps;
  out.force_mse_kalman /= steps;
  out.force_mse_open_loop /= steps;
  return out;
}

}  // namespace

// Every member of every class template is compiled (the all-outputs constructor only where its
// constraint Nm == outputs holds).
// (An explicit instantiation belongs to a namespace enclosing its template: this file's namespace
// is closed around them.)
}  // namespace estimation_steady_state_kalman_test
template class endohaptics::estimation::SteadyStateKalman<endohaptics::model::StateSpace<6, 2, 1>,
                                                          2>;
template class endohaptics::estimation::SteadyStateKalman<endohaptics::model::StateSpace<3, 1, 2>>;
template class endohaptics::estimation::SteadyStateKalman<endohaptics::model::StateSpace<2, 0, 1>>;
template class endohaptics::estimation::SteadyStateKalman<
    endohaptics::model::StateSpace<3, 1, 2, float>, 1>;
namespace estimation_steady_state_kalman_test {

TEST_CASE("DiscreteLinearModel contract: StateSpace models it, other types do not") {
  static_assert(DiscreteLinearModel<StateSpace<6, 2, 1>>);
  static_assert(DiscreteLinearModel<StateSpace<2, 0, 3, float>>);
  static_assert(!DiscreteLinearModel<int>);
  static_assert(!DiscreteLinearModel<Mat<3, 3>>);
  // The all-outputs constructor exists only when every output is measured (Nm == outputs).
  using Model = StateSpace<3, 1, 2>;
  static_assert(std::is_constructible_v<SteadyStateKalman<Model>, Model, Mat<3, 3>, Mat<2, 2>>);
  static_assert(!std::is_constructible_v<SteadyStateKalman<Model, 1>, Model, Mat<3, 3>, Mat<1, 1>>);
  CHECK(SteadyStateKalman<Model, 1>::measurements == 1);
  CHECK(SteadyStateKalman<Model>::measurements == 2);
}

TEST_CASE("gains and covariances match scipy") {
  const TestSystem sys;
  const auto filter = sys.filter();
  CHECK(relative_gap(filter.predicted_covariance(), scipy_P()) < 1e-10);
  CHECK(relative_gap(filter.gain(), scipy_M()) < 1e-10);
  CHECK(relative_gap(filter.filtered_covariance(), scipy_Pf()) < 1e-10);
  CHECK(relative_gap(filter.predictor_gain(), (sys.A * scipy_M()).eval()) < 1e-10);
  CHECK(filter.riccati().residual < 1e-13);
  CHECK(filter.measurement_C() == sys.Cm);
  CHECK(filter.measurement_D() == sys.Dm);
}

TEST_CASE("constructor from a StateSpace measures every output: Cm = C, Dm = D") {
  const TestSystem sys;
  Mat<2, 1> D_with_feedthrough(0.0, 0.2);
  const TestSystem::Model measured_model(sys.A, sys.B, sys.Cm, D_with_feedthrough, 0.001);
  const SteadyStateKalman<TestSystem::Model> all_outputs(measured_model, sys.Q, sys.R);
  CHECK(all_outputs.gain() == sys.filter().gain());  // the same computation, bit for bit
  CHECK(all_outputs.measurement_C() == sys.Cm);
  CHECK(all_outputs.measurement_D() == D_with_feedthrough);
}

TEST_CASE("Monte Carlo: empirical error covariances match P and P - M Cm P") {
  // 200k steps after a burn-in of 1000. Errors are correlated over about 1 / (1 - 0.84) steps
  // (closed-loop spectral radius 0.838 from scipy), so an entry's sampling error is about
  // sqrt(2 * 6 / 200000) = 0.8 % of the diagonal: 4 % is 5 sigma.
  const MonteCarlo mc = run_monte_carlo(1.0, 200000);
  CHECK(mc.bad_status == 0);
  const double tolerance = 0.04;
  CHECK(relative_gap(mc.predicted, scipy_P()) < tolerance);
  CHECK(relative_gap(mc.filtered, scipy_Pf()) < tolerance);
  CHECK(mc.force_mse_kalman == doctest::Approx(scipy_force_mse_kalman).epsilon(tolerance));

  SUBCASE("a filter tuned with R * 100 is worse, by the amount theory predicts") {
    const MonteCarlo detuned = run_monte_carlo(100.0, 200000);
    CHECK(detuned.filtered.trace() == doctest::Approx(scipy_trace_r100).epsilon(tolerance));
    CHECK(detuned.filtered.trace() > 2.5 * mc.filtered.trace());
  }
}

TEST_CASE("the filtered force estimate beats the open-loop model on a noisy system") {
  const MonteCarlo mc = run_monte_carlo(1.0, 200000);
  // scipy: 0.0709 (Kalman) against 0.2698 (open loop), a ratio of 0.263.
  CHECK(mc.force_mse_open_loop ==
        doctest::Approx(scipy_force_mse_open_loop).epsilon(0.08));  // slower decorrelation
  CHECK(mc.force_mse_kalman < 0.35 * mc.force_mse_open_loop);
}

TEST_CASE("non-finite measurement or input: status, and the estimate is unchanged") {
  const TestSystem sys;
  auto filter = sys.filter();
  const Mat<3, 1> x0(0.1, -0.2, 0.3);
  filter.reset(x0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const Mat<1, 1> u(0.5);
  CHECK(filter.update(Mat<2, 1>(nan, 0.0), u) == NumericStatus::non_finite_measurement);
  CHECK(filter.update(Mat<2, 1>(0.0, -inf), u) == NumericStatus::non_finite_measurement);
  CHECK(filter.update(Mat<2, 1>(0.0, 0.0), Mat<1, 1>(nan)) == NumericStatus::non_finite_input);
  CHECK(filter.predict(Mat<1, 1>(inf)) == NumericStatus::non_finite_input);
  CHECK(filter.state() == x0);

  // Then a good sample goes through: x <- x0 + M (z - Cm x0 - Dm u), then A x + B u.
  const Mat<2, 1> z(0.05, 0.4);
  REQUIRE(filter.update(z, u) == NumericStatus::ok);
  const Mat<3, 1> corrected = x0 + filter.gain() * (z - sys.Cm * x0 - sys.Dm * u);
  CHECK((filter.state() - corrected).norm() < 1e-15);
  REQUIRE(filter.predict(u) == NumericStatus::ok);
  CHECK((filter.state() - (sys.A * corrected + sys.B * u)).norm() < 1e-15);
}

TEST_CASE("reset, estimate_output and estimate_measurement") {
  const TestSystem sys;
  auto filter = sys.filter();
  CHECK(filter.state() == Mat<3, 1>::Zero());
  const Mat<3, 1> x0(1.0, 2.0, -4.0);
  filter.reset(x0);
  const Mat<1, 1> u(3.0);
  // y = C x0 + D u = [1 + 0.5 * -4, 2] and z = Cm x0 + Dm u = [2, -4 + 0.2 * 3].
  CHECK(filter.estimate_output(u) == Mat<2, 1>(-1.0, 2.0));
  CHECK((filter.estimate_measurement(u) - Mat<2, 1>(2.0, -3.4)).norm() < 1e-15);
  filter.reset();
  CHECK(filter.state() == Mat<3, 1>::Zero());
}

TEST_CASE("construction errors name the problem") {
  const TestSystem sys;
  SUBCASE("an unstable mode the measurements do not see") {
    Mat<3, 3> A = sys.A;
    A(0, 0) = 1.2;  // decouple state 0 from the measured states and make it unstable
    A(0, 1) = 0.0;
    A(1, 0) = 0.0;
    const TestSystem::Model model(A, sys.B, sys.C, sys.D, 0.001);
    CHECK_THROWS_WITH_AS(TestSystem::Filter(model, sys.Cm, sys.Dm, sys.Q, sys.R),
                         doctest::Contains("(A, C) is not detectable: eigenvalue 1.2 + 0i"), Error);
  }
  SUBCASE("non-finite measurement feedthrough") {
    Mat<2, 1> Dm = sys.Dm;
    Dm(1, 0) = std::numeric_limits<double>::quiet_NaN();
    CHECK_THROWS_WITH_AS(TestSystem::Filter(sys.model(), sys.Cm, Dm, sys.Q, sys.R),
                         "SteadyStateKalman: D_meas(1,0) is not finite (nan)", Error);
  }
  SUBCASE("R not positive definite") {
    CHECK_THROWS_WITH_AS(TestSystem::Filter(sys.model(), sys.Cm, sys.Dm, sys.Q,
                                            Mat<2, 2>(Mat<2, 1>(0.04, -0.01).asDiagonal())),
                         doctest::Contains("R is not positive definite"), Error);
  }
}

namespace {
template <int X, int U, int Y, int M>
struct Sizes {
  static constexpr int nx = X;
  static constexpr int nu = U;
  static constexpr int ny = Y;
  static constexpr int nm = M;
};
}  // namespace

TEST_CASE_TEMPLATE("random models: gain identities, convergence, no allocation per tick", S,
                   Sizes<1, 1, 1, 1>, Sizes<2, 0, 1, 1>, Sizes<3, 2, 2, 1>, Sizes<6, 2, 1, 2>,
                   Sizes<4, 1, 3, 3>) {
  constexpr int Nx = S::nx;
  constexpr int Nu = S::nu;
  constexpr int Ny = S::ny;
  constexpr int Nm = S::nm;
  using Model = StateSpace<Nx, Nu, Ny>;
  using Filter = SteadyStateKalman<Model, Nm>;
  std::mt19937_64 rng(4402);
  std::normal_distribution<double> normal;
  auto random = [&]<int Rows, int Cols>() {
    Mat<Rows, Cols> m;
    for (int j = 0; j < Cols; ++j) {
      for (int i = 0; i < Rows; ++i) m(i, j) = normal(rng);
    }
    return m;
  };
  Mat<Nx, Nx> A = random.template operator()<Nx, Nx>();
  A *= 0.9 / spectral_radius(A);
  const Model model(A, random.template operator()<Nx, Nu>(), random.template operator()<Ny, Nx>(),
                    random.template operator()<Ny, Nu>(), 0.002);
  const Mat<Nm, Nx> Cm = random.template operator()<Nm, Nx>();
  const Mat<Nm, Nu> Dm = random.template operator()<Nm, Nu>();
  const Mat<Nx, Nx> G = random.template operator()<Nx, Nx>();
  const Mat<Nm, Nm> H = random.template operator()<Nm, Nm>();
  const Mat<Nx, Nx> Q = G * G.transpose() + 0.01 * Mat<Nx, Nx>::Identity();
  const Mat<Nm, Nm> R = H * H.transpose() + Mat<Nm, Nm>::Identity();
  Filter filter(model, Cm, Dm, Q, R);
  // z = Cm x + Dm u (no product with an empty inner dimension when Nu == 0).
  auto measure = [&](const Mat<Nx, 1>& state, const typename Filter::Input& input) {
    Mat<Nm, 1> z = Cm * state;
    if constexpr (Nu > 0) z += Dm * input;
    return z;
  };

  // M (Cm P Cm' + R) = P Cm' and P - Pf = M Cm P.
  const Mat<Nx, Nx>& P = filter.predicted_covariance();
  const Mat<Nx, Nm>& M = filter.gain();
  CHECK((M * (Cm * P * Cm.transpose() + R) - P * Cm.transpose()).norm() < 1e-12 * P.norm());
  CHECK((P - filter.filtered_covariance() - M * Cm * P).norm() < 1e-12 * P.norm());
  CHECK(filter.riccati().residual < 1e-12);

  // Noise-free: the error follows e+ = A (I - M Cm) e and dies out.
  Mat<Nx, 1> x = random.template operator()<Nx, 1>();
  const double initial_error = x.norm();
  const Mat<Nx, Nx> error_map = A * (Mat<Nx, Nx>::Identity() - M * Cm);
  CHECK(spectral_radius(error_map) < 1.0);
  Model plant = model;
  plant.reset(x);
  typename Filter::Input u;
  bool recursion_holds = true;
  int bad_status = 0;
  for (int k = 0; k < 2000; ++k) {
    for (int i = 0; i < Nu; ++i) u[i] = std::sin(0.05 * k + i);
    const Mat<Nx, 1> e_before = plant.state() - filter.state();
    bad_status += filter.update(measure(plant.state(), u), u) != NumericStatus::ok;
    bad_status += filter.predict(u) != NumericStatus::ok;
    (void)plant.step(u);
    const Mat<Nx, 1> e_after = plant.state() - filter.state();
    if (k < 5) {
      recursion_holds =
          recursion_holds && (e_after - error_map * e_before).norm() <= 1e-12 * (1.0 + x.norm());
    }
  }
  CHECK(bad_status == 0);
  CHECK(recursion_holds);
  CHECK((plant.state() - filter.state()).norm() < 1e-9 * initial_error);

  // 10,000 ticks without one heap allocation (global operator new) or Eigen malloc.
  double sink = 0.0;
  const long allocations = allocations_during([&] {
    for (int k = 0; k < 10000; ++k) {
      for (int i = 0; i < Nu; ++i) u[i] = std::cos(0.01 * k + i);
      bad_status += filter.update(measure(plant.state(), u), u) != NumericStatus::ok;
      sink += filter.estimate_output(u)[0];
      bad_status += filter.predict(u) != NumericStatus::ok;
      (void)plant.step(u);
    }
  });
  CHECK(allocations == 0);
  CHECK(bad_status == 0);
  CHECK(std::isfinite(sink));
}

TEST_CASE("the allocation probes see allocations (so the tick test can fail)") {
  // operator new: what std containers and strings use. The pointer is volatile so the
  // allocation cannot be elided.
  CHECK(allocations_during([] {
          int* volatile p = new int(3);
          delete p;
        }) == 1);

  // Eigen allocates with malloc, not operator new: EIGEN_RUNTIME_NO_MALLOC sees that.
  const long eigen_before = endohaptics::test::eigen_mallocs.load();
  Eigen::MatrixXd heap;
  CHECK(allocations_during([&] { heap = Eigen::MatrixXd::Identity(3, 3); }) >= 1);
  CHECK(endohaptics::test::eigen_mallocs.load() > eigen_before);
  CHECK(heap.trace() == 3.0);
}

TEST_CASE("float instance: same gain as double to float accuracy, converges") {
  const TestSystem sys;
  using ModelF = StateSpace<3, 1, 2, float>;
  const ModelF model(sys.A.cast<float>(), sys.B.cast<float>(), sys.C.cast<float>(),
                     sys.D.cast<float>(), 0.001f);
  SteadyStateKalman<ModelF, 2> filter(model, sys.Cm.cast<float>(), sys.Dm.cast<float>(),
                                      sys.Q.cast<float>(), sys.R.cast<float>());
  CHECK(relative_gap(filter.gain(), scipy_M()) < 1e-5);
  CHECK(relative_gap(filter.predicted_covariance(), scipy_P()) < 1e-5);

  ModelF plant = model;
  plant.reset(Eigen::Vector3f(1.0f, -1.0f, 0.5f));
  for (int k = 0; k < 300; ++k) {
    const Eigen::Matrix<float, 1, 1> u(std::sin(0.02f * static_cast<float>(k)));
    const Eigen::Vector2f z = sys.Cm.cast<float>() * plant.state() + sys.Dm.cast<float>() * u;
    REQUIRE(filter.update(z, u) == NumericStatus::ok);
    REQUIRE(filter.predict(u) == NumericStatus::ok);
    (void)plant.step(u);
  }
  CHECK((plant.state() - filter.state()).norm() < 1e-5f);
}

}  // namespace estimation_steady_state_kalman_test
