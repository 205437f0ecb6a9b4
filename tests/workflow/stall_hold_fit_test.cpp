#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <endohaptics/files/endowrist_2016_log.hpp>
#include <endohaptics/identification/signal.hpp>
#include <endohaptics/workflow/stall_hold_fit.hpp>
#include <filesystem>
#include <vector>

#include "shared_data.hpp"
#include "test_support.hpp"

namespace workflow_stall_hold_fit_test {

namespace est = endohaptics::estimation;
namespace wf = endohaptics::workflow;
using endohaptics::test::message_of;

namespace {

// Hits of a clamp at 10 ms: move in (current ramps negative), stall (current relaxes, the force
// holds), move out. The truth is `gain` x the stall-hold value: the fit must find gain and side.
// `lag`: the truth's output time constant.
wf::StallHoldData synthetic_hits(double gain, int hits, double lag = 0.3) {
  wf::StallHoldData d;
  const int per_hit = 300;
  d.current.resize(hits * per_hit);
  d.velocity.resize(hits * per_hit);
  for (int h = 0; h < hits; ++h) {
    const double depth = 0.5 + 0.2 * h;
    for (int k = 0; k < per_hit; ++k) {
      const int i = h * per_hit + k;
      if (k < 100) {  // moving in
        d.velocity[i] = 0.07;
        d.current[i] = -depth * k / 100.0;
      } else if (k < 200) {  // stalled, current relaxing
        d.velocity[i] = 0.0;
        d.current[i] = -depth * std::exp(-(k - 100) / 20.0);
      } else {  // moving out: friction beyond the dead zone on the other side, no load
        d.velocity[i] = -0.07;
        d.current[i] = 0.4;
      }
    }
  }
  est::StallHoldParameters<double> truth;
  truth.sample_time = 0.01;
  truth.side = est::StallHoldSide::negative;
  truth.gain = gain;
  truth.output_time_constant = lag;
  d.force = wf::simulate_stall_hold(est::StallHold<double>(truth), d);
  return d;
}

}  // namespace

TEST_CASE("fit_stall_hold: recovers the gain and the side of noiseless hits") {
  const std::vector<wf::StallHoldData> data{synthetic_hits(-7.5, 4), synthetic_hits(-7.5, 3)};
  est::StallHoldParameters<double> prior;
  prior.sample_time = 0.01;
  const auto fit = wf::fit_stall_hold(data, prior, 0.5);
  CHECK(fit.parameters.gain == doctest::Approx(-7.5));
  CHECK(fit.parameters.side == est::StallHoldSide::negative);
  REQUIRE(fit.fit_percent.size() == 2);
  CHECK(fit.mean_fit_percent == doctest::Approx(100.0));

  wf::StallHoldData bad = data[0];
  bad.force.conservativeResize(10);
  CHECK(message_of([&] { (void)wf::fit_stall_hold(std::vector{bad}, prior); }) ==
        "fit_stall_hold: experiment 0: current, velocity and force differ in length");
  wf::StallHoldData quiet = data[0];
  quiet.current.setConstant(0.1);
  CHECK(message_of([&] {
          (void)wf::fit_stall_hold(std::vector{quiet}, prior);
        }).starts_with("fit_stall_hold: the current never exceeds the dead zone"));
}

TEST_CASE("choose_stall_hold_settings: the constants by cross-validation on the training data") {
  // The truth lags by 0.8 s (the prior says 0.3 s): the held-out fit must find it.
  const std::vector<wf::StallHoldData> data{
      synthetic_hits(-7.5, 4, 0.8), synthetic_hits(-7.5, 3, 0.8), synthetic_hits(-7.5, 2, 0.8)};
  est::StallHoldParameters<double> prior;
  prior.sample_time = 0.01;
  const std::vector<std::vector<std::size_t>> folds{{0}, {1}, {2}};
  const wf::StallHoldSelection chosen = wf::choose_stall_hold_settings(data, folds, prior, 0.5);
  CHECK(chosen.folds == 3);
  CHECK(chosen.candidates >= 106);  // the prior, then the 105 of the grid
  CHECK(chosen.settings.output_time_constant == 0.8);
  CHECK(chosen.held_out_fit == doctest::Approx(100.0));
  CHECK(chosen.prior_fit < 95.0);
  // One fold: nothing to cross-validate, the prior's constants.
  const wf::StallHoldSelection none = wf::choose_stall_hold_settings(data, {{0, 1, 2}}, prior, 0.5);
  CHECK(none.folds == 0);
  CHECK(none.settings.output_time_constant == 0.3);
  CHECK(message_of([&] {
          (void)wf::choose_stall_hold_settings(data, {{0}, {3}}, prior, 0.5);
        }) == "choose_stall_hold_settings: fold index 3 beyond the 3 experiments");
  auto short_run = data;
  short_run[2].force.conservativeResize(20);
  CHECK(message_of([&] { (void)wf::choose_stall_hold_settings(short_run, folds, prior, 0.5); }) ==
        "choose_stall_hold_settings: experiment 2: current, velocity and force must have one "
        "length, longer than the warm-up");
}

TEST_CASE("fit_stall_hold on the 2016 clamp hits, leave one file out, scored causally" *
          doctest::skip(!endohaptics::test::has_shared_data("endowrist-2016/clamp-hits"))) {
  // Each file: the 2016 reader, then a 10 ms grid (linear interpolation), velocity = backward
  // difference of the position on that grid (what a controller computes), force as logged (no
  // offset). Priors: table 5.2's clamp static friction 0.20 A, 0.05 rad/s, 30 ms, 0.3 s. The
  // gain and side are fitted on five files, the sixth scored from zero state after 1 s.
  std::vector<std::filesystem::path> paths;
  for (const auto& e : std::filesystem::directory_iterator(
           endohaptics::test::shared_data("endowrist-2016/clamp-hits"))) {
    paths.push_back(e.path());
  }
  std::sort(paths.begin(), paths.end());
  REQUIRE(paths.size() == 6);
  constexpr double ts = 0.01;
  std::vector<wf::StallHoldData> files;
  for (const auto& path : paths) {
    const auto log = endohaptics::files::read_endowrist_2016(path.string());
    Eigen::MatrixXd signals(log.rows(), 3);
    signals << log.signal("current"), log.signal("position"), log.signal("force");
    const auto segments = endohaptics::identification::resample_uniform(log.time, signals, ts);
    const auto& s = segments.longest();
    wf::StallHoldData d;
    d.current = s.data.col(0);
    d.force = s.data.col(2);
    d.velocity = Eigen::VectorXd::Zero(s.rows());
    for (Eigen::Index k = 1; k < s.rows(); ++k)
      d.velocity[k] = (s.data(k, 1) - s.data(k - 1, 1)) / ts;
    files.push_back(std::move(d));
  }
  est::StallHoldParameters<double> prior;
  prior.sample_time = ts;
  double sum = 0.0;
  for (std::size_t held_out = 0; held_out < files.size(); ++held_out) {
    std::vector<wf::StallHoldData> train;
    for (std::size_t f = 0; f < files.size(); ++f) {
      if (f != held_out) train.push_back(files[f]);
    }
    const auto fit = wf::fit_stall_hold(train, prior, 1.0);
    // Score the held-out file with the trained gain and side (not refitted).
    const auto y_hat =
        wf::simulate_stall_hold(est::StallHold<double>(fit.parameters), files[held_out]);
    const auto n = y_hat.size() - 100;
    const Eigen::VectorXd y = files[held_out].force.tail(n);
    const double score =
        100.0 * (1.0 - (y - y_hat.tail(n)).norm() / (y.array() - y.mean()).matrix().norm());
    MESSAGE(paths[held_out].filename().string()
            << ": causal fit " << score << " % (gain " << fit.parameters.gain << ")");
    sum += score;
  }
  const double mean = sum / static_cast<double>(files.size());
  MESSAGE("clamp-hits, leave one file out, causal: mean fit " << mean << " %");
  // 60.9 % with the priors above (per file 72.5, 42.8, 63.2, 70.7, 68.7, 47.7); the 2016 preset
  // and the identified Hammerstein-Wiener models score below (docs/identification_results.md).
  CHECK(mean > 58.0);
}

}  // namespace workflow_stall_hold_fit_test
