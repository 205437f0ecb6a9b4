#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include "endohaptics/model/state_space.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <type_traits>
#include <utility>
#include "test_support.hpp"

namespace model_state_space_test {

using endohaptics::test::message_of;

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using endohaptics::Error;
using endohaptics::model::ContinuousStateSpace;
using endohaptics::model::discretize_tustin;
using endohaptics::model::discretize_zoh;
using endohaptics::model::DynamicStateSpace;
using endohaptics::model::NumericStatus;
using endohaptics::model::StateSpace;
using endohaptics::test::allocations_during;

// Entry-wise |actual - expected| <= tol, reporting the entry that fails.
template <typename A, typename B>
void check_close(const A& actual, const B& expected, double tol) {
  REQUIRE(actual.rows() == expected.rows());
  REQUIRE(actual.cols() == expected.cols());
  for (Eigen::Index i = 0; i < actual.rows(); ++i) {
    for (Eigen::Index j = 0; j < actual.cols(); ++j) {
      INFO("entry (" << i << "," << j << "): " << actual(i, j) << " vs " << expected(i, j));
      CHECK(std::abs(static_cast<double>(actual(i, j)) - static_cast<double>(expected(i, j))) <=
            tol);
    }
  }
}

template <typename M>
M random_matrix(std::mt19937_64& rng, double scale = 1.0) {
  std::uniform_real_distribution<double> dist(-scale, scale);
  M m;
  for (Eigen::Index i = 0; i < m.size(); ++i) {
    m.data()[i] = static_cast<typename M::Scalar>(dist(rng));
  }
  return m;
}

template <typename SS>
SS random_model(std::mt19937_64& rng) {
  // Scale A so the model stays bounded over the short runs below.
  return SS(random_matrix<typename SS::MatrixA>(rng, 0.9 / SS::states),
            random_matrix<typename SS::MatrixB>(rng), random_matrix<typename SS::MatrixC>(rng),
            random_matrix<typename SS::MatrixD>(rng), typename SS::ScalarType(0.01));
}

// Mass-spring-damper x'' = -4 x - 0.4 x' + u, y = x.
using Msd = ContinuousStateSpace<2, 1, 1>;
Msd msd() {
  Msd::MatrixA A{{0.0, 1.0}, {-4.0, -0.4}};
  return Msd(A, Msd::MatrixB{{0.0}, {1.0}}, Msd::MatrixC{{1.0, 0.0}}, Msd::MatrixD::Zero());
}

}  // namespace

// Reference numbers: /usr/bin/python3 (scipy 1.10.1); the full script is in
// docs/models/state_space.md ("Reproducing the reference numbers"); the relevant lines:
//   A=[[0,1],[-4,-0.4]]; B=[[0],[1]]; C=[[1,0]]; D=[[0]]
//   scipy.signal.cont2discrete((A,B,C,D), 0.1, method='zoh' | 'bilinear')
// printed with np.set_printoptions(precision=17, floatmode='unique').
TEST_CASE("NumericStatus: one outcome for every numeric step, one name each for logs") {
  using endohaptics::NumericStatus;
  CHECK(to_string(NumericStatus::ok) == "ok");
  CHECK(to_string(NumericStatus::non_finite_input) == "non-finite input");
  CHECK(to_string(NumericStatus::non_finite_measurement) == "non-finite measurement");
  CHECK(to_string(NumericStatus::non_finite_result) == "non-finite result");
  CHECK(to_string(static_cast<NumericStatus>(200)) == "unknown");
}

TEST_CASE("discretize_zoh matches scipy cont2discrete 'zoh' (mass-spring-damper, Ts = 0.1 s)") {
  const auto d = discretize_zoh(msd(), 0.1);
  check_close(d.A(),
              Eigen::Matrix2d{{0.9803295444599633, 0.09737421592285536},
                              {-0.38949686369142156, 0.9413798580908213}},
              1e-14);
  check_close(d.B(), Eigen::Vector2d{0.004917613885009153, 0.09737421592285538}, 1e-14);
  check_close(d.C(), Eigen::RowVector2d{1.0, 0.0}, 0.0);
  check_close(d.D(), Eigen::Matrix<double, 1, 1>{0.0}, 0.0);
  CHECK(d.sample_time() == 0.1);
}

TEST_CASE("discretize_tustin matches scipy cont2discrete 'bilinear' (mass-spring-damper)") {
  const auto d = discretize_tustin(msd(), 0.1);
  check_close(d.A(),
              Eigen::Matrix2d{{0.9805825242718447, 0.0970873786407767},
                              {-0.3883495145631068, 0.9417475728155339}},
              1e-14);
  check_close(d.B(), Eigen::Vector2d{0.004854368932038835, 0.0970873786407767}, 1e-14);
  check_close(d.C(), Eigen::RowVector2d{0.9902912621359223, 0.04854368932038835}, 1e-14);
  check_close(d.D(), Eigen::Matrix<double, 1, 1>{0.0024271844660194177}, 1e-15);
}

// scipy: A3=[[-1,2,0],[-2,-1,0.5],[0,0,-3]]; B3=[[1,0],[0,2],[0.5,-1]];
// C3=[[1,0,1],[0,1,-1]]; D3=[[0.1,0],[0,-0.2]]; cont2discrete(..., 0.05, method=...).
TEST_CASE("3 states, 2 inputs, 2 outputs with feedthrough: zoh and bilinear match scipy") {
  using Css = ContinuousStateSpace<3, 2, 2>;
  const Css c(Css::MatrixA{{-1.0, 2.0, 0.0}, {-2.0, -1.0, 0.5}, {0.0, 0.0, -3.0}},
              Css::MatrixB{{1.0, 0.0}, {0.0, 2.0}, {0.5, -1.0}},
              Css::MatrixC{{1.0, 0.0, 1.0}, {0.0, 1.0, -1.0}},
              Css::MatrixD{{0.1, 0.0}, {0.0, -0.2}});
  SUBCASE("zoh") {
    const auto d = discretize_zoh(c, 0.05);
    check_close(d.A(),
                Eigen::Matrix3d{{0.9464772395132298, 0.09496448346290236, 0.001149402546841297},
                                {-0.09496448346290234, 0.9464772395132298, 0.02259171831888429},
                                {0.0, 0.0, 0.8607079764250578}},
                1e-14);
    check_close(d.B(),
                Eigen::Matrix<double, 3, 2>{{0.04870012901655207, 0.004812847936181071},
                                            {-0.002123965098398754, 0.09679620615757224},
                                            {0.023215337262490365, -0.04643067452498073}},
                1e-14);
    check_close(d.C(), c.C(), 0.0);
    check_close(d.D(), c.D(), 0.0);
  }
  SUBCASE("bilinear") {
    const auto d = discretize_tustin(c, 0.05);
    check_close(d.A(),
                Eigen::Matrix3d{{0.9465875370919882, 0.09495548961424334, 0.0011041336001656203},
                                {-0.09495548961424334, 0.9465875370919882, 0.022634738803395216},
                                {0.0, 0.0, 0.8604651162790699}},
                1e-14);
    check_close(d.B(),
                Eigen::Matrix<double, 3, 2>{{0.048678490097301776, 0.004720171140708027},
                                            {-0.0020909530053136436, 0.09676350838451454},
                                            {0.023255813953488375, -0.04651162790697675}},
                1e-14);
    check_close(d.C(),
                Eigen::Matrix<double, 2, 3>{
                    {0.9732937685459943, 0.04747774480712168, 0.9307846249396178},
                    {-0.04747774480712167, 0.9732937685459941, -0.9189151887378373}},
                1e-14);
    check_close(d.D(),
                Eigen::Matrix2d{{0.13596715202539508, -0.02089572838313436},
                                {-0.01267338347940101, -0.12836243185425436}},
                1e-14);
  }
}

// scipy: A0=[[0,1],[-1,0]], no inputs, Ts = 0.5: zoh gives the rotation by 0.5 rad
// [[cos .5, sin .5], [-sin .5, cos .5]]; 'bilinear' gives [[15/17, 8/17], [-8/17, 15/17]].
TEST_CASE("autonomous model (Nu == 0): harmonic oscillator discretised and stepped") {
  using Css = ContinuousStateSpace<2, 0, 1>;
  const Css c(Css::MatrixA{{0.0, 1.0}, {-1.0, 0.0}}, Css::MatrixB{}, Css::MatrixC{{1.0, 0.0}},
              Css::MatrixD{});
  auto zoh = discretize_zoh(c, 0.5);
  check_close(zoh.A(),
              Eigen::Matrix2d{{0.8775825618903728, 0.479425538604203},
                              {-0.479425538604203, 0.8775825618903728}},
              1e-15);
  check_close(discretize_tustin(c, 0.5).A(),
              Eigen::Matrix2d{{15.0 / 17.0, 8.0 / 17.0}, {-8.0 / 17.0, 15.0 / 17.0}}, 1e-15);
  // x(k) = rotation by -0.5 k rad of x(0) = [1, 0]: y(k) = cos(0.5 k).
  zoh.reset(Eigen::Vector2d{1.0, 0.0});
  for (int k = 0; k < 20; ++k) {
    CHECK(zoh.step(StateSpace<2, 0, 1>::Input{})[0] == doctest::Approx(std::cos(0.5 * k)));
  }
  CHECK(zoh.spectral_radius() == doctest::Approx(1.0).epsilon(1e-12));
  CHECK(zoh.dc_gain().size() == 0);
}

// scipy: Ad=[[0.9,0.1,0],[-0.2,0.8,0.05],[0,0.1,0.5]]; Bd=[[1,0],[0,0.5],[0.2,-0.3]];
// Cd=[[1,-1,0],[0,0.5,2]]; Dd=[[0,0.1],[0.2,0]];
// u=[[1,0],[0.5,-1],[0,2],[-1,0.25],[0.3,0.3],[2,-0.5]]; x0=[0.1,-0.2,0.3]
// t, y, x = scipy.signal.dlsim((Ad,Bd,Cd,Dd,0.01), u, x0=x0); x_end = Ad@x[-1] + Bd@u[-1];
// dc = Cd @ solve(I - Ad, Bd) + Dd; eig = scipy.linalg.eigvals(Ad).
TEST_CASE("simulate matches scipy dlsim, dc_gain, eigenvalues and spectral radius match scipy") {
  using SS = StateSpace<3, 2, 2>;
  SS model(SS::MatrixA{{0.9, 0.1, 0.0}, {-0.2, 0.8, 0.05}, {0.0, 0.1, 0.5}},
           SS::MatrixB{{1.0, 0.0}, {0.0, 0.5}, {0.2, -0.3}},
           SS::MatrixC{{1.0, -1.0, 0.0}, {0.0, 0.5, 2.0}}, SS::MatrixD{{0.0, 0.1}, {0.2, 0.0}},
           0.01);
  model.reset(SS::State{0.1, -0.2, 0.3});
  const Eigen::Matrix<double, 2, 6> u{{1.0, 0.5, 0.0, -1.0, 0.3, 2.0},
                                      {0.0, -1.0, 2.0, 0.25, 0.3, -0.5}};
  const Eigen::Matrix<double, 2, 6> y = model.simulate(u);
  const Eigen::Matrix<double, 2, 6> y_scipy{
      {0.30000000000000004, 1.135, 2.4760000000000004, 1.1693750000000003, 0.21405750000000015,
       0.2942201250000001},
      {0.7, 0.6775, 0.6822499999999999, -0.9801375000000001, -0.9235925000000003,
       -0.12689818750000026}};
  check_close(y, y_scipy, 1e-14);
  check_close(model.state(), SS::State{2.3516347375, -0.30743746250000015, 0.4172295375}, 1e-14);

  check_close(
      model.dc_gain(),
      Eigen::Matrix2d{{10.0, 0.10000000000000045}, {-3.56923076923077, -0.11538461538461542}},
      1e-13);
  const auto ev = model.eigenvalues();
  // One real pole 0.48619313135802755 and the pair 0.8569034343209867 +- 0.13219446373038038i.
  int real_poles = 0;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(ev[i].imag()) < 1e-12) {
      ++real_poles;
      CHECK(ev[i].real() == doctest::Approx(0.48619313135802755).epsilon(1e-13));
    } else {
      CHECK(ev[i].real() == doctest::Approx(0.8569034343209867).epsilon(1e-13));
      CHECK(std::abs(ev[i].imag()) == doctest::Approx(0.13219446373038038).epsilon(1e-12));
    }
  }
  CHECK(real_poles == 1);
  CHECK(model.spectral_radius() == doctest::Approx(0.8670402943301219).epsilon(1e-13));
  CHECK(model.is_stable());
}

TEST_CASE("dc_gain throws when I - A is singular (integrator), is_stable is false at |z| = 1") {
  using SS = StateSpace<2, 1, 1>;
  const SS integrator(SS::MatrixA{{1.0, 0.0}, {0.0, 0.5}}, SS::MatrixB{{1.0}, {1.0}},
                      SS::MatrixC{{1.0, 1.0}}, SS::MatrixD::Zero(), 0.01);
  CHECK_THROWS_AS((void)integrator.dc_gain(), Error);
  CHECK(message_of([&] { (void)integrator.dc_gain(); }).find("singular") != std::string::npos);
  CHECK_FALSE(integrator.is_stable());
  CHECK(integrator.spectral_radius() == doctest::Approx(1.0));
}

TEST_CASE("invalid construction throws Error naming the entry and the value") {
  using SS = StateSpace<2, 1, 1>;
  SS::MatrixA A = SS::MatrixA::Identity() * 0.5;
  const SS::MatrixB B = SS::MatrixB::Ones();
  const SS::MatrixC C = SS::MatrixC::Ones();
  const SS::MatrixD D = SS::MatrixD::Zero();
  CHECK_NOTHROW(SS(A, B, C, D, 0.02));

  A(1, 0) = std::numeric_limits<double>::quiet_NaN();
  const std::string nan_message = message_of([&] { SS(A, B, C, D, 0.02); });
  CHECK(nan_message.find("A(1,0)") != std::string::npos);
  CHECK(nan_message.find("nan") != std::string::npos);

  SS::MatrixD bad_d = D;
  bad_d(0, 0) = -std::numeric_limits<double>::infinity();
  CHECK(message_of([&] { SS(SS::MatrixA::Zero(), B, C, bad_d, 0.02); }).find("D(0,0)") !=
        std::string::npos);

  CHECK(message_of([&] { SS(SS::MatrixA::Zero(), B, C, D, -0.5); }).find("-0.5") !=
        std::string::npos);
  CHECK_THROWS_AS(SS(SS::MatrixA::Zero(), B, C, D, 0.0), Error);
  CHECK_THROWS_AS(SS(SS::MatrixA::Zero(), B, C, D, std::numeric_limits<double>::infinity()), Error);
  CHECK_THROWS_AS(SS(SS::MatrixA::Zero(), B, C, D, std::numeric_limits<double>::quiet_NaN()),
                  Error);
  CHECK(message_of([&] { (void)discretize_zoh(msd(), 0.0); }).find("sample time") !=
        std::string::npos);
  CHECK_THROWS_AS((void)discretize_tustin(msd(), -1.0), Error);

  using Css = ContinuousStateSpace<1, 1, 1>;
  CHECK(message_of([&] {
          Css(Css::MatrixA{{1.0}}, Css::MatrixB{{std::numeric_limits<double>::infinity()}},
              Css::MatrixC{{1.0}}, Css::MatrixD{{0.0}});
        }).find("B(0,0)") != std::string::npos);
  // Tustin is undefined when A has an eigenvalue at 2/Ts (here 20 1/s with Ts = 0.1 s).
  CHECK(message_of([] {
          (void)discretize_tustin(Css(Css::MatrixA{{20.0}}, Css::MatrixB{{1.0}},
                                      Css::MatrixC{{1.0}}, Css::MatrixD{{0.0}}),
                                  0.1);
        }).find("singular") != std::string::npos);
}

TEST_CASE_TEMPLATE("step, output, simulate and update follow eq. 4.2 entry by entry", SS,
                   StateSpace<1, 1, 1>, StateSpace<2, 0, 1>, StateSpace<3, 2, 2>,
                   StateSpace<4, 1, 3>, StateSpace<6, 2, 1>, StateSpace<5, 3, 2, float>) {
  using Scalar = typename SS::ScalarType;
  constexpr int nx = SS::states, nu = SS::inputs, ny = SS::outputs;
  const double tol = std::is_same_v<Scalar, float> ? 1e-5 : 1e-13;
  std::mt19937_64 rng(4242 + nx * 100 + nu * 10 + ny);
  SS model = random_model<SS>(rng);
  const auto x0 = random_matrix<typename SS::State>(rng);
  model.reset(x0);
  CHECK(model.state() == x0);

  // Hand loop (no Eigen products) of x+ = A x + B u, y = C x + D u.
  Eigen::Matrix<double, nx, 1> x = x0.template cast<double>();
  for (int k = 0; k < 50; ++k) {
    const auto u = random_matrix<typename SS::Input>(rng);
    Eigen::Matrix<double, ny, 1> y_hand;
    for (int i = 0; i < ny; ++i) {
      double acc = 0;
      for (int j = 0; j < nx; ++j) acc += double(model.C()(i, j)) * x[j];
      for (int j = 0; j < nu; ++j) acc += double(model.D()(i, j)) * double(u[j]);
      y_hand[i] = acc;
    }
    Eigen::Matrix<double, nx, 1> x_next;
    for (int i = 0; i < nx; ++i) {
      double acc = 0;
      for (int j = 0; j < nx; ++j) acc += double(model.A()(i, j)) * x[j];
      for (int j = 0; j < nu; ++j) acc += double(model.B()(i, j)) * double(u[j]);
      x_next[i] = acc;
    }
    const typename SS::State before = model.state();
    check_close(model.output(u), y_hand, tol);
    CHECK(model.state() == before);  // output() does not advance
    check_close(model.step(u), y_hand, tol);
    check_close(model.state(), x_next, tol);
    x = model.state().template cast<double>();  // re-anchor to keep float drift out
  }

  SUBCASE("simulate equals repeated steps and leaves the final state") {
    const auto inputs = random_matrix<Eigen::Matrix<Scalar, nu, 8>>(rng);
    SS copy = model;
    const Eigen::Matrix<Scalar, ny, 8> y = model.simulate(inputs);
    for (int k = 0; k < 8; ++k) check_close(y.col(k), copy.step(inputs.col(k)), 0.0);
    check_close(model.state(), copy.state(), 0.0);
  }
  SUBCASE("update equals step on finite data and refuses non-finite data untouched") {
    SS copy = model;
    const auto u = random_matrix<typename SS::Input>(rng);
    typename SS::Output y = SS::Output::Constant(Scalar(7));
    REQUIRE(model.update(u, y) == NumericStatus::ok);
    check_close(y, copy.step(u), 0.0);
    check_close(model.state(), copy.state(), 0.0);
    if constexpr (nu > 0) {
      typename SS::Input bad = u;
      bad[nu - 1] = std::numeric_limits<Scalar>::quiet_NaN();
      const typename SS::State before = model.state();
      typename SS::Output untouched = SS::Output::Constant(Scalar(7));
      CHECK(model.update(bad, untouched) == NumericStatus::non_finite_input);
      CHECK(model.state() == before);
      CHECK(untouched == SS::Output::Constant(Scalar(7)));
      // step() does not check: NaN reaches the state (documented), reset recovers.
      (void)model.step(bad);
      CHECK_FALSE(model.state().allFinite());
      model.reset();
      CHECK(model.state().isZero());
    }
  }
  SUBCASE("a diverging model reports non_finite_result instead of storing Inf") {
    using Scalar_ = Scalar;
    SS big(SS::MatrixA::Identity() * std::numeric_limits<Scalar_>::max(), SS::MatrixB::Zero(),
           SS::MatrixC::Identity(), SS::MatrixD::Zero(), Scalar_(1));
    big.reset(SS::State::Constant(Scalar_(4)));
    typename SS::Output y = SS::Output::Zero();
    CHECK(big.update(SS::Input::Zero(), y) == NumericStatus::non_finite_result);
    CHECK(big.state() == SS::State::Constant(Scalar_(4)));
  }
}

TEST_CASE("parallel: block-diagonal A, stacked inputs and outputs (hand result)") {
  using S1 = StateSpace<1, 1, 1>;
  using S2 = StateSpace<1, 1, 1>;
  S1 g1(S1::MatrixA{{0.5}}, S1::MatrixB{{1.0}}, S1::MatrixC{{2.0}}, S1::MatrixD{{0.1}}, 0.02);
  S2 g2(S2::MatrixA{{-0.3}}, S2::MatrixB{{2.0}}, S2::MatrixC{{1.0}}, S2::MatrixD{{0.0}}, 0.02);
  g1.reset(S1::State{1.0});
  g2.reset(S2::State{-2.0});
  auto p = endohaptics::model::parallel(g1, g2);
  static_assert(std::is_same_v<decltype(p), StateSpace<2, 2, 2>>);
  check_close(p.A(), Eigen::Matrix2d{{0.5, 0.0}, {0.0, -0.3}}, 0.0);
  check_close(p.B(), Eigen::Matrix2d{{1.0, 0.0}, {0.0, 2.0}}, 0.0);
  check_close(p.C(), Eigen::Matrix2d{{2.0, 0.0}, {0.0, 1.0}}, 0.0);
  check_close(p.D(), Eigen::Matrix2d{{0.1, 0.0}, {0.0, 0.0}}, 0.0);
  check_close(p.state(), Eigen::Vector2d{1.0, -2.0}, 0.0);
  // y1 = 2 * 1 + 0.1 * 3 = 2.3, y2 = 1 * -2 = -2; then x = [0.5 + 3, 0.6 + 2 * -1].
  check_close(p.step(Eigen::Vector2d{3.0, -1.0}), Eigen::Vector2d{2.3, -2.0}, 1e-15);
  check_close(p.state(), Eigen::Vector2d{3.5, -1.4}, 1e-15);

  // With an autonomous part: inputs are only those of the first model.
  using S0 = StateSpace<2, 0, 1>;
  const S0 osc(S0::MatrixA{{0.0, 1.0}, {-1.0, 0.0}}, S0::MatrixB{}, S0::MatrixC{{1.0, 0.0}},
               S0::MatrixD{}, 0.02);
  const auto q = endohaptics::model::parallel(g1, osc);
  static_assert(std::is_same_v<std::remove_const_t<decltype(q)>, StateSpace<3, 1, 2>>);
  check_close(q.B(), Eigen::Vector3d{1.0, 0.0, 0.0}, 0.0);
  check_close(q.A().bottomRightCorner<2, 2>(), osc.A(), 0.0);

  S2 other_rate(S2::MatrixA{{0.1}}, S2::MatrixB{{1.0}}, S2::MatrixC{{1.0}}, S2::MatrixD{{0.0}},
                0.01);
  CHECK(message_of([&] { (void)endohaptics::model::parallel(g1, other_rate); }).find("0.01") !=
        std::string::npos);
}

TEST_CASE("series: y of the first feeds u of the second (hand result and simulation)") {
  using S1 = StateSpace<1, 1, 1>;
  const S1 g1(S1::MatrixA{{0.5}}, S1::MatrixB{{1.0}}, S1::MatrixC{{2.0}}, S1::MatrixD{{0.1}}, 0.02);
  const S1 g2(S1::MatrixA{{-0.3}}, S1::MatrixB{{2.0}}, S1::MatrixC{{1.0}}, S1::MatrixD{{0.5}},
              0.02);
  const auto s = endohaptics::model::series(g1, g2);
  static_assert(std::is_same_v<std::remove_const_t<decltype(s)>, StateSpace<2, 1, 1>>);
  // A = [[a1, 0], [b2 c1, a2]] = [[0.5, 0], [4, -0.3]]; B = [b1; b2 d1] = [1; 0.2];
  // C = [d2 c1, c2] = [1, 1]; D = d2 d1 = 0.05.
  check_close(s.A(), Eigen::Matrix2d{{0.5, 0.0}, {4.0, -0.3}}, 1e-15);
  check_close(s.B(), Eigen::Vector2d{1.0, 0.2}, 1e-15);
  check_close(s.C(), Eigen::RowVector2d{1.0, 1.0}, 1e-15);
  check_close(s.D(), Eigen::Matrix<double, 1, 1>{0.05}, 1e-15);

  // MIMO: a 3x2x2 feeding a 2x2x1 equals stepping the two models one after the other.
  std::mt19937_64 rng(7);
  auto first = random_model<StateSpace<3, 2, 2>>(rng);
  auto second = random_model<StateSpace<2, 2, 1>>(rng);
  first.reset(random_matrix<StateSpace<3, 2, 2>::State>(rng));
  second.reset(random_matrix<StateSpace<2, 2, 1>::State>(rng));
  auto chain = endohaptics::model::series(first, second);
  for (int k = 0; k < 40; ++k) {
    const auto u = random_matrix<Eigen::Vector2d>(rng);
    check_close(chain.step(u), second.step(first.step(u)), 1e-12);
  }

  const S1 other_rate(S1::MatrixA{{0.1}}, S1::MatrixB{{1.0}}, S1::MatrixC{{1.0}},
                      S1::MatrixD{{0.0}}, 0.04);
  CHECK_THROWS_AS((void)endohaptics::model::series(g1, other_rate), Error);
}

// Same scipy reference as the double case (Ts = 0.1 s mass-spring-damper), float precision.
TEST_CASE("float instance: zoh of the mass-spring-damper and a step response") {
  using Css = ContinuousStateSpace<2, 1, 1, float>;
  const Css c(Css::MatrixA{{0.0f, 1.0f}, {-4.0f, -0.4f}}, Css::MatrixB{{0.0f}, {1.0f}},
              Css::MatrixC{{1.0f, 0.0f}}, Css::MatrixD::Zero());
  auto d = discretize_zoh(c, 0.1f);
  check_close(d.A(),
              Eigen::Matrix2d{{0.9803295444599633, 0.09737421592285536},
                              {-0.38949686369142156, 0.9413798580908213}},
              2e-6);
  check_close(d.B(), Eigen::Vector2d{0.004917613885009153, 0.09737421592285538}, 2e-6);
  // DC gain of 1 / (s^2 + 0.4 s + 4) is 1/4, preserved exactly by ZOH.
  CHECK(d.dc_gain()(0, 0) == doctest::Approx(0.25f).epsilon(1e-5));
  for (int k = 0; k < 2000; ++k) (void)d.step(StateSpace<2, 1, 1, float>::Input{1.0f});
  CHECK(d.output(StateSpace<2, 1, 1, float>::Input{1.0f})[0] ==
        doctest::Approx(0.25f).epsilon(1e-4));
  CHECK(d.is_stable());
}

// ---------------------------------------------------------------------------------------------
// The dynamic form (Eigen::Dynamic sizes) and the converting constructor.

namespace {

// The 3-state, 2-input, 2-output model of the scipy dlsim case above, as dynamic matrices.
DynamicStateSpace<> scipy_model_dynamic() {
  return {MatrixXd{{0.9, 0.1, 0.0}, {-0.2, 0.8, 0.05}, {0.0, 0.1, 0.5}},
          MatrixXd{{1.0, 0.0}, {0.0, 0.5}, {0.2, -0.3}},
          MatrixXd{{1.0, -1.0, 0.0}, {0.0, 0.5, 2.0}}, MatrixXd{{0.0, 0.1}, {0.2, 0.0}}, 0.01};
}

}  // namespace

TEST_CASE("DynamicStateSpace: sizes from the matrices, state zero of size n") {
  const DynamicStateSpace<> model = scipy_model_dynamic();
  static_assert(DynamicStateSpace<>::states == Eigen::Dynamic);
  static_assert(!DynamicStateSpace<>::fixed_size && StateSpace<3, 2, 2>::fixed_size);
  static_assert(!StateSpace<3, Eigen::Dynamic, 2>::fixed_size);
  CHECK(model.state_size() == 3);
  CHECK(model.input_size() == 2);
  CHECK(model.output_size() == 2);
  CHECK(model.state() == VectorXd::Zero(3));
  CHECK(model.sample_time() == 0.01);
  const StateSpace<3, 2, 2> fixed(model);
  CHECK(fixed.state_size() == 3);  // the runtime sizes of a fixed model are its template sizes
  CHECK(fixed.input_size() == 2);
  CHECK(fixed.output_size() == 2);

  // An autonomous dynamic model: n x 0 B, ny x 0 D, an empty input.
  DynamicStateSpace<> autonomous(MatrixXd{{0.5}}, MatrixXd(1, 0), MatrixXd{{2.0}}, MatrixXd(1, 0),
                                 0.1);
  CHECK(autonomous.input_size() == 0);
  autonomous.reset(VectorXd::Ones(1));
  CHECK(autonomous.step(VectorXd(0)) == VectorXd::Constant(1, 2.0));
  CHECK(autonomous.state() == VectorXd::Constant(1, 0.5));
  CHECK(autonomous.dc_gain().rows() == 1);
  CHECK(autonomous.dc_gain().cols() == 0);
}

TEST_CASE("DynamicStateSpace refuses matrices whose sizes disagree, naming the sizes") {
  const MatrixXd A = MatrixXd::Identity(2, 2) * 0.5;
  const MatrixXd B = MatrixXd::Ones(2, 2);
  const MatrixXd C = MatrixXd::Ones(1, 2);
  const MatrixXd D = MatrixXd::Zero(1, 2);
  CHECK_NOTHROW(DynamicStateSpace<>(A, B, C, D, 0.02));
  auto message = [](const MatrixXd& a, const MatrixXd& b, const MatrixXd& c, const MatrixXd& d) {
    return message_of([&] { DynamicStateSpace<>(a, b, c, d, 0.02); });
  };
  CHECK(message(MatrixXd::Ones(2, 3), B, C, D) ==
        "StateSpace: A is 2 x 3, expected n x n with n >= 1 states");
  CHECK(message(MatrixXd(0, 0), MatrixXd(0, 2), MatrixXd(1, 0), D) ==
        "StateSpace: A is 0 x 0, expected n x n with n >= 1 states");
  CHECK(message(A, MatrixXd::Ones(3, 2), C, D) ==
        "StateSpace: B is 3 x 2, expected 2 x nu (A has 2 states)");
  CHECK(message(A, B, MatrixXd::Ones(1, 3), D) ==
        "StateSpace: C is 1 x 3, expected ny x 2 with ny >= 1 outputs (A has 2 states)");
  CHECK(message(A, B, MatrixXd(0, 2), MatrixXd(0, 2)) ==
        "StateSpace: C is 0 x 2, expected ny x 2 with ny >= 1 outputs (A has 2 states)");
  CHECK(message(A, B, C, MatrixXd::Zero(1, 1)) ==
        "StateSpace: D is 1 x 1, expected 1 x 2 (outputs of C x inputs of B)");
  CHECK(message(A, B, C, MatrixXd::Zero(2, 2)) ==
        "StateSpace: D is 2 x 2, expected 1 x 2 (outputs of C x inputs of B)");
  // Values are checked as for fixed sizes.
  MatrixXd bad = B;
  bad(1, 0) = std::numeric_limits<double>::infinity();
  CHECK(message(A, bad, C, D) == "StateSpace: B(1,0) is not finite (inf)");
  CHECK(message_of([&] { DynamicStateSpace<>(A, B, C, D, 0.0); }) ==
        "StateSpace: sample time must be finite and > 0 s, got 0");
  // A partly dynamic type checks the dynamic sizes against the fixed ones.
  using Mixed = StateSpace<2, Eigen::Dynamic, 1>;
  CHECK_NOTHROW(Mixed(Mixed::MatrixA(A), B, Mixed::MatrixC(C), D, 0.02));
  CHECK(message_of([&] { Mixed(Mixed::MatrixA(A), B, Mixed::MatrixC(C), MatrixXd(1, 1), 0.02); }) ==
        "StateSpace: D is 1 x 1, expected 1 x 2 (outputs of C x inputs of B)");
}

TEST_CASE(
    "DynamicStateSpace steps like scipy dlsim and the fixed form, dc_gain and eigenvalues agree") {
  // The numbers of the scipy case above (dlsim from x0 = [0.1, -0.2, 0.3]).
  DynamicStateSpace<> model = scipy_model_dynamic();
  model.reset(VectorXd{{0.1, -0.2, 0.3}});
  StateSpace<3, 2, 2> fixed(model);
  const MatrixXd u{{1.0, 0.5, 0.0, -1.0, 0.3, 2.0}, {0.0, -1.0, 2.0, 0.25, 0.3, -0.5}};
  const MatrixXd y_scipy{{0.30000000000000004, 1.135, 2.4760000000000004, 1.1693750000000003,
                          0.21405750000000015, 0.2942201250000001},
                         {0.7, 0.6775, 0.6822499999999999, -0.9801375000000001, -0.9235925000000003,
                          -0.12689818750000026}};
  for (Eigen::Index k = 0; k < u.cols(); ++k) {
    const VectorXd uk = u.col(k);
    check_close(model.output(uk), y_scipy.col(k), 1e-14);
    check_close(model.step(uk), y_scipy.col(k), 1e-14);
    check_close(fixed.step(Eigen::Vector2d(uk)), y_scipy.col(k), 1e-14);
    check_close(model.state(), fixed.state(), 1e-14);
  }
  check_close(model.state(), Eigen::Vector3d{2.3516347375, -0.30743746250000015, 0.4172295375},
              1e-14);
  // update: the checked tick, on both forms.
  VectorXd y(2);
  const VectorXd before = model.state();
  CHECK(model.update(VectorXd{{std::nan(""), 0.0}}, y) ==
        endohaptics::model::NumericStatus::non_finite_input);
  CHECK(model.state() == before);
  CHECK(model.update(VectorXd{{0.5, 0.5}}, y) == endohaptics::model::NumericStatus::ok);
  check_close(y, fixed.step(Eigen::Vector2d{0.5, 0.5}), 1e-14);

  // scipy's dc gain; the same eigenvalues (one dynamic solver serves both forms).
  check_close(model.dc_gain(),
              MatrixXd{{10.0, 0.10000000000000045}, {-3.56923076923077, -0.11538461538461542}},
              1e-13);
  check_close(model.dc_gain(), fixed.dc_gain(), 1e-14);
  CHECK(model.eigenvalues() == Eigen::VectorXcd(fixed.eigenvalues()));
  CHECK(model.spectral_radius() == doctest::Approx(0.8670402943301219).epsilon(1e-13));
  CHECK(model.is_stable());
  // The DC gain error names the state count at run time.
  const DynamicStateSpace<> integrator(MatrixXd{{1.0, 0.0}, {0.0, 0.5}}, MatrixXd::Ones(2, 1),
                                       MatrixXd::Ones(1, 2), MatrixXd::Zero(1, 1), 0.01);
  CHECK(message_of([&] { (void)integrator.dc_gain(); }) ==
        "StateSpace: DC gain undefined, I - A is singular (rank 1 of 2; A has a pole at z = 1)");
}

TEST_CASE("reset: a dynamic model refuses an x0 of the wrong size, reset() zeros") {
  DynamicStateSpace<> model = scipy_model_dynamic();
  static_assert(!noexcept(model.reset(std::declval<const VectorXd&>())));
  static_assert(
      noexcept(std::declval<StateSpace<3, 2, 2>&>().reset(std::declval<const Eigen::Vector3d&>())));
  static_assert(noexcept(model.reset()));
  model.reset(VectorXd{{1.0, 2.0, 3.0}});
  CHECK(model.state() == VectorXd{{1.0, 2.0, 3.0}});
  CHECK(message_of([&] { model.reset(VectorXd::Zero(2)); }) ==
        "StateSpace::reset: x0 has 2 entries, the model 3 states");
  CHECK(message_of([&] { model.reset(VectorXd::Zero(4)); }) ==
        "StateSpace::reset: x0 has 4 entries, the model 3 states");
  CHECK(model.state() == VectorXd{{1.0, 2.0, 3.0}});  // unchanged
  model.reset();
  CHECK(model.state() == VectorXd::Zero(3));
}

TEST_CASE("converting constructor: dynamic -> fixed (sizes checked), fixed -> dynamic, -> float") {
  DynamicStateSpace<> dynamic = scipy_model_dynamic();
  dynamic.reset(VectorXd{{0.1, -0.2, 0.3}});

  const StateSpace<3, 2, 2> fixed(dynamic);
  CHECK(fixed.A() == dynamic.A());
  CHECK(fixed.B() == dynamic.B());
  CHECK(fixed.C() == dynamic.C());
  CHECK(fixed.D() == dynamic.D());
  CHECK(fixed.sample_time() == 0.01);
  CHECK(fixed.state() == dynamic.state());  // the current state is copied

  // Wrong sizes: refused, both sizes named.
  CHECK(message_of([&] { StateSpace<2, 2, 2>{dynamic}; }) ==
        "StateSpace: cannot convert a model with 3 states, 2 inputs, 2 outputs into "
        "StateSpace<2, 2, 2>");
  CHECK(message_of([&] { StateSpace<3, 1, 2>{dynamic}; }) ==
        "StateSpace: cannot convert a model with 3 states, 2 inputs, 2 outputs into "
        "StateSpace<3, 1, 2>");
  CHECK(message_of([&] { StateSpace<3, 2, 1, float>{dynamic}; }) ==
        "StateSpace: cannot convert a model with 3 states, 2 inputs, 2 outputs into "
        "StateSpace<3, 2, 1>");
  CHECK(message_of([&] { StateSpace<4, Eigen::Dynamic, 2>{dynamic}; }) ==
        "StateSpace: cannot convert a model with 3 states, 2 inputs, 2 outputs into "
        "StateSpace<4, Dynamic, 2>");
  // Two different fixed sizes cannot convert: that is known at compile time.
  static_assert(!std::is_constructible_v<StateSpace<2, 2, 2>, StateSpace<3, 2, 2>>);
  static_assert(std::is_constructible_v<StateSpace<3, 2, 2, float>, StateSpace<3, 2, 2>>);
  static_assert(!std::is_convertible_v<DynamicStateSpace<>, StateSpace<3, 2, 2>>);  // explicit
  // A partly dynamic target takes any size where it is dynamic.
  const StateSpace<3, Eigen::Dynamic, 2> mixed(dynamic);
  CHECK(mixed.input_size() == 2);

  // Fixed -> dynamic -> fixed: bit-exact, state included.
  const DynamicStateSpace<> back(fixed);
  CHECK(back.A() == fixed.A());
  CHECK(back.state() == fixed.state());
  CHECK(StateSpace<3, 2, 2>(back).D() == fixed.D());

  // double -> float (fixed and dynamic): rounded once, then the float model steps in float.
  const StateSpace<3, 2, 2, float> single(dynamic);
  CHECK(single.A() == dynamic.A().cast<float>());
  CHECK(single.B() == dynamic.B().cast<float>());
  CHECK(single.sample_time() == 0.01f);
  CHECK(single.state() == dynamic.state().cast<float>());
  const DynamicStateSpace<float> single_dynamic(fixed);
  CHECK(single_dynamic.C() == fixed.C().cast<float>());
  CHECK(StateSpace<3, 2, 2, double>(single).A() == single.A().cast<double>());  // float -> double
  // An entry that overflows float is refused as a non-finite entry of the target.
  MatrixXd huge_a = dynamic.A();
  huge_a(0, 0) = 1e300;
  const DynamicStateSpace<> huge(huge_a, dynamic.B(), dynamic.C(), dynamic.D(), 0.01);
  CHECK(message_of([&] { StateSpace<3, 2, 2, float>{huge}; }) ==
        "StateSpace: A(0,0) is not finite (inf)");
}

TEST_CASE("embed_states: a lower-order model in more states, output for output the same") {
  std::mt19937_64 rng(7);
  DynamicStateSpace<> low(random_model<StateSpace<2, 2, 1>>(rng));
  low.reset(VectorXd{{0.3, -0.1}});
  const DynamicStateSpace<> six = endohaptics::model::embed_states(low, 6);
  REQUIRE(six.state_size() == 6);
  CHECK(six.input_size() == 2);
  CHECK(six.output_size() == 1);
  CHECK(six.sample_time() == low.sample_time());
  CHECK(six.spectral_radius() == doctest::Approx(low.spectral_radius()));
  CHECK(six.state() == (VectorXd(6) << 0.3, -0.1, 0, 0, 0, 0).finished());
  // In the fixed 6-state type the real-time path runs: the same outputs, sample for sample.
  StateSpace<6, 2, 1> fixed(six);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  double worst = 0.0;
  for (int k = 0; k < 500; ++k) {
    const Eigen::Vector2d in(u(rng), u(rng));
    const double expected = low.step(VectorXd(in))(0);
    worst = std::max(worst, std::abs(fixed.step(in)(0) - expected));
  }
  CHECK(worst == 0.0);  // the added states are zero and decoupled: not even rounding differs
  CHECK(fixed.state().tail<4>().isZero());
  // Same order: the model as it is; fewer states than the order: refused.
  CHECK(endohaptics::model::embed_states(low, 2).A() == low.A());
  CHECK(message_of([&] { (void)endohaptics::model::embed_states(low, 1); }) ==
        "embed_states: a model of order 2 does not fit in 1 states");
}

TEST_CASE(
    "the fixed form converted from a dynamic one ticks without allocating, the dynamic does") {
  const DynamicStateSpace<> dynamic = scipy_model_dynamic();
  StateSpace<3, 2, 2> fixed(dynamic);
  DynamicStateSpace<> configured = dynamic;
  double sink = 0.0;
  const long fixed_allocations = allocations_during([&] {
    Eigen::Vector2d y;
    for (int k = 0; k < 10000; ++k) {
      const Eigen::Vector2d u{std::sin(0.01 * k), std::cos(0.01 * k)};
      sink += fixed.step(u)[0];
      if (fixed.update(u, y) == endohaptics::model::NumericStatus::ok) sink += y[1];
    }
  });
  CHECK(std::isfinite(sink));
  CHECK(fixed_allocations == 0);
  // The dynamic form is for configuration and offline use: its ticks allocate (documented).
  const VectorXd u = VectorXd::Ones(2);
  const long dynamic_allocations = allocations_during([&] {
    for (int k = 0; k < 10; ++k) sink += configured.step(u)[0];
  });
  CHECK(dynamic_allocations >= 10);
}

}  // namespace model_state_space_test
