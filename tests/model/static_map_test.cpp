#include "endohaptics/model/static_map.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "endohaptics/model/presets_2016.hpp"
#include "test_support.hpp"

namespace model_static_map_test {

using endohaptics::test::message_of;

namespace {

namespace m = endohaptics::model;
using Eigen::MatrixXd;
using endohaptics::Error;

}  // namespace

TEST_CASE("static map kinds: names round-trip, unknown names give nullopt") {
  for (const m::StaticMapKind kind :
       {m::StaticMapKind::none, m::StaticMapKind::deadzone, m::StaticMapKind::saturation}) {
    CHECK(m::static_map_kind_from_string(m::to_string(kind)) == kind);
  }
  CHECK(m::to_string(m::StaticMapKind::deadzone) == "deadzone");
  CHECK_FALSE(m::static_map_kind_from_string("relay").has_value());
  CHECK_FALSE(m::static_map_kind_from_string("Deadzone").has_value());  // case-sensitive
}

TEST_CASE("StaticMap::apply: dead zone, saturation, none, and NaN stays NaN") {
  const m::StaticMap dz{m::StaticMapKind::deadzone, -0.2, 0.3};
  CHECK(dz.apply(0.5) == doctest::Approx(0.2));
  CHECK(dz.apply(-0.5) == doctest::Approx(-0.3));
  CHECK(dz.apply(0.1) == 0.0);
  CHECK(std::isnan(dz.apply(std::nan(""))));
  const m::StaticMap sat{m::StaticMapKind::saturation, -1.0, 2.0};
  CHECK(sat.apply(3.0) == 2.0);
  CHECK(sat.apply(-3.0) == -1.0);
  CHECK(sat.apply(0.5) == 0.5);
  CHECK(m::StaticMap{}.apply(-7.5) == -7.5);
}

TEST_CASE("to_static_map and to_hammerstein_wiener: the yaw preset round-trips to its own type") {
  const auto preset = m::yaw_force_2016_hw();
  const m::DynamicStateSpace<> linear(preset.linear());
  const std::vector<m::StaticMap> input{m::to_static_map(preset.input_nonlinearity().channel(0)),
                                        m::to_static_map(preset.input_nonlinearity().channel(1))};
  const std::vector<m::StaticMap> output{m::to_static_map(preset.output_nonlinearity().channel(0))};
  CHECK(input[0].kind == m::StaticMapKind::deadzone);
  CHECK(input[0].upper == 0.21);
  CHECK(input[0].lower == -0.21);
  CHECK(output[0].kind == m::StaticMapKind::none);
  CHECK(m::to_static_map(m::Saturation<float>(-1.0f, 2.0f)).upper == 2.0);

  auto back = m::to_hammerstein_wiener<6, 2, 1>(linear, input, output);
  static_assert(std::is_same_v<decltype(back), m::YawForceHW2016<double>>);
  auto reference = preset;
  for (int k = 0; k < 100; ++k) {
    const Eigen::Vector2d u{0.6 * std::sin(0.05 * k), std::cos(0.03 * k)};
    REQUIRE(back.step(u) == reference.step(u));
  }
}

TEST_CASE("to_hammerstein_wiener refuses wrong map counts, sizes and unrepresentable maps") {
  const m::DynamicStateSpace<> linear(MatrixXd{{0.5}}, MatrixXd{{1.0}}, MatrixXd{{1.0}},
                                      MatrixXd{{0.0}}, 0.01);
  const std::vector<m::StaticMap> deadzone{{m::StaticMapKind::deadzone, -0.1, 0.1}};
  const std::vector<m::StaticMap> none{{}};
  CHECK(message_of([&] {
          (void)m::to_hammerstein_wiener<1, 1, 1>(linear, deadzone, std::vector<m::StaticMap>{});
        }) ==
        "to_hammerstein_wiener: 1 input and 0 output maps; the target type has 1 inputs "
        "and 1 outputs");
  CHECK(message_of([&] { (void)m::to_hammerstein_wiener<2, 1, 1>(linear, deadzone, none); }) ==
        "StateSpace: cannot convert a model with 1 states, 1 inputs, 1 outputs into "
        "StateSpace<2, 1, 1>");
  CHECK(message_of([&] {
          (void)m::to_hammerstein_wiener<1, 1, 1, double, m::Saturation<double>>(linear, deadzone,
                                                                                 none);
        }) ==
        "to_hammerstein_wiener: input 0 is a deadzone, which the requested nonlinearity "
        "type cannot represent");
  // A `none` input is a zero-width dead zone; unordered breakpoints are refused by Deadzone.
  const auto hw = m::to_hammerstein_wiener<1, 1, 1>(linear, none, none);
  CHECK(hw.input_nonlinearity().channel(0).upper() == 0.0);
  const std::vector<m::StaticMap> unordered{{m::StaticMapKind::deadzone, 0.2, -0.2}};
  CHECK_THROWS_AS((void)(m::to_hammerstein_wiener<1, 1, 1>(linear, unordered, none)), Error);
}

}  // namespace model_static_map_test
