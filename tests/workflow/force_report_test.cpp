#include "endohaptics/workflow/force_report.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "test_support.hpp"

namespace workflow_force_report_test {

using endohaptics::test::message_of;
using endohaptics::test::TempDir;
using endohaptics::test::write_text;

namespace {

namespace wf = endohaptics::workflow;
namespace files = endohaptics::files;

// The true force of motor 2: a 0.5 Hz sine of 2 N, sampled every ms for 4 s from t = 100 s (the
// emulator's CLOCK_MONOTONIC), as "time,force2".
double truth_at(double t) { return 2.0 * std::sin(M_PI * (t - 100.0)); }

std::string truth_csv() {
  std::ostringstream out;
  out.precision(12);
  out << "time,force0,force2\n";
  for (int k = 0; k <= 4000; ++k) {
    const double t = 100.0 + 1e-3 * k;
    out << t << ",0," << truth_at(t) << '\n';
  }
  return out.str();
}

// The bridge's tick log: the estimate 40 ms late, ticks every ms from t = 100.5 s to 103.5 s.
files::TickLog tick_log(int rows) {
  std::ostringstream out;
  out.precision(12);
  out << "time,motor_force0,motor_force2,stylus_fx,stylus_fy,stylus_fz\n";
  for (int k = 0; k < rows; ++k) {
    const double t = 100.5 + 1e-3 * k;
    out << t << ",0," << truth_at(t - 0.04) << ",0.3,0,0.4\n";
  }
  std::istringstream in(out.str());
  return files::parse_tick_log(in, "ticks.csv");
}

}  // namespace

TEST_CASE("force report: the estimate against the truth, its delay, the plots") {
  const TempDir dir("force_report");
  write_text(dir.path() / "truth.csv", truth_csv());
  const files::Log truth = wf::read_truth_log((dir.path() / "truth.csv").string());
  CHECK(truth.time[0] == doctest::Approx(100.0));  // kept as logged, not rebased
  const wf::ForceRun run = wf::force_run("preset", truth, tick_log(3000), "ticks.csv", 2, 0.5);
  CHECK(run.label == "preset");
  CHECK(run.t0 == doctest::Approx(100.5));
  CHECK(run.truth_time.size() == 4001);
  const auto& a = run.accuracy;
  CHECK(a.span == doctest::Approx(2.5).epsilon(0.01));  // after the 0.5 s skip
  CHECK(a.delay == doctest::Approx(0.04).epsilon(0.05));
  CHECK(a.fit_percent_at_delay > 99.0);
  CHECK(a.fit_percent < a.fit_percent_at_delay);
  CHECK(a.truth_peak == doctest::Approx(2.0).epsilon(0.01));
  CHECK_NOTHROW(wf::require_finite_accuracy(run));

  const wf::PlotFigure forces = wf::forces_figure({run}, 2);
  REQUIRE(forces.panels.size() == 1);
  CHECK(forces.panels[0].title ==
        "preset: motor 2, true external force (emulator) vs estimate "
        "(bridge)");
  REQUIRE(forces.panels[0].series.size() == 3);
  CHECK(forces.panels[0].series[1].title == "estimated (preset)");
  const wf::PlotFigure periods = wf::period_figure(run);
  REQUIRE(periods.panels.size() == 1);
  CHECK(periods.panels[0].title == "Bridge tick period (tick to tick), preset");
  CHECK(periods.panels[0].log_y);
}

TEST_CASE("force report: an empty tick log or no overlap after the skip fails, naming it") {
  const TempDir dir("force_report_errors");
  write_text(dir.path() / "truth.csv", truth_csv());
  const files::Log truth = wf::read_truth_log((dir.path() / "truth.csv").string());
  CHECK(message_of([&] { (void)wf::force_run("r", truth, tick_log(0), "ticks.csv", 2, 0.5); }) ==
        "ticks.csv: the tick log has no rows");
  // Nothing left after the skip; a force that never changes has no correlation.
  CHECK(message_of([&] {
          (void)wf::force_run("late", truth, tick_log(3000), "ticks.csv", 2, 100.0);
        }).find("fewer than 2 samples") != std::string::npos);
  const wf::ForceRun flat = wf::force_run("flat", truth, tick_log(3000), "ticks.csv", 0, 0.5);
  CHECK(message_of([&] {
          wf::require_finite_accuracy(flat);
        }).starts_with("flat: the force accuracy is not finite (fit "));
  CHECK(message_of([&] {
          (void)wf::force_run("r", truth, tick_log(10), "ticks.csv", 1, 0.0);
        }).find("force1") != std::string::npos);  // the truth has no force1 column
}

}  // namespace workflow_force_report_test
