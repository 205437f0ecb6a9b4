//! @file
//! endohaptics-force-report's runs: the bridge's per-tick log (estimated joint force, stylus
//! force; files/tick_log.hpp) against the emulator's truth log (true external force, N) of the
//! same teleoperation, compared on a common time base (sim::force_accuracy: fit %, correlation,
//! RMSE, delay in s, peaks); every motor at once, and the rendered stylus force against the ideal
//! one (eq. 5.8 applied to the true forces) and in free motion; the plots (workflow/gnuplot.hpp).
//! Configuration time: allocates, throws endohaptics::Error. Units: s, rad, N.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/joint_force_estimator.hpp"
#include "endohaptics/files/bridge_config.hpp"
#include "endohaptics/files/csv_log.hpp"
#include "endohaptics/files/log.hpp"
#include "endohaptics/files/model_set_file.hpp"
#include "endohaptics/files/tick_log.hpp"
#include "endohaptics/kinematics/cylindrical_mapper.hpp"
#include "endohaptics/protocol/motor_order.hpp"
#include "endohaptics/sim/force_accuracy.hpp"
#include "endohaptics/workflow/gnuplot.hpp"

namespace endohaptics::workflow {

//! One run: the emulator's truth log and the bridge's tick log of the same teleoperation.
struct ForceRun {
  std::string label;                //!< its name in the report
  std::string log_path;             //!< the tick log's file
  std::vector<double> truth_time;   //!< s: the truth log's times
  std::vector<double> truth_force;  //!< N: the truth log's force of the joint
  files::TickLog ticks;             //!< the bridge's tick log
  sim::ForceAccuracy accuracy;      //!< the estimate against the truth
  double t0 = 0.0;                  //!< s, the tick log's first time stamp
};

//! The emulator's truth log (a CSV, endohaptics-sbrio-emulator --truth-log), its times kept as
//! logged: both logs use CLOCK_MONOTONIC.
[[nodiscard]] inline files::Log read_truth_log(const std::string& path) {
  files::CsvOptions options;
  options.read.rebase_time = false;
  return files::read_csv(path, options);
}

//! The estimate of motor slot `joint` ("motor_force<joint>" of `ticks`, after the first `skip` s
//! of the tick log) against the true force (`truth_time`, `truth_force`): sim::force_accuracy.
//! Throws Error when the tick log has no rows or lacks a column, or as sim::force_accuracy.
[[nodiscard]] inline sim::ForceAccuracy estimate_accuracy(const std::vector<double>& truth_time,
                                                          const std::vector<double>& truth_force,
                                                          const files::TickLog& ticks, int joint,
                                                          double skip) {
  if (ticks.rows() == 0) ENDOHAPTICS_THROW(Error(ticks.source + ": the tick log has no rows"));
  const std::vector<double>& t_all = ticks.column("time");
  const std::vector<double>& f_all = ticks.column("motor_force" + std::to_string(joint));
  std::vector<double> t_est, f_est;
  for (std::size_t i = 0; i < t_all.size(); ++i) {
    if (t_all[i] >= t_all[0] + skip) {
      t_est.push_back(t_all[i]);
      f_est.push_back(f_all[i]);
    }
  }
  return sim::force_accuracy(truth_time, truth_force, t_est, f_est);
}

//! The run of `truth` and `ticks` for motor slot `joint` (0..3): the estimate
//! ("motor_force<joint>") after the first `skip` s of the tick log against the truth
//! ("force<joint>"). Throws Error when the tick log has no rows or lacks a column.
[[nodiscard]] inline ForceRun force_run(std::string label, const files::Log& truth,
                                        files::TickLog ticks, std::string log_path, int joint,
                                        double skip) {
  const std::string j = std::to_string(joint);
  ForceRun run;
  run.label = std::move(label);
  run.log_path = std::move(log_path);
  run.truth_time.assign(truth.time.data(), truth.time.data() + truth.time.size());
  const Eigen::VectorXd force = truth.signal("force" + j);
  run.truth_force.assign(force.data(), force.data() + force.size());
  run.ticks = std::move(ticks);
  if (run.ticks.rows() == 0) {
    ENDOHAPTICS_THROW(Error(run.log_path + ": the tick log has no rows"));
  }
  run.t0 = run.ticks.column("time")[0];
  run.accuracy = estimate_accuracy(run.truth_time, run.truth_force, run.ticks, joint, skip);
  return run;
}

//! No false success: throws Error naming the run when its fit, correlation or RMSE is not
//! finite (no overlap of the logs after the skip, or a constant force).
inline void require_finite_accuracy(const ForceRun& run) {
  const sim::ForceAccuracy& a = run.accuracy;
  if (!std::isfinite(a.fit_percent) || !std::isfinite(a.correlation) || !std::isfinite(a.rmse)) {
    ENDOHAPTICS_THROW(Error(run.label + ": the force accuracy is not finite (fit " +
                            endohaptics::detail::format_number(a.fit_percent) + " %, correlation " +
                            endohaptics::detail::format_number(a.correlation) +
                            "): no overlap of the logs after --skip, or a constant force"));
  }
}

//! One panel per run: true force, estimate and stylus |F| (N) over time since the run's first
//! tick (s).
[[nodiscard]] inline PlotFigure forces_figure(const std::vector<ForceRun>& runs, int joint) {
  const std::string j = std::to_string(joint);
  PlotFigure figure;
  figure.panel_height = 350;
  for (const ForceRun& run : runs) {
    PlotPanel& panel = figure.panels.emplace_back();
    panel.title =
        run.label + ": motor " + j + ", true external force (emulator) vs estimate (bridge)";
    panel.x_label = "time (s)";
    panel.y_label = "force (N)";
    panel.key = KeyPlacement::top_left;
    PlotSeries truth, estimate, stylus;
    truth.title = "true";
    estimate.title = "estimated (" + run.label + ")";
    truth.line_width = estimate.line_width = 2;
    stylus.title = "stylus |F|";
    for (std::size_t i = 0; i < run.truth_time.size(); ++i) {
      truth.add(run.truth_time[i] - run.t0, run.truth_force[i]);
    }
    const auto& t = run.ticks.column("time");
    const auto& f = run.ticks.column("motor_force" + j);
    const auto& fx = run.ticks.column("stylus_fx");
    const auto& fy = run.ticks.column("stylus_fy");
    const auto& fz = run.ticks.column("stylus_fz");
    for (std::size_t i = 0; i < t.size(); ++i) {
      estimate.add(t[i] - run.t0, f[i]);
      stylus.add(t[i] - run.t0, std::sqrt(fx[i] * fx[i] + fy[i] * fy[i] + fz[i] * fz[i]));
    }
    panel.series = {std::move(truth), std::move(estimate), std::move(stylus)};
  }
  return figure;
}

//! Histogram of the run's tick-to-tick periods in 5 us bins (log scale).
[[nodiscard]] inline PlotFigure period_figure(const ForceRun& run) {
  constexpr double bin = 5.0;  // us
  std::map<double, int> counts;
  const auto& t = run.ticks.column("time");
  for (std::size_t i = 1; i < t.size(); ++i) {
    ++counts[bin * std::floor((t[i] - t[i - 1]) * 1e6 / bin + 0.5)];
  }
  PlotFigure figure;
  figure.panel_height = 350;
  PlotPanel& panel = figure.panels.emplace_back();
  panel.title = "Bridge tick period (tick to tick), " + run.label;
  panel.x_label = "period (us)";
  panel.y_label = "ticks";
  panel.log_y = true;
  panel.key = KeyPlacement::none;
  PlotSeries& boxes = panel.series.emplace_back();
  boxes.style = PlotStyle::boxes;
  boxes.box_width = bin;
  for (const auto& [period, count] : counts) boxes.add(period, count);
  return figure;
}

// ---------------------------------------------------------------------------------------------
// Every motor, and the stylus force against the ideal one.

//! One motor's estimate against its true force.
struct JointScore {
  int motor = 0;                                  //!< motor slot, 0..3
  protocol::Motor joint = protocol::Motor::roll;  //!< the tool joint it drives (motor_order)
  bool rendered = false;  //!< its channel's mapping.force_scale is not 0: the stylus renders it
  sim::ForceAccuracy accuracy;  //!< as ForceRun::accuracy
};

//! The stylus force the bridge rendered against the ideal one, and in free motion.
struct StylusScore {
  //! Ticks compared: after --skip, inside the truth log's span, theta known (ThetaSource).
  std::size_t ticks = 0;
  //! N, sqrt(mean |F_rendered - F_ideal|^2) over those ticks (3-D vector difference).
  double rmse = std::numeric_limits<double>::quiet_NaN();
  //! N, the same RMS with the ideal force made of the bridge's own estimate (motor_force<j>)
  //! instead of the truth: ~0 when the report maps as the bridge did (its --config, theta, no
  //! passivity damping); larger when the configuration differs or theta is not known.
  double replay_rmse = std::numeric_limits<double>::quiet_NaN();
  double rendered_peak = 0.0;    //!< N, max |F_rendered| over those ticks
  double ideal_peak = 0.0;       //!< N, max |F_ideal| over those ticks
  std::size_t theta_logged = 0;  //!< of those, ticks whose theta is ThetaSource::logged
  //! Ticks after --skip inside the truth log's span left out: theta ThetaSource::unknown.
  std::size_t theta_unknown = 0;
  //! N, sqrt(mean |F_rendered|^2) in free motion: over a free-space run's ticks after --skip
  //! (free_motion_rms), else over this run's ticks at which every true force is 0.
  double free_rms = std::numeric_limits<double>::quiet_NaN();
  std::size_t free_ticks = 0;  //!< ticks free_rms is over (0: none, free_rms nan)
  std::string free_source;     //!< what free_rms is over, for the report
};

//! A run scored at every motor and at the stylus.
struct RunScores {
  std::string label;               //!< the run's name in the report
  std::vector<JointScore> joints;  //!< motor slots 0..3
  StylusScore stylus;              //!< the stylus force
};

//! The ideal stylus force of one tick: what the bridge would have rendered with a perfect force
//! sensor. `true_force` (motor order, N, along +setpoint) through the bridge's own eq. 5.8,
//! `mapper.map_force` at `theta` (mapping.force_scale, channel_limit, force_limit; zero when it
//! refuses), times the tick's ramp `ramp` (the tick log's force_scale: 0 when the loop rendered
//! nothing), then limited to `max_stylus_force` (safety.max_stylus_force), as TeleopLoop::tick
//! does. Without the passivity layer (its operator-side damping acts on the estimate; the ideal
//! is before it).
[[nodiscard]] inline Eigen::Vector3d ideal_stylus_force(
    const kinematics::CylindricalMapper<double>& mapper, const estimation::MotorVector& true_force,
    double theta, double ramp, double max_stylus_force) noexcept {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  if (!mapper.map_force(true_force, theta, force).ok()) force.setZero();
  force *= ramp;
  const double norm = force.norm();
  if (!std::isfinite(norm)) {
    force.setZero();
  } else if (norm > max_stylus_force) {
    force *= max_stylus_force / norm;
  }
  return force;
}

//! Where a tick's stylus angle theta came from (stylus_theta).
enum class ThetaSource : std::uint8_t {
  logged,         //!< the tick log's stylus_theta (the mapper's theta, exact)
  roll_setpoint,  //!< eq. 5.9 inverted on the roll setpoint sent
  //! Not known: the roll setpoint was at a limit of its range, or moved by more than half the
  //! setpoint rate limit's step (over the time since the previous tick, at most 1 ms) since the
  //! previous tick: it may lag the stylus (e.g. theta turns by pi when the stylus crosses the
  //! waist axis).
  unknown,
};

//! Per tick of a log, the stylus angle theta (rad) at which the bridge mapped the force.
struct StylusTheta {
  std::vector<double> theta;        //!< rad, one per tick (NaN where unknown)
  std::vector<ThetaSource> source;  //!< one per tick
};

//! The stylus angle of each tick of `ticks`: the log's "stylus_theta" where it has that column
//! with a finite value, else eq. 5.9 inverted on the roll setpoint sent, (setpoint - b_roll) /
//! a_roll, exact unless the setpoint was range- or rate-limited (ThetaSource::unknown) or held
//! back by the passivity layer (TDPA: not detected). `config` is the bridge's. Throws Error when a
//! column is missing.
[[nodiscard]] inline StylusTheta stylus_theta(const files::TickLog& ticks,
                                              const files::BridgeConfig& config) {
  const auto& mapping = config.mapping;
  const auto& safety = config.loop.safety;
  int roll_motor = 0;
  for (std::size_t m = 0; m < mapping.motor_order.size(); ++m) {
    if (mapping.motor_order[m] == protocol::Motor::roll) roll_motor = static_cast<int>(m);
  }
  const auto roll = static_cast<Eigen::Index>(protocol::Motor::roll);
  const double lower = std::max(mapping.lower[roll], safety.joint_lower[roll_motor]);
  const double upper = std::min(mapping.upper[roll], safety.joint_upper[roll_motor]);
  const std::vector<double>& time = ticks.column("time");
  const std::vector<double>& setpoint = ticks.column("setpoint" + std::to_string(roll_motor));
  const std::vector<double>* logged =
      ticks.has("stylus_theta") ? &ticks.column("stylus_theta") : nullptr;
  StylusTheta out;
  out.theta.resize(setpoint.size());
  out.source.resize(setpoint.size());
  constexpr double tolerance = 1e-6;  // rad: the log's 7 significant digits
  for (std::size_t i = 0; i < setpoint.size(); ++i) {
    if (logged != nullptr && std::isfinite((*logged)[i])) {
      out.theta[i] = (*logged)[i];
      out.source[i] = ThetaSource::logged;
      continue;
    }
    const bool at_limit = setpoint[i] <= lower + tolerance || setpoint[i] >= upper - tolerance;
    // The limiter's step is max_setpoint_rate x the tick's dt, dt at most one period (1 ms at
    // the tested --rate 1000): a long gap in the log does not allow a longer step.
    const bool moving =
        i > 0 && std::fabs(setpoint[i] - setpoint[i - 1]) >
                     0.5 * safety.max_setpoint_rate * std::min(time[i] - time[i - 1], 1e-3);
    if (at_limit || moving) {
      out.theta[i] = std::numeric_limits<double>::quiet_NaN();
      out.source[i] = ThetaSource::unknown;
    } else {
      out.theta[i] = (setpoint[i] - mapping.b_roll) / mapping.a_roll;
      out.source[i] = ThetaSource::roll_setpoint;
    }
  }
  return out;
}

namespace detail::force_report {

//! The truth log's force0..3 (N, motor order), each checked as sim::force_accuracy checks.
inline std::array<std::vector<double>, 4> truth_forces(const files::Log& truth,
                                                       std::vector<double>& time) {
  time.assign(truth.time.data(), truth.time.data() + truth.time.size());
  std::array<std::vector<double>, 4> forces;
  for (int j = 0; j < 4; ++j) {
    const Eigen::VectorXd f = truth.signal("force" + std::to_string(j));
    forces[static_cast<std::size_t>(j)].assign(f.data(), f.data() + f.size());
    sim::detail::check_series(time, forces[static_cast<std::size_t>(j)], "truth");
  }
  return forces;
}

//! RMS of the stylus force magnitude over the rows of `ticks` that `use` accepts (N); `count`
//! says how many (0: NaN).
template <typename Use>
double stylus_rms(const files::TickLog& ticks, Use&& use, std::size_t& count) {
  const auto& fx = ticks.column("stylus_fx");
  const auto& fy = ticks.column("stylus_fy");
  const auto& fz = ticks.column("stylus_fz");
  double sum = 0.0;
  count = 0;
  for (std::size_t i = 0; i < ticks.rows(); ++i) {
    if (!use(i)) continue;
    sum += fx[i] * fx[i] + fy[i] * fy[i] + fz[i] * fz[i];
    ++count;
  }
  return count > 0 ? std::sqrt(sum / static_cast<double>(count))
                   : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace detail::force_report

//! Scores run `label` at every motor slot (its estimate against the truth, after `skip` s of the
//! tick log, as force_run) and at the stylus: the rendered force (stylus_fx/fy/fz) against
//! ideal_stylus_force of the true forces interpolated (linearly) at each tick's time, over the
//! ticks after `skip` inside the truth log's span; `config` is the bridge's configuration of the
//! run (its mapping and safety.max_stylus_force). The free-motion figure is over the ticks whose
//! true forces are all 0 (replace it with free_motion_rms). Throws Error on a missing column, an
//! empty log or no overlap.
[[nodiscard]] inline RunScores score_run(std::string label, const files::Log& truth,
                                         const files::TickLog& ticks,
                                         const files::BridgeConfig& config, double skip) {
  namespace fr = detail::force_report;
  RunScores scores;
  scores.label = std::move(label);
  std::vector<double> truth_time;
  const auto forces = fr::truth_forces(truth, truth_time);
  const std::array<bool, 4> fed = files::force_feedback_motors(config.mapping);
  for (int m = 0; m < 4; ++m) {
    JointScore& j = scores.joints.emplace_back();
    j.motor = m;
    j.joint = config.mapping.motor_order[static_cast<std::size_t>(m)];
    j.rendered = fed[static_cast<std::size_t>(j.joint)];
    j.accuracy = estimate_accuracy(truth_time, forces[static_cast<std::size_t>(m)], ticks, m, skip);
  }
  // The stylus: the ticks after the skip inside the truth's span, in time order.
  const std::vector<double>& t = ticks.column("time");
  const std::vector<double>& ramp = ticks.column("force_scale");
  const StylusTheta theta = stylus_theta(ticks, config);
  std::vector<std::size_t> rows;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] >= t[0] + skip && t[i] >= truth_time.front() && t[i] <= truth_time.back()) {
      rows.push_back(i);
    }
  }
  if (rows.empty()) {
    ENDOHAPTICS_THROW(
        Error(ticks.source + ": no tick after --skip inside the truth log's time span"));
  }
  Eigen::VectorXd grid(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t k = 0; k < rows.size(); ++k) grid[static_cast<Eigen::Index>(k)] = t[rows[k]];
  std::array<Eigen::VectorXd, 4> true_at;
  for (std::size_t m = 0; m < 4; ++m) {
    true_at[m] = sim::detail::interpolate(truth_time, forces[m], grid);
  }
  const kinematics::CylindricalMapper<double> mapper(config.mapping);
  const auto& fx = ticks.column("stylus_fx");
  const auto& fy = ticks.column("stylus_fy");
  const auto& fz = ticks.column("stylus_fz");
  std::array<const std::vector<double>*, 4> estimate{};
  for (std::size_t m = 0; m < 4; ++m) {
    estimate[m] = &ticks.column("motor_force" + std::to_string(m));
  }
  StylusScore& s = scores.stylus;
  std::vector<bool> contact_free(t.size(), false);
  double sum = 0.0, replay_sum = 0.0;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const std::size_t i = rows[k];
    const auto e = static_cast<Eigen::Index>(k);
    const estimation::MotorVector f(true_at[0][e], true_at[1][e], true_at[2][e], true_at[3][e]);
    contact_free[i] = (f.array() == 0.0).all();
    if (theta.source[i] == ThetaSource::unknown) {
      ++s.theta_unknown;
      continue;
    }
    s.theta_logged += theta.source[i] == ThetaSource::logged ? 1u : 0u;
    ++s.ticks;
    const Eigen::Vector3d ideal =
        ideal_stylus_force(mapper, f, theta.theta[i], ramp[i], config.loop.safety.max_stylus_force);
    const Eigen::Vector3d rendered(fx[i], fy[i], fz[i]);
    sum += (rendered - ideal).squaredNorm();
    const estimation::MotorVector est((*estimate[0])[i], (*estimate[1])[i], (*estimate[2])[i],
                                      (*estimate[3])[i]);
    replay_sum += (rendered - ideal_stylus_force(mapper, est, theta.theta[i], ramp[i],
                                                 config.loop.safety.max_stylus_force))
                      .squaredNorm();
    s.rendered_peak = std::max(s.rendered_peak, rendered.norm());
    s.ideal_peak = std::max(s.ideal_peak, ideal.norm());
  }
  if (s.ticks > 0) {
    s.rmse = std::sqrt(sum / static_cast<double>(s.ticks));
    s.replay_rmse = std::sqrt(replay_sum / static_cast<double>(s.ticks));
  }
  s.free_rms = fr::stylus_rms(
      ticks, [&](std::size_t i) { return contact_free[i]; }, s.free_ticks);
  s.free_source = "the ticks of " + scores.label + " without contact (every true force 0)";
  return scores;
}

//! The free-motion figure of `score` from `free_log`, the bridge's tick log of a run in free
//! space (the emulator's --environment free: every true force 0): the RMS of the rendered stylus
//! force magnitude over its ticks after the first `skip` s. Throws Error when no tick is left.
inline void free_motion_rms(StylusScore& score, const files::TickLog& free_log, double skip) {
  if (free_log.rows() == 0) {
    ENDOHAPTICS_THROW(Error(free_log.source + ": the tick log has no rows"));
  }
  const std::vector<double>& t = free_log.column("time");
  std::size_t count = 0;
  const double rms = detail::force_report::stylus_rms(
      free_log, [&](std::size_t i) { return t[i] >= t[0] + skip; }, count);
  if (count == 0) {
    ENDOHAPTICS_THROW(Error(free_log.source + ": no tick after --skip for the free-motion RMS"));
  }
  score.free_rms = rms;
  score.free_ticks = count;
  score.free_source = free_log.source + " (free space)";
}

namespace detail::force_report {

//! snprintf into a string (the report's lines are short).
template <typename... Values>
std::string printf_line(const char* format, Values... values) {
  char text[512];
  std::snprintf(text, sizeof text, format, values...);
  return text;
}

}  // namespace detail::force_report

//! Checks the counts of endohaptics-force-report's repeated options: one --truth and one --log
//! per run, --label none or one per run, --config none, one (every run) or one per run,
//! --free-log none or one per run. Throws Error naming the counts.
inline void check_run_options(std::size_t truths, std::size_t logs, std::size_t labels,
                              std::size_t configs, std::size_t free_logs) {
  if (truths != logs || (labels != 0 && labels != logs) || (configs > 1 && configs != logs) ||
      (free_logs != 0 && free_logs != logs)) {
    ENDOHAPTICS_THROW(Error(
        "give one --truth and one --log per run, and one --label (if any) per run, one --config "
        "for all runs or one per run, one --free-log (if any) per run: " +
        std::to_string(truths) + " --truth, " + std::to_string(logs) + " --log, " +
        std::to_string(labels) + " --label, " + std::to_string(configs) + " --config, " +
        std::to_string(free_logs) + " --free-log"));
  }
}

//! The lines printed for each run as it is read: its estimate at motor `joint` (fit, correlation,
//! RMSE, delay, fit and correlation once delayed, peaks) and its tick-to-tick periods
//! (files::tick_period_stats: time stamps taken as each tick ended).
[[nodiscard]] inline std::string run_details(const ForceRun& run, int joint) {
  namespace fr = detail::force_report;
  const sim::ForceAccuracy& a = run.accuracy;
  const auto periods = files::tick_period_stats(run.ticks).period();
  return run.label +
         fr::printf_line(
             ": force feedback (motor %d) over %.1f s: fit %.1f %%, correlation %.3f, RMSE %.3f "
             "N, delay of the estimate %.0f ms (fit %.1f %%, correlation %.3f once delayed); peak "
             "true %.2f N, peak estimated %.2f N\n",
             joint, a.span, a.fit_percent, a.correlation, a.rmse, a.delay * 1e3,
             a.fit_percent_at_delay, a.correlation_at_delay, a.truth_peak, a.estimate_peak) +
         run.label +
         fr::printf_line(
             ": tick periods: %zu ticks, median %.1f us, p1 %.1f us, p99 %.1f us, max %.1f us\n",
             run.ticks.rows(), periods.quantile(0.5) * 1e6, periods.quantile(0.01) * 1e6,
             periods.quantile(0.99) * 1e6, periods.max() * 1e6);
}

//! "LABEL: fit X%, correlation Y, RMSE Z N, delay D ms, peak P N (true T N)": one run's line at
//! its --joint (the report's last lines without --all-joints).
[[nodiscard]] inline std::string summary_line(const std::string& label,
                                              const sim::ForceAccuracy& a) {
  return label + detail::force_report::printf_line(
                     ": fit %.1f%%, correlation %.3f, RMSE %.3f N, delay %.0f ms, peak %.2f N "
                     "(true %.2f N)",
                     a.fit_percent, a.correlation, a.rmse, a.delay * 1e3, a.estimate_peak,
                     a.truth_peak);
}

//! "LABEL, JOINT: fit X%, ..." (summary_line's figures, the tool joint's name after the label).
[[nodiscard]] inline std::string joint_line(const std::string& label, const JointScore& j) {
  return summary_line(label + ", " + std::string(protocol::to_string(j.joint)), j.accuracy);
}

//! "stylus: RMSE R N against the ideal force, free motion RMS F N", with "LABEL, " in front
//! when `label` is not empty.
[[nodiscard]] inline std::string stylus_line(const std::string& label, const StylusScore& s) {
  return (label.empty() ? "" : label + ", ") +
         detail::force_report::printf_line(
             "stylus: RMSE %.3f N against the ideal force, free motion RMS %.3f N", s.rmse,
             s.free_rms);
}

//! The lines before the last ones: what the stylus figures are over.
[[nodiscard]] inline std::string stylus_details(const std::string& label, const StylusScore& s) {
  namespace fr = detail::force_report;
  std::string out = label + fr::printf_line(
                                ": stylus against the ideal force over %zu ticks: RMSE %.3f N, "
                                "peak rendered %.2f N, peak ideal %.2f N; the mapping replayed "
                                "on the estimate: RMSE %.4f N; theta ",
                                s.ticks, s.rmse, s.rendered_peak, s.ideal_peak, s.replay_rmse);
  out += fr::printf_line(
      "logged at %zu ticks, from the roll setpoint at %zu, unknown (left out) at %zu",
      s.theta_logged, s.ticks - std::min(s.ticks, s.theta_logged), s.theta_unknown);
  out += "\n" + label +
         fr::printf_line(": free motion: RMS %.3f N over %zu ticks of ", s.free_rms, s.free_ticks) +
         s.free_source + "\n";
  return out;
}

}  // namespace endohaptics::workflow
