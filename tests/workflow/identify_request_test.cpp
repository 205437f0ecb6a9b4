#include "endohaptics/workflow/identify_request.hpp"

#include <doctest/doctest.h>
#include <algorithm>

#include <cmath>
#include <filesystem>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "endohaptics/workflow/replay_request.hpp"
#include "shared_data.hpp"
#include "test_support.hpp"

namespace workflow_identify_request_test {

using endohaptics::test::message_of;
using endohaptics::test::TempDir;
using endohaptics::test::write_text;

namespace {

namespace wf = endohaptics::workflow;
namespace files = endohaptics::files;
using wf::Method;

// y(k+1) = 0.8 y(k) + 0.2 u(k) + 0.05 u(k-1), u random levels held 1..10 samples of 10 ms:
// a first-order lag a static map cannot follow. "time,u,y" CSV, full precision.
std::string lag_csv(int rows, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> level(-1.0, 1.0);
  std::uniform_int_distribution<int> hold(1, 10);
  std::ostringstream out;
  out.precision(17);
  out << "time,u,y\n";
  double y = 0.0, u = 0.0, u_prev = 0.0;
  int left = 0;
  for (int k = 0; k < rows; ++k) {
    if (left-- == 0) {
      u = level(rng);
      left = hold(rng);
    }
    out << 0.01 * k << ',' << u << ',' << y << '\n';
    y = 0.8 * y + 0.2 * u + 0.05 * u_prev;
    u_prev = u;
  }
  return out.str();
}

wf::IdentifyRequest lag_request(const TempDir& dir) {
  write_text(dir.path() / "a.csv", lag_csv(600, 1));
  write_text(dir.path() / "b.csv", lag_csv(600, 2));
  wf::IdentifyRequest q;
  q.logs = {(dir.path() / "a.csv").string(), (dir.path() / "b.csv").string()};
  q.format = "csv";
  q.inputs = {"u"};
  q.outputs = {"y"};
  q.method = "moesp,static";
  q.max_order = 3;
  return q;
}

// Replay's mean fit of the model file `model_path` on the request's logs (csv).
double replayed_fit(const std::filesystem::path& model_path, const wf::IdentifyRequest& q) {
  wf::ReplayRequest replay;
  replay.model = model_path.string();
  replay.logs = q.logs;
  replay.format = "csv";
  return wf::run_replay(replay, {}).mean_fit;
}

}  // namespace

TEST_CASE("identify methods: one name table, --method lists, the subspace and joint kinds") {
  for (const wf::MethodName& m : wf::method_names) {
    CHECK(wf::to_string(m.method) == m.name);
    CHECK(wf::parse_methods(m.name) == std::vector<Method>{m.method});
  }
  CHECK(wf::parse_methods("best,static,stall_hold") ==
        std::vector<Method>{Method::n4sid, Method::moesp, Method::cva, Method::static_gain,
                            Method::stall_hold});
  CHECK(wf::weighting_of(Method::cva) == endohaptics::identification::Weighting::cva);
  CHECK_FALSE(wf::weighting_of(Method::static_gain).has_value());
  CHECK(wf::method_of(endohaptics::identification::Weighting::n4sid) == Method::n4sid);
  CHECK(wf::joint_kind_of(Method::push_load_observer) == files::ModelKind::push_load_observer);
  CHECK_FALSE(wf::joint_kind_of(Method::moesp).has_value());
  const std::string bad = message_of([] { (void)wf::parse_methods("moesp,mosep"); });
  CHECK(bad.find("--method moesp,mosep: unknown method \"mosep\"") == 0);
  CHECK(bad.find("bidirectional_load_observer") != std::string::npos);
  CHECK(message_of([] { (void)wf::parse_methods("moesp,"); }).find("unknown method \"\"") !=
        std::string::npos);
}

TEST_CASE("run_identify: a request on two logs of a first-order lag -> a report and its model") {
  const TempDir dir;
  const wf::IdentifyRequest q = lag_request(dir);
  std::vector<std::string> events;
  const wf::IdentifyReport r = wf::run_identify(
      q,
      {.text = [&](const std::string& s) { events.push_back("text " + s.substr(0, 4)); },
       .prepared =
           [&](const wf::IdentifyProgress& p) {
             events.push_back("prepared " + std::to_string(p.fit_logs.size()));
           },
       .subspace_fitted =
           [&](const wf::IdentifyProgress& p) {
             events.push_back("subspace " + std::to_string(p.subspace_result().candidates.size()));
           },
       .progress = [&](std::string_view) { events.push_back("progress"); }});
  // Progress in the order it is made: each log's summary, the grids, a progress line per model
  // fitted (each order of the search: one is enough here), the subspace family.
  REQUIRE(events.size() >= 5);
  CHECK(std::vector<std::string>(events.begin(), events.begin() + 3) ==
        std::vector<std::string>{"text " + q.logs[0].substr(0, 4), "text " + q.logs[1].substr(0, 4),
                                 "prepared 2"});
  CHECK(std::all_of(events.begin() + 3, events.end() - 1,
                    [](const std::string& e) { return e == "progress"; }));
  CHECK(events.back() == "subspace 2");
  // Resolved: the csv format has no defaults but the order (auto) and the median step as Ts.
  CHECK(r.selection.format == files::LogFormat::csv);
  CHECK(r.sample_time == doctest::Approx(0.01));
  CHECK(r.options.order == 0);
  CHECK(r.options.candidates == std::vector{endohaptics::identification::Weighting::moesp});
  CHECK(r.options.static_gain);
  CHECK(r.joint_kinds.empty());
  // The candidates carry their method as a type; the lag beats the static map.
  const wf::WorkflowResult& s = r.subspace_result();
  REQUIRE(s.candidates.size() == 2);
  CHECK(s.candidates[0].kind == Method::moesp);
  CHECK(s.candidates[1].kind == Method::static_gain);
  CHECK(s.chosen().kind == Method::moesp);
  CHECK(s.candidates[0].mean_fit > s.candidates[1].mean_fit + 10.0);
  CHECK(r.choice.family == "moesp");
  CHECK_FALSE(r.joint_chosen());
  CHECK(r.choice.model.state_space.state_size() >= 1);
  REQUIRE(r.choice.files.size() == 2);
  REQUIRE(r.oracle.size() == 2);
  CHECK(r.mean_fit > 95.0);
  CHECK(r.mean_fit ==
        doctest::Approx(0.5 * (r.choice.files[0].mean_fit() + r.choice.files[1].mean_fit())));
  CHECK(r.mean_rmse < 0.05);
  CHECK_NOTHROW(wf::check_scores(r));
  const std::string& notes = r.model.provenance.notes;
  CHECK(notes.find("preprocessing: lowpass_hz=0") == 0);
  CHECK(notes.find("x0 steady, warm-up 0.5 s") != std::string::npos);
  CHECK(notes.find("chosen: moesp\ntool: endohaptics-identify") != std::string::npos);

  // The model it wrote, replayed on the same logs: the same causal scores (run_replay takes the
  // preprocessing the model file records).
  const auto model_path = dir.path() / "model.json";
  files::save_model(model_path, r.model);
  wf::ReplayRequest replay;
  replay.model = model_path.string();
  replay.logs = q.logs;
  replay.format = "csv";
  int scored = 0;
  const wf::ReplayReport rr = wf::run_replay(
      replay, {.scored = [&](const wf::ReplayReport&, const wf::FileComparison&) { ++scored; }});
  CHECK(scored == 2);
  CHECK(rr.causal());
  CHECK(rr.recorded);
  CHECK(rr.selection.inputs == std::vector<std::string>{"u"});
  CHECK(rr.mean_fit == doctest::Approx(r.mean_fit).epsilon(1e-9));
  CHECK(rr.mean_rmse == doctest::Approx(r.mean_rmse).epsilon(1e-9));
}

TEST_CASE("free-motion threshold: the 99th percentile where the truth is 0, kept by replay") {
  // Chosen from the training comparisons alone: |estimate| where the true output is exactly 0,
  // after each segment's warm-up.
  wf::FileComparison c;
  c.warmup_samples = 10;
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(1010, 1);
  Eigen::MatrixXd y_hat(1010, 1);
  for (Eigen::Index i = 0; i < 1010; ++i) y_hat(i, 0) = (i % 2 ? -1.0 : 1.0) * 1e-3 * double(i);
  y_hat.topRows(10).setConstant(50.0);  // the warm-up: not counted
  y.bottomRows(500).setOnes();          // touching: not counted either
  c.y = {y};
  c.y_hat = {y_hat};
  // 500 free samples, |y_hat| = 0.010 .. 0.509: the 99th percentile is the 495th of them.
  CHECK(wf::free_motion_threshold_of({c}) == doctest::Approx(1e-3 * (10 + 495)));
  c.y = {Eigen::MatrixXd::Ones(1010, 1)};
  const std::string none = message_of([&] { (void)wf::free_motion_threshold_of({c}); });
  CHECK(none.find("0 scored samples whose true output is exactly 0 (of 1000") != std::string::npos);

  // A value: the model carries it, identify's scores and replay's agree (both apply it).
  const TempDir dir;
  wf::IdentifyRequest q = lag_request(dir);
  q.free_threshold = "0.05";
  const wf::IdentifyReport r = wf::run_identify(q, {});
  CHECK(r.model.free_motion_threshold == 0.05);
  const auto model_path = dir.path() / "model.json";
  files::save_model(model_path, r.model);
  CHECK(files::load_model(model_path).free_motion_threshold == 0.05);
  CHECK(replayed_fit(model_path, q) == doctest::Approx(r.mean_fit).epsilon(1e-9));
  q.free_threshold = "none";
  const double without = wf::run_identify(q, {}).mean_fit;
  CHECK(without != r.mean_fit);  // the threshold changed the estimate and the score says so
  // auto on logs whose output is never exactly 0: refused, saying why.
  q.free_threshold = "auto";
  CHECK(message_of([&] { (void)wf::run_identify(q, {}); }).find("--free-threshold auto") !=
        std::string::npos);
}

TEST_CASE("run_identify: a current play is fitted on, written, and replayed to the same score") {
  const TempDir dir;
  wf::IdentifyRequest q = lag_request(dir);
  q.current_play = 0.05;
  const wf::IdentifyReport r = wf::run_identify(q, {});
  CHECK(r.model.current_play == 0.05);
  const auto model_path = dir.path() / "model.json";
  files::save_model(model_path, r.model);
  CHECK(files::load_model(model_path).current_play == 0.05);
  // Identify scored the model on the played input; replay plays the raw input itself.
  CHECK(replayed_fit(model_path, q) == doctest::Approx(r.mean_fit).epsilon(1e-9));
  q.current_play = 0.0;
  const wf::IdentifyReport without = wf::run_identify(q, {});
  CHECK(without.model.current_play == 0.0);
  CHECK(without.mean_fit != r.mean_fit);  // the play changed the input and the score says so
  q.current_play = -0.1;
  CHECK(message_of([&] { (void)wf::run_identify(q, {}); }).starts_with("--current-play must be"));
}

TEST_CASE("run_identify and run_replay: bad requests name the option") {
  const TempDir dir;
  wf::IdentifyRequest q = lag_request(dir);
  q.x0 = "oracle";
  CHECK(message_of([&] { (void)wf::run_identify(q); }).starts_with("--x0 must be steady or zero"));
  q = lag_request(dir);
  q.method = "stall_hold";  // a joint model needs (current, velocity)
  CHECK(message_of([&] {
          (void)wf::run_identify(q);
        }).starts_with("--method stall_hold: joint models need 1 output"));
  q = lag_request(dir);
  q.inputs.clear();
  CHECK(message_of([&] { (void)wf::run_identify(q); }) ==
        "--format csv needs --input and --output column names");
  q = lag_request(dir);
  q.order = "0";
  CHECK(message_of([&] { (void)wf::run_identify(q); }).find("--order") != std::string::npos);

  wf::ReplayRequest replay;
  replay.model = "preset:yaw2016";
  replay.logs = q.logs;
  replay.format = "csv";
  replay.inputs = {"u"};  // the preset takes current and velocity
  CHECK(message_of([&] {
          (void)wf::run_replay(replay);
        }).starts_with("preset:yaw2016 has 2 input(s) (current, velocity) and 1 output(s)"));
  replay.inputs = {"u", "u"};
  replay.outputs = {"y"};
  replay.offset = "mean";  // whole-file offsets are for the oracle score only
  CHECK(message_of([&] { (void)wf::run_replay(replay); }).starts_with("--offset, --input-offset"));
}

TEST_CASE(
    "run_identify: a current play of the clamp's static friction on the 2016 clamp hits, "
    "leave one file out" *
    doctest::skip(!endohaptics::test::has_shared_data("endowrist-2016/clamp-hits"))) {
  // The Hammerstein-Wiener family (moesp, the format's other defaults) trained on five files and
  // replayed on the sixth, with and without a play of table 5.2's clamp static friction
  // K_s = 0.20 A on the current: a width fixed by the instrument, not by these scores.
  std::vector<std::string> paths;
  for (const auto& e : std::filesystem::directory_iterator(
           endohaptics::test::shared_data("endowrist-2016/clamp-hits"))) {
    paths.push_back(e.path().string());
  }
  std::sort(paths.begin(), paths.end());
  REQUIRE(paths.size() == 6);
  const TempDir dir;
  const auto held_out_mean = [&](double play) {
    double sum = 0.0;
    for (std::size_t k = 0; k < paths.size(); ++k) {
      wf::IdentifyRequest q;
      for (std::size_t j = 0; j < paths.size(); ++j) {
        if (j != k) q.logs.push_back(paths[j]);
      }
      q.inputs = {"current", "velocity"};
      q.outputs = {"force"};
      q.method = "moesp";
      q.current_play = play;
      const wf::IdentifyReport r = wf::run_identify(q, {});
      const auto model_path = dir.path() / "model.json";
      files::save_model(model_path, r.model);
      wf::ReplayRequest replay;
      replay.model = model_path.string();
      replay.logs = {paths[k]};
      const double fit = wf::run_replay(replay, {}).mean_fit;
      MESSAGE("play " << play << " A, held out " << paths[k] << ": causal fit " << fit << " %");
      sum += fit;
    }
    return sum / static_cast<double>(paths.size());
  };
  const double with_play = held_out_mean(0.2);
  const double without = held_out_mean(0.0);
  // Measured (play_nested.sh, docs/identification_results.md): 63.8 % with the play, 57.4 %
  // without; the clamp-hits target is 60 %.
  CHECK(with_play > 60.0);
  CHECK(with_play > without + 4.0);
}

TEST_CASE("run_identify: a current play is the subspace family's input only" *
          doctest::skip(!endohaptics::test::has_shared_data("endowrist-2016/clamp-hits"))) {
  wf::IdentifyRequest q;
  for (const auto& e : std::filesystem::directory_iterator(
           endohaptics::test::shared_data("endowrist-2016/clamp-hits"))) {
    q.logs.push_back(e.path().string());
  }
  std::sort(q.logs.begin(), q.logs.end());
  q.inputs = {"current", "velocity"};
  q.outputs = {"force"};
  q.current_play = 0.2;
  // A joint model alone: nothing would take the play, so it is refused, saying why.
  q.method = "stall_hold";
  CHECK(message_of([&] {
          (void)wf::run_identify(q, {});
        }).starts_with("--current-play: the method list has no subspace family"));
  // Beside a subspace family: the play is on its input in the family choice; a joint model
  // chosen is written without it, a subspace model with it.
  for (const char* method : {"moesp,stall_hold", "moesp"}) {
    q.method = method;
    const wf::IdentifyReport r = wf::run_identify(q, {});
    CHECK(r.model.current_play == (r.joint_chosen() ? 0.0 : 0.2));
  }
  q.method = "moesp";
  CHECK_FALSE(wf::run_identify(q, {}).joint_chosen());
}

TEST_CASE("run_identify: the nested joint constants, with the clamp's play, on clamp-hits 02-06" *
          doctest::skip(!endohaptics::test::has_shared_data("endowrist-2016/clamp-hits"))) {
  // Trained on files 02-06 (the fold that holds out 01), the play at table 5.2's K_s = 0.20 A.
  // The stall-hold's constants searched once on all five files score it 62.01 % in the family
  // choice against the played moesp's 61.82 %; searched again inside each fold (nothing of the
  // fold's held-out file seen) it scores 55.96 % and the played moesp is chosen.
  wf::IdentifyRequest q;
  for (int j = 2; j <= 6; ++j) {
    q.logs.push_back((endohaptics::test::shared_data("endowrist-2016/clamp-hits") /
                      ("clamp-hits-0" + std::to_string(j) + ".csv"))
                         .string());
  }
  q.inputs = {"current", "velocity"};
  q.outputs = {"force"};
  q.current_play = 0.2;
  const wf::IdentifyReport held = wf::run_identify(q, {});
  q.nested_joint_constants = true;
  const wf::IdentifyReport nested = wf::run_identify(q, {});
  CHECK(held.joint_chosen());
  CHECK(held.model.current_play == 0.0);
  CHECK_FALSE(nested.joint_chosen());
  CHECK(nested.model.current_play == 0.2);
  REQUIRE(nested.choice.families.size() == 2);
  CHECK(nested.choice.families[1].family == "stall_hold");
  CHECK(nested.choice.families[1].mean_fit < held.choice.families[1].mean_fit - 3.0);
}

}  // namespace workflow_identify_request_test
