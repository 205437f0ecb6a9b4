#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include "endohaptics/estimation/force_estimator.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "endohaptics/kinematics/cylindrical_mapper.hpp"
#include "endohaptics/teleop/teleop_loop.hpp"
#include "shared_data.hpp"
#include "test_support.hpp"

namespace estimation_force_estimator_test {

using endohaptics::test::message_of;

namespace {

namespace est = endohaptics::estimation;
namespace m = endohaptics::model;
namespace rate = endohaptics::estimation::rate;
using endohaptics::Error;
using endohaptics::protocol::Motor;
using endohaptics::test::allocations_during;
using est::ForceEstimator;
using est::ForceEstimator2016;
using est::JointState;
using est::NumericStatus;

using Decimated = ForceEstimator<rate::Decimate>;
using Forces = Decimated::Forces;

template <typename Scalar = double>
JointState<Scalar> constant_state(Scalar i_roll, Scalar i_pitch, Scalar i_clamp1, Scalar i_clamp2,
                                  Scalar velocity = 0) {
  JointState<Scalar> s;
  s.current << i_roll, i_pitch, i_clamp1, i_clamp2;
  s.velocity.setConstant(velocity);
  return s;
}

// A varying but repeatable input: currents beyond every gate level, small velocities.
JointState<double> wavy_state(int k) {
  JointState<double> s;
  const double t = 0.001 * k;
  s.current << 0.9 + 0.2 * std::sin(3 * t), 0.5 + 0.2 * std::sin(5 * t),
      0.5 + 0.2 * std::cos(4 * t), -0.5 - 0.2 * std::sin(2 * t);
  s.velocity << 0.1 * std::cos(3 * t), 0.05 * std::sin(7 * t), -0.08 * std::sin(4 * t),
      0.08 * std::sin(4 * t);
  s.position = 0.1 * s.velocity;
  s.setpoint = s.position.array() + 0.01;
  return s;
}

// The 2016 defaults with a pitch model that rate::Resample accepts: the linear yaw model (same
// type as the pitch preset; the pitch preset has the pole -0.0952 and cannot be resampled).
est::ForceModels<est::RollModel2016<>, est::PitchModel2016<>, est::ClampModel2016<>>
resamplable_models() {
  auto models = est::models_2016();
  models.pitch = est::PitchModel2016<>(m::yaw_force_2016());
  return models;
}

// Random continuous model with poles -1..-30 rad/s (and a complex pair when Nx >= 2),
// discretised with ZOH at 0.02 s: its discrete poles are never on the negative real axis.
template <int Nx, int Nu, int Ny>
m::StateSpace<Nx, Nu, Ny> random_discrete_model(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  using CSS = m::ContinuousStateSpace<Nx, Nu, Ny>;
  typename CSS::MatrixA D = CSS::MatrixA::Zero();
  for (int i = 0; i < Nx; ++i) D(i, i) = -1.0 - 29.0 * (0.5 + 0.5 * u(rng));
  if constexpr (Nx >= 2) {
    D(0, 1) = 8.0;
    D(1, 0) = -8.0;
    D(1, 1) = D(0, 0);
  }
  typename CSS::MatrixA T;
  for (Eigen::Index i = 0; i < T.size(); ++i) T.data()[i] = u(rng);
  T += 3.0 * CSS::MatrixA::Identity();  // well conditioned
  const typename CSS::MatrixA A = T * D * T.inverse();
  typename CSS::MatrixB B;
  for (Eigen::Index i = 0; i < B.size(); ++i) B.data()[i] = u(rng);
  typename CSS::MatrixC C;
  for (Eigen::Index i = 0; i < C.size(); ++i) C.data()[i] = u(rng);
  typename CSS::MatrixD Dd;
  for (Eigen::Index i = 0; i < Dd.size(); ++i) Dd.data()[i] = u(rng);
  return m::discretize_zoh(CSS(A, B, C, Dd), 0.02);
}

template <int Nx_, int Nu_, int Ny_>
struct Sizes {
  static constexpr int Nx = Nx_;
  static constexpr int Nu = Nu_;
  static constexpr int Ny = Ny_;
};

}  // namespace

TEST_CASE("a model sample time that differs from the loop period is refused by rate::SameRate") {
  // Appendix C models: 0.02 s; loop 1 kHz. The roll model is memoryless (C = 0) and exempt, so
  // the first joint named is the pitch.
  const std::string what = message_of([] { (void)ForceEstimator<rate::SameRate>(); });
  CHECK(what.find("pitch model's sample time 0.02 s differs from the loop period 0.001 s") !=
        std::string::npos);
  CHECK(what.find("rate::Decimate or rate::Resample") != std::string::npos);

  // At the models' own period the estimator is the models themselves, bit for bit:
  // f = -current_sign * unit_scale * y(k) = unit_scale * y(k) (2016 current_sign -1),
  // y(k) = C x(k) + D u(k) before x advances.
  est::ForceEstimatorSettings<double> settings;
  settings.loop_period = 0.02;
  ForceEstimator<rate::SameRate> estimator(settings);
  CHECK(estimator.ticks_per_model_step(Motor::pitch) == 1);
  auto roll = m::roll_torque_2016();
  auto pitch = m::pitch_force_2016();
  auto clamp1 = m::yaw_force_2016_hw(0.21);
  auto clamp2 = m::yaw_force_2016_hw(0.20);
  for (int k = 0; k < 500; ++k) {
    const JointState<double> s = wavy_state(20 * k);
    Forces f;
    REQUIRE(estimator.step(s, f) == NumericStatus::ok);
    const Eigen::Vector2d u_pitch(s.current[1], s.velocity[1]);
    const Eigen::Vector2d u_clamp1(s.current[2], s.velocity[2]);
    const Eigen::Vector2d u_clamp2(s.current[3], s.velocity[3]);
    const double roll_y = roll.step(Eigen::Matrix<double, 1, 1>(s.current[0]))[0];
    CAPTURE(k);
    CHECK(f[0] == roll_y);
    CHECK(f[1] == pitch.step(u_pitch)[0] * 9.80665e-3);
    CHECK(f[2] == clamp1.step(u_clamp1)[0]);
    CHECK(f[3] == clamp2.step(u_clamp2)[0]);
  }
}

TEST_CASE("every default template argument set constructs and runs with its default models") {
  // The default rate policy must accept the default (2016, Ts = 0.02 s) models at the default
  // loop period (1 ms): ForceEstimator<> and ForceEstimator2016<> construct and estimate.
  auto run = [](auto& estimator) {
    for (int k = 0; k < 200; ++k) {
      const JointState<double> s = wavy_state(k);
      endohaptics::protocol::MotorState<4> packet;
      packet.position = s.position;
      packet.velocity = s.velocity;
      packet.current = s.current;
      Eigen::Vector4d force = Eigen::Vector4d::Constant(std::numeric_limits<double>::quiet_NaN());
      REQUIRE(estimator.estimate(packet, s.setpoint, force));
      REQUIRE(force.allFinite());
    }
  };
  ForceEstimator<> defaults;
  run(defaults);
  CHECK(defaults.ticks_per_model_step(Motor::pitch) == 20);
  ForceEstimator2016<> defaults_2016;
  run(defaults_2016);
  ForceEstimator2016<rate::Decimate, float> in_float;
  run(in_float);
}

TEST_CASE("rate::Decimate needs an integer ratio within 1e-9, rate::Resample refuses the pitch") {
  est::ForceEstimatorSettings<double> settings;
  settings.loop_period = 0.003;  // 0.02 / 0.003 = 6.67
  CHECK(message_of([&] { (void)Decimated(settings); })
            .find("pitch model's sample time 0.02 s is not an integer multiple of the loop "
                  "period 0.003 s") != std::string::npos);
  settings.loop_period = 0.02 / (20.0 + 5e-8);  // ratio 20.00000005: off by 5e-8 > 1e-9
  CHECK_THROWS_AS((void)Decimated(settings), Error);
  settings.loop_period = 0.02 / (20.0 + 5e-10);  // within 1e-9
  CHECK(Decimated(settings).ticks_per_model_step(Motor::clamp1) == 20);
  settings.loop_period = 0.0008;  // 25 ticks per model step
  const Decimated at_1250_hz(settings);
  CHECK(at_1250_hz.ticks_per_model_step(Motor::pitch) == 25);
  CHECK(at_1250_hz.ticks_per_model_step(Motor::clamp2) == 25);
  CHECK(at_1250_hz.ticks_per_model_step(Motor::roll) == 1);  // memoryless: every tick
  CHECK(Decimated().ticks_per_model_step(Motor::clamp1) == 20);

  // scipy: numpy.linalg.eigvals of C.4 gives -0.0952137 (real) among the pitch poles.
  const std::string what = message_of([] { (void)ForceEstimator<rate::Resample>(); });
  CHECK(what.find("the pitch model cannot be resampled at 0.001 s") != std::string::npos);
  CHECK(what.find("eigenvalue -0.09521369805") != std::string::npos);
  CHECK(what.find("negative real axis") != std::string::npos);
  // With a resamplable pitch model every joint runs at the loop period.
  const ForceEstimator<rate::Resample> resampled(resamplable_models(), {});
  CHECK(resampled.ticks_per_model_step(Motor::clamp1) == 1);
  CHECK(resampled.joint_model<Motor::clamp1>().sample_time() == 0.001);
  CHECK(resampled.joint_model<Motor::roll>().sample_time() == 0.02);  // memoryless: kept
}

TEST_CASE("resample_zoh: the yaw model stepped 20 times at 1 ms equals one step at 20 ms") {
  const auto yaw = m::yaw_force_2016();
  auto fine = est::resample_zoh(yaw, 0.001);
  CHECK(fine.sample_time() == 0.001);
  // Back to 0.02 s: the printed matrices again.
  const auto back = est::resample_zoh(fine, 0.02);
  CHECK((back.A() - yaw.A()).norm() < 1e-11);
  CHECK((back.B() - yaw.B()).norm() < 1e-10);
  CHECK(back.C() == yaw.C());

  auto coarse = yaw;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> input(-1.0, 1.0);
  double worst = 0.0;
  for (int k = 0; k < 300; ++k) {
    const Eigen::Vector2d u(input(rng), input(rng));
    const double y_coarse = coarse.step(u)[0];
    double y_fine = 0;
    for (int i = 0; i < 20; ++i) {
      const double y = fine.step(u)[0];
      if (i == 0) y_fine = y;  // y at the start of the period, as the coarse model gives it
    }
    worst = std::max(worst, std::abs(y_fine - y_coarse));
    REQUIRE((fine.state() - coarse.state()).norm() <= 1e-9 * (1.0 + coarse.state().norm()));
  }
  CHECK(worst < 1e-9);

  // Memoryless models (C = 0) only change their sample time.
  const auto roll = est::resample_zoh(m::roll_torque_2016(), 0.001);
  CHECK(roll.sample_time() == 0.001);
  CHECK(roll.D()(0, 0) == 0.070);
  // No real logarithm: singular A, or a pole on the negative real axis.
  const m::StateSpace<2, 1, 1> singular(Eigen::Matrix2d{{0.5, 0.0}, {0.0, 0.0}},
                                        Eigen::Vector2d(1, 1), Eigen::RowVector2d(1, 1),
                                        Eigen::Matrix<double, 1, 1>::Zero(), 0.02);
  CHECK(message_of([&] { (void)est::resample_zoh(singular, 0.001); }).find("A is singular") !=
        std::string::npos);
  const m::StateSpace<2, 1, 1> negative(Eigen::Matrix2d{{0.5, 0.0}, {0.0, -0.3}},
                                        Eigen::Vector2d(1, 1), Eigen::RowVector2d(1, 1),
                                        Eigen::Matrix<double, 1, 1>::Zero(), 0.02);
  CHECK(message_of([&] {
          (void)est::to_continuous_zoh(negative);
        }).find("eigenvalue -0.3 + 0i on the negative real axis") != std::string::npos);
}

TEST_CASE_TEMPLATE("to_continuous_zoh inverts discretize_zoh, 20 fine steps = 1 coarse step", S,
                   Sizes<1, 1, 1>, Sizes<3, 2, 1>, Sizes<4, 2, 3>, Sizes<6, 2, 1>, Sizes<2, 0, 1>) {
  std::mt19937_64 rng(1000 + S::Nx * 100 + S::Nu * 10 + S::Ny);
  for (int trial = 0; trial < 20; ++trial) {
    auto coarse = random_discrete_model<S::Nx, S::Nu, S::Ny>(rng);
    const auto continuous = est::to_continuous_zoh(coarse);
    const auto again = m::discretize_zoh(continuous, 0.02);
    CHECK((again.A() - coarse.A()).norm() < 1e-12);
    if constexpr (S::Nu > 0) CHECK((again.B() - coarse.B()).norm() < 1e-12);

    auto fine = est::resample_zoh(coarse, 0.001);
    coarse.reset(m::StateSpace<S::Nx, S::Nu, S::Ny>::State::Ones());
    fine.reset(coarse.state());
    std::uniform_real_distribution<double> input(-1.0, 1.0);
    for (int k = 0; k < 50; ++k) {
      typename m::StateSpace<S::Nx, S::Nu, S::Ny>::Input u;
      for (int i = 0; i < S::Nu; ++i) u[i] = input(rng);
      (void)coarse.step(u);
      for (int i = 0; i < 20; ++i) (void)fine.step(u);
      REQUIRE((fine.state() - coarse.state()).norm() <= 1e-10 * (1.0 + coarse.state().norm()));
    }
  }
}

TEST_CASE("resample_zoh in float: 20 fine steps = 1 coarse step to float precision") {
  auto coarse = m::yaw_force_2016<float>();
  auto fine = est::resample_zoh(coarse, 0.001f);
  for (int k = 0; k < 100; ++k) {
    const Eigen::Vector2f u(0.5f, -0.2f);
    (void)coarse.step(u);
    for (int i = 0; i < 20; ++i) (void)fine.step(u);
  }
  // Measured relative error 2.0e-3 after 100 coarse steps (GCC 12 -O3): at 1 ms the slow yaw
  // poles are 0.99973 +- 0.00089i, and float rounding of the 20x as many steps adds up.
  CHECK((fine.state() - coarse.state()).norm() <= 5e-3f * coarse.state().norm());
}

TEST_CASE("decimate and resample agree at model periods and reach the same DC gain") {
  ForceEstimator<rate::Decimate> decimated(resamplable_models(), {});
  ForceEstimator<rate::Resample> resampled(resamplable_models(), {});
  const JointState<double> s = constant_state(0.8, 0.6, 0.6, -0.6, 0.05);
  // Expected DC: yaw dc_gain() = [15.1210937212035, 10.339654974423242] (scipy, see
  // tests/model/presets_2016_test.cpp), pitch joint without dead zone, clamps with 0.21/0.20 A.
  const auto dc = m::yaw_force_2016().dc_gain();
  const Forces expected(0.070 * 0.8, 9.80665e-3 * (dc(0, 0) * 0.6 + dc(0, 1) * 0.05),
                        dc(0, 0) * (0.6 - 0.21) + dc(0, 1) * 0.05,
                        dc(0, 0) * (-0.6 + 0.20) + dc(0, 1) * 0.05);
  Forces fd;
  Forces fr;
  Forces held;
  double worst_boundary = 0.0;
  for (int n = 0; n < 120000; ++n) {
    REQUIRE(decimated.step(s, fd) == NumericStatus::ok);
    REQUIRE(resampled.step(s, fr) == NumericStatus::ok);
    if (n % 20 == 0) {
      // Both outputs are the state at t = n ms: decimation's after n/20 model steps, the
      // resampled model's after n steps.
      worst_boundary = std::max(worst_boundary, (fd - fr).cwiseAbs().maxCoeff());
      held = fd;
    } else if (n < 2000) {
      REQUIRE(fd == held);  // between model steps the output is held
    }
  }
  CHECK(worst_boundary < 1e-9);
  for (int j = 0; j < 4; ++j) {
    CAPTURE(j);
    CHECK(fd[j] == doctest::Approx(expected[j]).epsilon(1e-9));
    CHECK(fr[j] == doctest::Approx(expected[j]).epsilon(1e-9));
  }
}

TEST_CASE_TEMPLATE("a steady input drives every joint to the preset's DC gain", Scalar, double,
                   float) {
  ForceEstimator2016<rate::Decimate, Scalar> estimator;
  const Scalar i = Scalar(0.6);
  const Scalar w = Scalar(0.04);
  const auto s = constant_state<Scalar>(Scalar(0.8), i, i, -i, w);
  typename ForceEstimator2016<rate::Decimate, Scalar>::Forces f;
  for (int n = 0; n < 150000; ++n) REQUIRE(estimator.step(s, f) == NumericStatus::ok);

  // DC gains of the Scalar presets, evaluated in double (float rounding of A moves the nearly
  // defective yaw model's DC gain by ~1e-4 relative).
  auto dc_of = [](const auto& model) {
    return m::StateSpace<6, 2, 1, double>(
               model.A().template cast<double>(), model.B().template cast<double>(),
               model.C().template cast<double>(), model.D().template cast<double>(), 0.02)
        .dc_gain();
  };
  const auto roll_dc = m::roll_torque_2016<double>().dc_gain();  // D = 0.070 N m/A
  const auto pitch_dc = dc_of(m::pitch_force_2016<Scalar>());
  const auto yaw_dc = dc_of(m::yaw_force_2016<Scalar>());
  const double id = static_cast<double>(i);
  const double wd = static_cast<double>(w);
  // f = -current_sign * unit_scale * DC gain * u, current_sign = -1 (2016 rig).
  const std::array<double, 4> expected = {roll_dc(0, 0) * 0.8,
                                          9.80665e-3 * (pitch_dc(0, 0) * id + pitch_dc(0, 1) * wd),
                                          yaw_dc(0, 0) * (id - 0.21) + yaw_dc(0, 1) * wd,
                                          yaw_dc(0, 0) * (-id + 0.20) + yaw_dc(0, 1) * wd};
  // float: measured relative errors 3.8e-4 (pitch), 2.9e-5 (clamp1), 4.8e-4 (clamp2): the
  // models' slow poles sit within 0.006 of z = 1, where float rounding of the state adds up.
  const double tolerance = std::is_same_v<Scalar, float> ? 1e-3 : 1e-9;
  for (std::size_t j = 0; j < 4; ++j) {
    CAPTURE(j);
    CHECK(static_cast<double>(f[static_cast<int>(j)]) ==
          doctest::Approx(expected[j]).epsilon(tolerance));
  }
  // Numbers: clamp1 15.1211 * 0.39 + 10.3397 * 0.04 = 6.3108 N,
  // clamp2 15.1211 * -0.40 + 10.3397 * 0.04 = -5.6349 N.
  const double rounding = std::is_same_v<Scalar, float> ? 1e-3 : 1e-6;
  CHECK(static_cast<double>(f[2]) == doctest::Approx(6.310813).epsilon(rounding));
  CHECK(static_cast<double>(f[3]) == doctest::Approx(-5.634851).epsilon(rounding));
}

TEST_CASE("friction gate: no output below the level, output above, hysteresis in between") {
  // The roll model is a static gain (0.070 N m/A), so the output follows the current at once.
  // Table 5.2 roll level 0.7 A; release below 0.75 * 0.7 = 0.525 A.
  Decimated estimator;
  struct Tick {
    double current;
    bool open;
  };
  const std::array<Tick, 9> ticks = {{{0.5, false},
                                      {0.69, false},
                                      {0.71, true},
                                      {0.6, true},
                                      {0.53, true},
                                      {0.52, false},
                                      {0.6, false},
                                      {-0.8, true},
                                      {-0.55, true}}};
  for (const Tick& t : ticks) {
    Forces f;
    REQUIRE(estimator.step(constant_state(t.current, 0.0, 0.0, 0.0), f) == NumericStatus::ok);
    CAPTURE(t.current);
    CHECK(estimator.gate_open()[0] == t.open);
    CHECK(estimator.raw_estimate()[0] == doctest::Approx(0.070 * t.current).epsilon(1e-15));
    CHECK(f[0] ==
          (t.open ? doctest::Approx(0.070 * t.current).epsilon(1e-15) : doctest::Approx(0.0)));
    // Zero current: every other gate stays closed and its output is exactly 0.
    CHECK(f[1] == 0.0);
    CHECK(f[2] == 0.0);
    CHECK(f[3] == 0.0);
  }
  estimator.reset();
  CHECK_FALSE(estimator.gate_open()[0]);
}

TEST_CASE("output dead zone and saturation per joint") {
  est::ForceEstimatorSettings<double> settings;
  settings.output_deadzone[0] = 0.01;  // N m
  settings.output_limit[0] = 0.05;     // N m
  Decimated estimator(settings);
  Forces f;
  REQUIRE(estimator.step(constant_state(0.8, 0.0, 0.0, 0.0), f) == NumericStatus::ok);
  CHECK(f[0] == doctest::Approx(0.056 - 0.01).epsilon(1e-14));  // 0.056 -> 0.046
  REQUIRE(estimator.step(constant_state(0.9, 0.0, 0.0, 0.0), f) == NumericStatus::ok);
  CHECK(f[0] == 0.05);  // 0.063 -> 0.053 -> limited
  // Default roll limit 0.084 N m = 1.2 A (figure E.8's largest current) x 0.070 N m/A.
  Decimated defaults;
  REQUIRE(defaults.step(constant_state(1.5, 0.0, 0.0, 0.0), f) == NumericStatus::ok);
  CHECK(defaults.raw_estimate()[0] == doctest::Approx(0.105));
  CHECK(f[0] == 0.084);
  REQUIRE(defaults.step(constant_state(1.0, 0.0, 0.0, 0.0), f) == NumericStatus::ok);
  CHECK(f[0] == doctest::Approx(0.070));
}

TEST_CASE(
    "stiction memory: the estimate is held while the motor backs off within the stuck travel") {
  // Roll, its gate open: the 2016 roll model is 0.070 N m/A x current, so the estimate follows
  // the current at once. Positive estimate: the motor pressed along -1 and backs off along +1.
  est::ForceEstimatorSettings<double> settings;
  settings.friction[0] = m::JointFriction<double>::simplified(0.0);
  settings.stick_travel[0] = 0.03;  // rad
  settings.stick_play[0] = 0.02;    // rad, added below stick_force
  settings.stick_force[0] = 0.02;   // N m
  auto roll_at = [](double current, double position) {
    JointState<double> s;
    s.current[0] = current;
    s.position[0] = position;
    return s;
  };
  Decimated estimator(settings);
  auto step = [&](double current, double position) {
    Forces f;
    REQUIRE(estimator.step(roll_at(current, position), f) == NumericStatus::ok);
    return f[0];
  };
  SUBCASE("held within the travel, followed beyond it") {
    CHECK(step(1.0, 0.50) == doctest::Approx(0.070));
    CHECK(step(0.5, 0.51) == doctest::Approx(0.070));    // backed off 0.01 rad: held
    CHECK(step(0.0, 0.525) == doctest::Approx(0.070));   // down to 0: still held
    CHECK(step(0.1, 0.535) == doctest::Approx(0.007));   // 0.035 > 0.03: the joint slides out
    CHECK(step(0.05, 0.536) == doctest::Approx(0.007));  // stuck again where it slid to
    CHECK(step(0.0, 0.586) == doctest::Approx(0.0));     // 0.007 < stick_force: 0.05 rad, beyond
  }
  SUBCASE("a fall with the motor not backed off is followed (a transient, not an unloading)") {
    CHECK(step(1.0, 0.50) == doctest::Approx(0.070));
    CHECK(step(0.5, 0.50) == doctest::Approx(0.035));
    CHECK(step(0.2, 0.49) == doctest::Approx(0.014));   // pressed further: followed
    CHECK(step(0.1, 0.495) == doctest::Approx(0.014));  // then backed off from 0.50: held
  }
  SUBCASE("below stick_force the play adds to the travel") {
    CHECK(step(0.2, 0.50) == doctest::Approx(0.014));  // 0.014 N m < 0.02: travel 0.05
    CHECK(step(0.0, 0.54) == doctest::Approx(0.014));  // 0.04 < 0.05: held
    CHECK(step(0.0, 0.551) == doctest::Approx(0.0));   // beyond: followed
  }
  SUBCASE("the other side is followed; reset forgets the hold") {
    CHECK(step(1.0, 0.50) == doctest::Approx(0.070));
    CHECK(step(-0.5, 0.51) == doctest::Approx(-0.035));
    CHECK(step(1.0, 0.50) == doctest::Approx(0.070));
    estimator.reset();
    CHECK(step(0.5, 0.51) == doctest::Approx(0.035));
  }
  SUBCASE("off by default: the estimate is passed on as it is") {
    settings.stick_travel[0] = 0.0;
    estimator = Decimated(settings);
    CHECK(step(1.0, 0.50) == doctest::Approx(0.070));
    CHECK(step(0.5, 0.51) == doctest::Approx(0.035));
  }
}

TEST_CASE("NaN or Inf anywhere in the joint state: status, output and state untouched") {
  Decimated a;
  for (int k = 0; k < 137; ++k) {  // mid-window: the decimation phase must survive too
    Forces f;
    REQUIRE(a.step(wavy_state(k), f) == NumericStatus::ok);
  }
  const std::array<double, 3> bad = {std::numeric_limits<double>::quiet_NaN(),
                                     std::numeric_limits<double>::infinity(),
                                     -std::numeric_limits<double>::infinity()};
  Decimated b = a;
  for (int field = 0; field < 4; ++field) {
    for (int motor = 0; motor < 4; ++motor) {
      for (const double value : bad) {
        JointState<double> s = wavy_state(137);
        auto& v = field == 0   ? s.position
                  : field == 1 ? s.velocity
                  : field == 2 ? s.current
                               : s.setpoint;
        v[motor] = value;
        Forces f = Forces::Constant(42.0);
        CAPTURE(field);
        CAPTURE(motor);
        CHECK(b.step(s, f) == NumericStatus::non_finite_input);
        CHECK(f == Forces::Constant(42.0));
      }
    }
  }
  CHECK(b.raw_estimate() == a.raw_estimate());
  CHECK(b.gate_open() == a.gate_open());
  for (int k = 137; k < 1000; ++k) {
    Forces fa;
    Forces fb;
    REQUIRE(a.step(wavy_state(k), fa) == NumericStatus::ok);
    REQUIRE(b.step(wavy_state(k), fb) == NumericStatus::ok);
    REQUIRE(fa == fb);  // bit for bit: the refused ticks left no trace
  }
}

TEST_CASE("a model that overflows on finite input: non_finite_result, every joint rolled back") {
  // Clamp 2 (the last joint ticked) gets a 1 ms model with B = 1e300: a finite current of 1e10 A
  // overflows its next state after roll, pitch and clamp 1 have ticked (mid-window).
  using SS = m::StateSpace<6, 2, 1>;
  using Linear = est::OpenLoop<SS>;
  const Linear overflowing(SS(0.5 * SS::MatrixA::Identity(), SS::MatrixB::Constant(1e300),
                              SS::MatrixC::Ones(), SS::MatrixD::Zero(), 0.001));
  const auto presets = est::models_2016();
  using Estimator =
      ForceEstimator<rate::Decimate, est::RollModel2016<>, est::PitchModel2016<>, Linear>;
  Estimator a({presets.roll, presets.pitch, Linear(m::yaw_force_2016()), overflowing}, {});
  auto tame = [](int k) {
    JointState<double> s = wavy_state(k);
    s.current[3] = 1e-302;
    return s;
  };
  for (int k = 0; k < 55; ++k) {
    Forces f;
    REQUIRE(a.step(tame(k), f) == NumericStatus::ok);
  }
  auto b = a;
  JointState<double> huge = tame(55);
  huge.current[3] = 1e10;
  Forces f = Forces::Constant(7.0);
  CHECK(b.step(huge, f) == NumericStatus::non_finite_result);
  CHECK(f == Forces::Constant(7.0));
  CHECK(b.raw_estimate() == a.raw_estimate());
  for (int k = 55; k < 400; ++k) {
    Forces fa;
    Forces fb;
    REQUIRE(a.step(tame(k), fa) == NumericStatus::ok);
    REQUIRE(b.step(tame(k), fb) == NumericStatus::ok);
    REQUIRE(fa == fb);  // the decimation windows of pitch and clamp 1 were rolled back too
  }
}

TEST_CASE("finite signals so large that the decimation window overflows are refused") {
  // A position of 1e308 rad is finite, and the open-loop models do not use the position, but
  // two of them in one window overflow its sum: the second tick is refused and rolled back, so
  // the window never holds an Inf and the estimator carries on.
  Decimated a;
  Forces fa;
  for (int k = 0; k < 30; ++k) REQUIRE(a.step(wavy_state(k), fa) == NumericStatus::ok);
  JointState<double> huge = wavy_state(30);
  huge.position[2] = 1e308;
  REQUIRE(a.step(huge, fa) == NumericStatus::ok);
  Decimated b = a;
  Forces fb = Forces::Constant(5.0);
  CHECK(b.step(huge, fb) == NumericStatus::non_finite_result);
  CHECK(fb == Forces::Constant(5.0));
  for (int k = 31; k < 200; ++k) {
    REQUIRE(a.step(wavy_state(k), fa) == NumericStatus::ok);
    REQUIRE(b.step(wavy_state(k), fb) == NumericStatus::ok);
    REQUIRE(fa == fb);
  }
}

TEST_CASE("clamp sign convention: a grip pushes the stylus open, along +e_r") {
  // Moving the stylus in (r down) raises the clamp 1 setpoint and lowers clamp 2's (eq. 5.9,
  // P_clamp2 = -P_clamp1). On the 2016 rig positive current drives a joint towards negative
  // setpoints (current_sign -1), so squeezing an object draws negative current on clamp 1 and
  // positive current on clamp 2. The object pushes back: the external force is negative along
  // clamp 1's setpoint and positive along clamp 2's.
  Decimated estimator;
  Forces f;
  for (int n = 0; n < 150000; ++n) {
    REQUIRE(estimator.step(constant_state(0.0, 0.0, -0.6, 0.6), f) == NumericStatus::ok);
  }
  const double gain = m::yaw_force_2016().dc_gain()(0, 0);             // 15.1211 N/A
  CHECK(f[2] == doctest::Approx(-gain * (0.6 - 0.21)).epsilon(1e-9));  // -5.897 N
  CHECK(f[3] == doctest::Approx(gain * (0.6 - 0.20)).epsilon(1e-9));   // +6.048 N

  // Through the mapper (eq. 5.8): radial force sign(a_clamp) (f2 - f1) / 2 > 0, along e_r,
  // outwards: the feedback resists the closing motion.
  endohaptics::kinematics::CylindricalMapper<double> mapper;
  const double theta = 0.3;
  const Eigen::Vector3d e_r(std::sin(theta), std::cos(theta), 0.0);
  Eigen::Vector3d stylus = Eigen::Vector3d::Zero();
  REQUIRE(mapper.map_force(estimator.in_motor_order(f), theta, stylus).ok());
  // (5.897 + 6.048) / 2 = 5.97 N, limited to the clamp channel's 1.4 N (channel_limit)
  CHECK(stylus.dot(e_r) == doctest::Approx(1.4));
  CHECK(stylus.cross(e_r).norm() < 1e-12);

  // A motor wired the other way round: current_sign +1 on clamp 2 flips its force, so the
  // same grip now draws negative current on both clamps.
  est::ForceEstimatorSettings<double> settings;
  settings.current_sign[3] = 1.0;
  Decimated rewired(settings);
  for (int n = 0; n < 150000; ++n) {
    REQUIRE(rewired.step(constant_state(0.0, 0.0, -0.6, -0.6), f) == NumericStatus::ok);
  }
  CHECK(f[2] == doctest::Approx(-gain * (0.6 - 0.21)).epsilon(1e-9));
  CHECK(f[3] == doctest::Approx(gain * (0.6 - 0.20)).epsilon(1e-9));
}

TEST_CASE("motor_order: the same signals in other motor slots give the same tool-joint forces") {
  est::ForceEstimatorSettings<double> permuted;
  permuted.motor_order = {Motor::clamp2, Motor::clamp1, Motor::roll, Motor::pitch};
  Decimated reference;
  Decimated other(permuted);
  for (int k = 0; k < 3000; ++k) {
    const JointState<double> s = wavy_state(k);
    JointState<double> p;  // slot m holds tool joint motor_order[m]
    for (int slot = 0; slot < 4; ++slot) {
      const int j = static_cast<int>(permuted.motor_order[static_cast<std::size_t>(slot)]);
      p.position[slot] = s.position[j];
      p.velocity[slot] = s.velocity[j];
      p.current[slot] = s.current[j];
      p.setpoint[slot] = s.setpoint[j];
    }
    Forces fr;
    Forces fo;
    REQUIRE(reference.step(s, fr) == NumericStatus::ok);
    REQUIRE(other.step(p, fo) == NumericStatus::ok);
    REQUIRE(fr == fo);
    if (k == 2999) {
      const Forces motor = other.in_motor_order(fo);
      CHECK(motor[0] == fo[3]);
      CHECK(motor[1] == fo[2]);
      CHECK(motor[2] == fo[0]);
      CHECK(motor[3] == fo[1]);
      CHECK(fo[2] != 0.0);
    }
  }
}

TEST_CASE("Kalman correction hook: a synthetic augmented model recovers an unmodelled force") {
  // Pitch joint, 1 ms model, states x = [e; f]: position error e (rad) and external force f (N,
  // a random walk). e(k+1) = 0.9 e + 0.05 i - 0.02 f, f(k+1) = f; y = [f; e], u = [i; omega].
  // Only e is measured (setpoint - position). The open-loop model cannot see f at all.
  using Aug = m::StateSpace<2, 2, 2>;
  const Aug augmented(Aug::MatrixA{{0.9, -0.02}, {0.0, 1.0}}, Aug::MatrixB{{0.05, 0.0}, {0.0, 0.0}},
                      Aug::MatrixC{{0.0, 1.0}, {1.0, 0.0}}, Aug::MatrixD::Zero(), 0.001);
  using Corrected = est::KalmanCorrected<2, 2, 2>;
  const Corrected corrected(augmented, {est::Measured::position_error},
                            Eigen::Matrix2d{{1e-8, 0.0}, {0.0, 1e-4}},
                            Eigen::Matrix<double, 1, 1>(1e-6));
  using WithKalman = ForceEstimator<rate::Decimate, est::RollModel2016<>, Corrected>;
  using OpenLoopEstimator =
      ForceEstimator<rate::Decimate, est::RollModel2016<>, est::OpenLoop<Aug>>;
  const auto presets = est::models_2016();
  est::ForceEstimatorSettings<double> settings;
  settings.unit_scale[1] = 1.0;  // the synthetic model is in N
  WithKalman with_kalman({presets.roll, corrected, presets.clamp1, presets.clamp2}, settings);
  OpenLoopEstimator open_loop(
      {presets.roll, est::OpenLoop<Aug>(augmented), presets.clamp1, presets.clamp2}, settings);
  CHECK(with_kalman.ticks_per_model_step(Motor::pitch) == 1);

  // The true joint: f = 1.5 N pushes on it while the motor draws 0.5 A.
  const double f_true = 1.5;
  double e_true = 0.0;
  Forces fk;
  Forces fo;
  for (int k = 0; k < 3000; ++k) {
    JointState<double> s;
    s.current[1] = 0.5;
    s.setpoint[1] = e_true;  // position 0: position error = e_true
    REQUIRE(with_kalman.step(s, fk) == NumericStatus::ok);
    REQUIRE(open_loop.step(s, fo) == NumericStatus::ok);
    e_true = 0.9 * e_true + 0.05 * 0.5 - 0.02 * f_true;
  }
  // Steady e = (0.025 - 0.03) / 0.1 = -0.05 rad; the filter attributes it to f = 1.5 N.
  CHECK(e_true == doctest::Approx(-0.05).epsilon(1e-9));
  CHECK(fk[1] == doctest::Approx(f_true).epsilon(1e-6));  // -current_sign = +1: y0 = f
  CHECK(fo[1] == 0.0);                                    // open loop: f stays 0
  CHECK(fk[2] == fo[2]);                                  // other joints unaffected
  CHECK(with_kalman.joint_model<Motor::pitch>().filter().gain().norm() > 0.0);

  CHECK(message_of([&] {
          (void)Corrected(augmented, {static_cast<est::Measured>(9)}, Eigen::Matrix2d::Identity(),
                          Eigen::Matrix<double, 1, 1>(1.0));
        }).find("measured[0] is not a Measured signal: 9") != std::string::npos);
}

TEST_CASE("a tick allocates nothing (operator new counter, EIGEN_RUNTIME_NO_MALLOC)") {
  Decimated decimated;
  ForceEstimator<rate::Resample> resampled(resamplable_models(), {});
  est::ForceEstimatorSettings<double> at_model_rate;
  at_model_rate.loop_period = 0.02;
  ForceEstimator<rate::SameRate> same(at_model_rate);
  using Aug = m::StateSpace<2, 2, 2>;
  const Aug augmented(Aug::MatrixA{{0.9, -0.02}, {0.0, 1.0}}, Aug::MatrixB{{0.05, 0.0}, {0.0, 0.0}},
                      Aug::MatrixC{{0.0, 1.0}, {1.0, 0.0}}, Aug::MatrixD::Zero(), 0.001);
  using Corrected = est::KalmanCorrected<2, 2, 2>;
  const auto presets = est::models_2016();
  ForceEstimator<rate::Decimate, est::RollModel2016<>, Corrected> kalman(
      {presets.roll,
       Corrected(augmented, {est::Measured::position_error}, Eigen::Matrix2d::Identity() * 1e-4,
                 Eigen::Matrix<double, 1, 1>(1e-6)),
       presets.clamp1, presets.clamp2},
      {});
  Forces f;
  double sink = 0.0;
  for (int k = 0; k < 100; ++k) {  // warm-up
    (void)decimated.step(wavy_state(k), f);
    (void)resampled.step(wavy_state(k), f);
    (void)same.step(wavy_state(k), f);
    (void)kalman.step(wavy_state(k), f);
  }
  const long allocations = allocations_during([&] {
    for (int k = 100; k < 10100; ++k) {
      const JointState<double> s = wavy_state(k);
      if (decimated.step(s, f) == NumericStatus::ok) sink += f.sum();
      if (resampled.step(s, f) == NumericStatus::ok) sink += f.sum();
      if (same.step(s, f) == NumericStatus::ok) sink += f.sum();
      if (kalman.step(s, f) == NumericStatus::ok) sink += f.sum();
      JointState<double> bad = s;
      bad.current[2] = std::numeric_limits<double>::quiet_NaN();
      sink += static_cast<double>(decimated.step(bad, f));
    }
  });
  CHECK(std::isfinite(sink));
  CHECK(allocations == 0);

  // The detector works: dynamic-size Eigen allocates.
  const long dynamic = allocations_during([] {
    Eigen::VectorXd v(6);
    v.setOnes();
    (void)v;
  });
  CHECK(dynamic >= 1);
}

TEST_CASE("settings are validated, errors name the field, the joint and the value") {
  auto error_for = [](auto change) {
    est::ForceEstimatorSettings<double> s;
    change(s);
    return message_of([&] { (void)Decimated(s); });
  };
  CHECK(error_for([](auto& s) { s.motor_order[3] = Motor::pitch; }) ==
        "ForceEstimator: motor_order is not a permutation: pitch appears twice (again at motor 3)");
  CHECK(error_for([](auto& s) { s.motor_order[0] = static_cast<Motor>(7); }) ==
        "ForceEstimator: motor_order[0] is not a tool joint: 7");
  CHECK(error_for([](auto& s) { s.current_sign[2] = 0.5; }) ==
        "ForceEstimator: current_sign[2] must be +1 or -1, got 0.5");
  CHECK(error_for([](auto& s) { s.unit_scale[1] = 0.0; }) ==
        "ForceEstimator: unit_scale[1] must be finite and > 0, got 0");
  CHECK(error_for([](auto& s) { s.output_deadzone[3] = -1.0; }) ==
        "ForceEstimator: output_deadzone[3] must be finite and >= 0, got -1");
  CHECK(error_for([](auto& s) {
          s.output_limit[0] = std::numeric_limits<double>::quiet_NaN();
        }).find("ForceEstimator: output_limit[0] must be finite and > 0, got ") == 0);
  CHECK(error_for([](auto& s) {
          s.loop_period = -0.001;
        }).find("loop period: sample time must be finite and > 0 s, got -0.001") !=
        std::string::npos);
  CHECK(error_for([](auto& s) { s.friction[1].static_level = -0.1; }) ==
        "ForceEstimator: friction_level[1] must be finite and >= 0 A, got -0.1");
  CHECK(error_for([](auto& s) { s.stick_travel[1] = -1.0; }) ==
        "ForceEstimator: stick_travel[1] must be finite and >= 0 rad, got -1");
  CHECK(error_for([](auto& s) {
          s.stick_play[2] = std::numeric_limits<double>::infinity();
        }).find("ForceEstimator: stick_play[2] must be finite and >= 0 rad, got ") == 0);
  CHECK(error_for([](auto& s) { s.stick_force[3] = -0.5; }) ==
        "ForceEstimator: stick_force[3] must be finite and >= 0, got -0.5");
}

TEST_CASE("TeleopLoop interface: estimate() = step() on the packet, forces in motor order") {
  static_assert(endohaptics::teleop::JointForceEstimator<Decimated>);
  static_assert(
      endohaptics::teleop::JointForceEstimator<ForceEstimator2016<rate::Decimate, float>>);
  est::ForceEstimatorSettings<double> settings;
  settings.motor_order = {Motor::pitch, Motor::roll, Motor::clamp2, Motor::clamp1};
  Decimated via_step(settings);
  Decimated via_estimate(settings);
  for (int k = 0; k < 500; ++k) {
    const JointState<double> s = wavy_state(k);
    endohaptics::protocol::MotorState<4> packet;
    packet.position = s.position;
    packet.velocity = s.velocity;
    packet.current = s.current;
    Forces tool;
    REQUIRE(via_step.step(s, tool) == NumericStatus::ok);
    Eigen::Vector4d motor = Eigen::Vector4d::Zero();
    REQUIRE(via_estimate.estimate(packet, s.setpoint, motor));
    REQUIRE(motor == via_step.in_motor_order(tool));
    REQUIRE(motor[0] == tool[1]);  // slot 0 carries the pitch
  }
  endohaptics::protocol::MotorState<4> bad;
  bad.current[2] = std::numeric_limits<double>::quiet_NaN();
  Eigen::Vector4d untouched = Eigen::Vector4d::Constant(3.0);
  CHECK_FALSE(via_estimate.estimate(bad, Eigen::Vector4d::Zero(), untouched));
  CHECK(via_estimate.last_status() == NumericStatus::non_finite_input);
  CHECK(untouched == Eigen::Vector4d::Constant(3.0));
}

TEST_CASE("joint_state takes the sbRIO packet and the setpoint we sent") {
  endohaptics::protocol::MotorState<4> measured;
  measured.position << 0.1, 0.2, 0.3, 0.4;
  measured.velocity << -1.0, -2.0, -3.0, -4.0;
  measured.current << 0.5, 0.6, 0.7, 0.8;
  endohaptics::protocol::MotorSetpoint<4> sent;
  sent.position << 0.15, 0.25, 0.35, 0.45;
  const auto s = est::joint_state(measured, sent);
  CHECK(s.position == measured.position);
  CHECK(s.velocity == measured.velocity);
  CHECK(s.current == measured.current);
  CHECK(s.setpoint == sent.position);
  const auto sf = est::joint_state<float>(measured, sent);
  CHECK(sf.current[3] == 0.8f);
}

namespace {

// Rows of a 2016 force log whose first 7 comma-separated fields all parse as numbers (header
// lines, empty fields and short lines are skipped); CRLF tolerated.
std::vector<std::array<double, 7>> read_force_log(const std::filesystem::path& path) {
  std::vector<std::array<double, 7>> rows;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::array<double, 7> row{};
    std::size_t start = 0;
    bool ok = true;
    for (std::size_t c = 0; c < row.size() && ok; ++c) {
      const std::size_t end = std::min(line.find(',', start), line.size());
      const std::string field = line.substr(start, end - start);
      char* stop = nullptr;
      row[c] = std::strtod(field.c_str(), &stop);
      ok = !field.empty() && stop == field.c_str() + field.size() && (end < line.size() || c == 6);
      start = end + 1;
    }
    if (ok) rows.push_back(row);
  }
  return rows;
}

}  // namespace

TEST_CASE("2016 logs: the motor current opposes the position error (current_sign = -1)" *
          doctest::skip(!endohaptics::test::has_shared_data("endowrist-2016"))) {
  // Columns: time, V, kN, setpoint rad, position rad, current A, demand A. Samples with
  // |current| > 0.3 A and |setpoint - position| > 0.005 rad. Same numbers from
  // /usr/bin/python3 (numpy, float() per field, rows with fewer than 7 numbers skipped):
  // 41 logs with such samples, 40 with a majority of opposite signs, 14,815 of 16,127 samples.
  int logs = 0;
  int logs_opposite = 0;
  long samples = 0;
  long opposite = 0;
  for (const char* folder : {"clamp-hits", "clamp-static", "one-clamp-down", "pitch"}) {
    const auto dir = endohaptics::test::shared_data(std::string("endowrist-2016/") + folder);
    std::vector<std::filesystem::path> files;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      if (entry.path().extension() == ".csv") files.push_back(entry.path());
    }
    for (const auto& file : files) {
      long n = 0;
      long o = 0;
      for (const auto& row : read_force_log(file)) {
        const double error = row[3] - row[4];
        const double current = row[5];
        if (std::abs(current) > 0.3 && std::abs(error) > 0.005) {
          ++n;
          if ((current > 0) != (error > 0)) ++o;
        }
      }
      if (n == 0) continue;
      ++logs;
      if (2 * o > n) ++logs_opposite;
      samples += n;
      opposite += o;
    }
  }
  CHECK(logs == 41);
  CHECK(logs_opposite == 40);
  CHECK(samples == 16127);
  CHECK(opposite == 14815);  // 91.9 %
  CHECK(est::ForceEstimatorSettings<double>().current_sign == Eigen::Vector4d::Constant(-1.0));
}

}  // namespace estimation_force_estimator_test
