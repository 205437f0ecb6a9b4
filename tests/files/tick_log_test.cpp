#include "endohaptics/files/tick_log.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include "test_support.hpp"

namespace files_tick_log_test {

using endohaptics::test::message_of;

namespace {

namespace files = endohaptics::files;
namespace tp = endohaptics::teleop;
using endohaptics::Error;

files::TickLog parse(const std::string& text, const files::TickLogOptions& options = {}) {
  std::istringstream in(text);
  return files::parse_tick_log(in, "ticks.csv", options);
}

std::string header() {
  std::string h;
  for (const auto name : tp::tick_log_columns) h += (h.empty() ? "" : ",") + std::string(name);
  return h;
}

}  // namespace

TEST_CASE("what TickRecorder writes is read back by column name") {
  const auto path = std::filesystem::temp_directory_path() / "endohaptics_tick_log_roundtrip.csv";
  {
    std::FILE* out = std::fopen(path.c_str(), "w");
    REQUIRE(out != nullptr);
    tp::TickRecorder recorder(16);
    tp::TickRecorder::write_header(out);
    for (int i = 0; i < 3; ++i) {
      tp::TickResult r;
      r.status = tp::TickStatus::degraded;
      r.link = tp::LinkState::recovering;
      r.enable_mask = 0x0F;
      r.measured.active_mask = 0x03;
      r.force_scale = 0.25 * i;
      r.setpoint << 0.1, 0.2, 0.3, 0.4;
      r.measured.position << 1.1, 1.2, 1.3, 1.4;
      r.measured.velocity << 2.1, 2.2, 2.3, 2.4;
      r.measured.current << 3.1, 3.2, 3.3, 3.4;
      r.motor_force << 4.1, 4.2, 4.3 + i, 4.4;
      r.stylus_force = Eigen::Vector3d(0.5, -1.25, 2.0);
      REQUIRE(recorder.push(tp::TickRecord::from(r, std::chrono::milliseconds(1000 + i))));
    }
    CHECK(recorder.drain(out) == 3);
    std::fclose(out);
  }
  const files::TickLog log = files::read_tick_log(path);
  std::filesystem::remove(path);
  REQUIRE(log.columns.size() == tp::tick_log_columns.size());
  for (std::size_t c = 0; c < log.columns.size(); ++c) {
    CHECK(log.columns[c] == tp::tick_log_columns[c]);
  }
  CHECK(log.rows() == 3);
  CHECK(log.dropped == 0);
  CHECK(log.column("time")[2] == doctest::Approx(1.002));
  CHECK(log.column("status")[0] == static_cast<int>(tp::TickStatus::degraded));
  CHECK(log.column("link")[0] == static_cast<int>(tp::LinkState::recovering));
  CHECK(log.column("enable_mask")[0] == 15);
  CHECK(log.column("active_mask")[0] == 3);
  CHECK(log.column("force_scale")[2] == 0.5);
  // Each vector in its columns, in motor order: the header and the rows agree.
  for (int m = 0; m < 4; ++m) {
    const std::string i = std::to_string(m);
    CHECK(log.column("setpoint" + i)[0] == doctest::Approx(0.1 * (m + 1)));
    CHECK(log.column("position" + i)[0] == doctest::Approx(1.1 + 0.1 * m));
    CHECK(log.column("velocity" + i)[0] == doctest::Approx(2.1 + 0.1 * m));
    CHECK(log.column("current" + i)[0] == doctest::Approx(3.1 + 0.1 * m));
  }
  CHECK(log.column("motor_force2")[1] == doctest::Approx(5.3));
  CHECK(log.column("stylus_fx")[0] == 0.5);
  CHECK(log.column("stylus_fy")[0] == -1.25);
  CHECK(log.column("stylus_fz")[0] == 2.0);
  CHECK(log.index("stylus_fz") == tp::tick_log_columns.size() - 1);
}

TEST_CASE("columns are found by name whatever their order, and a missing one is a clear error") {
  const files::TickLog log = parse("link,time,extra\n1,0.5,7\n3,0.6,8\n");
  CHECK(log.column("time") == std::vector<double>{0.5, 0.6});
  CHECK(log.column("link") == std::vector<double>{1, 3});
  CHECK(log.has("extra"));
  CHECK_FALSE(log.has("stylus_fx"));
  CHECK(message_of([&] { (void)log.column("stylus_fx"); }) ==
        "ticks.csv: no column 'stylus_fx' in the tick log (header: link,time,extra)");
}

TEST_CASE("malformed lines are dropped and counted, or refused with strict") {
  const std::string text =
      header() + "\n" +
      "1,0,1,0,15,15,0.0001,1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n"
      "\n"  // blank: skipped, not counted
      "1.001,0,1,0,15,15,0.0001,1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,"
      "0,0,x\n"
      "1.002,0,1,0,15,15,0.0001,1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,"
      "0,0,nan\r\n"
      "1.003,0,1,15\n";  // cut short: the bridge was killed mid-row
  const files::TickLog log = parse(text);
  CHECK(log.rows() == 2);
  CHECK(log.dropped == 2);
  REQUIRE(log.issues.size() == 2);
  CHECK(log.issues[0].line == 4);
  CHECK(log.issues[0].what == "column 'stylus_fz': not a number: 'x'");
  CHECK(log.issues[1].line == 6);
  CHECK(log.issues[1].what == "4 fields, the header has 35");
  CHECK(std::isnan(log.column("stylus_fz")[1]));  // what the recorder writes for NaN
  CHECK(log.report() ==
        "ticks.csv: 2 malformed lines dropped\n"
        "  line 4: column 'stylus_fz': not a number: 'x'\n"
        "  line 6: 4 fields, the header has 35\n");

  files::TickLogOptions strict;
  strict.strict = true;
  CHECK(message_of([&] { (void)parse(text, strict); }) ==
        "ticks.csv: line 4: column 'stylus_fz': not a number: 'x'");

  files::TickLogOptions few;
  few.max_issues = 1;
  const files::TickLog counted = parse(text, few);
  CHECK(counted.dropped == 2);
  CHECK(counted.issues.size() == 1);
  CHECK(counted.report().find("(1 more)") != std::string::npos);

  // A repeated or backward time is dropped too (unless asked not to check).
  const std::string times = "time,link\n1.0,1\n1.0,2\n0.5,3\n1.5,4\n";
  const files::TickLog timed = parse(times);
  CHECK(timed.column("time") == std::vector<double>{1.0, 1.5});
  CHECK(timed.column("link") == std::vector<double>{1, 4});
  CHECK(timed.report() ==
        "ticks.csv: 2 malformed lines dropped\n"
        "  line 3: time 1 is not after 1\n"
        "  line 4: time 0.5 is not after 1\n");
  files::TickLogOptions any_time;
  any_time.increasing_time = false;
  CHECK(parse(times, any_time).rows() == 4);

  // A long field is echoed cut to 60 characters.
  const files::TickLog long_field = parse("time\n" + std::string(1000, 'y') + "\n");
  REQUIRE(long_field.issues.size() == 1);
  CHECK(long_field.issues[0].what ==
        "column 'time': not a number: '" + std::string(60, 'y') + "...'");
}

TEST_CASE("header errors") {
  CHECK(message_of([] { (void)parse(""); }) ==
        "ticks.csv: empty, expected the tick-log header (time,status,...)");
  CHECK(message_of([] { (void)parse("time,,link\n"); }) ==
        "ticks.csv: line 1: empty column name in the header");
  CHECK(message_of([] { (void)parse("time,link,time\n"); }) ==
        "ticks.csv: line 1: column 'time' appears twice in the header");
  CHECK(message_of([] { (void)files::read_tick_log("/nonexistent/ticks.csv"); }) ==
        "tick log '/nonexistent/ticks.csv' cannot be opened: the file does not exist");
}

TEST_CASE("tick periods come from LoopStats") {
  std::string text = "time,link\n";
  for (int i = 0; i <= 100; ++i) {
    // 1 ms periods, one of 3 ms.
    const double t = 5.0 + 1e-3 * i + (i >= 50 ? 2e-3 : 0.0);
    text += std::to_string(t) + ",1\n";
  }
  const auto stats = files::tick_period_stats(parse(text), std::chrono::milliseconds(1));
  CHECK(stats.ticks() == 101);
  CHECK(stats.period().count() == 100);
  CHECK(std::abs(stats.period().max() - 3e-3) < 1e-9);
  // The upper edge of the 1 us histogram bin holding the quantile.
  CHECK(std::abs(stats.period().quantile(0.5) - 1.001e-3) < 1e-9);
  CHECK(std::abs(stats.period().quantile(0.99) - 1.001e-3) < 1e-9);
  CHECK(std::abs(stats.period().quantile(1.0) - 3e-3) < 1e-9);
  CHECK(stats.deadline_misses() == 1);
  CHECK(message_of([] { (void)files::tick_period_stats(parse("link\n1\n")); }) ==
        "ticks.csv: no column 'time' in the tick log (header: link)");
}

}  // namespace files_tick_log_test
