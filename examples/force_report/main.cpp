// endohaptics-force-report: how good was the force feedback? For each run (--truth/--log pairs,
// e.g. the 2016 preset and an identified model) compares the bridge's per-tick log (estimated
// joint force, stylus force) with the emulator's truth log (true external force), prints fit %,
// correlation, RMSE, delay and peaks (sim::force_accuracy) and the tick periods
// (teleop::LoopStats), one panel per run in one plot, then one summary line per run. The tick
// log's columns are found by name (files::read_tick_log); the runs and plots are
// workflow/force_report.hpp's.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <endohaptics/files/tick_log.hpp>
#include <endohaptics/workflow/command_line.hpp>
#include <endohaptics/workflow/force_report.hpp>
#include <endohaptics/workflow/gnuplot.hpp>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "../cli_numbers.hpp"

namespace files = endohaptics::files;
namespace wf = endohaptics::workflow;

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
    std::vector<wf::ForceRun> runs;
    for (std::size_t r = 0; r < log_paths.size(); ++r) {
      const files::Log truth = wf::read_truth_log(truth_paths[r]);
      if (truth.report.dropped() > 0) {
        fmt::print("force-report: {}: {} rows dropped\n{}", truth_paths[r], truth.report.dropped(),
                   truth.report.to_string());
      }
      files::TickLog ticks = files::read_tick_log(log_paths[r]);
      if (ticks.dropped > 0) fmt::print("force-report: {}", ticks.report());
      const wf::ForceRun& run = runs.emplace_back(
          wf::force_run(labels.empty() ? "run " + std::to_string(r + 1) : labels[r], truth,
                        std::move(ticks), log_paths[r], joint, skip));
      const auto& a = run.accuracy;
      fmt::print(
          "{}: force feedback (motor {}) over {:.1f} s: fit {:.1f} %, correlation {:.3f}, RMSE "
          "{:.3f} N, delay of the estimate {:.0f} ms (fit {:.1f} %, correlation {:.3f} once "
          "delayed); peak true {:.2f} N, peak estimated {:.2f} N\n",
          run.label, joint, a.span, a.fit_percent, a.correlation, a.rmse, a.delay * 1e3,
          a.fit_percent_at_delay, a.correlation_at_delay, a.truth_peak, a.estimate_peak);
      // Tick-to-tick periods from the bridge log (time stamps taken as each tick ended).
      const auto stats = files::tick_period_stats(run.ticks);
      const auto& periods = stats.period();
      fmt::print(
          "{}: tick periods: {} ticks, median {:.1f} us, p1 {:.1f} us, p99 {:.1f} us, max {:.1f} "
          "us\n",
          run.label, run.ticks.rows(), periods.quantile(0.5) * 1e6, periods.quantile(0.01) * 1e6,
          periods.quantile(0.99) * 1e6, periods.max() * 1e6);
      wf::require_finite_accuracy(run);  // no false success
    }
    if (!plot_dir.empty()) {  // asked for: a plot that fails fails the run
      std::filesystem::create_directories(plot_dir);
      const std::filesystem::path forces = std::filesystem::path(plot_dir) / "forces.png";
      const std::filesystem::path period = std::filesystem::path(plot_dir) / "period.png";
      wf::write_png(wf::forces_figure(runs, joint), forces);
      wf::write_png(wf::period_figure(runs.back()), period);
      fmt::print("plots: {} and {}\n", forces.string(), period.string());
    }
    // Last: one line per run, side by side (./run demo ends with these).
    for (const wf::ForceRun& run : runs) {
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
