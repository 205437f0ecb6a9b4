// endohaptics-force-report: how good was the force feedback? For each run (--truth/--log pairs,
// e.g. the 2016 preset and an identified model) compares the bridge's per-tick log (estimated
// joint force, stylus force) with the emulator's truth log (true external force), prints fit %,
// correlation, RMSE, delay and peaks (sim::force_accuracy) and the tick periods
// (teleop::LoopStats), one panel per run in one plot, then one summary line per run. The tick
// log's columns are found by name (files::read_tick_log).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <endohaptics/files/log_reader.hpp>
#include <endohaptics/files/tick_log.hpp>
#include <endohaptics/sim/force_accuracy.hpp>
#include <endohaptics/workflow/command_line.hpp>
#include <endohaptics/workflow/gnuplot.hpp>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "../cli_numbers.hpp"

namespace files = endohaptics::files;
namespace sim = endohaptics::sim;
namespace wf = endohaptics::workflow;

namespace {

std::vector<double> to_vector(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

files::Log read_truth(const std::string& path) {
  files::CsvOptions options;
  options.read.rebase_time = false;  // both logs use CLOCK_MONOTONIC: keep them aligned
  files::Log log = files::read_csv(path, options);
  if (log.report.dropped() > 0) {
    fmt::print("force-report: {}: {} rows dropped\n{}", path, log.report.dropped(),
               log.report.to_string());
  }
  return log;
}

// One run: the emulator's truth log and the bridge's tick log of the same teleoperation.
struct Run {
  std::string label, truth_path, log_path;
  std::vector<double> truth_time, truth_force;  // the truth log's time and force of the joint
  files::TickLog ticks;
  sim::ForceAccuracy accuracy;
  double t0 = 0.0;  // the tick log's first time stamp
};

// One panel per run: true force, estimate and stylus force over time since the run's first tick.
wf::PlotFigure forces_figure(const std::vector<Run>& runs, int joint) {
  const std::string j = std::to_string(joint);
  wf::PlotFigure figure;
  figure.panel_height = 350;
  for (const Run& run : runs) {
    wf::PlotPanel& panel = figure.panels.emplace_back();
    panel.title = fmt::format("{}: motor {}, true external force (emulator) vs estimate (bridge)",
                              run.label, joint);
    panel.x_label = "time (s)";
    panel.y_label = "force (N)";
    panel.key = wf::KeyPlacement::top_left;
    wf::PlotSeries truth, estimate, stylus;
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

// Histogram of the run's tick-to-tick periods in 5 us bins.
wf::PlotFigure period_figure(const Run& run) {
  constexpr double bin = 5.0;  // us
  std::map<double, int> counts;
  const auto& t = run.ticks.column("time");
  for (std::size_t i = 1; i < t.size(); ++i) {
    ++counts[bin * std::floor((t[i] - t[i - 1]) * 1e6 / bin + 0.5)];
  }
  wf::PlotFigure figure;
  figure.panel_height = 350;
  wf::PlotPanel& panel = figure.panels.emplace_back();
  panel.title = "Bridge tick period (tick to tick), " + run.label;
  panel.x_label = "period (us)";
  panel.y_label = "ticks";
  panel.log_y = true;
  panel.key = wf::KeyPlacement::none;
  wf::PlotSeries& boxes = panel.series.emplace_back();
  boxes.style = wf::PlotStyle::boxes;
  boxes.box_width = bin;
  for (const auto& [period, count] : counts) boxes.add(period, count);
  return figure;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"endohaptics force report: bridge log vs emulator truth"};
  std::vector<std::string> truth_paths, log_paths, labels;
  std::string plot_dir;
  int joint = 2;
  double skip = 0.5;
  app.add_option("--truth", truth_paths, "emulator truth log (--truth-log); repeat per run")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--log", log_paths, "bridge tick log (--log); repeat per run, same order")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--label", labels, "name of each run in the summary lines (default: run N)");
  app.add_option("--joint", joint, "motor slot to compare (0 roll, 1 pitch, 2 clamp1, 3 clamp2)")
      ->check(examples::number_in(0, 3))
      ->capture_default_str();
  app.add_option("--skip", skip, "seconds at the start of the bridge log to leave out (start-up)")
      ->check(examples::number_in(0.0, 1e7))
      ->capture_default_str();
  app.add_option("--plot-dir", plot_dir,
                 "write forces.png (every run) and period.png (the last) here (needs gnuplot; "
                 "a plot that fails is an error)");
  CLI11_PARSE(app, argc, argv);

  try {
    if (truth_paths.size() != log_paths.size() ||
        (!labels.empty() && labels.size() != log_paths.size())) {
      throw endohaptics::Error(
          "give one --truth and one --log (and one --label, if any) per run: " +
          std::to_string(truth_paths.size()) + " --truth, " + std::to_string(log_paths.size()) +
          " --log, " + std::to_string(labels.size()) + " --label");
    }
    const std::string j = std::to_string(joint);
    std::vector<Run> runs;
    for (std::size_t r = 0; r < log_paths.size(); ++r) {
      Run run;
      run.label = labels.empty() ? "run " + std::to_string(r + 1) : labels[r];
      run.truth_path = truth_paths[r];
      run.log_path = log_paths[r];
      const files::Log truth = read_truth(run.truth_path);
      run.truth_time = to_vector(truth.time);
      run.truth_force = to_vector(truth.signal("force" + j));
      run.ticks = files::read_tick_log(run.log_path);
      if (run.ticks.dropped > 0) fmt::print("force-report: {}", run.ticks.report());
      if (run.ticks.rows() == 0)
        throw endohaptics::Error(run.log_path + ": the tick log has no rows");
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
      const auto& a = run.accuracy =
          sim::force_accuracy(run.truth_time, run.truth_force, t_est, f_est);
      fmt::print(
          "{}: force feedback (motor {}) over {:.1f} s: fit {:.1f} %, correlation {:.3f}, RMSE "
          "{:.3f} N, delay of the estimate {:.0f} ms (fit {:.1f} %, correlation {:.3f} once "
          "delayed); peak true {:.2f} N, peak estimated {:.2f} N\n",
          run.label, joint, a.span, a.fit_percent, a.correlation, a.rmse, a.delay * 1e3,
          a.fit_percent_at_delay, a.correlation_at_delay, a.truth_peak, a.estimate_peak);
      // Tick-to-tick periods from the bridge log (time stamps taken as each tick ended).
      const endohaptics::teleop::LoopStats stats = files::tick_period_stats(run.ticks);
      const auto& periods = stats.period();
      fmt::print(
          "{}: tick periods: {} ticks, median {:.1f} us, p1 {:.1f} us, p99 {:.1f} us, max {:.1f} "
          "us\n",
          run.label, t_all.size(), periods.quantile(0.5) * 1e6, periods.quantile(0.01) * 1e6,
          periods.quantile(0.99) * 1e6, periods.max() * 1e6);
      // No false success: results that are not finite.
      if (!std::isfinite(a.fit_percent) || !std::isfinite(a.correlation) ||
          !std::isfinite(a.rmse)) {
        throw endohaptics::Error(run.label + ": the force accuracy is not finite (fit " +
                                 fmt::format("{}", a.fit_percent) + " %, correlation " +
                                 fmt::format("{}", a.correlation) +
                                 "): no overlap of the logs after --skip, or a constant force");
      }
      runs.push_back(std::move(run));
    }

    if (!plot_dir.empty()) {  // asked for: a plot that fails fails the run
      std::filesystem::create_directories(plot_dir);
      const std::filesystem::path forces = std::filesystem::path(plot_dir) / "forces.png";
      const std::filesystem::path period = std::filesystem::path(plot_dir) / "period.png";
      wf::write_png(forces_figure(runs, joint), forces);
      wf::write_png(period_figure(runs.back()), period);
      fmt::print("plots: {} and {}\n", forces.string(), period.string());
    }
    // Last: one line per run, side by side (./run demo ends with these).
    for (const Run& run : runs) {
      const auto& a = run.accuracy;
      fmt::print(
          "{}: fit {:.1f}%, correlation {:.3f}, RMSE {:.3f} N, delay {:.0f} ms, peak {:.2f} N "
          "(true {:.2f} N)\n",
          run.label, a.fit_percent, a.correlation, a.rmse, a.delay * 1e3, a.estimate_peak,
          a.truth_peak);
    }
    wf::require_written(stdout, "standard output");
    return 0;
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
}
