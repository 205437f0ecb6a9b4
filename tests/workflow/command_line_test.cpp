#include "endohaptics/workflow/command_line.hpp"

#include <doctest/doctest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "endohaptics/files/model_file.hpp"
#include "endohaptics/workflow/workflow.hpp"
#include "test_support.hpp"

// Strict command lines and no false success (docs/safety.md). Every case below failed
// before the fix (the lax parse, the silent truncation, the unchecked write, the -Inf score).
namespace workflow_command_line_test {

using endohaptics::test::message_of;
using endohaptics::test::TempFile;

namespace {

namespace wf = endohaptics::workflow;
namespace files = endohaptics::files;
namespace model = endohaptics::model;
using Eigen::MatrixXd;
using Eigen::VectorXd;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// "time,u,y" rows at 0.01 s: u random-ish, y = 2 u.
std::string small_csv(int rows) {
  std::string out = "time,u,y\n";
  for (int k = 0; k < rows; ++k) {
    const double u = ((k * 7919) % 13) / 13.0 - 0.5;
    out += std::to_string(0.01 * k) + "," + std::to_string(u) + "," + std::to_string(2 * u) + "\n";
  }
  return out;
}

wf::LogSelection csv_selection(std::vector<std::string> inputs, std::vector<std::string> outputs) {
  wf::LogSelection sel;
  sel.format = files::LogFormat::csv;
  sel.inputs = std::move(inputs);
  sel.outputs = std::move(outputs);
  return sel;
}

}  // namespace

TEST_CASE("parse_number: whole decimal numbers in range, or an error naming the option") {
  CHECK(wf::parse_number("100", "--rate", 1.0, 1e5) == 100.0);
  CHECK(wf::parse_number("2.5e3", "--rate", 1.0, 1e5) == 2500.0);
  CHECK(wf::parse_number("-1", "--cpu", -1, 1023) == -1);
  // What std::stod and CLI11 accepted: a number followed by text, hexadecimal, NaN, infinity.
  for (const char* bad : {"100abc", "0x10", "nan", "inf", "-inf", "1e999", " 5", "+5", "", "5 "}) {
    CAPTURE(bad);
    const std::string m = message_of([&] { (void)wf::parse_number(bad, "--rate", 1.0, 1e5); });
    CHECK(m.starts_with("--rate: "));
    CHECK(contains(m, "[1, 100000]"));
  }
  CHECK(message_of([] { (void)wf::parse_number("0", "--rate", 1.0, 1e5); }) ==
        "--rate: '0' is outside [1, 100000]");
  CHECK(contains(message_of([] { (void)wf::parse_number("1.5", "--order", 1, 100); }),
                 "is not an integer"));
  // Out of the type's range (what an int cast would have wrapped) is an error, not a wrap.
  CHECK(contains(message_of([] { (void)wf::parse_number("4294967298", "--order", 1, 100); }),
                 "out of range"));
  CHECK(contains(
      message_of([] { (void)wf::parse_number<std::uint16_t>("-1", "--sbrio port", 1, 65535); }),
      "--sbrio port: '-1' is not an integer"));
}

TEST_CASE("NumberCheck: CLI11's validator shape, keywords, leading zeros, --help text") {
  const wf::NumberCheck<double> rate(1.0, 1e5, {"max"});
  std::string text = "max";
  CHECK(rate(text).empty());
  text = "250";
  CHECK(rate(text).empty());
  CHECK(text == "250");  // left as given
  text = "100abc";
  CHECK(contains(rate(text), "(or max)"));
  CHECK(rate.description() == "FLOAT in [1, 100000] or max");
  const wf::NumberCheck<int> priority(0, 99);
  text = "010";  // octal 8 for CLI11 and strtol
  CHECK(contains(priority(text), "leading zero"));
  text = "0";
  CHECK(priority(text).empty());
  text = "-0";
  CHECK(priority(text).empty());
  CHECK(priority.description() == "INT in [0, 99]");
}

TEST_CASE("close_written / require_written: a full disk is an error, not a success") {
  if (!std::filesystem::exists("/dev/full")) return;  // Linux only
  std::FILE* full = std::fopen("/dev/full", "w");
  REQUIRE(full != nullptr);
  std::fputs("time,x\n0,1\n", full);  // buffered: fputs itself succeeds
  const std::string m = message_of([&] { wf::close_written(full, "the log '/dev/full'"); });
  CHECK(m.starts_with("writing the log '/dev/full' failed"));
  CHECK(contains(m, "No space left on device"));

  std::FILE* again = std::fopen("/dev/full", "w");
  REQUIRE(again != nullptr);
  std::fputs("x\n", again);
  CHECK(contains(message_of([&] { wf::require_written(again, "standard output"); }),
                 "writing standard output failed"));
  std::fclose(again);

  const TempFile ok("ok.txt");
  std::FILE* file = std::fopen(ok.path.c_str(), "w");
  REQUIRE(file != nullptr);
  std::fputs("fine\n", file);
  CHECK(message_of([&] { wf::close_written(file, "ok.txt"); }) == "(no exception)");
}

TEST_CASE("Preprocessing outside its ranges is refused, also from a model file's notes") {
  wf::Preprocessing p;
  CHECK(message_of([&] { wf::validate(p); }) == "(no exception)");
  p.min_segment = -1;
  CHECK(contains(message_of([&] { wf::validate(p); }), "min_segment is -1"));
  p = {};
  p.cutoff = std::numeric_limits<double>::quiet_NaN();
  CHECK(contains(message_of([&] { wf::validate(p); }), "lowpass_hz"));
  p = {};
  p.filter_order = 0;
  CHECK(contains(message_of([&] { wf::validate(p); }), "filter_order is 0"));
  // The text form: a float where an integer belongs used to be cast (1e300 to Index: UB).
  CHECK(contains(message_of([] { (void)wf::parse_preprocessing("min_segment=1e300"); }),
                 "min_segment"));
  CHECK(contains(message_of([] { (void)wf::parse_preprocessing("filter_order=4.5"); }),
                 "filter_order"));
  CHECK(
      contains(message_of([] { (void)wf::parse_preprocessing("min_segment=-1"); }), "min_segment"));
}

TEST_CASE("prepare_log: one column as input and output, and a tiny ts, are refused up front") {
  const TempFile file("log.csv", small_csv(200));
  const std::string path = file.path.string();
  CHECK(contains(
      message_of([&] { (void)wf::prepare_log(path, csv_selection({"u"}, {"u"}), 0.01, {}); }),
      "signal 'u' is named twice (as input and as output)"));
  CHECK(contains(message_of([&] {
                   (void)wf::prepare_log(path, csv_selection({"u", "u"}, {"y"}), 0.01, {});
                 }),
                 "named twice"));
  // 1.99 s at 1e-12 s would be 2e12 samples (16 TB per signal): refused before allocating.
  const std::string m =
      message_of([&] { (void)wf::prepare_log(path, csv_selection({"u"}, {"y"}), 1e-12, {}); });
  CHECK(contains(m, "more than the limit of 10000000 per log"));
  wf::Preprocessing bad;
  bad.min_segment = -1;
  CHECK(contains(
      message_of([&] { (void)wf::prepare_log(path, csv_selection({"u"}, {"y"}), 0.01, bad); }),
      "min_segment is -1"));
  CHECK(wf::prepare_log(path, csv_selection({"u"}, {"y"}), 0.01, {}).samples() == 200);
}

TEST_CASE("model file: states beyond an int or above the limit are refused, not truncated") {
  const model::DynamicStateSpace<> g(MatrixXd{{0.5, 0.1}, {0.0, 0.3}}, MatrixXd{{1.0}, {0.5}},
                                     MatrixXd{{1.0, 0.0}}, MatrixXd{{0.0}}, 0.01);
  const files::ModelFile m{.state_space = g, .inputs = {{"u", ""}}, .outputs = {{"y", ""}}};
  nlohmann::json j = files::to_json(m);
  REQUIRE(files::model_from_json(j).state_space.state_size() == 2);
  j["states"] = 4294967298ULL;  // 2^32 + 2: an int read wrapped it to 2 and accepted the file
  CHECK(contains(message_of([&] { (void)files::model_from_json(j, "m.json"); }),
                 "field \"states\" is 4294967298, outside [1, 100]"));
  j["states"] = 101;
  CHECK(
      contains(message_of([&] { (void)files::model_from_json(j, "m.json"); }), "outside [1, 100]"));
  j["states"] = 0;
  CHECK(
      contains(message_of([&] { (void)files::model_from_json(j, "m.json"); }), "outside [1, 100]"));
  j["states"] = 2;
  j["version"] = -4294967295LL;
  CHECK(contains(message_of([&] { (void)files::model_from_json(j, "m.json"); }),
                 "field \"version\" is -4294967295"));
  if (std::filesystem::exists("/dev/full")) {
    CHECK(contains(message_of([&] { files::save_model("/dev/full", m); }), "failed"));
  }
}

TEST_CASE("require_finite_scores: a diverging model or an undefined score is an error") {
  // y = 2 u measured; the model doubles its state every step: the simulation overflows.
  const TempFile file("log.csv", small_csv(3000));
  const wf::PreparedLog log =
      wf::prepare_log(file.path.string(), csv_selection({"u"}, {"y"}), 0.01, {});
  const model::DynamicStateSpace<> unstable(MatrixXd{{2.0}}, MatrixXd{{1.0}}, MatrixXd{{1.0}},
                                            MatrixXd{{0.0}}, 0.01);
  const files::ModelFile m{.state_space = unstable, .inputs = {{"u", ""}}, .outputs = {{"y", ""}}};
  const wf::FileComparison c = wf::compare_log(m, log, {wf::InitialStateMode::zero});
  CHECK(c.fit[0] == -std::numeric_limits<double>::infinity());  // what replay printed, exit 0
  CHECK(contains(message_of([&] { wf::require_finite_scores(c, {"y"}); }),
                 "the simulated output is not finite"));
  // A model that predicts a constant: correlation undefined.
  const model::DynamicStateSpace<> nothing(MatrixXd{{0.5}}, MatrixXd{{0.0}}, MatrixXd{{1.0}},
                                           MatrixXd{{0.0}}, 0.01);
  const files::ModelFile zero{
      .state_space = nothing, .inputs = {{"u", ""}}, .outputs = {{"y", ""}}};
  const wf::FileComparison z = wf::compare_log(zero, log, {wf::InitialStateMode::zero});
  CHECK(contains(message_of([&] { wf::require_finite_scores(z, {"y"}); }),
                 "correlation of 'y' is undefined"));
  // A good model passes.
  const model::DynamicStateSpace<> gain(MatrixXd{{0.0}}, MatrixXd{{0.0}}, MatrixXd{{0.0}},
                                        MatrixXd{{2.0}}, 0.01);
  const files::ModelFile good{.state_space = gain, .inputs = {{"u", ""}}, .outputs = {{"y", ""}}};
  const wf::FileComparison g = wf::compare_log(good, log, {wf::InitialStateMode::zero});
  CHECK(message_of([&] { wf::require_finite_scores(g, {"y"}); }) == "(no exception)");
  CHECK(g.fit[0] > 99.99);  // the CSV holds 6 decimals
}

TEST_CASE("parse_endpoint: HOST:PORT, IPv6 in brackets, the port whole and in range") {
  const wf::Endpoint a = wf::parse_endpoint("169.254.4.42:61556", "--sbrio", false);
  CHECK(a.host == "169.254.4.42");
  CHECK(a.port == 61556);
  const wf::Endpoint b = wf::parse_endpoint("[::1]:0", "--listen", true);
  CHECK(b.host == "::1");
  CHECK(b.port == 0);
  CHECK(wf::parse_endpoint("fe80::1:5000", "--sbrio", false).host == "fe80::1");
  CHECK(message_of([] { (void)wf::parse_endpoint("localhost", "--sbrio", false); }) ==
        "--sbrio must be HOST:PORT, got 'localhost'");
  CHECK(message_of([] { (void)wf::parse_endpoint(":80", "--sbrio", false); }) ==
        "--sbrio must be HOST:PORT, got ':80'");
  CHECK(message_of([] { (void)wf::parse_endpoint("host:", "--sbrio", false); }) ==
        "--sbrio must be HOST:PORT, got 'host:'");
  // Port 0 (any free port) only where the option allows it; never beyond 65535 or partly a number.
  CHECK(message_of([] {
          (void)wf::parse_endpoint("host:0", "--sbrio", false);
        }).starts_with("--sbrio port"));
  CHECK(message_of([] {
          (void)wf::parse_endpoint("host:65536", "--listen", true);
        }).starts_with("--listen port"));
  CHECK(message_of([] {
          (void)wf::parse_endpoint("host:80x", "--listen", true);
        }).starts_with("--listen port"));
}

}  // namespace workflow_command_line_test
