// The bridge's identified Hammerstein-Wiener model with a current play (files::ModelFile::
// current_play): the force stays while the current falls back through the play's band, and the
// tick's play is the one replay and identify apply offline (identification::played_input).
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

#include "endohaptics/estimation/bridge_force_models.hpp"
#include "endohaptics/estimation/force_models_2016.hpp"
#include "endohaptics/identification/hammerstein_wiener_fit.hpp"

namespace estimation_identified_hammerstein_wiener_test {

namespace est = endohaptics::estimation;
using endohaptics::model::NumericStatus;
using Model = est::IdentifiedHammersteinWiener<double>;

// `ticks` model periods at `current` A (velocity 0); the last force.
double hold(Model& m, double current, int ticks) {
  const est::JointSignals<double> s{0.0, 0.0, current, 0.0};
  double f = 0.0;
  for (int k = 0; k < ticks; ++k) {
    f = m.force(s);
    REQUIRE(m.advance(s) == NumericStatus::ok);
  }
  return f;
}

TEST_CASE("identified model: the current play holds the force while the current backs off") {
  const auto yaw = est::models_2016<double>().clamp1.model();  // dead zone 0.21 A
  Model plain(yaw);
  Model played(yaw, {}, 0.2);
  CHECK(played.current_play() == 0.2);
  // Loaded at 1.0 A until settled, then backed off to 0.65 A: within 2 x 0.2 A of the loading
  // current, so the play's output stays at 0.8 A and so does the force.
  const double plain_loaded = hold(plain, 1.0, 20000);
  const double played_loaded = hold(played, 1.0, 20000);
  REQUIRE(std::fabs(played_loaded) > 0.1);
  const double plain_unloaded = hold(plain, 0.65, 20000);
  const double played_unloaded = hold(played, 0.65, 20000);
  CHECK(played_unloaded == doctest::Approx(played_loaded).epsilon(1e-6));
  CHECK(std::fabs(plain_unloaded) < 0.8 * std::fabs(plain_loaded));  // without: it falls
  // Backed off beyond the band (below 1.0 - 2 x 0.2 A): the force follows the current down.
  const double played_released = hold(played, 0.3, 20000);
  CHECK(std::fabs(played_released) < 0.8 * std::fabs(played_loaded));
  // The play's output is the state's last entry; reset() centres it.
  CHECK(played.state()[Model::State::RowsAtCompileTime - 1] == doctest::Approx(0.5));
  played.reset();
  CHECK(played.state().isZero(0.0));
}

TEST_CASE("identified model: the tick's play is identification::played_input, bit for bit") {
  const auto yaw = est::models_2016<double>().clamp1.model();
  Model played(yaw, {}, 0.17);
  Model plain(yaw);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> step(-0.05, 0.05);
  const int n = 3000;
  Eigen::MatrixXd u(n, 2);
  double current = 0.0;
  for (int k = 0; k < n; ++k) {
    current = std::fmax(-1.5, std::fmin(1.5, current + step(rng)));
    u(k, 0) = current;
    u(k, 1) = 2.0 * std::sin(0.01 * k);
  }
  const Eigen::MatrixXd p = endohaptics::identification::played_input(u, 0.17);
  CHECK(p.col(1) == u.col(1));  // the velocity passes
  CHECK((p.col(0) - u.col(0)).cwiseAbs().maxCoeff() <= 0.17 + 1e-15);
  for (int k = 0; k < n; ++k) {
    const est::JointSignals<double> s{0.0, u(k, 1), u(k, 0), 0.0};
    const est::JointSignals<double> q{0.0, u(k, 1), p(k, 0), 0.0};
    REQUIRE(played.force(s) == plain.force(q));
    REQUIRE(played.advance(s) == NumericStatus::ok);
    REQUIRE(plain.advance(q) == NumericStatus::ok);
  }
  // Width 0: the input unchanged.
  CHECK(endohaptics::identification::played_input(u, 0.0) == u);
}

TEST_CASE("identified model: a negative or non-finite current play is refused") {
  const auto yaw = est::models_2016<double>().clamp1.model();
  CHECK_THROWS_AS(Model(yaw, {}, -0.1), endohaptics::Error);
  CHECK_THROWS_AS(Model(yaw, {}, std::nan("")), endohaptics::Error);
}

}  // namespace estimation_identified_hammerstein_wiener_test
