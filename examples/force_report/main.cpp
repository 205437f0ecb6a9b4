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
#include <filesystem>
#include <string>
#include <vector>

#include "../cli_numbers.hpp"

namespace files = endohaptics::files;
namespace sim = endohaptics::sim;

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

bool plot(const std::string& script) {
  std::FILE* gp = popen("gnuplot 2>&1", "w");
  if (gp == nullptr) return false;
  std::fputs(script.c_str(), gp);
  return pclose(gp) == 0;
}

// One run: the emulator's truth log and the bridge's tick log of the same teleoperation.
struct Run {
  std::string label, truth_path, log_path;
  files::TickLog ticks;
  sim::ForceAccuracy accuracy;
  double t0 = 0.0;  // the tick log's first time stamp
};

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
                 "write forces.png (every run) and period.png (the last) here (needs gnuplot)");
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
      const auto& a = run.accuracy = sim::force_accuracy(
          to_vector(truth.time), to_vector(truth.signal("force" + j)), t_est, f_est);
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

    if (!plot_dir.empty()) {
      std::filesystem::create_directories(plot_dir);
      const std::string forces = plot_dir + "/forces.png";
      const std::string period = plot_dir + "/period.png";
      // One panel per run: truth, estimate and stylus force. gnuplot reads the logs itself, by
      // the column numbers the reader found by name.
      std::string script = fmt::format(
          "set terminal pngcairo size 1400,{0} noenhanced\n"
          "set datafile separator ','\nset datafile columnheaders\n"
          "set output '{1}'\nset multiplot layout {2},1\n"
          "set xlabel 'time (s)'; set ylabel 'force (N)'; set grid; set key top left\n",
          350 * runs.size() + 100, forces, runs.size());
      for (const Run& run : runs) {
        const auto col = [&run](const std::string& name) { return run.ticks.index(name) + 1; };
        script += fmt::format(
            "set title '{0}: motor {1}, true external force (emulator) vs estimate (bridge)'\n"
            "t0 = {2:.9f}\n"
            "plot '{3}' using (column('time')-t0):(column('force{1}')) with lines lw 2 title "
            "'true', '{4}' using (${5}-t0):{6} with lines lw 2 title 'estimated ({0})', "
            "'{4}' using (${5}-t0):(sqrt(${7}**2+${8}**2+${9}**2)) with lines title "
            "'stylus |F|'\n",
            run.label, joint, run.t0, run.truth_path, run.log_path, col("time"),
            col("motor_force" + j), col("stylus_fx"), col("stylus_fy"), col("stylus_fz"));
      }
      const Run& last = runs.back();
      const auto time_col = last.ticks.index("time") + 1;
      script += fmt::format(
          "unset multiplot\nset output '{0}'\n"
          "set title 'Bridge tick period (tick to tick), {1}'\n"
          "set xlabel 'period (us)'; set ylabel 'ticks'; set logscale y; unset key\n"
          "binwidth = 5; bin(x) = binwidth * floor(x / binwidth + 0.5)\n"
          "set style fill solid 0.6\n"
          "prev = {2:.9f}\n"
          "plot '{3}' every ::1 using (d = (${4} - prev) * 1e6, prev = ${4}, bin(d)):(1) "
          "smooth frequency with boxes\n",
          period, last.label, last.t0, last.log_path, time_col);
      if (plot(script)) {
        fmt::print("plots: {} and {}\n", forces, period);
      } else {
        fmt::print("plots: gnuplot failed or is not installed (apt-get install gnuplot-nox)\n");
      }
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
    endohaptics::workflow::require_written(stdout, "standard output");
    return 0;
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
}
