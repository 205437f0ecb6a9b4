#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <endohaptics/files/log_reader.hpp>
#include <endohaptics/files/umn_mis_2018_log.hpp>
#include <filesystem>
#include <numbers>
#include <vector>

#include "shared_data.hpp"
#include "test_support.hpp"

namespace files_umn_mis_2018_log_test {

namespace files = endohaptics::files;
using endohaptics::Error;
using endohaptics::test::message_of;
using endohaptics::test::TempDir;

namespace {

const char* const header =
    "%This file containts data collection taken by Trevor Stephens and Nathan Kong\n"
    "%Used left spindle of tool number 5 with a 0.10 Hz Sine wave, amplitude 30.00 degrees\n"
    "%idxPulse_1=864\n"
    "%torque0AverageTorque=224.67\n"
    "%torque2ZeroLoad=0.00\n"
    "%Back-end Time [ms], Back-end CUI Encoder [counts], Back-end Futek Torque [counts], "
    "Measured Current [Amps], Front-end Maxon Encoder [counts], Front-end Futek Torque [counts], "
    "Front-end Command [amps?], Back-end Command [-1:1], Back-end Maxon [counts], Trajectory "
    "Target [counts?]\n";

}  // namespace

TEST_CASE("UMN log: header, conversions to SI, causal velocity, metadata") {
  const TempDir dir("umn");
  const auto path = dir.write("00.TXT", std::string(header) +
                                            "0.000,0.00,1224.00,0.091,859.00,-322.00,0.10,-0.05,"
                                            "1901.00,0.00\n"
                                            "0.001,8.00,1218.00,-0.007,859.00,-316.00,0.10,0.00,"
                                            "1911.00,0.00\r\n"
                                            "0.002,16.00,1208.00,-0.003,860.00,-300.00,0.10,-0.00,"
                                            "1931.00,2.50\n");
  const files::Log log = files::read_umn_mis_2018(path);
  REQUIRE(log.rows() == 3);
  CHECK(log.time[1] == doctest::Approx(0.001));  // "ms" values that step by 0.001: seconds
  CHECK(log.signal("current")[0] == doctest::Approx(0.091));
  CHECK(log.signal("current_command")[0] == doctest::Approx(-0.05));
  constexpr double motor_rad = 2 * std::numbers::pi / (4196.0 * 35);
  CHECK(log.signal("motor_position")[2] == doctest::Approx(1931.0 * motor_rad));
  // Backward difference: (1931 - 1911) counts in 1 ms; 0 at the first row.
  CHECK(log.signal("motor_velocity")[0] == 0.0);
  CHECK(log.signal("motor_velocity")[1] == doctest::Approx(10.0 * motor_rad / 0.001));
  CHECK(log.signal("motor_velocity")[2] == doctest::Approx(20.0 * motor_rad / 0.001));
  CHECK(log.signal("grip_torque")[0] == doctest::Approx(-322.0 * 0.039811));  // mN m
  CHECK(log.signal("spindle_torque")[0] == doctest::Approx(1224.0 * 0.039811));
  CHECK(log.signal("spindle_position")[1] == doctest::Approx(8.0 * 2 * std::numbers::pi / 8192));
  CHECK(log.signal("jaw_position")[2] == doctest::Approx(860.0 * 2 * std::numbers::pi / 4000));
  CHECK(log.signal("trajectory_target")[2] == doctest::Approx(2.5 * motor_rad));
  CHECK(log.units[static_cast<std::size_t>(log.column("grip_torque"))] == "mN m");
  REQUIRE(log.metadata.size() == 3);
  CHECK(log.metadata[0] == std::pair<std::string, std::string>{"idxPulse_1", "864"});
  CHECK(log.metadata[1].second == "224.67");
  CHECK(log.report.header);
  CHECK(log.report.crlf_lines == 1);

  // The command-line entry point reads the same.
  CHECK(files::parse_log_format("umn-mis-2018") == files::LogFormat::umn_mis_2018);
  CHECK(files::read_log(path, files::LogFormat::umn_mis_2018).rows() == 3);
}

TEST_CASE("UMN log: bad rows are dropped and counted, a file without header is refused") {
  const TempDir dir("umn-bad");
  const auto path =
      dir.write("bad.TXT", std::string(header) + "0.000,0,0,0.1,0,-1,0,0,0,0\n" +
                               "0.001,0,0,nan,0,-1,0,0,0,0\n" +  // non-finite current
                               "0.002,0,0,0.1,0,-1\n" +          // short
                               "0.002,0,0,0.1,0,-1,0,0,0,0\n" + "0.001,0,0,0.1,0,-1,0,0,0,0\n");
  const files::Log log = files::read_umn_mis_2018(path);
  CHECK(log.rows() == 2);
  CHECK(log.report.non_finite == 1);
  CHECK(log.report.short_lines == 1);
  CHECK(log.report.backward_time == 1);

  const auto plain = dir.write("plain.TXT", "0.000,0,0,0.1,0,-1,0,0,0,0\n");
  CHECK(message_of([&] { (void)files::read_umn_mis_2018(plain); }) ==
        "read_umn_mis_2018: " + plain +
            ": no '%' header lines: not a UMN "
            "mis-tool-characterization log");
  files::UmnMis2018Options o;
  o.futek_newton_metres = -1;
  CHECK_THROWS_AS((void)files::read_umn_mis_2018(path, o), Error);
}

TEST_CASE("UMN log: the first five runs of each session load whole" *
          doctest::skip(!endohaptics::test::has_shared_data("umn-mis-tool-2018"))) {
  // Independent count (awk, rows: lines not starting with '%', first five files in name order):
  // L_2 99,987 rows, L_4 99,970 rows, every row 10 fields. Five per session keep the sanitized
  // test short; identification reads every run (tests/workflow, docs/identification_results.md).
  struct Session {
    const char* folder;
    std::size_t rows;
  };
  for (const Session s :
       {Session{"Tool_4_Maryland_L_2", 99987}, Session{"Tool_4_Maryland_L_4", 99970}}) {
    CAPTURE(s.folder);
    std::vector<std::filesystem::path> paths;
    for (const auto& entry : std::filesystem::directory_iterator(
             endohaptics::test::shared_data(std::string("umn-mis-tool-2018/") + s.folder))) {
      paths.push_back(entry.path());
    }
    std::sort(paths.begin(), paths.end());
    REQUIRE(paths.size() >= 5);
    std::size_t rows = 0;
    for (std::size_t i = 0; i < 5; ++i) {
      const files::Log log = files::read_umn_mis_2018(paths[i].string());
      CHECK(log.report.dropped() == 0);
      CHECK(log.report.gaps == 0);
      CHECK(log.report.median_step == doctest::Approx(0.001));
      CHECK(log.signal("motor_velocity").allFinite());
      CHECK(log.signal("grip_torque").cwiseAbs().maxCoeff() < 1000.0);  // mN m, sensor range
      CHECK_FALSE(log.metadata.empty());
      rows += static_cast<std::size_t>(log.rows());
    }
    CHECK(rows == s.rows);
  }
}

}  // namespace files_umn_mis_2018_log_test
