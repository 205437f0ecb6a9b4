#include "endohaptics/files/log_reader.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "endohaptics/identification/signal.hpp"
#include "shared_data.hpp"
#include "test_support.hpp"

namespace files_log_reader_test {

using endohaptics::test::TempDir;

namespace {

namespace files = endohaptics::files;
namespace id = endohaptics::identification;
namespace fs = std::filesystem;
using endohaptics::Error;

// Every defect of the README once, CRLF line ends, no newline after the last line. Positions
// follow 0.05 rad/s, with a 1 rad jump across the 0.98 s hole (which velocity must not see).
const std::string defects_file =
    "Timestamp,Loadcell,Force,Setpoint,Position,Current,Current Demand\r\n"  // 1 header
    "100.00,0.4,0.001,0,0.000,0.1,0.1\r\n"                                   // 2
    "100.02,0.4,0.001,0,0.001,0.1,0.1\r\n"                                   // 3
    "   \r\n"                                                                // 4 blank
    "100.04,0.4,,0,0.002,0.1,0.1\r\n"                                        // 5 empty field
    "100.06,0.4,0.001\r\n"                                                   // 6 short line
    "100.08,0.4,abc,0,0.004,0.1,0.1\r\n"                                     // 7 garbage
    "100.10,nan,0.001,0,0.005,0.1,0.1\r\n"                                   // 8 NaN
    "100.02,0.4,0.001,0,0.006,0.1,0.1\r\n"                                   // 9 repeated
    "100.01,0.4,0.001,0,0.006,0.1,0.1\r\n"                                   // 10 backward
    "100.04,0.4,0.001,0,0.002,0.1,0.1\r\n"                                   // 11
    "101.02,0.4,0.001,0,1.051,0.1,0.1\r\n"                                   // 12 after a gap
    "101.04,0.4,0.001,0,1.052,0.1,0.1,99\r\n"                                // 13 extra field
    "101.06,0.4,0.002,0,1.053,0.1,0.1\r\n"  // 14 force 2 N but 0.4 V x 2.5 N/V = 1 N
    "#### garbage ####\r\n"                 // 15 garbage
    "101.08,0.4,0.001,0,1.054,0.1,0.1";     // 16, no newline

}  // namespace

TEST_CASE("EndoWrist log: each defect counted exactly, rows and signals right") {
  const TempDir dir;
  const std::string path = dir.write("defects.csv", defects_file);
  const files::Log log = files::read_endowrist_2016(path);
  const files::LogReport& r = log.report;
  CHECK(r.source == path);
  CHECK(r.lines == 16);
  CHECK(r.header);
  CHECK_FALSE(r.byte_order_mark);
  CHECK(r.crlf_lines == 15);
  CHECK(r.blank_lines == 1);
  CHECK(r.empty_fields == 1);
  CHECK(r.short_lines == 1);
  CHECK(r.non_numeric == 2);
  CHECK(r.non_finite == 1);
  CHECK(r.repeated_time == 1);
  CHECK(r.backward_time == 1);
  CHECK(r.dropped() == 7);
  CHECK(r.extra_fields == 1);
  CHECK(r.force_mismatch == 1);
  CHECK(r.rows == 7);
  CHECK(r.median_step == doctest::Approx(0.02));
  CHECK(r.gap_threshold == doctest::Approx(0.1));  // 5 x median step
  CHECK(r.gaps == 1);
  CHECK(r.largest_step == doctest::Approx(0.98));
  CHECK(r.time_offset == 100.0);

  // Issues in line order, each with its line.
  const std::vector<std::pair<std::size_t, files::LogIssueKind>> expected = {
      {5, files::LogIssueKind::empty_field},
      {6, files::LogIssueKind::short_line},
      {7, files::LogIssueKind::non_numeric},
      {8, files::LogIssueKind::non_finite},
      {9, files::LogIssueKind::repeated_time},
      {10, files::LogIssueKind::backward_time},
      {12, files::LogIssueKind::gap},
      {13, files::LogIssueKind::extra_fields},
      {14, files::LogIssueKind::force_mismatch},
      {15, files::LogIssueKind::non_numeric}};
  REQUIRE(r.issues.size() == expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    CHECK(r.issues[i].line == expected[i].first);
    CHECK(r.issues[i].kind == expected[i].second);
  }
  CHECK(r.issues[0].detail == "field 3 (force): ''");
  CHECK(r.issues[1].detail == "3 of 7 fields");
  const std::string text = r.to_string();
  CHECK(text.find("dropped 7: empty field 1, short line 1, non-numeric 2, non-finite 1, "
                  "repeated time 1, backward time 1") != std::string::npos);
  CHECK(text.find("line 15: non-numeric field: field 1 (time): '#### garbage ####'") !=
        std::string::npos);

  // Signals, units, kN -> N, rebased time, velocity that does not bridge the hole.
  CHECK(log.names == std::vector<std::string>{"loadcell_voltage", "force", "setpoint", "position",
                                              "current", "current_demand", "velocity"});
  CHECK(log.units[1] == "N");
  REQUIRE(log.rows() == 7);
  const Eigen::VectorXd t = log.signal("time");
  CHECK(t[0] == 0.0);
  CHECK(t[3] == doctest::Approx(1.02));
  CHECK(log.signal("force")[0] == doctest::Approx(1.0));
  CHECK(log.signal("force")[5] == doctest::Approx(2.0));
  const Eigen::VectorXd v = log.signal("velocity");
  for (Eigen::Index k = 0; k < 7; ++k) CHECK(v[k] == doctest::Approx(0.05));
  const Eigen::MatrixXd sel = log.select({"current", "time"});
  CHECK(sel.cols() == 2);
  CHECK(sel(6, 1) == doctest::Approx(1.08));
}

TEST_CASE("EndoWrist log: policies make each defect throw with file, line and field") {
  const TempDir dir;
  const std::string path = dir.write("defects.csv", defects_file);
  files::Endowrist2016Options strict;
  strict.read = files::LogReadOptions::strict();
  const std::string first_bad = path + ":5: empty field: field 3 (force)";
  CHECK_THROWS_WITH_AS((void)files::read_endowrist_2016(path, strict),
                       doctest::Contains(first_bad.c_str()), Error);

  // Only the time policy throws: the bad lines are dropped, the repeated stamp throws.
  files::Endowrist2016Options time_only;
  time_only.read.on_bad_time = files::OnBadRow::throw_error;
  CHECK_THROWS_WITH_AS((void)files::read_endowrist_2016(path, time_only),
                       doctest::Contains(":9: repeated time stamp: time 100.02"), Error);

  // Extra fields refused on their own.
  const std::string extra = dir.write("extra.csv",
                                      "0,0,0,0,0,0,0\n"
                                      "0.02,0,0,0,0,0,0,7\n"
                                      "0.04,0,0,0,0,0,0\n");
  files::Endowrist2016Options no_extra;
  no_extra.read.allow_extra_fields = false;
  CHECK_THROWS_WITH_AS((void)files::read_endowrist_2016(extra, no_extra),
                       doctest::Contains(":2: extra fields: 8 fields, expected 7"), Error);
  CHECK(files::read_endowrist_2016(extra).report.extra_fields == 1);
}

TEST_CASE("EndoWrist log: LF or CRLF, with or without header, same data") {
  const TempDir dir;
  const std::string body = "5.0,0.4,0.001,0.1,0.2,0.3,0.4\n5.02,0.8,0.002,0.1,0.2,0.3,0.4\n";
  std::string crlf;
  for (const char c : body) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  const files::Log a = files::read_endowrist_2016(dir.write("lf.csv", body));
  const files::Log b =
      files::read_endowrist_2016(dir.write("crlf.csv", "\xEF\xBB\xBFTime,x\r\n" + crlf));
  CHECK(a.report.crlf_lines == 0);
  CHECK_FALSE(a.report.header);
  CHECK(b.report.crlf_lines == 3);
  CHECK(b.report.header);
  CHECK(b.report.byte_order_mark);
  CHECK(a.data == b.data);
  CHECK(a.time == b.time);
  CHECK(a.report.time_offset == 5.0);
  CHECK(a.signal("force")[1] == doctest::Approx(2.0));
  CHECK(a.report.force_mismatch == 0);
}

TEST_CASE("EndoWrist friction log: 3 columns (a 4th ignored), ticks to rad, velocity") {
  const TempDir dir;
  const std::string path = dir.write("friction.csv",
                                     "10.0,-138,0.06,1\r\n"
                                     "10.476,-138,0.05,2\r\n"
                                     "10.486,-128,0.07,3\r\n"
                                     "10.496,-118,0.06,4\r\n");
  const files::Log log = files::read_endowrist_2016(path);
  CHECK(log.names == std::vector<std::string>{"ticks", "position", "current", "velocity"});
  CHECK(log.report.extra_fields == 4);
  CHECK(log.report.gaps == 1);
  CHECK(log.report.largest_step == doctest::Approx(0.476));
  CHECK(log.report.time_offset == 10.0);
  const double rad = 2.0 * std::numbers::pi / 76000.0;
  CHECK(log.signal("position")[2] == doctest::Approx(-128 * rad));
  CHECK(log.signal("velocity")[0] == 0.0);                          // isolated by the hole
  CHECK(log.signal("velocity")[2] == doctest::Approx(1000 * rad));  // 10 ticks per 10 ms
  CHECK_FALSE(log.has("force"));
  CHECK_THROWS_WITH_AS((void)log.signal("force"),
                       doctest::Contains("no signal named 'force' (signals: time, ticks, "
                                         "position, current, velocity)"),
                       Error);

  files::Endowrist2016Options forced;
  forced.layout = files::Endowrist2016Layout::measurement;  // every line is then short
  CHECK_THROWS_WITH_AS((void)files::read_endowrist_2016(path, forced),
                       doctest::Contains("no usable rows (0 kept, 2 needed)"), Error);
}

TEST_CASE("EndoWrist log: unreadable, empty, unrecognised files throw with the file name") {
  const TempDir dir;
  const std::string missing = (dir.path() / "missing.csv").string();
  const std::string message =
      "read_endowrist_2016: log file '" + missing + "' cannot be opened: the file does not exist";
  CHECK_THROWS_WITH_AS((void)files::read_endowrist_2016(missing),
                       doctest::Contains(message.c_str()), Error);
  CHECK_THROWS_WITH_AS((void)files::read_endowrist_2016(dir.path().string()),
                       doctest::Contains("is a directory"), Error);
  CHECK_THROWS_WITH_AS((void)files::read_endowrist_2016(dir.write("empty.csv", "\r\n\r\n")),
                       doctest::Contains("no usable rows"), Error);
  CHECK_THROWS_WITH_AS(
      (void)files::read_endowrist_2016(dir.write("header.csv", "Timestamp,Loadcell,Force\r\n")),
      doctest::Contains("cannot tell the log layout"), Error);
  CHECK_THROWS_WITH_AS(
      (void)files::read_endowrist_2016(dir.write("five.csv", "1,2,3,4,5\n2,2,3,4,5\n")),
      doctest::Contains("five.csv:1: cannot tell the log layout: most lines have "
                        "5 fields"),
      Error);
  CHECK_THROWS_WITH_AS((void)files::read_endowrist_2016(dir.write("one.csv", "0,0,0,0,0,0,0\n")),
                       doctest::Contains("no usable rows (1 kept, 2 needed)"), Error);
  CHECK(files::read_endowrist_2016(dir.write("one.csv", "0,0,0,0,0,0,0\n"),
                                   [] {
                                     files::Endowrist2016Options o;
                                     o.read.min_rows = 1;
                                     return o;
                                   }())
            .rows() == 1);
}

TEST_CASE("read_csv: header names, separators detected, time column by name") {
  const TempDir dir;
  const files::Log comma = files::read_csv(dir.write("c.csv", "u,y\n6.41,4.766\n3.41,4.764\n"));
  CHECK(comma.names == std::vector<std::string>{"u", "y"});
  CHECK(comma.report.header);
  CHECK(comma.time == Eigen::Vector2d(0.0, 1.0));  // no time column: row ordinal x 1 s
  CHECK(comma.signal("y")[1] == 4.764);

  files::CsvOptions o;
  o.sample_time = 0.1;
  const files::Log semi =
      files::read_csv(dir.write("s.csv", "\"u\" ; \"y\"\r\n1,5;2\r\n7;8\r\n9;10\r\n"), o);
  CHECK(semi.names == std::vector<std::string>{"u", "y"});
  CHECK(semi.report.non_numeric == 1);  // decimal comma is not a number here
  CHECK(semi.rows() == 2);
  CHECK(semi.time[0] == 0.0);  // rebased from 0.1: the dropped row leaves its hole
  CHECK(semi.report.time_offset == doctest::Approx(0.1));
  CHECK(semi.signal("u")[1] == 9.0);

  const files::Log blanks =
      files::read_csv(dir.write("w.txt", "time   u\ty\n0.0  1 2\n0.5\t3   4\n1.0 5 6\n"));
  CHECK(blanks.names == std::vector<std::string>{"u", "y"});  // "time" taken as time
  CHECK(blanks.time == Eigen::Vector3d(0.0, 0.5, 1.0));
  CHECK(blanks.report.median_step == 0.5);

  o = {};
  o.time_column = "t_s";
  const files::Log named = files::read_csv(dir.write("t.csv", "a,t_s\n1,3.0\n2,3.5\n3,3.5\n"), o);
  CHECK(named.names == std::vector<std::string>{"a"});
  CHECK(named.report.repeated_time == 1);
  CHECK(named.report.time_offset == 3.0);

  o.time_column = "seconds";
  CHECK_THROWS_WITH_AS((void)files::read_csv(dir.write("t2.csv", "a,t_s\n1,3.0\n2,3.5\n"), o),
                       doctest::Contains("t2.csv:1: no column named 'seconds' for time "
                                         "(columns: a, t_s)"),
                       Error);
  CHECK_THROWS_WITH_AS((void)files::read_csv(dir.write("n.csv", "1,2\n3,4\n")),
                       doctest::Contains("n.csv:1: expected a header line"), Error);
  CHECK_THROWS_WITH_AS((void)files::read_csv(dir.write("d.csv", "a,b,a\n1,2,3\n")),
                       doctest::Contains("d.csv:1: column 3 repeats the name 'a'"), Error);
  CHECK_THROWS_WITH_AS((void)files::read_csv(dir.write("e.csv", "a,,b\n1,2,3\n")),
                       doctest::Contains("e.csv:1: column 2 has no name"), Error);

  files::CsvOptions headerless;
  headerless.column_names = {"x", "z"};
  const files::Log h = files::read_csv(dir.write("h.csv", "1,2\n3,4\n"), headerless);
  CHECK(h.signal("z")[1] == 4.0);
  CHECK_FALSE(h.report.header);
}

TEST_CASE("read_log and parse_log_format: the command-line entry points") {
  CHECK(files::parse_log_format("endowrist-2016") == files::LogFormat::endowrist_2016);
  CHECK(files::parse_log_format("csv") == files::LogFormat::csv);
  CHECK_THROWS_WITH_AS(
      (void)files::parse_log_format("mat"),
      doctest::Contains("unknown log format 'mat' (valid: endowrist-2016, csv, umn-mis-2018)"),
      Error);
  const TempDir dir;
  const files::Log log =
      files::read_log(dir.write("a.csv", "0,0.4,0.001,0,0,0,0\n0.02,0.4,0.001,0,0,0,0\n"),
                      files::LogFormat::endowrist_2016);
  CHECK(log.has("current_demand"));
}

// ---------------------------------------------------------------------------------------------
// The real 2016 logs (../shared/data/endowrist-2016). Expected numbers from an independent
// reading in /usr/bin/python3 (numpy 1.24.2), per file f:
//   lines = open(f, 'rb').read().decode().splitlines(); rows: lines whose fields all parse
//   with float(); t = column 0, F = 1000 * column 2, V = column 1:
//   np.diff(t).max(), np.median(np.diff(t)), t[0], np.median(F[t - t[0] < 0.5]),
//   np.sum(np.abs(F - 2.5 * V) > 0.01), len(rows) summed over the 55 files.

TEST_CASE("real logs: every file of every folder loads, nothing needs dropping" *
          doctest::skip(!endohaptics::test::has_shared_data("endowrist-2016"))) {
  const fs::path root = endohaptics::test::shared_data("endowrist-2016");
  std::size_t files = 0;
  std::size_t rows = 0;
  std::size_t mismatches = 0;
  for (const auto& folder : {"clamp-hits", "clamp-static", "friction", "one-clamp-down", "pitch"}) {
    std::vector<fs::path> paths;
    for (const auto& e : fs::directory_iterator(root / folder)) paths.push_back(e.path());
    std::sort(paths.begin(), paths.end());
    CHECK(!paths.empty());
    for (const auto& p : paths) {
      INFO(p.string());
      const files::Log log = files::read_endowrist_2016(p.string());
      ++files;
      rows += log.report.rows;
      mismatches += log.report.force_mismatch;
      // This copy has none of the line defects the README lists: every line but a header is
      // a row, all with CRLF ends.
      CHECK(log.report.dropped() == 0);
      CHECK(log.report.crlf_lines == log.report.lines);
      CHECK(log.report.rows + (log.report.header ? 1u : 0u) == log.report.lines);
      CHECK(log.report.header == (std::string(folder) == "pitch"));
      CHECK(log.time[0] == 0.0);
      const bool friction = std::string(folder) == "friction";
      CHECK(log.has("velocity"));
      CHECK(log.has("force") == !friction);
      if (!friction && p.filename() != "pitch-up-01.csv") {
        // Forces in N: the load cell is rated 1 kg (9.8 N); the largest push is 10.15 N.
        const Eigen::VectorXd f = log.signal("force");
        CHECK(f.maxCoeff() < 10.2);
        CHECK(f.minCoeff() > -0.6);
      }
      CHECK(log.signal("velocity").cwiseAbs().maxCoeff() < 10.0);  // rad/s
    }
  }
  CHECK(files == 55);
  CHECK(rows == 74160);
  CHECK(mismatches == 1499 + 1);  // pitch-up-01 (all rows) and one-clamp-down-02 (last row)
}

TEST_CASE("real logs: pitch-up-01 has a header and a -232 N load-cell offset" *
          doctest::skip(!endohaptics::test::has_shared_data("endowrist-2016"))) {
  const files::Log log = files::read_endowrist_2016(
      endohaptics::test::shared_data("endowrist-2016/pitch/pitch-up-01.csv").string());
  const files::LogReport& r = log.report;
  CHECK(r.header);
  CHECK(r.lines == 1500);
  CHECK(r.rows == 1499);
  CHECK(r.crlf_lines == 1500);
  CHECK(r.dropped() == 0);
  CHECK(r.gaps == 0);
  CHECK(r.time_offset == 0.0);
  CHECK(r.median_step == doctest::Approx(0.02).epsilon(0.01));
  // The force column does not follow 2.5 N/V x voltage anywhere in this file (all others do).
  CHECK(r.force_mismatch == 1499);
  const Eigen::VectorXd f = log.signal("force");
  // Offset: median of the first 0.5 s (25 samples) = -0.2322464 kN as logged.
  const double offset = id::estimate_offset(f, {0, 25, id::OffsetEstimator::median});
  CHECK(offset == doctest::Approx(-232.2464));
  CHECK(f.minCoeff() == doctest::Approx(-233.52).epsilon(1e-4));
  CHECK(f.maxCoeff() == doctest::Approx(-226.50).epsilon(1e-4));
  // After removing it the contact force is a few N, like the other pitch-up logs.
  CHECK((f.array() - offset).abs().maxCoeff() < 6.0);
}

TEST_CASE("real logs: known time defects and the force check" *
          doctest::skip(!endohaptics::test::has_shared_data("endowrist-2016"))) {
  const auto read = [](const std::string& rel) {
    return files::read_endowrist_2016(
        endohaptics::test::shared_data("endowrist-2016/" + rel).string());
  };
  // clamp-hits: clock starts at 1080 s; a 0.866 s hole after the first sample; ~100 Hz.
  const files::Log hits = read("clamp-hits/clamp-hits-01.csv");
  CHECK(hits.report.time_offset == 1080.013428);
  CHECK(hits.report.rows == 1879);
  CHECK(hits.report.gaps == 1);
  CHECK(hits.report.largest_step == doctest::Approx(0.866089).epsilon(1e-5));
  CHECK(hits.report.median_step == doctest::Approx(0.01001).epsilon(1e-3));
  CHECK(hits.report.force_mismatch == 0);
  REQUIRE(!hits.report.issues.empty());
  CHECK(hits.report.issues[0].line == 2);
  CHECK(hits.report.issues[0].kind == files::LogIssueKind::gap);
  // Resampled at 100 Hz: the isolated first sample is dropped, one 19.11 s segment remains.
  const id::Segments seg = id::resample_uniform(hits.time, hits.select({"current", "force"}), 0.01);
  CHECK(seg.gaps == 1);
  CHECK(seg.dropped_segments == 1);
  CHECK(seg.dropped_source_rows == 1);
  REQUIRE(seg.segments.size() == 1);
  CHECK(seg.segments[0].rows() == 1911);

  // friction/pitch-free-00: clock at 10 s, 0.476 s hole; pitch-free-06: a 4th column.
  const files::Log free00 = read("friction/pitch-free-00.csv");
  CHECK(free00.report.time_offset == 10.00206375);
  CHECK(free00.report.gaps == 1);
  CHECK(free00.report.largest_step == doctest::Approx(0.476011).epsilon(1e-5));
  CHECK(read("friction/pitch-free-06.csv").report.extra_fields == 1337);

  // one-clamp-down-02: the last line's force field holds a voltage-like value (0.99 N at
  // -0.0003 V): the only mismatch in the 41 measurement logs besides pitch-up-01.
  const files::Log down = read("one-clamp-down/one-clamp-down-02.csv");
  CHECK(down.report.force_mismatch == 1);
  REQUIRE(!down.report.issues.empty());
  CHECK(down.report.issues.back().line == 1500);
  CHECK(down.report.issues.back().kind == files::LogIssueKind::force_mismatch);
}

TEST_CASE("property: random damage never crashes and every line is accounted for") {
  // Seeded: 200 files of 40 lines mixing good rows, defects, random bytes and line ends.
  std::mt19937 rng(20160501);
  const std::vector<std::string> pieces = {"0.5,0.4,0.001,0,0.1,0.2,0.3",
                                           ",",
                                           ",,",
                                           "nan",
                                           "-inf",
                                           "1e999",
                                           "1e-999",
                                           "abc",
                                           " ",
                                           "\t",
                                           "\r",
                                           "\"",
                                           ";",
                                           "+",
                                           "-",
                                           "0x1p3",
                                           "7",
                                           "3.25",
                                           "\xEF\xBB\xBF",
                                           "\xff\xfe"};
  const TempDir dir;
  for (int file = 0; file < 200; ++file) {
    std::string content;
    double t = 0;
    for (int line = 0; line < 40; ++line) {
      if (rng() % 3 == 0) {
        for (auto k = rng() % 6; k > 0; --k) content += pieces[rng() % pieces.size()];
      } else {
        t += (rng() % 5 == 0) ? -0.01 : 0.02;
        content += std::to_string(t) + ",0.4,0.001,0,0.1,0.2,0.3";
      }
      content += rng() % 2 ? "\r\n" : "\n";
    }
    const std::string path = dir.write("random.csv", content);
    files::Endowrist2016Options o;
    o.read.min_rows = 0;
    o.layout = files::Endowrist2016Layout::measurement;
    const files::Log log = files::read_endowrist_2016(path, o);
    const files::LogReport& r = log.report;
    INFO("file " << file);
    CHECK(r.lines == 40);
    CHECK(r.rows + r.dropped() + r.blank_lines + (r.header ? 1u : 0u) == r.lines);
    CHECK(log.rows() == static_cast<Eigen::Index>(r.rows));
    CHECK(log.data.allFinite());
    for (Eigen::Index k = 1; k < log.rows(); ++k) CHECK(log.time[k] > log.time[k - 1]);
  }
}

TEST_CASE("real CSV: the DaISy records load with their header names" *
          doctest::skip(!endohaptics::test::has_shared_data("daisy"))) {
  const auto read = [](const std::string& name) {
    return files::read_csv(endohaptics::test::shared_data("daisy/" + name).string());
  };
  // Sample counts from daisy/README.md; first values from the files' second line.
  const files::Log dryer = read("dryer.csv");
  CHECK(dryer.names == std::vector<std::string>{"u", "y"});
  CHECK(dryer.rows() == 1000);
  CHECK(dryer.report.dropped() == 0);
  CHECK(dryer.report.header);
  CHECK(dryer.signal("u")[0] == 6.41);
  CHECK(dryer.signal("y")[0] == 4.7660989);
  CHECK(dryer.time[999] == 999.0);  // no time column: unit sample time
  const files::Log cd = read("CD_player_arm.csv");
  CHECK(cd.names == std::vector<std::string>{"u1", "u2", "y1", "y2"});
  CHECK(cd.rows() == 2048);
  CHECK(cd.report.dropped() == 0);
  CHECK(cd.signal("u2")[0] == -0.0313);
  const files::Log ballbeam = read("ballbeam.csv");
  CHECK(ballbeam.rows() == 1000);
  CHECK(ballbeam.signal("y")[0] == -4.885198e-03);
  CHECK_THROWS_WITH_AS((void)dryer.select({"u", "temperature"}),
                       doctest::Contains("no signal named 'temperature' (signals: time, u, y)"),
                       Error);
}

}  // namespace files_log_reader_test
