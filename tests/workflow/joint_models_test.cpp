// The joint force models in the identify/replay workflow: simulation and causal
// scoring of model files of kind stall_hold / push_load_observer / bidirectional_load_observer,
// their fit from prepared logs,
// the family choice by inner cross-validation, and the formats' defaults.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <endohaptics/workflow/workflow.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "test_support.hpp"

namespace workflow_joint_models_test {

namespace est = endohaptics::estimation;
namespace files = endohaptics::files;
namespace wf = endohaptics::workflow;
using endohaptics::test::message_of;

namespace {

const std::vector<files::SignalInfo> inputs{{"current", "A"}, {"velocity", "rad/s"}};
const std::vector<files::SignalInfo> outputs{{"force", "N"}};

// Clamp hits at 10 ms (move in with the current ramping negative, stall while it relaxes, move
// out), the force a stall-hold of gain `gain`, one hit depth per hit; as a prepared log. The
// output lag is 0.4 s, a value on the grid of the fit's inner cross-validation (its prior is 0.3
// s), so that a fit on two files or more must find it to reproduce the force exactly.
wf::PreparedLog hits_log(double gain, int hits, double first_depth, const std::string& name) {
  const int per_hit = 300;
  Eigen::MatrixXd u(hits * per_hit, 2);
  for (int h = 0; h < hits; ++h) {
    const double depth = first_depth + 0.2 * h;
    for (int k = 0; k < per_hit; ++k) {
      const int i = h * per_hit + k;
      if (k < 100) {
        u.row(i) << -depth * k / 100.0, 0.07;
      } else if (k < 200) {
        u.row(i) << -depth * std::exp(-(k - 100) / 20.0), 0.0;
      } else {
        u.row(i) << 0.4, -0.07;
      }
    }
  }
  est::StallHoldParameters<double> truth;
  truth.sample_time = 0.01;
  truth.side = est::StallHoldSide::negative;
  truth.gain = gain;
  truth.output_time_constant = 0.4;
  const files::ModelFile model = files::make_joint_model_file(truth, inputs, outputs);
  wf::PreparedLog log;
  log.source = name;
  log.sample_time = 0.01;
  log.preparation = wf::Preparation::score;
  log.segments.push_back({u, wf::simulate_joint_model(model, u)});
  log.start_time.push_back(0.0);
  return log;
}

// The largest difference between `y` (a 3-input observer file replayed on `u` at 1 kHz) and the
// estimation types composed by hand: the current referred to its command, then `observer` on the
// encoder angle summed from the velocity.
template <typename Observer>
double by_hand(const files::ModelFile& file, Observer observer, const Eigen::MatrixXd& u,
               const Eigen::VectorXd& y) {
  est::CurrentOffsetReference<double> reference(*file.current_reference);
  double position = 0.0, largest = 0.0;
  for (Eigen::Index k = 0; k < u.rows(); ++k) {
    position += u(k, 1) * 0.001;
    REQUIRE(reference.advance(u(k, 0), u(k, 2)) == endohaptics::model::NumericStatus::ok);
    const est::JointSignals<double> s{position, u(k, 1), reference.corrected(), 0.0};
    REQUIRE(observer.advance(s) == endohaptics::model::NumericStatus::ok);
    largest = std::max(largest, std::fabs(observer.force(s) - y[k]));
  }
  return largest;
}

}  // namespace

TEST_CASE("joint models: a stall-hold file simulates as the estimation type, scored causally") {
  const wf::PreparedLog log = hits_log(-7.5, 3, 0.5, "hits.csv");
  est::StallHoldParameters<double> p;
  p.sample_time = 0.01;
  p.side = est::StallHoldSide::negative;
  p.gain = -7.5;
  p.output_time_constant = 0.4;  // the truth's (hits_log)
  const wf::StallHoldData data{log.segments[0].u.col(0), log.segments[0].u.col(1),
                               log.segments[0].y.col(0)};
  const Eigen::VectorXd direct = wf::simulate_stall_hold(est::StallHold<double>(p), data);
  CHECK(direct.isApprox(log.segments[0].y.col(0)));
  CHECK(direct.maxCoeff() > 3.0);  // the hits carry force

  est::StallHoldParameters<double> clamp{0.2, 0.05, 0.03, 0.4, -7.5, est::StallHoldSide::negative,
                                         0.01};
  const files::ModelFile model = files::make_joint_model_file(clamp, inputs, outputs);
  const wf::FileComparison c = wf::compare_log(model, log);
  CHECK(c.fit[0] == doctest::Approx(100.0));
  CHECK(c.rmse[0] == doctest::Approx(0.0).epsilon(1e-9));
  CHECK(c.warmup_samples == 50);  // the default 0.5 s
  // No output-fitted state for a joint model, and no other grid than its own.
  CHECK(message_of([&] {
          (void)wf::compare_log(model, log, {wf::InitialStateMode::oracle, 0.0, 1.0});
        }).starts_with("--x0 oracle: a stall_hold model has no linear state"));
  wf::PreparedLog other = log;
  other.sample_time = 0.02;
  CHECK(message_of([&] { (void)wf::compare_log(model, other); }) ==
        "hits.csv: prepared at 0.02 s, the stall_hold model runs at 0.01 s");
  CHECK(message_of([&] { (void)wf::simulate_joint_model(model, Eigen::MatrixXd::Zero(5, 3)); }) ==
        "simulate_joint_model: 3 input columns, the model takes 2 (current, velocity)");
}

TEST_CASE("joint models: fit_joint_model recovers the stall-hold gain and side from logs") {
  const std::vector<wf::PreparedLog> logs{hits_log(-7.5, 3, 0.5, "a"), hits_log(-7.5, 2, 0.7, "b")};
  const wf::JointModelFit fit =
      wf::fit_joint_model(files::ModelKind::stall_hold, logs, inputs, outputs, 0.5);
  REQUIRE(fit.model.kind() == files::ModelKind::stall_hold);
  const auto& fitted = files::joint_model_parameters<est::StallHoldParameters<double>>(fit.model);
  CHECK(fitted.gain == doctest::Approx(-7.5));
  CHECK(fitted.side == est::StallHoldSide::negative);
  CHECK(fit.model.provenance.files == std::vector<std::string>{"a", "b"});
  CHECK(fit.summary.find("loaded side negative") != std::string::npos);
  // The lag (and the threshold) by the inner cross-validation over the two files, not the prior.
  CHECK(fitted.output_time_constant == 0.4);
  CHECK(fit.summary.find("by 2-fold blocked cross-validation on the training files") !=
        std::string::npos);
  // One file: no folds, the priors, said so.
  const wf::JointModelFit one =
      wf::fit_joint_model(files::ModelKind::stall_hold, {logs[0]}, inputs, outputs, 0.5);
  CHECK(files::joint_model_parameters<est::StallHoldParameters<double>>(one.model)
            .output_time_constant == 0.3);
  CHECK(one.summary.find("the priors: fewer than two training files") != std::string::npos);
  CHECK(message_of([&] {
          (void)wf::fit_joint_model(files::ModelKind::stall_hold, logs, {inputs[0]}, outputs, 0.5);
        }) ==
        "fit_joint_model: stall_hold needs 2 inputs (current, velocity) and 1 output, got 1 "
        "and 1");
  CHECK(message_of([&] {
          (void)wf::fit_joint_model(files::ModelKind::hammerstein_wiener, logs, inputs, outputs,
                                    0.5);
        }) == "fit_joint_model: kind \"hammerstein_wiener\" is not a joint model");
}

TEST_CASE("joint models: the family is chosen by inner cross-validation on the training files") {
  CHECK(wf::inner_folds(1).empty());
  CHECK(wf::inner_folds(3) == std::vector<std::vector<std::size_t>>{{0}, {1}, {2}});
  const auto seven = wf::inner_folds(7);
  REQUIRE(seven.size() == 5);
  CHECK(seven[0] == std::vector<std::size_t>{0, 5});
  CHECK(seven[4] == std::vector<std::size_t>{4});
  // The constants inside a fit: contiguous blocks in the files' order.
  CHECK(wf::blocked_folds(1).empty());
  CHECK(wf::blocked_folds(3) == std::vector<std::vector<std::size_t>>{{0}, {1}, {2}});
  CHECK(wf::blocked_folds(7) ==
        std::vector<std::vector<std::size_t>>{{0, 1}, {2, 3}, {4}, {5}, {6}});
  const auto fifty = wf::blocked_folds(50);
  REQUIRE(fifty.size() == 5);
  CHECK(fifty[1].front() == 10);
  CHECK(fifty[1].back() == 19);

  std::vector<wf::PreparedLog> logs;
  for (int f = 0; f < 4; ++f) logs.push_back(hits_log(-7.5, 2, 0.5 + 0.1 * f, std::to_string(f)));
  // The observer never sees the motor push against a load in these hits (the current of the
  // moving-in phase does not grow with any load it can fit): it fails or scores below, and loses.
  const wf::ModelChoice choice = wf::choose_family(
      nullptr, {files::ModelKind::push_load_observer, files::ModelKind::stall_hold}, {}, {}, logs,
      inputs, outputs, wf::WorkflowOptions{});
  REQUIRE(choice.families.size() == 2);
  CHECK(choice.folds.size() == 4);  // leave one file out
  CHECK(choice.family == "stall_hold");
  CHECK(choice.best == 1);
  CHECK(choice.families[1].mean_fit == doctest::Approx(100.0));
  CHECK(choice.families[1].fold_fit.size() == 4);
  CHECK(choice.families[0].mean_fit < choice.families[1].mean_fit);
  REQUIRE(choice.model.kind() == files::ModelKind::stall_hold);
  CHECK(files::joint_model_parameters<est::StallHoldParameters<double>>(choice.model).gain ==
        doctest::Approx(-7.5));
  CHECK(choice.files.size() == 4);
  CHECK_FALSE(choice.joint_summary.empty());
  // One family: no cross-validation, that family.
  const wf::ModelChoice only = wf::choose_family(nullptr, {files::ModelKind::stall_hold}, {}, {},
                                                 logs, inputs, outputs, wf::WorkflowOptions{});
  CHECK(only.folds.empty());
  CHECK(only.family == "stall_hold");
  CHECK(message_of([&] {
          (void)wf::choose_family(nullptr, {}, {}, {}, logs, inputs, outputs,
                                  wf::WorkflowOptions{});
        }) == "identify: no model family to fit");
}

TEST_CASE(
    "joint models: the family choice searches a fit's constants once, on all training files") {
  std::vector<wf::PreparedLog> logs;
  for (int f = 0; f < 4; ++f) logs.push_back(hits_log(-7.5, 2, 0.5 + 0.1 * f, std::to_string(f)));
  using Params = est::StallHoldParameters<double>;
  // The constants alone: the blocked cross-validation over the four files finds the truth's lag.
  const wf::JointConstants c =
      wf::choose_joint_constants(files::ModelKind::stall_hold, logs, inputs, outputs, 0.5);
  CHECK(c.kind == files::ModelKind::stall_hold);
  CHECK(c.files == 4);
  REQUIRE(c.stall_hold.has_value());
  CHECK(c.stall_hold->folds == 4);
  CHECK(c.stall_hold->settings.output_time_constant == 0.4);
  CHECK_FALSE(c.bidirectional.has_value());
  // Fitted with them on the same files: the model and report of the fit that searches itself,
  // without a search.
  const wf::JointModelFit searched =
      wf::fit_joint_model(files::ModelKind::stall_hold, logs, inputs, outputs, 0.5);
  const wf::JointModelFit held =
      wf::fit_joint_model(files::ModelKind::stall_hold, logs, inputs, outputs, 0.5, &c);
  CHECK(searched.constant_searches == 1);
  CHECK(held.constant_searches == 0);
  const auto& a = files::joint_model_parameters<Params>(searched.model);
  const auto& b = files::joint_model_parameters<Params>(held.model);
  CHECK(a.gain == b.gain);
  CHECK(a.side == b.side);
  CHECK(a.velocity_threshold == b.velocity_threshold);
  CHECK(a.velocity_time_constant == b.velocity_time_constant);
  CHECK(a.output_time_constant == b.output_time_constant);
  CHECK(held.summary == searched.summary);
  CHECK(held.training_fit == searched.training_fit);
  // Refitted on one of the files: the constants held (a search on one file would keep the
  // prior's 0.3 s lag), the gain fitted, and the summary says where the constants came from.
  const wf::JointModelFit one =
      wf::fit_joint_model(files::ModelKind::stall_hold, {logs[2]}, inputs, outputs, 0.5, &c);
  CHECK(one.constant_searches == 0);
  CHECK(files::joint_model_parameters<Params>(one.model).output_time_constant == 0.4);
  CHECK(files::joint_model_parameters<Params>(one.model).gain == doctest::Approx(-7.5));
  CHECK(one.summary.find("chosen on 4 training files, held in this refit on 1") !=
        std::string::npos);
  // The push observer has nothing to choose: no search, whether or not constants are given.
  const wf::JointConstants none =
      wf::choose_joint_constants(files::ModelKind::push_load_observer, logs, inputs, outputs, 0.5);
  CHECK_FALSE(none.stall_hold.has_value());
  CHECK_FALSE(none.bidirectional.has_value());
  // Constants of another kind, or a kind's constants missing, are refused by name.
  CHECK(message_of([&] {
          (void)wf::fit_joint_model(files::ModelKind::push_load_observer, logs, inputs, outputs,
                                    0.5, &c);
        }) ==
        "fit_joint_model: the constants given are for kind \"stall_hold\", the fit is of kind "
        "\"push_load_observer\"");
  wf::JointConstants empty = c;
  empty.stall_hold.reset();
  CHECK(message_of([&] {
          (void)wf::fit_joint_model(files::ModelKind::stall_hold, logs, inputs, outputs, 0.5,
                                    &empty);
        }) ==
        "fit_joint_model: the constants given are for kind \"stall_hold\" but hold none of its "
        "constants, the fit is of kind \"stall_hold\"");
  CHECK(message_of([&] {
          (void)wf::choose_joint_constants(files::ModelKind::stall_hold, {}, inputs, outputs, 0.5);
        }) == "choose_joint_constants: no logs");

  // The family choice: stall_hold refitted in each of 4 folds and once on all files, the push
  // observer in 4 folds; one constant search in all (stall_hold's, on the 4 training files). Run
  // again in each fold, as the constants once were, it would count 4 more.
  std::vector<std::string> lines;
  wf::WorkflowOptions options;
  options.progress = [&lines](std::string_view line) { lines.emplace_back(line); };
  const wf::ModelChoice choice = wf::choose_family(
      nullptr, {files::ModelKind::push_load_observer, files::ModelKind::stall_hold}, {}, {}, logs,
      inputs, outputs, options);
  CHECK(choice.family == "stall_hold");
  CHECK(choice.folds.size() == 4);
  CHECK(choice.constant_searches == 1);
  CHECK(std::count_if(lines.begin(), lines.end(), [](const std::string& l) {
          return l ==
                 "family stall_hold: constants chosen on all 4 training files, held in the "
                 "folds' refits";
        }) == 1);
  // The chosen model is the fit on every training file with those constants.
  const auto& chosen = files::joint_model_parameters<Params>(choice.model);
  CHECK(chosen.gain == a.gain);
  CHECK(chosen.output_time_constant == a.output_time_constant);
  CHECK(choice.joint_summary == searched.summary);
  // Each fold's refit holds the lag the truth has: the held-out hits are reproduced.
  CHECK(choice.families[1].mean_fit == doctest::Approx(100.0));
  // Nested (the search again in each fold, on its 3 training files, and once for the final fit):
  // 5 searches, the same model.
  options.nested_joint_constants = true;
  const wf::ModelChoice nested = wf::choose_family(
      nullptr, {files::ModelKind::push_load_observer, files::ModelKind::stall_hold}, {}, {}, logs,
      inputs, outputs, options);
  CHECK(nested.constant_searches == 5);
  CHECK(nested.family == "stall_hold");
  CHECK(files::joint_model_parameters<Params>(nested.model).gain == a.gain);
  CHECK(nested.joint_summary == searched.summary);
}

TEST_CASE("joint models: an observer with the current command third, and hostile input lists") {
  // A grasper at 1 kHz sweeping +-0.5 rad at 0.5 Hz against a load that steps per run; the
  // amplifier makes the current follow the command, i = -2.06 u, measured 0.01 A high.
  auto log_of = [](double load, const std::string& name, bool constant_command) {
    const int n = 6000;
    Eigen::MatrixXd u(n, 3);
    Eigen::MatrixXd y(n, 1);
    for (int k = 0; k < n; ++k) {
      const double w = 2 * 3.141592653589793 * 0.5;
      const double v = 0.5 * w * std::cos(w * 1e-3 * k);
      const double current = v > 0 ? 1.45 * load + 0.07 : -0.03;
      u.row(k) << current + 0.01, v, constant_command ? 0.0 : current / -2.06;
      y(k, 0) = load;
    }
    wf::PreparedLog log;
    log.source = name;
    log.sample_time = 0.001;
    log.preparation = wf::Preparation::score;
    log.segments.push_back({u, y});
    log.start_time.push_back(0.0);
    return log;
  };
  const std::vector<files::SignalInfo> three{
      {"current", "A"}, {"motor_velocity", "rad/s"}, {"current_command", "1"}};
  const std::vector<files::SignalInfo> load{{"grip_torque", "N m"}};
  const std::vector<wf::PreparedLog> logs{log_of(0.04, "a", false), log_of(0.06, "b", false)};
  const wf::JointModelFit fit =
      wf::fit_joint_model(files::ModelKind::push_load_observer, logs, three, load, 0.5);
  CHECK(fit.model.kind() == files::ModelKind::push_load_observer);
  CHECK(fit.model.inputs.size() == 3);
  REQUIRE(fit.model.current_reference.has_value());
  CHECK(fit.model.current_reference->command_gain == doctest::Approx(-2.06).epsilon(0.01));
  CHECK(fit.model.current_reference->reference_offset == doctest::Approx(0.01).epsilon(0.01));
  CHECK(fit.summary.find("current referred to the command") != std::string::npos);
  // Replayed through the file: the same as the estimation types composed by hand.
  const Eigen::MatrixXd& u = logs[1].segments[0].u;
  const Eigen::VectorXd y = wf::simulate_joint_model(fit.model, u);
  CHECK(by_hand(
            fit.model,
            est::PushLoadObserver<double>(
                files::joint_model_parameters<est::PushLoadObserverParameters<double>>(fit.model)),
            u, y) == 0.0);
  CHECK(message_of([&] { (void)wf::simulate_joint_model(fit.model, u.leftCols(2)); }) ==
        "simulate_joint_model: 2 input columns, the model takes 3 (current, velocity, current "
        "command)");
  // A command that never varies: no reference can be fitted, said so.
  const std::vector<wf::PreparedLog> flat{log_of(0.04, "a", true), log_of(0.06, "b", true)};
  CHECK(message_of([&] {
          (void)wf::fit_joint_model(files::ModelKind::push_load_observer, flat, three, load, 0.5);
        }).find("current_command, or it does not vary") != std::string::npos);
  // The roles are positional: the command in the velocity's place is refused, naming the order.
  const std::vector<files::SignalInfo> swapped{three[0], three[2], three[1]};
  CHECK(message_of([&] {
          (void)wf::fit_joint_model(files::ModelKind::push_load_observer, logs, swapped, load, 0.5);
        }) ==
        "fit_joint_model: push_load_observer takes (current, velocity, current command) in that "
        "order; got (current, current_command, motor_velocity)");
  // Logs with other columns than the inputs named.
  CHECK(message_of([&] {
          (void)wf::fit_joint_model(files::ModelKind::push_load_observer, logs,
                                    {three[0], three[1]}, load, 0.5);
        }) ==
        "fit_joint_model: a: a segment of 3 input and 1 output columns, for 2 inputs and 1 "
        "output");
  // A file with a third input but no reference is refused.
  const auto& plain =
      files::joint_model_parameters<est::PushLoadObserverParameters<double>>(fit.model);
  CHECK(message_of([&] {
          (void)files::make_joint_model_file(plain, three, load);
        }).find("needs 2 inputs (current, velocity) and 1 output, got 3") != std::string::npos);
}

TEST_CASE("joint models: the bidirectional observer through the workflow, with the command") {
  // A grasper at 1 kHz sweeping +-0.5 rad at 0.5 Hz against one load per run: forward the current
  // is 1.4 mA per mN m + 70 mA, backward 0.7 mA per mN m - 90 mA; the amplifier makes it follow
  // the command, i = -2.06 u, measured 0.01 A high.
  auto log_of = [](double load, const std::string& name) {
    const int n = 8000;
    Eigen::MatrixXd u(n, 3);
    Eigen::MatrixXd y(n, 1);
    for (int k = 0; k < n; ++k) {
      const double w = 2 * 3.141592653589793 * 0.5;
      const double v = 0.5 * w * std::cos(w * 1e-3 * k);
      const double current = v > 0 ? 1.4e-3 * load + 0.07 : 0.7e-3 * load - 0.09;
      u.row(k) << current + 0.01, v, current / -2.06;
      y(k, 0) = load + (v > 0 ? 3.0 : -3.0);
    }
    wf::PreparedLog log;
    log.source = name;
    log.sample_time = 0.001;
    log.preparation = wf::Preparation::score;
    log.segments.push_back({u, y});
    log.start_time.push_back(0.0);
    return log;
  };
  const std::vector<files::SignalInfo> three{
      {"current", "A"}, {"motor_velocity", "rad/s"}, {"current_command", "1"}};
  const std::vector<files::SignalInfo> load{{"grip_torque", "mN m"}};
  const std::vector<wf::PreparedLog> logs{log_of(20.0, "a"), log_of(50.0, "b"), log_of(80.0, "c")};
  const wf::JointModelFit fit =
      wf::fit_joint_model(files::ModelKind::bidirectional_load_observer, logs, three, load, 0.5);
  CHECK(fit.model.kind() == files::ModelKind::bidirectional_load_observer);
  CHECK(fit.model.inputs.size() == 3);
  REQUIRE(fit.model.current_reference.has_value());
  CHECK(fit.model.current_reference->command_gain == doctest::Approx(-2.06).epsilon(0.01));
  CHECK(fit.summary.starts_with("bidirectional_load_observer: forward "));
  CHECK(fit.training_fit.size() == 3);
  // Replayed through the file: the same as the estimation types composed by hand.
  const Eigen::MatrixXd& u = logs[1].segments[0].u;
  const Eigen::VectorXd y = wf::simulate_joint_model(fit.model, u);
  CHECK(by_hand(fit.model,
                est::BidirectionalLoadObserver<double>(
                    files::joint_model_parameters<est::BidirectionalLoadObserverParameters<double>>(
                        fit.model)),
                u, y) == 0.0);
  // The truth is the level +-3 mN m by direction: after the first cycle the estimate follows it.
  const auto& truth = logs[1].segments[0].y;
  CHECK(std::sqrt((y.tail(4000) - truth.col(0).tail(4000)).squaredNorm() / 4000.0) < 1.0);
  // With the constants it chose given back: the same observer, no search; refitted on two of the
  // files with them, the front end and the noise rule held.
  CHECK(fit.constant_searches == 1);
  REQUIRE(fit.constants.bidirectional.has_value());
  CHECK(fit.constants.files == 3);
  const wf::JointModelFit again = wf::fit_joint_model(files::ModelKind::bidirectional_load_observer,
                                                      logs, three, load, 0.5, &fit.constants);
  CHECK(again.constant_searches == 0);
  CHECK(again.summary == fit.summary);
  using Observer = est::BidirectionalLoadObserverParameters<double>;
  const auto& p = files::joint_model_parameters<Observer>(fit.model);
  CHECK(files::joint_model_parameters<Observer>(again.model).forward_gain == p.forward_gain);
  CHECK(files::joint_model_parameters<Observer>(again.model).forward_variance ==
        p.forward_variance);
  const wf::JointModelFit two =
      wf::fit_joint_model(files::ModelKind::bidirectional_load_observer, {logs[0], logs[2]}, three,
                          load, 0.5, &fit.constants);
  const auto& q = files::joint_model_parameters<Observer>(two.model);
  CHECK(q.current_cutoff == p.current_cutoff);
  CHECK(q.velocity_cutoff == p.velocity_cutoff);
  CHECK(q.direction_scale == p.direction_scale);
  CHECK(q.velocity_threshold == p.velocity_threshold);
  CHECK(two.summary.find("chosen on 3 training files, held in this refit on 2") !=
        std::string::npos);
  CHECK(message_of([&] {
          (void)wf::fit_joint_model(files::ModelKind::bidirectional_load_observer, logs,
                                    {three[0], three[2], three[1]}, load, 0.5);
        }) ==
        "fit_joint_model: bidirectional_load_observer takes (current, velocity, current command) "
        "in that order; got (current, current_command, motor_velocity)");
  CHECK(wf::joint_model_kind("bidirectional_load_observer") ==
        files::ModelKind::bidirectional_load_observer);
}

TEST_CASE("joint models: the formats' defaults offer them, --method names them") {
  const auto aau = wf::format_defaults(files::LogFormat::endowrist_2016);
  CHECK(aau.method == "moesp,stall_hold");
  CHECK(aau.joint_sample_time == 0.01);
  const auto umn = wf::format_defaults(files::LogFormat::umn_mis_2018);
  CHECK(umn.method == "moesp,static,push_load_observer,bidirectional_load_observer");
  CHECK(umn.joint_sample_time == 0.001);
  CHECK(wf::joint_model_kind("stall_hold") == files::ModelKind::stall_hold);
  CHECK(wf::joint_model_kind("push_load_observer") == files::ModelKind::push_load_observer);
  CHECK_FALSE(wf::joint_model_kind("moesp").has_value());
}

}  // namespace workflow_joint_models_test
