#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <endohaptics/estimation/bidirectional_load_observer.hpp>
#include <endohaptics/files/umn_mis_2018_log.hpp>
#include <endohaptics/workflow/bidirectional_observer_fit.hpp>
#include <filesystem>
#include <random>
#include <vector>

#include "shared_data.hpp"
#include "test_support.hpp"
#include "umn_sessions.hpp"

namespace workflow_bidirectional_observer_fit_test {

namespace est = endohaptics::estimation;
namespace wf = endohaptics::workflow;
using endohaptics::test::message_of;
using Observer = est::BidirectionalLoadObserver<double>;

namespace {

constexpr double pi = 3.141592653589793;

// A grasper at 1 kHz sweeping +-0.5 rad at `hz` against a constant `load` (mN m) that rises with
// the travel since the last reversal (a jaw-side hysteresis of +-4 mN m, 10 % more per 100 mN m
// of load). Forward the current is 1.4 mA per mN m + 70 mA, backward 0.7 mA per mN m - 90 mA, both
// following the truth; `friction` A is added forward and taken backward (an instrument's own);
// 2 mA noise. `start_top`: the run starts at the top of its stroke, moving back first.
wf::LoadObserverData grasper(unsigned seed, double load, double hz, double friction,
                             bool start_top = false, int n = 20000) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.002);
  const double w = 2 * pi * hz;
  wf::LoadObserverData d;
  d.current.resize(n);
  d.position.resize(n);
  d.load.resize(n);
  for (int k = 0; k < n; ++k) {
    const double t = 1e-3 * k;
    const double phase = start_top ? w * t + pi / 2 : w * t - pi / 2;
    const double q = 0.5 * std::sin(phase);
    const double v = 0.5 * w * std::cos(phase);
    // The jaw-side hysteresis: +4 while closing (forward), -4 while opening, scaled by the load.
    const double y = load + (v > 0 ? 4.0 : -4.0) * (1.0 + load / 1000.0);
    d.position[k] = q;
    d.load[k] = y;
    d.current[k] =
        (v > 0 ? 1.4e-3 * y + 0.07 + friction : 0.7e-3 * y - 0.09 - friction) + noise(rng);
  }
  return d;
}

double mean(const std::vector<double>& r) {
  double m = 0.0;
  for (const double x : r) m += x / static_cast<double>(r.size());
  return m;
}

double rmse(const Observer& model, const wf::LoadObserverData& d,
            const wf::CurrentReference& reference = std::nullopt) {
  const Eigen::VectorXd y = wf::simulate_bidirectional_observer(model, d, reference);
  const auto n = d.load.size() - 1000;
  return std::sqrt((d.load.tail(n) - y.tail(n)).squaredNorm() / static_cast<double>(n));
}

}  // namespace

TEST_CASE("bidirectional observer fit: the maps, the hysteresis, and another instrument") {
  // Training: five levels and two speeds of one instrument whose friction wanders by +-5 mA from
  // run to run (wear, temperature: the UMN runs' forward bias spreads by 2-3 mN m).
  std::vector<wf::LoadObserverData> train;
  unsigned seed = 1;
  for (const double load : {10.0, 30.0, 50.0, 70.0, 90.0}) {
    for (const double hz : {0.2, 0.4}) {
      train.push_back(grasper(seed, load, hz, seed % 2 == 0 ? 0.005 : -0.005));
      ++seed;
    }
  }
  const auto fit = wf::fit_bidirectional_load_observer(train, {}, 1.0);
  const auto& p = fit.parameters;
  // The truth moves +-4 around the level: the maps see the level +-4 (and the gain of the
  // hysteresis), the fit recovers them within that.
  // (Relative checks: doctest's Approx is absolute near 0.)
  CHECK(std::fabs(p.forward_gain / 1.4e-3 - 1.0) < 0.05);
  CHECK(std::fabs(p.backward_gain / 0.7e-3 - 1.0) < 0.05);
  // Forward the truth is L_e + 4 (x 1.05 at most), so the offset absorbs 4 gains.
  CHECK(std::fabs((p.forward_offset - 4.0 * p.forward_gain) / 0.07 - 1.0) < 0.03);
  CHECK(std::fabs(p.initial_load / 50.0 - 1.0) < 0.01);
  CHECK(fit.forward_fraction > 0.3);
  CHECK(fit.backward_fraction > 0.3);
  CHECK_FALSE(fit.reference.has_value());
  MESSAGE("training RMSE " << fit.mean_rmse << " mN m, friction prior sd "
                           << std::sqrt(p.friction_variance));
  CHECK(fit.mean_rmse < 2.0);
  // Another instrument: 15 mA more friction both ways (10.7 mN m on the forward inversion), at a
  // level and speed not trained on, starting at either end of the stroke.
  const Observer model(p);
  for (const bool top : {false, true}) {
    const auto other = grasper(99, 60.0, 0.3, 0.015, top);
    const double e = rmse(model, other);
    // The forward map alone (what a push-only observer sees) reads 10.7 mN m high.
    auto forward_only = p;
    forward_only.backward_variance = 1e6;
    forward_only.friction_variance = 0.0;
    const double biased = rmse(Observer(forward_only), other);
    MESSAGE((top ? std::string("start at the top") : std::string("start at the bottom"))
            << ": RMSE " << e << " mN m, forward map only " << biased);
    CHECK(e < 5.0);  // measured 2.4 (bottom) and 4.3 (top: backward first, at the prior)
    CHECK(e < 0.5 * biased);
  }
}

TEST_CASE("bidirectional observer fit: the current referred to its command") {
  // The amplifier makes the current follow the command, i = -2.06 u; the test instrument measures
  // it 15 mA low (a sensor offset, common to both directions).
  auto with_command = [](wf::LoadObserverData d, double offset) {
    d.command = d.current / -2.06;
    d.current.array() += offset;
    return d;
  };
  std::vector<wf::LoadObserverData> train;
  for (unsigned s = 1; s <= 4; ++s) {
    train.push_back(with_command(grasper(s, 20.0 * s, 0.25, 0.0), 0.0));
  }
  const auto fit = wf::fit_bidirectional_load_observer(train, {}, 1.0);
  REQUIRE(fit.reference.has_value());
  CHECK(std::fabs(fit.reference->command_gain / -2.06 - 1.0) < 0.01);
  const auto test = with_command(grasper(9, 45.0, 0.25, 0.0), -0.015);
  const Observer model(fit.parameters);
  const double referred = rmse(model, test, fit.reference);
  MESSAGE("15 mA sensor offset: RMSE " << referred << " mN m referred to the command");
  CHECK(referred < 3.0);
  CHECK(message_of([&] {
          auto plain = test;
          plain.command.resize(0);
          (void)wf::simulate_bidirectional_observer(model, plain, fit.reference);
        }).starts_with("simulate_bidirectional_observer: the model refers the current"));
}

TEST_CASE("bidirectional observer fit: data it cannot fit are refused, saying why") {
  const std::vector<wf::LoadObserverData> one{grasper(1, 30.0, 0.2, 0.0)};
  std::vector<wf::LoadObserverData> forward_only{grasper(1, 30.0, 0.2, 0.0),
                                                 grasper(2, 60.0, 0.2, 0.0)};
  for (auto& d : forward_only) {
    for (Eigen::Index k = 0; k < d.position.size(); ++k) {
      d.position[k] = 1e-4 * static_cast<double>(k);  // always forward
    }
  }
  CHECK(message_of([&] { (void)wf::fit_bidirectional_load_observer(forward_only, {}, 1.0); }) ==
        "fit_bidirectional_load_observer: 0 samples moving backward: the observer needs motion "
        "both ways in the training data");
  auto short_load = one;
  short_load[0].load.conservativeResize(100);
  CHECK(message_of([&] { (void)wf::fit_bidirectional_load_observer(short_load, {}, 1.0); })
            .starts_with("fit_bidirectional_load_observer: experiment 0: current, position and "
                         "load must have the same length"));
  CHECK(message_of([&] {
          (void)wf::fit_bidirectional_load_observer(std::vector<wf::LoadObserverData>{}, {});
        }) == "fit_bidirectional_load_observer: no data");
  // One level only: the maps cannot separate gain from offset.
  const std::string single =
      message_of([&] { (void)wf::fit_bidirectional_load_observer(one, {}, 1.0); });
  CHECK(single.starts_with(
      "fit_bidirectional_load_observer: every experiment moving forward is at the same load "
      "level (29.7"));
  CHECK(single.ends_with("): the map needs experiments at two levels or more"));
}

TEST_CASE("bidirectional observer: the constants no physics fixes, by cross-validation") {
  // Four runs at four levels, 10 s each; two folds of two runs (each fold trains on two levels).
  std::vector<wf::LoadObserverData> data;
  unsigned seed = 40;
  for (const double load : {20.0, 40.0, 60.0, 80.0}) {
    data.push_back(grasper(seed, load, 0.4, seed % 2 == 0 ? 0.004 : -0.004, false, 10000));
    ++seed;
  }
  const std::vector<std::vector<std::size_t>> folds{{0, 1}, {2, 3}};
  const est::BidirectionalLoadObserverParameters<double> prior;
  const wf::BidirectionalSelection chosen =
      wf::choose_bidirectional_settings(data, folds, prior, 1.0);
  MESSAGE("held-out RMSE " << chosen.held_out_rmse << " mN m (the research note's constants "
                           << chosen.prior_rmse << "), " << chosen.candidates
                           << " settings; correlation time "
                           << chosen.settings.rule.correlation_time << " s, friction prior x"
                           << chosen.settings.rule.friction_prior_scale << ", load walk "
                           << chosen.settings.rule.load_walk << ", cut-off "
                           << chosen.settings.current_cutoff << " Hz");
  CHECK(chosen.folds == 2);
  CHECK(chosen.candidates >= 61);  // the 60 of the noise grid and the research note's rule
  CHECK(std::isfinite(chosen.held_out_rmse));
  CHECK(chosen.held_out_rmse <= chosen.prior_rmse);
  CHECK(chosen.settings.current_cutoff < 500.0);
  // The fit with the chosen constants scores every held-out run as the search did.
  double sum = 0.0;
  for (const auto& fold : folds) {
    std::vector<wf::LoadObserverData> train;
    for (std::size_t e = 0; e < data.size(); ++e) {
      if (std::find(fold.begin(), fold.end(), e) == fold.end()) train.push_back(data[e]);
    }
    const auto fit = wf::fit_bidirectional_load_observer(
        train, wf::with_settings(prior, chosen.settings), 1.0, chosen.settings.rule);
    for (const std::size_t e : fold) sum += rmse(Observer(fit.parameters), data[e]);
  }
  CHECK(sum / 4.0 == doctest::Approx(chosen.held_out_rmse).epsilon(1e-9));
  // Fewer than two folds: the prior's front end and the research note's rule.
  const wf::BidirectionalSelection none =
      wf::choose_bidirectional_settings(data, {{0, 1, 2, 3}}, prior, 1.0);
  CHECK(none.folds == 0);
  CHECK(none.settings.rule.correlation_time == 0.2);
  CHECK(none.settings.current_cutoff == prior.current_cutoff);
  CHECK(message_of([&] {
          (void)wf::choose_bidirectional_settings(data, {{0}, {4}}, prior, 1.0);
        }) == "choose_bidirectional_settings: fold index 4 beyond the 4 experiments");
  auto short_run = data;
  short_run[3].load.conservativeResize(500);
  CHECK(
      message_of([&] { (void)wf::choose_bidirectional_settings(short_run, folds, prior, 1.0); }) ==
      "choose_bidirectional_settings: experiment 3: current, position and load must have "
      "the same length, longer than the warm-up");
  // The encoder's step: none on these smooth angles, the step on quantised ones.
  CHECK_FALSE(wf::encoder_step(data).has_value());
  auto counted = data;
  for (auto& d : counted) d.position = (d.position / 1e-4).array().round() * 1e-4;
  const auto step = wf::encoder_step(counted);
  REQUIRE(step.has_value());
  CHECK(*step == doctest::Approx(1e-4));
}

TEST_CASE("bidirectional observer on the UMN grasper, one session to the other, scored causally" *
          doctest::skip(!endohaptics::test::has_shared_data("umn-mis-tool-2018"))) {
  // Five runs per session spread evenly in name order (frequencies and levels both vary), to keep
  // the sanitized test short; the current, its command and the motor encoder only (only its
  // increments are used); grip torque in mN m as logged; RMSE on every sample after 1 s.
  const auto l2 = endohaptics::test::umn_session_runs("Tool_4_Maryland_L_2");
  const auto l4 = endohaptics::test::umn_session_runs("Tool_4_Maryland_L_4");
  const auto cross = [](const std::vector<wf::LoadObserverData>& train,
                        const std::vector<wf::LoadObserverData>& test) {
    const auto fit = wf::fit_bidirectional_load_observer(train, {}, 1.0);
    REQUIRE(fit.reference.has_value());
    const Observer model(fit.parameters);
    std::vector<double> r;
    for (const auto& d : test) r.push_back(rmse(model, d, fit.reference));
    // The same without the friction state (its prior 0): both directions' inversions averaged.
    auto fixed = fit.parameters;
    fixed.friction_variance = 0.0;
    std::vector<double> f;
    for (const auto& d : test) f.push_back(rmse(Observer(fixed), d, fit.reference));
    return std::pair{mean(r), mean(f)};
  };
  const auto [to_l4, to_l4_fixed] = cross(l2, l4);
  const auto [to_l2, to_l2_fixed] = cross(l4, l2);
  MESSAGE("L_2 -> L_4 (5 runs each): " << to_l4 << " mN m (without the friction state "
                                       << to_l4_fixed << "); L_4 -> L_2: " << to_l2 << " ("
                                       << to_l2_fixed << ")");
  // Measured 5.70 and 4.75 mN m (without the friction state 6.50 / 5.74); the push-load observer
  // on the same runs: 11.9 and 8.6 mN m (push_load_observer_fit_test).
  CHECK(to_l4 < 8.0);
  CHECK(to_l2 < 6.5);
  CHECK(to_l4 < to_l4_fixed);
}

TEST_CASE("bidirectional observer on the UMN grasper, blind constants, whole sessions" *
          doctest::skip(!endohaptics::test::has_shared_data("umn-mis-tool-2018"))) {
  // The held-out figure of the fixed UMN line (docs/identification_results.md, umn_loso.sh):
  // every run of one session trains, every run of the other is scored causally after 0.5 s, with
  // the constants identify's blocked cross-validation on the training session chose (the search
  // itself takes 23 and 45 s in a Release build: the script runs it; here the fit and the replay
  // with its choice). The rest threshold is one encoder step per sample.
  const auto l2 = endohaptics::test::umn_session_all("Tool_4_Maryland_L_2");
  const auto l4 = endohaptics::test::umn_session_all("Tool_4_Maryland_L_4");
  REQUIRE(l2.size() == 20);
  REQUIRE(l4.size() == 50);
  const auto cross = [](const std::vector<wf::LoadObserverData>& train,
                        const std::vector<wf::LoadObserverData>& test,
                        const wf::BidirectionalSettings& s) {
    est::BidirectionalLoadObserverParameters<double> prior;
    const auto step = wf::encoder_step(train);
    REQUIRE(step.has_value());
    prior.velocity_threshold = *step / prior.sample_time;
    auto chosen = s;
    chosen.velocity_threshold = prior.velocity_threshold;
    const auto fit = wf::fit_bidirectional_load_observer(train, wf::with_settings(prior, chosen),
                                                         0.5, chosen.rule);
    const Observer model(fit.parameters);
    double sum = 0.0;
    for (const auto& d : test) {
      const Eigen::VectorXd y = wf::simulate_bidirectional_observer(model, d, fit.reference);
      const auto n = d.load.size() - 500;
      sum += std::sqrt((d.load.tail(n) - y.tail(n)).squaredNorm() / static_cast<double>(n));
    }
    return sum / static_cast<double>(test.size());
  };
  // Chosen on L_2: correlation time 0.05 s, friction prior x1, load walk 0.1 % / 81 (the grid's
  // lowest, walked four steps of 3 below it); 20 Hz, 5 Hz, q0 0.1 rad, stops x 1.
  wf::BidirectionalSettings on_l2;
  on_l2.rule = {0.05, 1.0, 0.001 / 81.0};
  on_l2.current_cutoff = 20.0;
  on_l2.velocity_cutoff = 5.0;
  on_l2.direction_scale = 0.1;
  // Chosen on L_4: 0.1414 s, x1, 0.3 %; 80 Hz, 20 Hz, q0 0.05 rad, stops x 1.
  wf::BidirectionalSettings on_l4;
  on_l4.rule = {0.1414, 1.0, 0.003};
  on_l4.current_cutoff = 80.0;
  on_l4.velocity_cutoff = 20.0;
  on_l4.direction_scale = 0.05;
  // Both correlation times are values of the search's grid (the factor-sqrt(2) refinement).
  const auto grid = wf::noise_rule_grid();
  CHECK(grid.size() == 144);
  for (const double t : {0.05, 0.1414}) {
    CHECK(std::any_of(grid.begin(), grid.end(), [t](const wf::BidirectionalNoiseRule& r) {
      return r.correlation_time == t;
    }));
  }
  const double to_l4 = cross(l2, l4, on_l2);
  const double to_l2 = cross(l4, l2, on_l4);
  MESSAGE("blind constants, L_2 -> L_4 " << to_l4 << " mN m, L_4 -> L_2 " << to_l2
                                         << ", mean of the two " << (to_l4 + to_l2) / 2);
  // Measured 5.011 and 3.757 mN m (mean 4.384; with the factor-2 grid's choice 5.065 / 3.790,
  // 4.43): the goal is at most 4.4, below O'Neill et al.'s 4.42.
  CHECK(to_l4 < 5.02);
  CHECK(to_l2 < 3.77);
  CHECK((to_l4 + to_l2) / 2 <= 4.4);
}

}  // namespace workflow_bidirectional_observer_fit_test
