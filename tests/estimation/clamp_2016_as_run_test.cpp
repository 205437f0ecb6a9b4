// Clamp2016AsRun against the 2016 code's formulas (filipmrc/endohap src/Kalman.cc
// Kalman::estimateOutput, src/Endowrist.cc Endowrist::forceEstimation, include/endohap/utils.h
// deadzone), the sign gate and the dead zone, and the clamp presets defined once
// (estimation/clamp_presets.hpp): the bridge's estimator and the replay path run the same chain.
#include <doctest/doctest.h>

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <vector>

#include "endohaptics/estimation/clamp_2016_as_run.hpp"
#include "endohaptics/estimation/clamp_presets.hpp"

namespace estimation_clamp_2016_as_run_test {

namespace est = endohaptics::estimation;
using endohaptics::model::NumericStatus;

TEST_CASE("clamp2016-as-run: R(1,1) is the code's 32-bit wrapped product over T") {
  // (unsigned int)100000000*100000000 = 1e16 mod 2^32 = 1874919424 (python3: (10**16) % 2**32).
  CHECK(est::as_run_2016_force_variance == doctest::Approx(9.37459712e10).epsilon(1e-12));
  CHECK(est::as_run_2016_velocity_variance == doctest::Approx(5000.0));
}

TEST_CASE("clamp2016-as-run: six messages match the 2016 formulas computed by hand") {
  // Reference: Kalman.cc and Endowrist.cc transcribed line by line into plain Python (lists, no
  // library): per message yv = [position / 0.02; 0], u = -current, estimateOutput twice on one
  // filter, F = deadzone((ye1 + ye4) / 2, 0.1) when both force estimates share a strict sign.
  // Columns: ye1 force, ye4 force, F. Message 5's estimates disagree in sign: F = 0.
  struct Message {
    double position, current, ye1, ye4, force;
  };
  const std::array<Message, 6> messages{{
      {0.10, -0.50, 0.2352976216312509, 0.6612328186824046, 0.3482652201568277},
      {0.12, -0.80, 0.5462111865290888, 0.6664805524953392, 0.506345869512214},
      {0.15, -1.20, 0.5882905717333098, 0.8313786231331552, 0.6098345974332325},
      {0.15, -1.00, 0.6472440612057407, 0.3144126007398833, 0.380828330972812},
      {0.14, -0.30, 0.2800236918597345, -0.31946385659292853, 0.0},
      {0.13, 0.20, -0.10054773787035542, -0.3115794621671675, -0.10606360001876144},
  }};
  est::Clamp2016AsRun<double> m;
  for (const Message& msg : messages) {
    CAPTURE(msg.position);
    const est::JointSignals<double> s{msg.position, 123.0 /* not read */, msg.current, 0.0};
    // The two filter steps, by hand on the model's own state.
    using M = est::Clamp2016AsRun<double>;
    M::Vector6 x = m.state().head<6>();
    M::Matrix6 P = Eigen::Map<const M::Matrix6>(m.state().data() + 6);
    M::Output ye1, ye4;
    const M::Output yv(msg.position / 0.02, 0.0);
    m.filter_step(yv, -msg.current, x, P, ye1);
    m.filter_step(yv, -msg.current, x, P, ye4);
    CHECK(ye1[1] == doctest::Approx(msg.ye1).epsilon(1e-9));
    CHECK(ye4[1] == doctest::Approx(msg.ye4).epsilon(1e-9));
    CHECK(m.force(s) == doctest::Approx(msg.force).epsilon(1e-9));
    REQUIRE(m.advance(s) == NumericStatus::ok);
  }
  // The state after the six messages (same Python): x and two diagonal entries of P.
  const Eigen::Matrix<double, 6, 1> x_ref{-0.18738308784694369, 3.7673452692166194,
                                          0.6008351829781344,   -1.1503058947791107,
                                          -0.6270602779529483,  -0.6441105884366767};
  CHECK((m.state().head<6>() - x_ref).cwiseAbs().maxCoeff() < 1e-9);
  CHECK(m.state()[6] == doctest::Approx(18.193751675901662).epsilon(1e-9));       // P(0,0)
  CHECK(m.state()[6 + 35] == doctest::Approx(329.01998857006674).epsilon(1e-9));  // P(5,5)
}

TEST_CASE("clamp2016-as-run: the sign gate and the 0.1 dead zone") {
  const est::Clamp2016AsRun<double> m;
  CHECK(m.combine(0.5, 0.3) == doctest::Approx(0.3));  // (0.5 + 0.3) / 2 - 0.1
  CHECK(m.combine(-0.5, -0.3) == doctest::Approx(-0.3));
  CHECK(m.combine(0.5, -0.3) == 0.0);   // disagree: nothing
  CHECK(m.combine(0.5, 0.0) == 0.0);    // zero has no sign: nothing
  CHECK(m.combine(0.15, 0.04) == 0.0);  // mean 0.095 < 0.1
  CHECK(m.combine(0.1, 0.1) == 0.0);    // |mean| = 0.1: 0.1 - 0.1
  est::Clamp2016AsRunParameters<double> p;
  p.deadzone = 0.0;
  CHECK(est::Clamp2016AsRun<double>(p).combine(0.15, 0.04) == doctest::Approx(0.095));
}

TEST_CASE("clamp2016-as-run: the input sign, a bad parameter, a non-finite signal") {
  est::Clamp2016AsRunParameters<double> p;
  p.input_sign = 1.0;
  est::Clamp2016AsRun<double> plus(p);
  est::Clamp2016AsRun<double> minus;
  // Mirrored signals give mirrored forces: the filter is linear, the gate and dead zone odd.
  for (int k = 0; k < 50; ++k) {
    const double pos = 0.1 * std::sin(0.2 * k);
    const double cur = -0.8 * std::sin(0.13 * k);
    const est::JointSignals<double> s{pos, 0.0, cur, 0.0};
    const est::JointSignals<double> mirrored{-pos, 0.0, cur, 0.0};
    CHECK(plus.force(s) == doctest::Approx(-minus.force(mirrored)));
    REQUIRE(plus.advance(s) == NumericStatus::ok);
    REQUIRE(minus.advance(mirrored) == NumericStatus::ok);
  }
  p.input_sign = 0.5;
  CHECK_THROWS_AS(est::Clamp2016AsRun<double>{p}, endohaptics::Error);
  p = {};
  p.message_period = 0.0;
  CHECK_THROWS_AS(est::Clamp2016AsRun<double>{p}, endohaptics::Error);
  const auto before = minus.state();
  CHECK(minus.advance({NAN, 0.0, 0.1, 0.0}) == NumericStatus::non_finite_input);
  CHECK(minus.advance({0.0, 0.0, INFINITY, 0.0}) == NumericStatus::non_finite_input);
  CHECK(minus.state() == before);
  // The velocity is not read (the code divided the position instead).
  CHECK(minus.advance({0.0, NAN, 0.1, 0.0}) == NumericStatus::ok);
}

TEST_CASE("clamp presets: names, and the one definition the bridge and replay share") {
  CHECK(est::clamp_preset("yaw2016") == est::ClampPreset::yaw2016);
  CHECK(est::clamp_preset("clamp2016-as-run") == est::ClampPreset::clamp2016_as_run);
  CHECK_THROWS_WITH_AS((void)est::clamp_preset("clamp2016"),
                       doctest::Contains("valid: yaw2016, clamp2016-as-run"), endohaptics::Error);
  for (const est::ClampPreset preset :
       {est::ClampPreset::yaw2016, est::ClampPreset::clamp2016_as_run}) {
    CAPTURE(est::to_string(preset));
    // A clamp squeeze at 50 Hz, run (a) by the bridge's estimator at 1 kHz ticks, each signal
    // held for 20 ticks, and (b) by run_clamp_preset at the 20 ms grid replay uses: with the
    // held signals the decimation window means equal the 50 Hz samples, so both must agree
    // sample for sample.
    constexpr int n = 150;
    std::vector<est::JointSignals<double>> s(n);
    for (int k = 0; k < n; ++k) {
      const double squeeze = k > 30 && k < 110 ? -1.1 : -0.05;
      s[static_cast<std::size_t>(k)] = {0.2 + 0.001 * k, k > 30 && k < 40 ? -0.5 : 0.0,
                                        squeeze + 0.05 * std::sin(0.3 * k), 0.0};
    }
    Eigen::VectorXd replay(n);
    REQUIRE(est::run_clamp_preset(
                preset, 0.02, [&](Eigen::Index k) { return s[static_cast<std::size_t>(k)]; },
                replay) == NumericStatus::ok);
    auto bridge = est::preset_force_estimator(preset, 0.001);
    const auto clamp1 = static_cast<Eigen::Index>(est::Motor::clamp1);
    est::BridgeForceEstimator::Input in;
    est::BridgeForceEstimator::Forces f;
    double peak = 0.0;
    for (int k = 0; k < n; ++k) {
      const auto& x = s[static_cast<std::size_t>(k)];
      in.position[clamp1] = x.position;
      in.velocity[clamp1] = x.velocity;
      in.current[clamp1] = x.current;
      for (int tick = 0; tick < 20; ++tick) {
        REQUIRE(bridge.step(in, f) == NumericStatus::ok);
        // The force of the first tick of each message is the one before the window's advance.
        if (tick == 0) CHECK(f[clamp1] == doctest::Approx(replay[k]).epsilon(1e-12));
      }
      peak = std::fmax(peak, std::fabs(replay[k]));
    }
    CHECK(peak > 0.0);  // the squeeze gives a force: the comparison is not of zeros
    // The yaw2016 preset keeps its gate and dead zone: the bare linear model does not.
    if (preset == est::ClampPreset::yaw2016) {
      CHECK(bridge.settings().friction[2].static_level == doctest::Approx(0.21));
    } else {
      CHECK(bridge.settings().friction[2].static_level == 0.0);
      CHECK(bridge.joint_model<est::Motor::clamp1>().get<est::Clamp2016AsRun<double>>() != nullptr);
    }
  }
}

}  // namespace estimation_clamp_2016_as_run_test
