#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include "endohaptics/model/friction_model.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <cstddef>
#include <limits>
#include <random>

namespace model_friction_model_test {

namespace {

using endohaptics::Error;
using endohaptics::model::FrictionModel;
using endohaptics::model::FrictionOptions;
using endohaptics::model::JointFriction;
using endohaptics::model::NumericStatus;
using endohaptics::test::allocations_during;
namespace friction_2016 = endohaptics::model::friction_2016;

constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();

// Joint j gets Ks = 0.2 + 0.1 j, Kc = 0.15 + 0.1 j, F_mu = 0.05 (j + 1): distinct per joint.
template <typename Model>
Model make_model(typename Model::Options options = {}) {
  using S = typename Model::Vector::Scalar;
  typename Model::Joints joints{};
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const auto x = static_cast<S>(j);
    joints[j] = {S(0.2) + S(0.1) * x, S(0.15) + S(0.1) * x, S(0.05) * (x + S(1))};
  }
  return Model(joints, options);
}

}  // namespace

TEST_CASE("table 5.2 presets: the simplified 2016 model Kc = Ks, F_mu = 0") {
  const auto model = endohaptics::model::endowrist_2016_friction();
  const double table[4] = {0.7, 0.17, 0.21, 0.20};  // worksheet table 5.2, A
  for (int j = 0; j < 4; ++j) {
    CAPTURE(j);
    CHECK(model.joint(j).static_level == table[j]);
    CHECK(model.joint(j).coulomb_level == table[j]);
    CHECK(model.joint(j).viscous_gain == 0.0);
  }
  CHECK(model.joint(friction_2016::yaw_joint) == friction_2016::yaw);
  CHECK(model.options().release_fraction == 0.75);
  CHECK(model.options().standstill_velocity == 0.01);
  const auto single = endohaptics::model::endowrist_2016_friction<float>();
  CHECK(single.joint(friction_2016::pitch_joint).static_level == 0.17f);
}

TEST_CASE_TEMPLATE("levels: Ks at standstill, Kc + F_mu |omega| when sliding (eqs. 5.5-5.7)", Model,
                   FrictionModel<1>, FrictionModel<4>, FrictionModel<7>, FrictionModel<4, float>) {
  using V = typename Model::Vector;
  using S = typename V::Scalar;
  const Model model = make_model<Model>();
  const S tol = std::is_same_v<S, float> ? S(1e-6) : S(1e-15);

  V velocity;
  V level;
  for (const S w : {S(0), S(0.01), S(-0.01), S(0.5), S(-2)}) {  // 0.01 = threshold: standstill
    velocity.setConstant(w);
    REQUIRE(model.breakaway_level(velocity, level) == NumericStatus::ok);
    for (int j = 0; j < Model::joints; ++j) {
      CAPTURE(j);
      CAPTURE(w);
      const auto& c = model.joint(j);
      const S expected =
          std::abs(w) <= S(0.01) ? c.static_level : c.coulomb_level + c.viscous_gain * std::abs(w);
      CHECK(level[j] == doctest::Approx(expected).epsilon(tol));
    }
  }
  // Joint 0: Ks 0.2, Kc 0.15, F_mu 0.05 -> at 2 rad/s the level is 0.15 + 0.1 = 0.25 A.
  velocity.setConstant(S(2));
  REQUIRE(model.breakaway_level(velocity, level) == NumericStatus::ok);
  CHECK(level[0] == doctest::Approx(S(0.25)).epsilon(tol));
}

TEST_CASE_TEMPLATE("compensate: friction opposes motion, static friction is a dead zone", Model,
                   FrictionModel<1>, FrictionModel<4>, FrictionModel<7>, FrictionModel<4, float>) {
  using V = typename Model::Vector;
  using S = typename V::Scalar;
  const Model model = make_model<Model>();
  V current, velocity, friction, external;

  // Sliding at +-1 rad/s with joint 0 constants: friction current = +-(0.15 + 0.05) A.
  velocity.setConstant(S(1));
  current.setConstant(S(0.5));
  REQUIRE(model.compensate(current, velocity, friction, external) == NumericStatus::ok);
  CHECK(friction[0] == doctest::Approx(S(0.2)));
  CHECK(external[0] == doctest::Approx(S(0.3)));
  velocity.setConstant(S(-1));
  current.setConstant(S(-0.5));
  REQUIRE(model.compensate(current, velocity, friction, external) == NumericStatus::ok);
  CHECK(friction[0] == doctest::Approx(S(-0.2)));
  CHECK(external[0] == doctest::Approx(S(-0.3)));

  // Standstill: up to Ks = 0.2 A the current is all friction; beyond it the excess is external.
  velocity.setZero();
  for (const S i : {S(0.1), S(-0.15), S(0.35), S(-0.5)}) {
    current.setConstant(i);
    REQUIRE(model.compensate(current, velocity, friction, external) == NumericStatus::ok);
    CAPTURE(i);
    const S expected = std::abs(i) <= S(0.2) ? S(0) : i - std::copysign(S(0.2), i);
    CHECK(external[0] == doctest::Approx(expected));
    CHECK(friction[0] + external[0] == doctest::Approx(i));
    for (int j = 0; j < Model::joints; ++j) {
      CHECK(std::abs(friction[j]) <= model.joint(j).static_level);
    }
  }

  // NaN on the last joint: zeros there, the others still computed.
  current.setConstant(S(0.5));
  velocity.setConstant(S(1));
  velocity[Model::joints - 1] = std::numeric_limits<S>::quiet_NaN();
  CHECK(model.compensate(current, velocity, friction, external) == NumericStatus::non_finite_input);
  CHECK(friction[Model::joints - 1] == S(0));
  CHECK(external[Model::joints - 1] == S(0));
  if constexpr (Model::joints > 1) CHECK(external[0] == doctest::Approx(S(0.3)));
}

TEST_CASE_TEMPLATE("gate (5.2.3): opens above the level, closes below release_fraction * level",
                   Model, FrictionModel<1>, FrictionModel<4>, FrictionModel<7>,
                   FrictionModel<4, float>) {
  using V = typename Model::Vector;
  using S = typename V::Scalar;
  Model model = make_model<Model>({S(0.01), S(0.5)});  // release at half the level
  const V velocity = V::Zero();                        // standstill: level = Ks = 0.2 A (joint 0)
  const V estimate = V::Constant(S(3.5));              // N, whatever the estimator says
  V feedback;

  // Current on joint 0 (A) and the expected gate state after each tick.
  const double currents[] = {0.0, 0.15, 0.2, 0.21, 0.15, 0.101, 0.099, 0.15, 0.2, -0.25, -0.09};
  const bool open[] = {false, false, false, true, true, true, false, false, false, true, false};
  for (std::size_t k = 0; k < std::size(currents); ++k) {
    V current = V::Zero();
    current[0] = static_cast<S>(currents[k]);
    REQUIRE(model.update(current, velocity, estimate, feedback) == NumericStatus::ok);
    CAPTURE(k);
    CHECK(model.gate_open()[0] == open[k]);
    CHECK(feedback[0] == (open[k] ? S(3.5) : S(0)));
    for (int j = 1; j < Model::joints; ++j) CHECK(feedback[j] == S(0));  // never opened
  }

  // Sliding lowers the level to Kc + F_mu |omega| = 0.15 + 0.05 * 0.2 = 0.16 A: 0.18 A opens.
  model.reset();
  V current = V::Constant(S(0.18));
  REQUIRE(model.update(current, V::Constant(S(0.2)), estimate, feedback) == NumericStatus::ok);
  CHECK(model.gate_open()[0]);
  CHECK(feedback[0] == S(3.5));
  // The same current at standstill would not have opened it (Ks = 0.2 A).
  model.reset();
  REQUIRE(model.update(current, velocity, estimate, feedback) == NumericStatus::ok);
  CHECK_FALSE(model.gate_open()[0]);
}

TEST_CASE_TEMPLATE("gate: NaN closes that joint's gate and zeroes its feedback only", Model,
                   FrictionModel<1>, FrictionModel<4>, FrictionModel<7>, FrictionModel<4, float>) {
  using V = typename Model::Vector;
  using S = typename V::Scalar;
  Model model = make_model<Model>();
  V feedback;
  const V estimate = V::Constant(S(2));
  REQUIRE(model.update(V::Constant(S(5)), V::Zero(), estimate, feedback) == NumericStatus::ok);
  for (int j = 0; j < Model::joints; ++j) REQUIRE(model.gate_open()[static_cast<std::size_t>(j)]);

  const S bad = std::numeric_limits<S>::quiet_NaN();
  const S inf = std::numeric_limits<S>::infinity();
  const int last = Model::joints - 1;
  for (int field = 0; field < 3; ++field) {
    V current = V::Constant(S(5));
    V velocity = V::Zero();
    V est = estimate;
    if (field == 0) current[last] = bad;
    if (field == 1) velocity[last] = inf;
    if (field == 2) est[last] = bad;
    REQUIRE(model.update(V::Constant(S(5)), V::Zero(), estimate, feedback) == NumericStatus::ok);
    CAPTURE(field);
    CHECK(model.update(current, velocity, est, feedback) == NumericStatus::non_finite_input);
    CHECK_FALSE(model.gate_open()[static_cast<std::size_t>(last)]);
    CHECK(feedback[last] == S(0));
    for (int j = 0; j < last; ++j) {
      CHECK(model.gate_open()[static_cast<std::size_t>(j)]);
      CHECK(feedback[j] == S(2));
    }
  }
}

TEST_CASE("hysteresis stops the chatter of the 2016 gate on noisy current") {
  // Current hovering at the 0.2 A level with the noise measured at standstill in the friction
  // logs (standard deviation 0.015 A, docs/models/friction_model.md), seeded.
  std::mt19937_64 rng(52);
  std::normal_distribution<double> noise(0.0, 0.015);
  using Model = FrictionModel<1>;
  Model chatty({JointFriction<double>::simplified(0.2)}, {0.01, 1.0});  // the 2016 gate
  Model damped({JointFriction<double>::simplified(0.2)}, {0.01, 0.75});
  Model::Vector feedback;
  int toggles_chatty = 0, toggles_damped = 0;
  bool was_chatty = false, was_damped = false;
  for (int k = 0; k < 2000; ++k) {
    const Model::Vector current = Model::Vector::Constant(0.21 + noise(rng));
    REQUIRE(chatty.update(current, Model::Vector::Zero(), Model::Vector::Ones(), feedback) ==
            NumericStatus::ok);
    REQUIRE(damped.update(current, Model::Vector::Zero(), Model::Vector::Ones(), feedback) ==
            NumericStatus::ok);
    toggles_chatty += chatty.gate_open()[0] != was_chatty;
    toggles_damped += damped.gate_open()[0] != was_damped;
    was_chatty = chatty.gate_open()[0];
    was_damped = damped.gate_open()[0];
  }
  // 0.15 A would need a -4 sigma excursion: the damped gate opens once and stays open.
  CHECK(toggles_damped == 1);
  CHECK(toggles_chatty > 200);
}

TEST_CASE("constructor refuses invalid constants and options, naming them") {
  using Model = FrictionModel<2>;
  const Model::Joints good = {JointFriction<double>::simplified(0.2), {0.3, 0.2, 0.01}};
  CHECK_NOTHROW(Model{good});
  auto bad = good;
  bad[1].coulomb_level = -0.1;
  CHECK_THROWS_WITH_AS(Model{bad}, doctest::Contains("joint 1 coulomb_level (Kc)"), Error);
  CHECK_THROWS_WITH_AS(Model{bad}, doctest::Contains("-0.1"), Error);
  bad = good;
  bad[0].viscous_gain = not_a_number;
  CHECK_THROWS_WITH_AS(Model{bad}, doctest::Contains("joint 0 viscous_gain (F_mu)"), Error);
  bad = good;
  bad[0].static_level = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH_AS(Model{bad}, doctest::Contains("static_level (Ks)"), Error);
  CHECK_THROWS_WITH_AS(Model(good, {0.01, 0.0}), doctest::Contains("release_fraction"), Error);
  CHECK_THROWS_WITH_AS(Model(good, {0.01, 1.5}), doctest::Contains("1.5"), Error);
  CHECK_THROWS_WITH_AS(Model(good, {-1e-3, 0.5}), doctest::Contains("standstill_velocity"), Error);
  CHECK_NOTHROW(Model(good, {0.0, 1.0}));
}

TEST_CASE(
    "FrictionModel: a tick allocates nothing (operator new counter, EIGEN_RUNTIME_NO_MALLOC)") {
  auto model = endohaptics::model::endowrist_2016_friction();
  using V = decltype(model)::Vector;
  V current, velocity, feedback, friction, external, level;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int statuses_ok = 0;
  const long allocations = allocations_during([&] {
    for (int k = 0; k < 10000; ++k) {
      for (int j = 0; j < 4; ++j) {
        current[j] = 0.8 * u(rng);
        velocity[j] = 0.05 * u(rng);
      }
      if (k % 100 == 0) velocity[1] = not_a_number;
      statuses_ok += model.update(current, velocity, current, feedback) == NumericStatus::ok;
      statuses_ok += model.compensate(current, velocity, friction, external) == NumericStatus::ok;
      statuses_ok += model.breakaway_level(velocity, level) == NumericStatus::ok;
    }
  });
  CHECK(allocations == 0);
  CHECK(statuses_ok == 3 * (10000 - 100));
}

}  // namespace model_friction_model_test
