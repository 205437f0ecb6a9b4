//! @file
//! endohaptics-force-report's runs: the bridge's per-tick log (estimated joint force, stylus
//! force; files/tick_log.hpp) against the emulator's truth log (true external force, N) of the
//! same teleoperation, compared on a common time base (sim::force_accuracy: fit %, correlation,
//! RMSE, delay in s, peaks), and the plots of them (workflow/gnuplot.hpp).
//! Configuration time: allocates, throws endohaptics::Error.
#pragma once

#include <cmath>
#include <cstddef>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/files/csv_log.hpp"
#include "endohaptics/files/log.hpp"
#include "endohaptics/files/tick_log.hpp"
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
  const std::vector<double>& t_all = run.ticks.column("time");
  const std::vector<double>& f_all = run.ticks.column("motor_force" + j);
  run.t0 = t_all[0];
  std::vector<double> t_est, f_est;
  for (std::size_t i = 0; i < t_all.size(); ++i) {
    if (t_all[i] >= t_all[0] + skip) {
      t_est.push_back(t_all[i]);
      f_est.push_back(f_all[i]);
    }
  }
  run.accuracy = sim::force_accuracy(run.truth_time, run.truth_force, t_est, f_est);
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

}  // namespace endohaptics::workflow
