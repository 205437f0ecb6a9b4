#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include "endohaptics/model/dense_numerics.hpp"
#include "endohaptics/model/human_arm_model.hpp"

#include <doctest/doctest.h>

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <vector>

namespace model_human_arm_model_test {

namespace {

using endohaptics::Error;
using endohaptics::model::human_arm_admittance;
using endohaptics::model::human_arm_impedance;
using endohaptics::model::HumanArm3;
using endohaptics::model::HumanArmModel;
using endohaptics::model::HumanArmParameters;
using endohaptics::model::NumericStatus;
using endohaptics::test::allocations_during;
using cd = std::complex<double>;

// Reference numbers from /usr/bin/python3 (numpy 1.24.2, scipy 1.10.1), built from eq. 5.3 and
// table 5.1 alone (not from the header's matrices):
//   b1, b2, k1, k2, m = 4.5, 7.9, 48.8, 375.0, 1.46
//   num = [m, b1 + b2, k1 + k2]
//   den = [m*b1, m*k1 + b1*b2, k1*b2 + b1*k2, k2*k1]
//   np.roots(den)  -> poles of x_m/F_h
//   np.roots(num)  -> zeros of x_m/F_h (= poles of the impedance)
//   A, B, C, D = scipy.signal.tf2ss(num, den)
//   Ad, Bd, Cd, Dd, _ = scipy.signal.cont2discrete((A, B, C, D), 1e-3, method='zoh')
//   t, y, x = scipy.signal.dlsim((Ad, Bd, Cd, Dd, 1e-3), np.ones(1001))
//   y[[10, 100, 300, 1000], 0]  -> unit force step response x_m(k)
const std::array<cd, 3> numpy_poles = {cd(-10.844444444444447, 0.0),
                                       cd(-2.705479452054786, -15.796508981512405),
                                       cd(-2.705479452054786, 15.796508981512405)};
const std::array<cd, 2> numpy_zeros = {cd(-4.246575342465754, -16.499714253995478),
                                       cd(-4.246575342465754, 16.499714253995478)};
const std::array<int, 4> scipy_steps = {10, 100, 300, 1000};
const std::array<double, 4> scipy_step_response = {0.00213953393033398, 0.01589997262146249,
                                                   0.02253787499947493, 0.02333830668587894};

// Orders complex numbers by real part, then imaginary part (real parts within 1e-9 count as
// equal, so the two members of a conjugate pair always come out imaginary-negative first).
bool by_real_then_imag(cd a, cd b) {
  return std::abs(a.real() - b.real()) > 1e-9 ? a.real() < b.real() : a.imag() < b.imag();
}

template <typename Vector>
std::vector<cd> sorted_eigenvalues(const Vector& values) {
  std::vector<cd> out;
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    out.emplace_back(static_cast<double>(values[i].real()), static_cast<double>(values[i].imag()));
  }
  std::sort(out.begin(), out.end(), by_real_then_imag);
  return out;
}

// Eigenvalues of A by the library's dynamic-size solver (model/dense_numerics.hpp: compiled once
// for the tests, where a fixed-size EigenSolver per size costs seconds of compile time).
Eigen::VectorXcd eigenvalues_of(const Eigen::MatrixXd& A) {
  Eigen::VectorXcd values;
  REQUIRE(endohaptics::model::numerics::eigenvalues<double>(A, values));
  return values;
}

// Frequency response C (jw I - A)^-1 B + D of a continuous model at w rad/s.
template <typename Model>
Eigen::MatrixXcd frequency_response(const Model& m, double w) {
  const auto n = m.A().rows();
  const Eigen::MatrixXcd sI_A =
      cd(0.0, w) * Eigen::MatrixXcd::Identity(n, n) - m.A().template cast<cd>();
  return m.C().template cast<cd>() * sI_A.partialPivLu().solve(m.B().template cast<cd>()) +
         m.D().template cast<cd>();
}

}  // namespace

TEST_CASE("table 5.1 defaults and the static compliance (k1 + k2) / (k1 k2)") {
  const HumanArmParameters<> p;
  CHECK(p.b1 == 4.5);
  CHECK(p.b2 == 7.9);
  CHECK(p.k1 == 48.8);
  CHECK(p.k2 == 375.0);
  CHECK(p.m_h == 1.46);
  // (48.8 + 375) / (48.8 * 375) = 423.8 / 18300 = 0.0231584699... m/N
  CHECK(p.static_compliance() == doctest::Approx(423.8 / 18300.0).epsilon(1e-15));

  // DC of the continuous admittance, -C A^-1 B + D: x_m = compliance * F, v_m = 0.
  const auto G = human_arm_admittance(p);
  const Eigen::Vector2d dc = -G.C() * G.A().partialPivLu().solve(G.B()) + G.D();
  CHECK(dc[0] == doctest::Approx(p.static_compliance()).epsilon(1e-12));
  CHECK(std::abs(dc[1]) < 1e-15);
  // And of the discrete one, at the loop rates of the worksheet (1 kHz, 638 Hz, 100 Hz).
  for (const double ts : {1e-3, 1.0 / 638.0, 1e-2}) {
    const HumanArmModel<> arm(ts);
    const auto gain = arm.admittance().dc_gain();
    CAPTURE(ts);
    CHECK(gain(0, 0) == doctest::Approx(p.static_compliance()).epsilon(1e-10));
    CHECK(std::abs(gain(1, 0)) < 1e-12);
    // Impedance at DC: F = k1 (x_m - x_h) with x_h = k1 x_m / (k1 + k2): k1 k2 / (k1 + k2).
    const auto z = arm.impedance().dc_gain();
    CHECK(z(0, 0) == doctest::Approx(1.0 / p.static_compliance()).epsilon(1e-10));
  }
}

TEST_CASE("continuous poles are the roots of the eq. 5.3 denominator (numpy.roots)") {
  const HumanArmParameters<> p;
  const auto G = human_arm_admittance(p);
  const auto poles = sorted_eigenvalues(eigenvalues_of(G.A()));
  REQUIRE(poles.size() == 3);
  for (std::size_t i = 0; i < 3; ++i) {
    CAPTURE(i);
    CHECK(std::abs(poles[i] - numpy_poles[i]) < 1e-12);
  }
  // The impedance's poles are the zeros of eq. 5.3.
  const auto Z = human_arm_impedance(p);
  const auto zeros = sorted_eigenvalues(eigenvalues_of(Z.A()));
  for (std::size_t i = 0; i < 2; ++i) CHECK(std::abs(zeros[i] - numpy_zeros[i]) < 1e-12);
  // The whole transfer function x_m/F_h equals eq. 5.3 at a few frequencies.
  for (const double w : {0.1, 3.0, 16.0, 100.0}) {
    const cd s(0.0, w);
    const cd eq_5_3 = (p.m_h * s * s + (p.b2 + p.b1) * s + (p.k2 + p.k1)) /
                      (p.m_h * p.b1 * s * s * s + (p.m_h * p.k1 + p.b1 * p.b2) * s * s +
                       (p.k1 * p.b2 + p.b1 * p.k2) * s + p.k2 * p.k1);
    CAPTURE(w);
    CHECK(std::abs(frequency_response(G, w)(0, 0) - eq_5_3) < 1e-12 * std::abs(eq_5_3));
  }
}

TEST_CASE("discrete poles are exp(continuous poles * Ts)") {
  for (const double ts : {1e-3, 1.0 / 638.0, 1e-2}) {
    const HumanArmModel<> arm(ts);
    const auto discrete = sorted_eigenvalues(arm.admittance().eigenvalues());
    std::vector<cd> expected;
    for (const cd p : numpy_poles) expected.push_back(std::exp(p * ts));
    std::sort(expected.begin(), expected.end(), by_real_then_imag);
    CAPTURE(ts);
    for (std::size_t i = 0; i < 3; ++i) CHECK(std::abs(discrete[i] - expected[i]) < 1e-12);
    const auto impedance = sorted_eigenvalues(arm.impedance().eigenvalues());
    for (std::size_t i = 0; i < 2; ++i) {
      const cd z = std::exp(numpy_zeros[i] * ts);
      const bool found = std::any_of(impedance.begin(), impedance.end(),
                                     [&](cd e) { return std::abs(e - z) < 1e-12; });
      CHECK(found);
    }
  }
}

TEST_CASE_TEMPLATE("a force step settles to the static compliance", Scalar, double, float) {
  const double ts = 1e-3;
  HumanArmModel<Scalar> arm(static_cast<Scalar>(ts));
  const double compliance = HumanArmParameters<>{}.static_compliance();
  const double tol = std::is_same_v<Scalar, float> ? 1e-5 : 1e-12;
  Scalar x = 0, v = 0;
  for (int k = 0; k <= 10000; ++k) {  // 10 s; slowest time constant 1 / 2.705 s = 0.37 s
    REQUIRE(arm.apply_force(Scalar(1), x, v) == NumericStatus::ok);
    for (std::size_t i = 0; i < scipy_steps.size(); ++i) {
      if (k == scipy_steps[i]) {
        CAPTURE(k);
        CHECK(static_cast<double>(x) == doctest::Approx(scipy_step_response[i])
                                            .epsilon(std::is_same_v<Scalar, float> ? 1e-4 : 1e-10));
      }
    }
  }
  CHECK(static_cast<double>(x) == doctest::Approx(compliance).epsilon(tol * 100));
  CHECK(std::abs(static_cast<double>(v)) < tol);
  // The hand settles at F / k2 (the arm spring carries the whole force).
  CHECK(static_cast<double>(arm.hand_position()) ==
        doctest::Approx(1.0 / 375.0).epsilon(tol * 100));
  // A 2 N step doubles everything (linearity), from rest.
  arm.reset();
  for (int k = 0; k <= 10000; ++k) REQUIRE(arm.apply_force(Scalar(2), x, v) == NumericStatus::ok);
  CHECK(static_cast<double>(x) == doctest::Approx(2 * compliance).epsilon(tol * 100));
}

TEST_CASE("the two directions agree: imposing the motion a force produced recovers the force") {
  const HumanArmParameters<> p;
  // Continuous time, exactly: the admittance's [x_m, v_m] per newton fed to the impedance.
  const auto G = human_arm_admittance(p);
  const auto Z = human_arm_impedance(p);
  for (const double w : {0.01, 1.0, 10.0, 15.8, 100.0, 1000.0}) {
    const Eigen::MatrixXcd motion = frequency_response(G, w);  // 2 x 1
    const cd force = (frequency_response(Z, w) * motion)(0, 0);
    CAPTURE(w);
    CHECK(std::abs(force - cd(1.0, 0.0)) < 1e-12);
  }

  // Discrete time at 1 kHz: a smooth force (1 N + 2 N at 1 Hz + 0.5 N at 7 Hz).
  const double ts = 1e-3;
  HumanArmModel<> forward(ts), backward(ts);
  double worst = 0;
  for (int k = 0; k < 5000; ++k) {
    const double t = k * ts;
    const double f = 1.0 + 2.0 * std::sin(2 * std::numbers::pi * t) +
                     0.5 * std::sin(2 * std::numbers::pi * 7.0 * t);
    double x = 0, v = 0, recovered = 0;
    REQUIRE(forward.apply_force(f, x, v) == NumericStatus::ok);
    REQUIRE(backward.impose_motion(x, v, recovered) == NumericStatus::ok);
    worst = std::max(worst, std::abs(recovered - f));
  }
  MESSAGE("largest force mismatch over 5 s at 1 kHz: " << worst << " N (peak force 3.5 N)");
  CHECK(worst < 2e-3);

  // A constant force: both directions agree to rounding once settled.
  HumanArmModel<> a(ts), b(ts);
  double x = 0, v = 0, recovered = 0;
  for (int k = 0; k < 10000; ++k) {
    REQUIRE(a.apply_force(1.5, x, v) == NumericStatus::ok);
    REQUIRE(b.impose_motion(x, v, recovered) == NumericStatus::ok);
  }
  CHECK(recovered == doctest::Approx(1.5).epsilon(1e-9));
}

TEST_CASE("one model switches causality on the same hand state") {
  const double ts = 1e-3;
  HumanArmModel<> reference(ts), switching(ts);
  double x = 0, v = 0, f = 0;
  for (int k = 0; k < 300; ++k) {
    REQUIRE(reference.apply_force(1.0, x, v) == NumericStatus::ok);
    REQUIRE(switching.apply_force(1.0, x, v) == NumericStatus::ok);
  }
  // Hold the stylus where the force left it: the hand keeps moving, the force changes.
  REQUIRE(switching.impose_motion(x, 0.0, f) == NumericStatus::ok);
  CHECK(switching.hand_position() == doctest::Approx(reference.hand_position()).epsilon(1e-3));
  // The force at the switch is the force on the hand through the spring and damper (eq. 5.1):
  // with the stylus stopped, v_m = 0.
  const double expected =
      48.8 * (x - reference.hand_position()) + 4.5 * (0.0 - reference.hand_velocity());
  CHECK(f == doctest::Approx(expected).epsilon(1e-3));
  // Held long enough, the hand settles against the held stylus: x_h = k1 x_m / (k1 + k2).
  for (int k = 0; k < 10000; ++k) REQUIRE(switching.impose_motion(x, 0.0, f) == NumericStatus::ok);
  CHECK(switching.hand_position() == doctest::Approx(48.8 * x / 423.8).epsilon(1e-9));
  CHECK(f == doctest::Approx(48.8 * 375.0 / 423.8 * x).epsilon(1e-9));
  // Back to admittance with zero force: the arm relaxes to the origin.
  for (int k = 0; k < 10000; ++k) REQUIRE(switching.apply_force(0.0, x, v) == NumericStatus::ok);
  CHECK(std::abs(x) < 1e-9);
  CHECK(std::abs(switching.hand_position()) < 1e-9);
}

TEST_CASE("non-finite inputs are replaced and reported, the state stays finite") {
  HumanArmModel<> arm(1e-3);
  double x = 0, v = 0, f = 0;
  for (int k = 0; k < 100; ++k) REQUIRE(arm.apply_force(1.0, x, v) == NumericStatus::ok);
  HumanArmModel<> zero_force = arm;  // the same arm, fed 0 N instead of NaN
  double x0 = 0, v0 = 0;
  CHECK(arm.apply_force(std::numeric_limits<double>::quiet_NaN(), x, v) ==
        NumericStatus::non_finite_input);
  REQUIRE(zero_force.apply_force(0.0, x0, v0) == NumericStatus::ok);
  CHECK(x == x0);
  CHECK(v == v0);
  CHECK(arm.admittance().state().allFinite());

  const double held = x;
  CHECK(arm.impose_motion(std::numeric_limits<double>::infinity(), 0.1, f) ==
        NumericStatus::non_finite_input);
  CHECK(std::isfinite(f));
  CHECK(arm.impedance().state().allFinite());
  REQUIRE(arm.impose_motion(0.01, 0.0, f) == NumericStatus::ok);
  CHECK(arm.impose_motion(std::numeric_limits<double>::quiet_NaN(), 0.0, f) ==
        NumericStatus::non_finite_input);
  CHECK(std::isfinite(f));
  CHECK(held != 0.0);
}

TEST_CASE("parameters and sample time are validated, naming the culprit") {
  HumanArmParameters<> p;
  CHECK_NOTHROW(HumanArmModel<>(1e-3, p));
  p.b1 = 0.0;
  CHECK_THROWS_WITH_AS(HumanArmModel<>(1e-3, p),
                       "HumanArmParameters: b1 must be finite and > 0, got 0", Error);
  p = {};
  p.k2 = -375.0;
  CHECK_THROWS_WITH_AS(HumanArmModel<>(1e-3, p),
                       doctest::Contains("k2 must be finite and > 0, got -375"), Error);
  p = {};
  p.m_h = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH_AS(static_cast<void>(human_arm_admittance(p)), doctest::Contains("m_h"), Error);
  CHECK_THROWS_WITH_AS(static_cast<void>(human_arm_impedance(p)), doctest::Contains("m_h"), Error);
  CHECK_THROWS_WITH_AS(HumanArmModel<>(0.0),
                       doctest::Contains("sample time must be finite and > 0 s, got 0"), Error);
  CHECK_THROWS_WITH_AS(HumanArmModel<float>(-1e-3f), doctest::Contains("sample time"), Error);
  CHECK_THROWS_WITH_AS(HumanArm3<>(1e-3, {HumanArmParameters<>{}, HumanArmParameters<>{}, p}),
                       doctest::Contains("m_h"), Error);
}

TEST_CASE("HumanArm3: three independent axes, each equal to the scalar model") {
  HumanArmParameters<> stiff;
  stiff.k2 = 750.0;
  HumanArm3<> arm(1e-3, {HumanArmParameters<>{}, stiff, HumanArmParameters<>{}});
  HumanArmModel<> x_axis(1e-3), y_axis(1e-3, stiff);
  Eigen::Vector3d position, velocity, force;
  double x = 0, vx = 0, y = 0, vy = 0;
  for (int k = 0; k < 2000; ++k) {
    const Eigen::Vector3d f(1.0, 1.0, -0.5 * std::sin(0.01 * k));
    REQUIRE(arm.apply_force(f, position, velocity) == NumericStatus::ok);
    REQUIRE(x_axis.apply_force(f[0], x, vx) == NumericStatus::ok);
    REQUIRE(y_axis.apply_force(f[1], y, vy) == NumericStatus::ok);
    REQUIRE(position[0] == x);
    REQUIRE(velocity[0] == vx);
    REQUIRE(position[1] == y);
  }
  CHECK(position[1] < position[0]);  // the stiffer arm yields less to the same force
  CHECK(arm.axis(1).parameters() == stiff);

  Eigen::Vector3d bad_force(0.0, std::numeric_limits<double>::quiet_NaN(), 0.0);
  CHECK(arm.apply_force(bad_force, position, velocity) == NumericStatus::non_finite_input);
  CHECK(position.allFinite());
  REQUIRE(arm.impose_motion(position, Eigen::Vector3d::Zero(), force) == NumericStatus::ok);
  CHECK(force.allFinite());
  arm.reset();
  REQUIRE(arm.apply_force(Eigen::Vector3d::Zero(), position, velocity) == NumericStatus::ok);
  CHECK(position == Eigen::Vector3d::Zero());
}

TEST_CASE(
    "HumanArmModel: a tick allocates nothing (operator new counter, EIGEN_RUNTIME_NO_MALLOC)") {
  HumanArm3<> arm(1e-3);
  HumanArmModel<float> single(1e-3f);
  Eigen::Vector3d position, velocity, force;
  float x = 0, v = 0, f = 0;
  int ok = 0;
  const long allocations = allocations_during([&] {
    for (int k = 0; k < 10000; ++k) {
      const Eigen::Vector3d applied = Eigen::Vector3d::Constant(std::sin(0.001 * k));
      if (k % 2 == 0) {
        ok += arm.apply_force(applied, position, velocity) == NumericStatus::ok;
        ok += single.apply_force(static_cast<float>(applied[0]), x, v) == NumericStatus::ok;
      } else {
        ok += arm.impose_motion(position, velocity, force) == NumericStatus::ok;
        ok += single.impose_motion(x, v, f) == NumericStatus::ok;
      }
    }
  });
  CHECK(allocations == 0);
  CHECK(ok == 20000);
  CHECK(position.allFinite());
}

}  // namespace model_human_arm_model_test
