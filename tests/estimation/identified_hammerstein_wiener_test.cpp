// The bridge's identified Hammerstein-Wiener model with a current play (files::ModelFile::
// current_play): the force stays while the current falls back through the play's band, and the
// tick's play is the one replay and identify apply offline (identification::played_input).
#include <doctest/doctest.h>

#include <cmath>
#include <optional>
#include <random>
#include <vector>

#include "endohaptics/estimation/bridge_force_models.hpp"
#include "endohaptics/estimation/force_models_2016.hpp"
#include "endohaptics/identification/hammerstein_wiener_fit.hpp"
#include "endohaptics/model/stop_operators.hpp"

namespace estimation_identified_hammerstein_wiener_test {

namespace est = endohaptics::estimation;
using endohaptics::model::NumericStatus;
using Model = est::IdentifiedHammersteinWiener<double>;

// `n` ticks of a current random-walking by steps within +-`step` A (clamped to +-1.5 A, from
// `seed`) and a velocity `amplitude` sin(`rate` k): the input columns identify and replay play.
Eigen::MatrixXd random_walk_input(unsigned seed, double step, double amplitude, double rate,
                                  int n = 3000) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> draw(-step, step);
  Eigen::MatrixXd u(n, 2);
  double current = 0.0;
  for (int k = 0; k < n; ++k) {
    current = std::fmax(-1.5, std::fmin(1.5, current + draw(rng)));
    u(k, 0) = current;
    u(k, 1) = amplitude * std::sin(rate * static_cast<double>(k));
  }
  return u;
}

// Runs `played` on `u` and `plain` on the played input `p` (the same velocity): the forces equal
// tick for tick.
void check_same_forces(Model& played, Model& plain, const Eigen::MatrixXd& u,
                       const Eigen::MatrixXd& p) {
  for (Eigen::Index k = 0; k < u.rows(); ++k) {
    const est::JointSignals<double> s{0.0, u(k, 1), u(k, 0), 0.0};
    const est::JointSignals<double> q{0.0, u(k, 1), p(k, 0), 0.0};
    REQUIRE(played.force(s) == plain.force(q));
    REQUIRE(played.advance(s) == NumericStatus::ok);
    REQUIRE(plain.advance(q) == NumericStatus::ok);
  }
}

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
  // The play's output is the state's last entry but one; reset() centres it.
  CHECK(played.state()[Model::State::RowsAtCompileTime - 2] == doctest::Approx(0.5));
  played.reset();
  CHECK(played.state().isZero(0.0));
}

TEST_CASE("identified model: the tick's play is identification::played_input, bit for bit") {
  const auto yaw = est::models_2016<double>().clamp1.model();
  Model played(yaw, {}, 0.17);
  Model plain(yaw);
  const Eigen::MatrixXd u = random_walk_input(7, 0.05, 2.0, 0.01);
  const Eigen::MatrixXd p = endohaptics::identification::played_input(u, 0.17);
  CHECK(p.col(1) == u.col(1));  // the velocity passes
  CHECK((p.col(0) - u.col(0)).cwiseAbs().maxCoeff() <= 0.17 + 1e-15);
  check_same_forces(played, plain, u, p);
  // Width 0: the input unchanged.
  CHECK(endohaptics::identification::played_input(u, 0.0) == u);
}

TEST_CASE(
    "identified model: a velocity whose viscous current overflows is refused, the play kept") {
  const auto yaw = est::models_2016<double>().clamp1.model();
  Model m(yaw, {}, 0.13, 0.065, 2.0);
  (void)hold(m, 0.5, 50);  // the play's output moved to 0.37 A
  const Model::State before = m.state();
  for (const double v : {1e308, -1e308, std::nan("")}) {
    CAPTURE(v);
    const est::JointSignals<double> s{0.0, v, 0.5, 0.0};
    CHECK(m.advance(s) != NumericStatus::ok);
    CHECK_FALSE(std::isfinite(m.force(s)));
    CHECK(m.state() == before);
  }
}

TEST_CASE("identified model: a negative or non-finite current play is refused") {
  const auto yaw = est::models_2016<double>().clamp1.model();
  CHECK_THROWS_AS(Model(yaw, {}, -0.1), endohaptics::Error);
  CHECK_THROWS_AS(Model(yaw, {}, std::nan("")), endohaptics::Error);
  // The sliding width within [0, play], the viscous coefficient finite, both only with a play.
  CHECK_THROWS_AS(Model(yaw, {}, 0.13, 0.2), endohaptics::Error);
  CHECK_THROWS_AS(Model(yaw, {}, 0.13, -0.01), endohaptics::Error);
  CHECK_THROWS_AS(Model(yaw, {}, 0.13, 0.065, std::nan("")), endohaptics::Error);
  CHECK_THROWS_AS(Model(yaw, {}, 0.0, 0.05), endohaptics::Error);
  CHECK_THROWS_AS(Model(yaw, {}, 0.0, std::nullopt, -0.025), endohaptics::Error);
  const Model roll(yaw, {}, 0.13, 0.065, -0.025);
  CHECK(roll.current_play_slide() == 0.065);
  CHECK(roll.current_play_viscous() == -0.025);
  CHECK(Model(yaw, {}, 0.17).current_play_slide() == 0.17);  // none: a plain play
}

// The emulated roll's friction in the current domain (docs/models/sim.md, "Parameters"): static
// K_s 0.13 A, Coulomb K_c 0.065 A, viscous F_mu 0.025 A s/rad.
constexpr double k_s = 0.13, k_c = 0.065, f_mu = 0.025;

TEST_CASE("friction play: stuck within the static band, sliding at the Coulomb one") {
  using endohaptics::model::friction_play;
  double z = 0.0, sliding = 0.0;
  // Up to K_s the joint stays stuck and z at 0; beyond, it slides and the load takes q - K_c.
  z = friction_play(z, sliding, 0.12, k_s, k_c);
  CHECK(z == 0.0);
  CHECK(sliding == 0.0);
  z = friction_play(z, sliding, 0.14, k_s, k_c);
  CHECK(sliding == 1.0);
  CHECK(z == doctest::Approx(0.14 - k_c));
  z = friction_play(z, sliding, 0.5, k_s, k_c);
  CHECK(z == doctest::Approx(0.5 - k_c));
  // Backed off: stuck again, z holds down to K_c + K_s below the sliding current (a plain play
  // of K_c would let it fall from 2 K_c below on).
  z = friction_play(z, sliding, 0.45, k_s, k_c);
  CHECK(sliding == 0.0);
  CHECK(z == doctest::Approx(0.5 - k_c));
  z = friction_play(z, sliding, 0.5 - k_c - k_s + 0.001, k_s, k_c);
  CHECK(z == doctest::Approx(0.5 - k_c));
  // Beyond the band below it: the joint slides back and the load takes q + K_c.
  z = friction_play(z, sliding, 0.25, k_s, k_c);
  CHECK(sliding == -1.0);
  CHECK(z == doctest::Approx(0.25 + k_c));
  // Sliding back on, a current that wavers up a little while the joint still moves back (its
  // viscous current keeps the slide's sign): z follows the current, it does not stick.
  z = friction_play(z, sliding, 0.2, k_s, k_c, -0.01);
  CHECK(z == doctest::Approx(0.2 + 0.01 + k_c));
  z = friction_play(z, sliding, 0.21, k_s, k_c, -0.01);
  CHECK(sliding == -1.0);
  CHECK(z == doctest::Approx(0.21 + 0.01 + k_c));
  // The same waver once the joint has stopped (no viscous current): it sticks.
  z = friction_play(z, sliding, 0.23, k_s, k_c, 0.0);
  CHECK(sliding == 0.0);
  CHECK(z == doctest::Approx(0.21 + 0.01 + k_c));
}

TEST_CASE("friction play: with the Coulomb band equal to the static one it is the plain play") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> step(-0.05, 0.05);
  double z_play = 0.0, z = 0.0, sliding = 0.0, q = 0.0;
  for (int k = 0; k < 5000; ++k) {
    q = std::fmax(-1.5, std::fmin(1.5, q + step(rng)));
    z_play = endohaptics::model::play(z_play, q, 0.17);
    z = endohaptics::model::friction_play(z, sliding, q, 0.17, 0.17);
    REQUIRE(z == z_play);
  }
}

TEST_CASE("friction play: sliding in free motion the load reads 0 at any velocity") {
  // The joint slides at velocity v with nothing to touch: the motor's current is the Coulomb
  // and viscous friction's, sign(v) (K_c + F_mu |v|), and was K_s at the breakaway. In the
  // reported signals' signs of a rig that reports the current negated (the emulator): current
  // -i, viscous coefficient -F_mu.
  for (const double v : {0.2, 0.7, -1.3}) {
    CAPTURE(v);
    double z = 0.0, sliding = 0.0;
    const double s = v > 0 ? 1.0 : -1.0;
    z = endohaptics::model::friction_play(z, sliding, -s * (k_s + 1e-3), k_s, k_c, 0.0);
    REQUIRE(sliding == -s);
    for (int k = 0; k < 100; ++k) {
      const double current = -s * (k_c + f_mu * std::fabs(v));
      z = endohaptics::model::friction_play(z, sliding, current, k_s, k_c, -f_mu * v);
      REQUIRE(sliding == -s);
      REQUIRE(std::fabs(z) < 1e-12);
    }
  }
}

TEST_CASE("identified model: the friction play in the tick is identification::played_input") {
  const auto yaw = est::models_2016<double>().clamp1.model();
  Model played(yaw, {}, k_s, k_c, -f_mu);
  Model plain(yaw);
  const Eigen::MatrixXd u = random_walk_input(5, 0.03, 1.5, 0.013);
  const Eigen::MatrixXd p = endohaptics::identification::played_input(u, k_s, k_c, -f_mu);
  CHECK(p.col(1) == u.col(1));  // the velocity passes
  // The played input differs from the plain play's of either width somewhere.
  CHECK(p != endohaptics::identification::played_input(u, k_s));
  CHECK(p != endohaptics::identification::played_input(u, k_c));
  check_same_forces(played, plain, u, p);
  // The sliding state is the state's last entry; reset() clears it.
  played.reset();
  CHECK(played.state().isZero(0.0));
  // A viscous term needs the velocity column.
  CHECK_THROWS_AS(
      static_cast<void>(endohaptics::identification::played_input(u.leftCols(1), k_s, k_c, -f_mu)),
      endohaptics::Error);
  // The same widths and no viscous term: the plain play.
  CHECK(endohaptics::identification::played_input(u, 0.17, 0.17, 0.0) ==
        endohaptics::identification::played_input(u, 0.17));
}

}  // namespace estimation_identified_hammerstein_wiener_test
