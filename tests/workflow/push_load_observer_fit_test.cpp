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

}  // namespace

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
  REQUIRE(m.advance(s) == endohaptics::model::StepStatus::ok);
  CHECK(m.filtered_current() == doctest::Approx(0.1));  // steady state of the first sample
  CHECK(m.filtered_velocity() == doctest::Approx(0.0));
  CHECK(m.regime() == 0.0);
  const auto before = m.state();
  CHECK(m.advance({std::nan(""), 0.0, 0.1, 0.0}) ==
        endohaptics::model::StepStatus::non_finite_input);
  CHECK(m.state() == before);
  est::PushLoadObserverParameters<double> p;
  p.push_sign = 0.5;
  CHECK(message_of([&] { est::PushLoadObserver<double> bad(p); }) ==
        "PushLoadObserverParameters: push_sign must be +1 or -1, got 0.5");
  p = {};
  p.initial_load = 1e308;  // finite, but the estimate would be Inf on every tick
  CHECK(message_of([&] { est::PushLoadObserver<double> bad(p); }) ==
        "PushLoadObserverParameters: an offset, slope or initial load must be in [-1e6, 1e6], got "
        "1e+308");
  p = {};
  p.current_per_load = 1e-12;
  CHECK(message_of([&] { est::PushLoadObserver<double> bad(p); }) ==
        "PushLoadObserverParameters: current_per_load must be of magnitude in [1e-9, 1e6], got "
        "1e-12");
}

TEST_CASE("push-load observer on the UMN grasper, one session to the other, scored causally" *
          doctest::skip(!endohaptics::test::has_shared_data("umn-mis-tool-2018"))) {
  // Five runs per session (first in name order) to keep the sanitized test short; the current
  // and the motor encoder only (no absolute position: only increments are used); grip torque in
  // mN m as logged; RMSE on every sample after 1 s of warm-up, state from reset.
  auto session = [](const char* folder) {
    std::vector<std::filesystem::path> paths;
    for (const auto& e : std::filesystem::directory_iterator(
             endohaptics::test::shared_data(std::string("umn-mis-tool-2018/") + folder))) {
      paths.push_back(e.path());
    }
    std::sort(paths.begin(), paths.end());
    std::vector<wf::LoadObserverData> out;
    for (std::size_t i = 0; i < 5 && i < paths.size(); ++i) {
      const auto log = endohaptics::files::read_umn_mis_2018(paths[i].string());
      out.push_back(
          {log.signal("current"), log.signal("motor_position"), log.signal("grip_torque")});
    }
    return out;
  };
  const auto l2 = session("Tool_4_Maryland_L_2");
  const auto l4 = session("Tool_4_Maryland_L_4");
  est::PushLoadObserverParameters<double> prior;
  prior.initial_variance = 100.0;  // mN m^2
  prior.process_variance = 1e-2;   // (1e-8 N m^2 in mN m)
  // Pushing is positive motor motion (the jaws close against the reaction; the research note's
  // reading of the data, not chosen on the test runs).
  prior.push_sign = 1.0;
  const auto fit = wf::fit_push_load_observer(l2, prior, 1.0);
  const auto test = wf::load_observer_rmse(est::PushLoadObserver<double>(fit.parameters), l4, 1.0);
  double mean = 0.0;
  for (const double r : test) mean += r / static_cast<double>(test.size());
  MESSAGE("trained on L_2 (5 runs): RMSE " << fit.mean_rmse << " mN m; on L_4 (5 runs): " << mean
                                           << " mN m");
  // 7.8 mN m trained, 6.7 mN m on the other session (the static regression baseline: 37-46 mN m
  // across sessions; the target: 5 mN m on another instrument).
  CHECK(mean < 9.0);
}

}  // namespace workflow_push_load_observer_fit_test
