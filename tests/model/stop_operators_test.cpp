#include <doctest/doctest.h>

#include <cmath>
#include <endohaptics/model/stop_operators.hpp>
#include <limits>
#include <optional>
#include <random>
#include <vector>

#include "test_support.hpp"

namespace model_stop_operators_test {

namespace md = endohaptics::model;
using endohaptics::test::message_of;
using Stops = md::StopOperators<double, 3>;

namespace {

// The outputs along a path of positions, from the initial state.
std::vector<Stops::Values> run(const Stops& stops, const std::vector<double>& path) {
  Stops::State x = Stops::initial_state();
  std::vector<Stops::Values> out;
  for (const double q : path) {
    Stops::Values s;
    stops.step(x, q, s);
    out.push_back(s);
  }
  return out;
}

}  // namespace

TEST_CASE("stop operators: zero until the first travel, then saturated against the first move") {
  const Stops stops(Stops::Thresholds(0.1, 0.2, 0.4), 0.01);
  // At rest, then 5 mrad up (below the start travel), then to 0.01 rad: the operators start as if
  // the motion before had come down, each at -1 at the start position.
  const auto s = run(stops, {1.0, 1.0, 1.005, 1.01, 1.05});
  CHECK(s[0].isZero(0.0));
  CHECK(s[2].isZero(0.0));
  // At 1.01: travel 0.01 from the start, each s_j = -1 + 0.01 / r_j.
  CHECK(s[3][0] == doctest::Approx(-1.0 + 0.01 / 0.1));
  CHECK(s[3][1] == doctest::Approx(-1.0 + 0.01 / 0.2));
  CHECK(s[3][2] == doctest::Approx(-1.0 + 0.01 / 0.4));
  CHECK(s[4][0] == doctest::Approx(-1.0 + 0.05 / 0.1));
  // The first move down instead: +1 at the start.
  const auto d = run(stops, {1.0, 0.98});
  CHECK(d[1][0] == doctest::Approx(1.0 - 0.02 / 0.1));
  // A start travel of 0 starts at the first motion whatever its size.
  const Stops eager(Stops::Thresholds(0.1, 0.2, 0.4), 0.0);
  const auto e = run(eager, {0.0, 0.0, 1e-6});
  CHECK(e[1].isZero(0.0));
  CHECK(e[2][0] == doctest::Approx(-1.0 + 1e-5).epsilon(1e-12));
}

TEST_CASE("stop operators: the travel since the last reversal, clipped to [-1, 1] (a triangle)") {
  const Stops stops(Stops::Thresholds(0.1, 0.2, 0.4), 0.0);
  std::vector<double> path;
  for (int k = 0; k <= 100; ++k) path.push_back(0.01 * k);       // up 1 rad
  for (int k = 1; k <= 30; ++k) path.push_back(1.0 - 0.01 * k);  // down 0.3 rad
  const auto s = run(stops, path);
  // After 1 rad up every operator is saturated at +1.
  CHECK(s[100].isApproxToConstant(1.0, 1e-12));
  // Down from the reversal: s_r = 1 - travel / r until -1 (the play is 2 r wide).
  CHECK(s[130][0] == doctest::Approx(-1.0));
  CHECK(s[130][1] == doctest::Approx(1.0 - 0.3 / 0.2));
  CHECK(s[130][2] == doctest::Approx(1.0 - 0.3 / 0.4));
  CHECK(s[110][2] == doctest::Approx(1.0 - 0.1 / 0.4));
  CHECK(s[120][0] == doctest::Approx(-1.0));
}

TEST_CASE("stop operators: bounded, rate-independent and blind to the absolute position") {
  const Stops stops(Stops::Thresholds(0.05, 0.2, 0.5), 0.005);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> step(-0.03, 0.03);
  std::vector<double> coarse{0.0};
  for (int k = 0; k < 5000; ++k) coarse.push_back(coarse.back() + step(rng));
  // The same path with every step cut in four (a four times faster sampling of it).
  std::vector<double> fine{0.0};
  for (std::size_t k = 1; k < coarse.size(); ++k) {
    for (int i = 1; i <= 4; ++i) {
      fine.push_back(coarse[k - 1] + 0.25 * i * (coarse[k] - coarse[k - 1]));
    }
  }
  std::vector<double> shifted = coarse;
  for (double& q : shifted) q += 123.4;
  const auto a = run(stops, coarse);
  const auto b = run(stops, fine);
  const auto c = run(stops, shifted);
  double rate = 0.0, shift = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    CHECK(a[k].cwiseAbs().maxCoeff() <= 1.0 + 1e-12);
    // Play operators are exact on piecewise-linear paths: the subdivided path ends each coarse
    // step at the same outputs.
    rate = std::max(rate, (a[k] - b[4 * k]).cwiseAbs().maxCoeff());
    shift = std::max(shift, (a[k] - c[k]).cwiseAbs().maxCoeff());
  }
  CHECK(rate < 1e-9);
  CHECK(shift < 1e-9);
}

TEST_CASE("stop operators: thresholds must increase, errors name the value") {
  CHECK(message_of([] { Stops bad(Stops::Thresholds(0.1, 0.1, 0.4), 0.0); }) ==
        "StopOperators: threshold 1 must be finite, > 0 and above the one before, got 0.1");
  CHECK(message_of([] { Stops bad(Stops::Thresholds(0.0, 0.1, 0.4), 0.0); }) ==
        "StopOperators: threshold 0 must be finite, > 0 and above the one before, got 0");
  CHECK(message_of([] {
          Stops bad(Stops::Thresholds(0.1, 0.2, std::nan("")), 0.0);
        }).starts_with("StopOperators: threshold 2 must be finite"));
  CHECK(message_of([] { Stops bad(Stops::Thresholds(0.1, 0.2, 0.4), -1.0); }) ==
        "StopOperators: start_travel must be finite and >= 0, got -1");
}

TEST_CASE("stop operators: float") {
  const md::StopOperators<float, 2> stops({0.1F, 0.2F}, 0.0F);
  md::StopOperators<float, 2>::State x = md::StopOperators<float, 2>::initial_state();
  md::StopOperators<float, 2>::Values s;
  stops.step(x, 0.0F, s);
  stops.step(x, 0.05F, s);
  CHECK(s[0] == doctest::Approx(-0.5F));
  CHECK(stops.values(x, 0.05F)[1] == doctest::Approx(-0.75F));
}

TEST_CASE("friction play: one rule for its constants, worded with the reader's names") {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::nan("");
  const auto refusal = [](double play, std::optional<double> slide, double viscous) {
    return message_of([&] { md::check_friction_play(play, slide, viscous, "m.json"); });
  };
  // Accepted: a plain play, a friction play with or without a viscous term, no play at all, the
  // edges of each range.
  CHECK(refusal(0.13, std::nullopt, 0.0) == "(no exception)");
  CHECK(refusal(0.13, 0.065, -0.025) == "(no exception)");
  CHECK(refusal(0.13, 0.0, 0.0) == "(no exception)");
  CHECK(refusal(0.13, 0.13, 0.0) == "(no exception)");
  CHECK(refusal(0.0, std::nullopt, 0.0) == "(no exception)");
  CHECK(refusal(md::max_joint_model_parameter, std::nullopt, -md::max_joint_model_parameter) ==
        "(no exception)");
  // Each rule, named, after the place.
  for (const double play : {-0.1, nan, inf, 2 * md::max_joint_model_parameter}) {
    CAPTURE(play);
    CHECK(refusal(play, std::nullopt, 0.0).starts_with("m.json: current_play must be in [0, "));
  }
  for (const double slide : {-0.01, 0.2, nan, inf}) {
    CAPTURE(slide);
    CHECK(refusal(0.13, slide, 0.0)
              .starts_with("m.json: current_play_slide must be in [0, current_play = 0.13], got"));
  }
  for (const double viscous : {nan, inf, -inf, 2 * md::max_joint_model_parameter}) {
    CAPTURE(viscous);
    CHECK(refusal(0.13, 0.065, viscous)
              .starts_with("m.json: current_play_viscous must be finite, at most "));
  }
  CHECK(refusal(0.0, 0.0, 0.0) ==
        "m.json: current_play_slide and current_play_viscous need a current_play");
  CHECK(refusal(0.0, std::nullopt, -0.025) ==
        "m.json: current_play_slide and current_play_viscous need a current_play");
  // Another reader's names, no place.
  CHECK(message_of([] {
          md::check_friction_play(0.0, std::nullopt, 0.5, "", {"--play", "--slide", "--viscous"});
        }) == "--slide and --viscous need a --play");
}

TEST_CASE("friction play: without a sliding half width it slides at its own, and is the play") {
  CHECK(md::friction_play_slide(0.13, std::nullopt) == 0.13);
  CHECK(md::friction_play_slide(0.13, std::optional<double>(0.05)) == 0.05);
  CHECK(md::friction_play_slide(0.13, std::optional<double>(0.0)) == 0.0);  // a given 0 is kept
  // With the default slide and no viscous term the friction play is play(), sample by sample.
  const double stick = 0.13;
  const double slide = md::friction_play_slide(stick, std::nullopt);
  double z = 0.0;
  double sliding = 0.0;
  double z_play = 0.0;
  for (const double q : {0.0, 0.1, 0.2, 0.35, 0.3, 0.1, -0.05, -0.2, -0.1, 0.05, 0.3}) {
    CAPTURE(q);
    z = md::friction_play(z, sliding, q, stick, slide);
    z_play = md::play(z_play, q, stick);
    CHECK(z == doctest::Approx(z_play));
  }
}

}  // namespace model_stop_operators_test
