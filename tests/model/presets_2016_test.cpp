#include "endohaptics/model/presets_2016.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "shared_data.hpp"

namespace model_presets_2016_test {

namespace {

using endohaptics::Error;
using endohaptics::model::StateSpace;
namespace m = endohaptics::model;

// |lambda| of A's eigenvalues, sorted descending.
template <typename SS>
std::vector<double> pole_moduli(const SS& model) {
  const auto ev = model.eigenvalues();
  std::vector<double> moduli;
  for (int i = 0; i < ev.size(); ++i) moduli.push_back(std::abs(ev[i]));
  std::sort(moduli.rbegin(), moduli.rend());
  return moduli;
}

struct PerturbationStats {
  double min_radius = std::numeric_limits<double>::infinity();
  double max_radius = 0.0;
  int unstable = 0;
};

// Adds independent uniform noise in [-5e-5, 5e-5] (half a unit in the 4th decimal, i.e. every
// matrix the printed one could have been rounded from) to each entry of A.
PerturbationStats perturb_rounding(const StateSpace<6, 2, 1>& model, int trials) {
  std::mt19937_64 rng(2016);
  std::uniform_real_distribution<double> half_ulp(-5e-5, 5e-5);
  PerturbationStats stats;
  for (int t = 0; t < trials; ++t) {
    StateSpace<6, 2, 1>::MatrixA A = model.A();
    for (Eigen::Index i = 0; i < A.size(); ++i) A.data()[i] += half_ulp(rng);
    const StateSpace<6, 2, 1> perturbed(A, model.B(), model.C(), model.D(), 0.02);
    const double radius = perturbed.spectral_radius();
    stats.min_radius = std::min(stats.min_radius, radius);
    stats.max_radius = std::max(stats.max_radius, radius);
    stats.unstable += radius >= 1.0 ? 1 : 0;
  }
  return stats;
}

// Columns of the 2016 logs (shared/data/endowrist-2016/README.md): time s, load-cell V,
// force kN, setpoint rad, position rad, current A, demanded current A. Lines that are not 7
// numbers (header, short lines) are skipped.
std::vector<std::array<double, 7>> load_log(const std::string& relative) {
  std::ifstream in(endohaptics::test::shared_data(relative));
  std::vector<std::array<double, 7>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::array<double, 7> row{};
    std::istringstream fields(line);
    std::string field;
    int n = 0;
    bool ok = true;
    while (n < 7 && std::getline(fields, field, ',')) {
      char* end = nullptr;
      row[static_cast<std::size_t>(n)] = std::strtod(field.c_str(), &end);
      ok = ok && end != field.c_str();
      ++n;
    }
    if (ok && n == 7) rows.push_back(row);
  }
  return rows;
}

}  // namespace

TEST_CASE("appendix C matrices are those printed in the worksheet (C.1-C.6), D = 0, Ts = 0.02 s") {
  const auto yaw = m::yaw_force_2016();
  CHECK(yaw.A()(0, 0) == 0.9745);
  CHECK(yaw.A()(1, 1) == 1.0135);
  CHECK(yaw.A()(0, 5) == -5.5391);
  CHECK(yaw.A()(5, 5) == 0.8887);
  CHECK(yaw.B()(2, 0) == 12.9892);
  CHECK(yaw.B()(5, 1) == -0.0104);
  CHECK(yaw.C()(0, 0) == -0.3687);
  CHECK(yaw.C()(0, 5) == 0.1893);
  CHECK(yaw.D().isZero());
  CHECK(yaw.sample_time() == 0.02);

  const auto pitch = m::pitch_force_2016();
  CHECK(pitch.A()(1, 5) == 6.5551);
  CHECK(pitch.A()(4, 4) == -0.4513);
  CHECK(pitch.B()(0, 0) == 27203.0);  // 2.7203 * 10^4 (C.5)
  CHECK(pitch.B()(1, 0) == -51162.0);
  CHECK(pitch.B()(5, 1) == -111.0);  // -0.0111 * 10^4
  CHECK(pitch.C()(0, 2) == -0.4790);
  CHECK(pitch.D().isZero());
  CHECK(pitch.sample_time() == 0.02);

  // float32 rounding moves A by <= 1.7e-7; scipy on the float-rounded A: radius 0.994594609.
  const auto yaw_f = m::yaw_force_2016<float>();
  CHECK(yaw_f.A()(0, 0) == 0.9745f);
  CHECK(yaw_f.sample_time() == 0.02f);
  CHECK(yaw_f.spectral_radius() == doctest::Approx(0.994594609f).epsilon(1e-5));
  CHECK(yaw_f.is_stable());
}

// Reference: /usr/bin/python3 (scipy 1.10.1), script presets.py in docs/models/presets_2016.md:
//   ev = scipy.linalg.eigvals(A); abs(ev); dc = C @ scipy.linalg.solve(eye(6) - A, B)
// with A, B, C typed from C.1-C.6. Yaw poles 0.99444 +- 0.01774i, 0.95945 +- 0.16148i,
// 0.77746 +- 0.53177i; pitch poles 0.92810 +- 0.35217i, 0.97700 +- 0.06836i, 0.12082, -0.09521.
TEST_CASE("rounded appendix C models are stable: poles and DC gains match scipy") {
  const auto yaw = m::yaw_force_2016();
  const auto yaw_moduli = pole_moduli(yaw);
  const std::array<double, 6> yaw_scipy{0.9945946152877617, 0.9945946152877617, 0.9729448492715822,
                                        0.9729448492715822, 0.9419270160043769, 0.9419270160043769};
  for (std::size_t i = 0; i < 6; ++i) {
    CHECK(yaw_moduli[i] == doctest::Approx(yaw_scipy[i]).epsilon(1e-10));
  }
  CHECK(yaw.spectral_radius() == doctest::Approx(0.9945946152877617).epsilon(1e-10));
  CHECK(yaw.is_stable());
  const auto yaw_dc = yaw.dc_gain();
  CHECK(yaw_dc(0, 0) == doctest::Approx(15.1210937212035).epsilon(1e-9));    // per A
  CHECK(yaw_dc(0, 1) == doctest::Approx(10.339654974423242).epsilon(1e-9));  // per rad/s

  const auto pitch = m::pitch_force_2016();
  const auto pitch_moduli = pole_moduli(pitch);
  const std::array<double, 6> pitch_scipy{0.9926636104571419,  0.9926636104571419,
                                          0.9793921031035231,  0.9793921031035231,
                                          0.12081726113678663, 0.09521369805838886};
  for (std::size_t i = 0; i < 6; ++i) {
    CHECK(pitch_moduli[i] == doctest::Approx(pitch_scipy[i]).epsilon(1e-10));
  }
  CHECK(pitch.is_stable());
  const auto pitch_dc = pitch.dc_gain();
  CHECK(pitch_dc(0, 0) == doctest::Approx(301.66372410809777).epsilon(1e-9));
  CHECK(pitch_dc(0, 1) == doctest::Approx(159.27570719120786).epsilon(1e-9));
}

// What the 4-decimal rounding hides. scipy (same script, 10,000 trials, numpy default_rng(2016))
// gave: yaw spectral radius in [0.983478, 1.086255], 84.53 % of perturbed yaw models unstable;
// pitch in [0.991921, 0.993411], none unstable. Eigenvalue condition numbers (scipy
// eig(left=True)): yaw slow pair 5682, middle pair 708; pitch at most 66.
TEST_CASE("rounding to 4 decimals: the yaw poles near 0.995 are fragile, the pitch poles are not") {
  const auto yaw = perturb_rounding(m::yaw_force_2016(), 2000);
  MESSAGE("yaw: radius in [" << yaw.min_radius << ", " << yaw.max_radius << "], " << yaw.unstable
                             << " / 2000 unstable");
  CHECK(yaw.unstable > 1000);    // most matrices that round to C.1 are unstable
  CHECK(yaw.max_radius > 1.05);  // by a lot: a pole at 1.05 doubles in 14 samples (0.28 s)
  CHECK(yaw.min_radius < 0.99);

  const auto pitch = perturb_rounding(m::pitch_force_2016(), 2000);
  MESSAGE("pitch: radius in [" << pitch.min_radius << ", " << pitch.max_radius << "], "
                               << pitch.unstable << " / 2000 unstable");
  CHECK(pitch.unstable == 0);
  CHECK(pitch.min_radius > 0.9915);
  CHECK(pitch.max_radius < 0.9940);
}

// Roll gain: figure E.8 data (SBKrogh/16gr735, Measurements/roll_force.m: torque N cm =
// 20 * (V - offset), 4 runs, 39 points) fitted with /usr/bin/python3 roll.py
// (docs/models/presets_2016.md): through the origin 0.07008 N m/A; affine 0.07073 N m/A; per run
// 0.0675 to 0.0714 N m/A.
TEST_CASE("roll torque placeholder: static gain 0.070 N m/A, y = gain * current") {
  auto roll = m::roll_torque_2016();
  CHECK(m::roll_torque_gain_2016 == 0.070);
  CHECK(roll.D()(0, 0) == 0.070);
  CHECK(roll.step(StateSpace<1, 1, 1>::Input{1.2})[0] == doctest::Approx(0.084));
  CHECK(roll.step(StateSpace<1, 1, 1>::Input{-0.5})[0] == doctest::Approx(-0.035));
  CHECK(roll.dc_gain()(0, 0) == doctest::Approx(0.070));
  CHECK(roll.sample_time() == 0.02);
  CHECK(m::roll_torque_2016(0.0675).D()(0, 0) == 0.0675);
  CHECK_THROWS_AS((void)m::roll_torque_2016(std::numeric_limits<double>::quiet_NaN()), Error);
}

TEST_CASE("yaw Hammerstein preset: table 5.2 dead zone on the current, velocity unchanged") {
  auto hw = m::yaw_force_2016_hw();
  CHECK(hw.input_nonlinearity().channel(0).upper() == 0.21);
  CHECK(hw.input_nonlinearity().channel(0).lower() == -0.21);
  CHECK(hw.input_nonlinearity().channel(1).upper() == 0.0);
  CHECK(
      m::yaw_force_2016_hw(m::clamp_static_friction_2016).input_nonlinearity().channel(0).upper() ==
      0.20);
  CHECK_THROWS_AS((void)m::yaw_force_2016_hw(-0.1), Error);

  // Inside the dead zone and at rest the linear block sees nothing: force stays exactly 0.
  for (int k = 0; k < 100; ++k) CHECK(hw.step(Eigen::Vector2d{0.2, 0.0})[0] == 0.0);
  // Above it, the linear block sees current - 0.21 A.
  auto linear = m::yaw_force_2016();
  for (int k = 0; k < 200; ++k) {
    const double current = 0.6 * std::sin(0.05 * k);
    const double velocity = 0.3 * std::cos(0.05 * k);
    const double seen = current > 0.21 ? current - 0.21 : (current < -0.21 ? current + 0.21 : 0.0);
    CHECK(hw.step(Eigen::Vector2d{current, velocity})[0] ==
          doctest::Approx(linear.step(Eigen::Vector2d{seen, velocity})[0]).epsilon(1e-12));
  }
}

// Output unit of the pitch model, from the real pitch logs: simulate the preset on
// u = [current A; (position(k) - position(k-1)) / 0.02 s] and fit force_N = s * y.
// /usr/bin/python3 pitch_units.py (docs/models/presets_2016.md; scipy dlsim, same procedure) gave
// s = -0.00930, -0.00891, 0.00900, 0.00768 N/unit and correlation -0.984, -0.992, 0.895,
// 0.932 for pitch-down-01, -03, pitch-up-02, -03: about one gram-force (0.00981 N) per unit.
TEST_CASE("pitch model output is about one gram-force per unit on the 2016 pitch logs" *
          doctest::skip(!endohaptics::test::has_shared_data("endowrist-2016"))) {
  const std::array<const char*, 4> logs{
      "endowrist-2016/pitch/pitch-down-01.csv", "endowrist-2016/pitch/pitch-down-03.csv",
      "endowrist-2016/pitch/pitch-up-02.csv", "endowrist-2016/pitch/pitch-up-03.csv"};
  const std::array<double, 4> scipy_scale{-0.00930, -0.00891, 0.00900, 0.00768};
  for (std::size_t l = 0; l < logs.size(); ++l) {
    const auto rows = load_log(logs[l]);
    REQUIRE(rows.size() == 1499);
    auto pitch = m::pitch_force_2016();
    double yy = 0, yf = 0, ff = 0, sy = 0, sf = 0;
    const double force0 = rows[0][2] * 1000.0;
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const double velocity = k == 0 ? 0.0 : (rows[k][4] - rows[k - 1][4]) / 0.02;
      const double y = pitch.step(Eigen::Vector2d{rows[k][5], velocity})[0];
      const double f = rows[k][2] * 1000.0 - force0;
      yy += y * y;
      yf += y * f;
      ff += f * f;
      sy += y;
      sf += f;
    }
    const double n = static_cast<double>(rows.size());
    const double scale = yf / yy;
    const double corr = (yf - sy * sf / n) / std::sqrt((yy - sy * sy / n) * (ff - sf * sf / n));
    INFO(logs[l] << ": scale " << scale << " N/unit, correlation " << corr);
    CHECK(scale == doctest::Approx(scipy_scale[l]).epsilon(0.005));
    CHECK(std::abs(corr) > 0.89);
    CHECK(std::abs(scale) > 0.0075);
    CHECK(std::abs(scale) < 0.0095);
  }
}

}  // namespace model_presets_2016_test
