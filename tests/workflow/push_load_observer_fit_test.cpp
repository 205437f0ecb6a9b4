#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <endohaptics/estimation/push_load_observer.hpp>
#include <endohaptics/files/umn_mis_2018_log.hpp>
#include <endohaptics/workflow/push_load_observer_fit.hpp>
#include <filesystem>
#include <random>
#include <vector>

#include "shared_data.hpp"
#include "test_support.hpp"
#include "umn_sessions.hpp"

namespace workflow_push_load_observer_fit_test {

namespace est = endohaptics::estimation;
namespace wf = endohaptics::workflow;
using endohaptics::test::message_of;

namespace {

// A grasper at 1 kHz: the spindle sweeps +-0.5 rad at 0.1 Hz against a load that steps between
// levels each stroke. Pushing (positive motion), the current is 1.45 A per unit load + 0.07 A;
// back-driven it is 0.03 A below zero whatever the load (friction exceeds it); 2 mA noise.
wf::LoadObserverData synthetic(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.002);
  wf::LoadObserverData d;
  const int n = 30000;
  d.current.resize(n);
  d.position.resize(n);
  d.load.resize(n);
  double load = 0.05;
  for (int k = 0; k < n; ++k) {
    const double t = 1e-3 * k;
    const double phase = std::fmod(t, 10.0);
    if (k % 10000 == 0) load = 0.03 + 0.02 * static_cast<double>(k / 10000);
    d.position[k] = 0.5 * std::sin(2 * 3.141592653589793 * 0.1 * t);
    const double v = 0.5 * 2 * 3.141592653589793 * 0.1 * std::cos(2 * 3.141592653589793 * 0.1 * t);
    d.load[k] = load;
    d.current[k] = (v > 0 ? 1.45 * load + 0.07 : -0.03) + noise(rng);
    (void)phase;
  }
  return d;
}

// As synthetic(), but back-driven the current sees the load too (0.8 A per unit load - 0.05 A,
// less than pushing: tendon friction), and `start_back_driven` starts the run at the top of its
// stroke moving down (cosine), with a constant `load`.
wf::LoadObserverData back_drivable(unsigned seed, bool start_back_driven, double load) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.002);
  const double w = 2 * 3.141592653589793 * 0.1;
  wf::LoadObserverData d;
  const int n = 30000;
  d.current.resize(n);
  d.position.resize(n);
  d.load.resize(n);
  for (int k = 0; k < n; ++k) {
    const double t = 1e-3 * k;
    const double y = load > 0 ? load : 0.03 + 0.02 * static_cast<double>(k / 10000);
    d.position[k] = 0.5 * (start_back_driven ? std::cos(w * t) : std::sin(w * t));
    const double v = 0.5 * w * (start_back_driven ? -std::sin(w * t) : std::cos(w * t));
    d.load[k] = y;
    d.current[k] = (v > 0 ? 1.45 * y + 0.07 : 0.8 * y - 0.05) + noise(rng);
  }
  return d;
}

}  // namespace

TEST_CASE("push-load observer: before the first push, the load from the back-driven current") {
  // Trained on runs that start pushing; run on one that starts back-driven with a load above the
  // training mean (0.09 against 0.05).
  const std::vector<wf::LoadObserverData> data{back_drivable(1, false, 0.0),
                                               back_drivable(2, false, 0.0)};
  est::PushLoadObserverParameters<double> prior;
  const auto fit = wf::fit_push_load_observer(data, prior, 1.0);
  const auto& p = fit.parameters;
  CHECK(p.back_current_per_load == doctest::Approx(0.8).epsilon(0.05));
  CHECK(p.back_current_offset == doctest::Approx(-0.05).epsilon(0.05));
  CHECK(p.back_variance < 1e-4);  // (0.01 load units)^2: 2 mA noise / 0.8 A per unit, filtered
  CHECK(p.initial_load == doctest::Approx(0.05).epsilon(0.05));
  const auto run = back_drivable(3, true, 0.09);
  const Eigen::VectorXd with_map =
      wf::simulate_load_observer(est::PushLoadObserver<double>(p), run);
  auto no_map = p;
  no_map.back_current_per_load = 0.0;
  const Eigen::VectorXd prior_only =
      wf::simulate_load_observer(est::PushLoadObserver<double>(no_map), run);
  // 4 s in: still on the first, back-driven half stroke (no push yet).
  CHECK(with_map[4000] == doctest::Approx(0.09).epsilon(0.1));
  CHECK(prior_only[4000] ==
        doctest::Approx(p.initial_load + p.output_offset + p.output_slope * p.initial_load));
  // After the first push (5-10 s) the back-driven current no longer moves the estimate: a 20 mA
  // shift over the second back-driven half stroke (10-15 s) changes nothing.
  auto shifted = run;
  for (Eigen::Index k = 10500; k < 14500; ++k) shifted.current[k] += 0.02;
  const Eigen::VectorXd after =
      wf::simulate_load_observer(est::PushLoadObserver<double>(p), shifted);
  CHECK((after.segment(10500, 4000) - with_map.segment(10500, 4000)).cwiseAbs().maxCoeff() == 0.0);
  CHECK(std::fabs(with_map[14000] - 0.09) < 0.005);
  // ... while before the first push it does (the same shift over 0.5-4.5 s).
  auto early = run;
  for (Eigen::Index k = 500; k < 4500; ++k) early.current[k] += 0.02;
  const Eigen::VectorXd moved = wf::simulate_load_observer(est::PushLoadObserver<double>(p), early);
  CHECK(std::fabs(moved[4000] - with_map[4000]) > 0.01);
}

TEST_CASE("push-load observer: the load follows the angle after the first push (stiffness)") {
  // The load steps per stroke (0.03, 0.05, 0.07) and grows by 0.01 per rad of travel in the push
  // direction (a jaw-side spring); back-driven the current says nothing (synthetic()'s -0.03 A).
  auto stiff = [](unsigned seed) {
    auto d = synthetic(seed);
    for (Eigen::Index k = 0; k < d.load.size(); ++k) {
      d.load[k] += 0.01 * d.position[k];
      if (d.current[k] > 0.0) d.current[k] += 1.45 * 0.01 * d.position[k];  // pushing
    }
    return d;
  };
  const std::vector<wf::LoadObserverData> data{stiff(1), stiff(2)};
  const auto fit = wf::fit_push_load_observer(data, est::PushLoadObserverParameters<double>{}, 1.0);
  CHECK(fit.parameters.load_per_angle == doctest::Approx(0.01).epsilon(0.35));
  auto rigid = fit.parameters;
  rigid.load_per_angle = 0.0;
  const auto without = wf::load_observer_rmse(est::PushLoadObserver<double>(rigid), data, 1.0);
  MESSAGE("stiffness " << fit.parameters.load_per_angle << ": RMSE " << fit.mean_rmse
                       << ", without it " << (without[0] + without[1]) / 2);
  CHECK(fit.mean_rmse < 0.8 * (without[0] + without[1]) / 2);
}

TEST_CASE("push-load observer: the current referred to its command carries over a sensor offset") {
  // The amplifier makes the current follow the command, i = -2.06 u; the training session measures
  // it as it is, the test session 0.015 A low (a current-measurement offset: 0.01 load units).
  auto session = [](unsigned seed, double offset) {
    auto d = back_drivable(seed, false, 0.0);
    d.command = d.current / -2.06;
    d.current.array() += offset;
    return d;
  };
  const std::vector<wf::LoadObserverData> train{session(1, 0.0), session(2, 0.0)};
  const std::vector<wf::LoadObserverData> test{session(3, -0.015)};
  const auto fit =
      wf::fit_push_load_observer(train, est::PushLoadObserverParameters<double>{}, 1.0);
  REQUIRE(fit.reference.has_value());
  CHECK(fit.reference->command_gain == doctest::Approx(-2.06).epsilon(0.01));
  CHECK(std::fabs(fit.reference->reference_offset) < 0.002);
  const est::PushLoadObserver<double> model(fit.parameters);
  const double referred = wf::load_observer_rmse(model, test, 1.0, fit.reference)[0];
  const double measured = wf::load_observer_rmse(model, test, 1.0)[0];
  MESSAGE("test session 0.015 A low: RMSE " << referred << " referred to the command, " << measured
                                            << " as measured");
  CHECK(referred < 0.5 * measured);
  // No command in the data: no reference, the current as measured.
  auto plain = train;
  for (auto& d : plain) d.command.resize(0);
  CHECK_FALSE(
      wf::fit_push_load_observer(plain, est::PushLoadObserverParameters<double>{}, 1.0).reference);
  // A model with a reference needs the command.
  CHECK(message_of([&] {
          (void)wf::simulate_load_observer(model, plain[0], fit.reference);
        }).starts_with("simulate_load_observer: the model refers the current to the command"));
}

TEST_CASE("push-load observer: the fit recovers the push-regime current model") {
  const std::vector<wf::LoadObserverData> data{synthetic(1), synthetic(2)};
  est::PushLoadObserverParameters<double> prior;
  const auto fit = wf::fit_push_load_observer(data, prior, 1.0);
  CHECK(fit.parameters.current_per_load == doctest::Approx(1.45).epsilon(0.05));
  CHECK(fit.parameters.current_offset == doctest::Approx(0.07).epsilon(0.05));
  CHECK(fit.push_fraction > 0.3);
  CHECK(fit.push_fraction < 0.6);
  // Causal: the load is held through the back-driven half, where the current says nothing.
  CHECK(fit.mean_rmse < 0.005);
  CHECK(message_of([&] {
          auto bad = data[0];
          bad.load.conservativeResize(10);
          (void)wf::fit_push_load_observer(std::vector{bad}, prior);
        }).starts_with("fit_push_load_observer: experiment 0"));
  auto never = data[0];
  never.position.setZero();  // never moves: never pushes
  CHECK(message_of([&] {
          (void)wf::fit_push_load_observer(std::vector{never}, prior);
        }).find("never pushes against the load") != std::string::npos);
}

TEST_CASE("push-load observer: filters start at the first sample, allocation-free state") {
  est::PushLoadObserver<double> m;
  const est::JointSignals<double> s{0.2, 0.0, 0.1, 0.0};
  REQUIRE(m.advance(s) == endohaptics::model::NumericStatus::ok);
  CHECK(m.filtered_current() == doctest::Approx(0.1));  // steady state of the first sample
  CHECK(m.filtered_velocity() == doctest::Approx(0.0));
  CHECK(m.regime() == 0.0);
  const auto before = m.state();
  CHECK(m.advance({std::nan(""), 0.0, 0.1, 0.0}) ==
        endohaptics::model::NumericStatus::non_finite_input);
  CHECK(m.state() == before);
  est::PushLoadObserverParameters<double> p;
  p.push_sign = 0.5;
  CHECK(message_of([&] { est::PushLoadObserver<double> bad(p); }) ==
        "PushLoadObserverParameters: push_sign must be +1 or -1, got 0.5");
  p = {};
  p.initial_load = 1e308;  // finite, but the estimate would be Inf on every tick
  CHECK(message_of([&] { est::PushLoadObserver<double> bad(p); }) ==
        "PushLoadObserverParameters: initial_load must be in [-1e6, 1e6], got 1e+308");
  p = {};
  p.current_per_load = 1e-12;
  CHECK(message_of([&] { est::PushLoadObserver<double> bad(p); }) ==
        "PushLoadObserverParameters: current_per_load must be of magnitude in [1e-9, 1e6], got "
        "1e-12");
  p = {};
  p.back_current_per_load = 1e-12;  // 0 (none) or invertible
  CHECK(message_of([&] { est::PushLoadObserver<double> bad(p); }) ==
        "PushLoadObserverParameters: back_current_per_load must be 0 or of magnitude in [1e-9, "
        "1e6], got 1e-12");
  p = {};
  p.back_variance = 0.0;
  CHECK(message_of([&] { est::PushLoadObserver<double> bad(p); }) ==
        "PushLoadObserverParameters: back_variance must be in (0, 1e6], got 0");
  p = {};
  p.direction_scale = 1e308;  // before: accepted (bounded like every joint-model parameter now)
  CHECK(message_of([&] { est::PushLoadObserver<double> bad(p); }) ==
        "PushLoadObserverParameters: direction_scale must be in (0, 1e6] rad, got 1e+308");
  p = {};
  p.velocity_threshold = 1e308;
  CHECK(message_of([&] { est::PushLoadObserver<double> bad(p); }) ==
        "PushLoadObserverParameters: velocity_threshold must be in [0, 1e6] rad/s, got 1e+308");
}

TEST_CASE("push-load observer on the UMN grasper, one session to the other, scored causally" *
          doctest::skip(!endohaptics::test::has_shared_data("umn-mis-tool-2018"))) {
  // Five runs per session, spread evenly in name order (frequencies and levels both vary), to keep
  // the sanitized test short; the current, its command and the motor encoder only (no absolute
  // position: only increments are used); grip torque in mN m as logged; RMSE on every sample
  // after 1 s of warm-up, state from reset.
  const auto l2 = endohaptics::test::umn_session_runs("Tool_4_Maryland_L_2");
  const auto l4 = endohaptics::test::umn_session_runs("Tool_4_Maryland_L_4");
  // The priors as fit_joint_model sets them: P0 the variance of the training loads, Q = (0.03 x
  // the largest |load|)^2 per second. Pushing is positive motor motion (the jaws close against the
  // reaction; the research note's reading of the data, not chosen on the test runs).
  const auto prior_of = [](const std::vector<wf::LoadObserverData>& train) {
    double sum = 0.0, sum2 = 0.0, peak = 0.0, n = 0.0;
    for (const auto& d : train) {
      sum += d.load.sum();
      sum2 += d.load.squaredNorm();
      peak = std::max(peak, d.load.cwiseAbs().maxCoeff());
      n += static_cast<double>(d.load.size());
    }
    est::PushLoadObserverParameters<double> p;
    p.initial_variance = sum2 / n - (sum / n) * (sum / n);
    p.process_variance = (0.03 * peak) * (0.03 * peak) * p.sample_time;
    p.push_sign = 1.0;
    return p;
  };
  const auto mean_of = [](const std::vector<double>& r) {
    double m = 0.0;
    for (const double x : r) m += x / static_cast<double>(r.size());
    return m;
  };
  const auto without_command = [](std::vector<wf::LoadObserverData> d) {
    for (auto& e : d) e.command.resize(0);
    return d;
  };
  // Trained on one session, scored on the other: the current referred to its command, and as
  // measured (fitted again without the command).
  const auto cross = [&](const std::vector<wf::LoadObserverData>& train,
                         const std::vector<wf::LoadObserverData>& test) {
    const auto fit = wf::fit_push_load_observer(train, prior_of(train), 1.0);
    REQUIRE(fit.reference.has_value());
    const auto plain = wf::fit_push_load_observer(without_command(train), prior_of(train), 1.0);
    REQUIRE_FALSE(plain.reference.has_value());
    return std::pair{mean_of(wf::load_observer_rmse(est::PushLoadObserver<double>(fit.parameters),
                                                    test, 1.0, fit.reference)),
                     mean_of(wf::load_observer_rmse(est::PushLoadObserver<double>(plain.parameters),
                                                    test, 1.0))};
  };
  const auto [to_l4, to_l4_plain] = cross(l2, l4);
  const auto [to_l2, to_l2_plain] = cross(l4, l2);
  MESSAGE("L_2 -> L_4 (5 runs each): " << to_l4 << " mN m referred to the command, " << to_l4_plain
                                       << " as measured; L_4 -> L_2: " << to_l2 << " / "
                                       << to_l2_plain << " mN m");
  // Measured 11.9 / 7.9 and 8.6 / 8.7 mN m. L_2's five runs reach 40 % of the reaction torque,
  // L_4's 100 %: that way the model extrapolates, and the reference (fitted on L_2 alone) costs;
  // the other way it gains (research note, K6; the static regression baseline: 37-46 mN m across
  // sessions; the target: 5 mN m on another instrument).
  CHECK(to_l4 < 13.0);
  CHECK(to_l2 < 9.5);
  CHECK(to_l2 < to_l2_plain);
  // L_2's runs start at the top of the stroke, back-driven for the first half stroke: there the
  // back-driven map, not the training mean, gives the load.
  const auto fit4 = wf::fit_push_load_observer(l4, prior_of(l4), 1.0);
  REQUIRE(fit4.parameters.back_current_per_load != 0.0);
  auto held = fit4.parameters;
  held.back_current_per_load = 0.0;
  const double with_map = mean_of(wf::load_observer_rmse(
      est::PushLoadObserver<double>(fit4.parameters), l2, 1.0, fit4.reference));
  const double prior_only =
      mean_of(wf::load_observer_rmse(est::PushLoadObserver<double>(held), l2, 1.0, fit4.reference));
  MESSAGE("L_4 -> L_2: " << with_map << " mN m; held at the prior until the first push: "
                         << prior_only << " mN m");
  CHECK(with_map < prior_only - 3.0);  // measured 8.6 against 14.3 mN m
}

}  // namespace workflow_push_load_observer_fit_test
