#include "endohaptics/workflow/force_report.hpp"

#include <doctest/doctest.h>

#include <algorithm>
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

namespace {

// Every motor and the stylus: the true force of clamp 1 (motor 2) is -2 max(0, sin(pi t)) N (in
// contact half the time), the others 0, every ms from t = 100 s for 4 s.
double clamp1_truth(double t) { return -2.0 * std::max(0.0, std::sin(M_PI * (t - 100.0))); }

std::string full_truth_csv() {
  std::ostringstream out;
  out.precision(12);
  out << "time,force0,force1,force2,force3\n";
  for (int k = 0; k <= 4000; ++k) {
    const double t = 100.0 + 1e-3 * k;
    out << t << ",0,0," << clamp1_truth(t) << ",0\n";
  }
  return out.str();
}

// The bridge's log of a run whose estimate is `sign` x the truth, rendered with the default
// mapping by hand: the stylus straight ahead (roll setpoint a_roll pi/2 + b_roll: theta = pi/2),
// so eq. 5.8 gives F = (c, 0, 0), c = (f_clamp2 - f_clamp1) / 2 limited to 1.4 N. `theta` adds
// the stylus_theta column (pi/2) when true.
std::string full_tick_csv(double sign, bool theta = false) {
  std::ostringstream out;
  out.precision(12);
  out << "time,force_scale,setpoint0,setpoint1,setpoint2,setpoint3,motor_force0,motor_force1,"
         "motor_force2,motor_force3,stylus_fx,stylus_fy,stylus_fz"
      << (theta ? ",stylus_theta\n" : "\n");
  const double roll = 0.7096 * M_PI / 2 - 1.108;
  for (int k = 0; k < 3000; ++k) {
    const double t = 100.5 + 1e-3 * k;
    const double f2 = sign * clamp1_truth(t);
    const double c = std::clamp(-f2 / 2, -1.4, 1.4);
    out << t << ",1," << roll << ",0,0.5,-0.5,0,0," << f2 << ",0," << c << ",0,0";
    if (theta) out << "," << M_PI / 2;
    out << '\n';
  }
  return out.str();
}

files::TickLog parse_ticks(const std::string& text, const std::string& name = "ticks.csv") {
  std::istringstream in(text);
  return files::parse_tick_log(in, name);
}

}  // namespace

TEST_CASE("force report: an estimate equal to the truth scores 100 % and renders the ideal force") {
  const TempDir dir("force_report_full");
  write_text(dir.path() / "truth.csv", full_truth_csv());
  const files::Log truth = wf::read_truth_log((dir.path() / "truth.csv").string());
  const wf::RunScores s = wf::score_run("identified", truth, parse_ticks(full_tick_csv(1.0)),
                                        files::BridgeConfig{}, 0.5);
  CHECK(s.label == "identified");
  REQUIRE(s.joints.size() == 4);
  for (int m = 0; m < 4; ++m) {
    CHECK(s.joints[static_cast<std::size_t>(m)].motor == m);
    CHECK(s.joints[static_cast<std::size_t>(m)].rendered);  // default force_scale: every channel
  }
  CHECK(s.joints[0].joint == endohaptics::protocol::Motor::roll);
  CHECK(s.joints[2].joint == endohaptics::protocol::Motor::clamp1);
  const auto& clamp1 = s.joints[2].accuracy;
  CHECK(clamp1.fit_percent == doctest::Approx(100.0));
  CHECK(clamp1.correlation == doctest::Approx(1.0));
  CHECK(clamp1.rmse < 1e-6);
  CHECK(clamp1.truth_peak == doctest::Approx(2.0).epsilon(0.01));
  const wf::StylusScore& st = s.stylus;
  CHECK(st.ticks == 2500);  // 3 s of ticks, 0.5 s skipped
  CHECK(st.theta_logged == 0);
  CHECK(st.theta_unknown == 0);
  CHECK(st.rmse < 1e-9);
  CHECK(st.replay_rmse < 1e-9);
  CHECK(st.ideal_peak == doctest::Approx(1.0).epsilon(0.01));
  // Contact-free: from 101 s to 103.5 s, sin(pi t) <= 0 but from 102 to 103 s: 1.5 s of ticks,
  // where the stylus renders 0.
  CHECK(st.free_ticks == doctest::Approx(1500).epsilon(0.01));
  CHECK(st.free_rms == 0.0);
  CHECK(wf::joint_line("identified", s.joints[2]) ==
        "identified, clamp1: fit 100.0%, correlation 1.000, RMSE 0.000 N, delay 0 ms, peak 2.00 N "
        "(true 2.00 N)");
  CHECK(wf::stylus_line("", st) ==
        "stylus: RMSE 0.000 N against the ideal force, free motion RMS 0.000 N");
  CHECK(wf::stylus_line("identified", st).starts_with("identified, stylus: RMSE 0.000 N"));
  CHECK(wf::summary_line("identified", clamp1) ==
        "identified: fit 100.0%, correlation 1.000, RMSE 0.000 N, delay 0 ms, peak 2.00 N (true "
        "2.00 N)");

  // The logged theta is used where the log has it.
  const wf::RunScores logged =
      wf::score_run("r", truth, parse_ticks(full_tick_csv(1.0, true)), files::BridgeConfig{}, 0.5);
  CHECK(logged.stylus.theta_logged == 2500);
  CHECK(logged.stylus.rmse < 1e-9);
}

TEST_CASE("force report: an estimate of the wrong sign scores badly at the joint and the stylus") {
  const TempDir dir("force_report_sign");
  write_text(dir.path() / "truth.csv", full_truth_csv());
  const files::Log truth = wf::read_truth_log((dir.path() / "truth.csv").string());
  const wf::RunScores s =
      wf::score_run("wrong", truth, parse_ticks(full_tick_csv(-1.0)), files::BridgeConfig{}, 0.5);
  CHECK(s.joints[2].accuracy.correlation == doctest::Approx(-1.0));
  CHECK(s.joints[2].accuracy.fit_percent < 0.0);
  // The rendered force is -c where the ideal is c: RMSE = 2 RMS(c), c = max(0, sin(pi t)) over
  // 101..103.5 s (1 s of a positive half sine): 2 sqrt(0.5 / 2.5) = 0.894 N.
  CHECK(s.stylus.rmse == doctest::Approx(2.0 * std::sqrt(0.2)).epsilon(0.01));
  CHECK(s.stylus.replay_rmse < 1e-9);  // the bridge mapped its (wrong) estimate as the report does

  // Another mapping than the bridge ran (half the clamp channel's scale): the replay says so.
  files::BridgeConfig half;
  half.mapping.force_scale[0] = 0.5;
  const wf::RunScores other =
      wf::score_run("right", truth, parse_ticks(full_tick_csv(1.0)), half, 0.5);
  CHECK(other.stylus.ideal_peak == doctest::Approx(0.5).epsilon(0.01));
  CHECK(other.stylus.rmse == doctest::Approx(std::sqrt(0.2) / 2).epsilon(0.01));  // RMS(c / 2)
  CHECK(other.stylus.replay_rmse == doctest::Approx(std::sqrt(0.2) / 2).epsilon(0.01));
}

TEST_CASE("force report: the ideal force is eq. 5.8's, ramped and limited as the loop does") {
  const endohaptics::kinematics::CylindricalMapper<double> mapper;
  const endohaptics::estimation::MotorVector f(0.5, -0.25, -1.0, 1.0);  // roll, pitch, clamps
  const Eigen::Vector3d full = wf::ideal_stylus_force(mapper, f, M_PI / 2, 1.0, 3.0);
  // theta = pi/2: x = clamp channel (1 - -1) / 2 = 1, y = -roll = -0.5, z = pitch = -0.25.
  CHECK(full.x() == doctest::Approx(1.0));
  CHECK(full.y() == doctest::Approx(-0.5));
  CHECK(full.z() == doctest::Approx(-0.25));
  CHECK(wf::ideal_stylus_force(mapper, f, M_PI / 2, 0.5, 3.0).isApprox(full / 2));  // the ramp
  CHECK(wf::ideal_stylus_force(mapper, f, M_PI / 2, 1.0, 0.5).norm() ==
        doctest::Approx(0.5));  // safety.max_stylus_force
  const endohaptics::estimation::MotorVector big(0.0, 0.0, -10.0, 10.0);
  CHECK(wf::ideal_stylus_force(mapper, big, M_PI / 2, 1.0, 3.0).x() ==
        doctest::Approx(1.4));  // mapping.channel_limit
  CHECK(wf::ideal_stylus_force(mapper, f, std::nan(""), 1.0, 3.0).isZero());  // refused: zero
}

TEST_CASE("force report: theta from the roll setpoint, unknown at a limit or while rate-limited") {
  const files::BridgeConfig config;
  std::ostringstream text;
  text << "time,setpoint0\n";
  const double pi2 = 0.7096 * M_PI / 2 - 1.108;
  // 0: pi/2; 1: moved 4 mrad in 1 ms (the 4 rad/s rate limit); 2: steady; 3: at the upper limit.
  text << "1.000," << pi2 << "\n1.001," << pi2 + 0.004 << "\n1.002," << pi2 + 0.004
       << "\n1.003,1.028\n";
  const wf::StylusTheta th = wf::stylus_theta(parse_ticks(text.str()), config);
  REQUIRE(th.theta.size() == 4);
  CHECK(th.source[0] == wf::ThetaSource::roll_setpoint);
  CHECK(th.theta[0] == doctest::Approx(M_PI / 2));
  CHECK(th.source[1] == wf::ThetaSource::unknown);
  CHECK(std::isnan(th.theta[1]));
  CHECK(th.source[2] == wf::ThetaSource::roll_setpoint);
  CHECK(th.theta[2] == doctest::Approx(M_PI / 2 + 0.004 / 0.7096));
  CHECK(th.source[3] == wf::ThetaSource::unknown);
  // The limiter's step is at most one period's (1 ms): a 4 mrad step after a 5 ms gap is limited.
  const wf::StylusTheta gap =
      wf::stylus_theta(parse_ticks("time,setpoint0\n1.000," + std::to_string(pi2) + "\n1.005," +
                                   std::to_string(pi2 + 0.004) + "\n"),
                       config);
  CHECK(gap.source[1] == wf::ThetaSource::unknown);
  // A logged theta wins where finite; nan falls back to the setpoint.
  const wf::StylusTheta logged =
      wf::stylus_theta(parse_ticks("time,setpoint0,stylus_theta\n1.000," + std::to_string(pi2) +
                                   ",2.5\n1.001," + std::to_string(pi2) + ",nan\n"),
                       config);
  CHECK(logged.source[0] == wf::ThetaSource::logged);
  CHECK(logged.theta[0] == 2.5);
  CHECK(logged.source[1] == wf::ThetaSource::roll_setpoint);
}

TEST_CASE("force report: free motion from a free-space log after the skip, and option counts") {
  std::ostringstream free;
  free << "time,stylus_fx,stylus_fy,stylus_fz\n";
  for (int k = 0; k < 2000; ++k) {
    // 2 N in the first 0.5 s (start-up, skipped), then |F| = 0.05 N.
    const double f = k < 500 ? 2.0 : 0.03;
    free << 10.0 + 1e-3 * k << "," << f << ",0," << (k < 500 ? 0.0 : 0.04) << "\n";
  }
  wf::StylusScore s;
  wf::free_motion_rms(s, parse_ticks(free.str(), "free.csv"), 0.5);
  CHECK(s.free_ticks == 1500);
  CHECK(s.free_rms == doctest::Approx(0.05));
  CHECK(s.free_source == "free.csv (free space)");
  wf::free_motion_rms(s, parse_ticks(free.str(), "free.csv"), 0.0);
  CHECK(s.free_rms > 0.5);  // the start-up counts without the skip
  CHECK(message_of([&] { wf::free_motion_rms(s, parse_ticks(free.str(), "free.csv"), 5.0); }) ==
        "free.csv: no tick after --skip for the free-motion RMS");

  CHECK_NOTHROW(wf::check_run_options(3, 3, 3, 1, 0));
  CHECK_NOTHROW(wf::check_run_options(2, 2, 0, 2, 2));
  CHECK(message_of([] {
          wf::check_run_options(2, 2, 0, 3, 0);
        }).ends_with("2 --truth, 2 --log, 0 --label, 3 --config, 0 --free-log"));
  CHECK_THROWS(wf::check_run_options(2, 2, 0, 0, 1));
  CHECK_THROWS(wf::check_run_options(2, 1, 0, 0, 0));
}

}  // namespace workflow_force_report_test
