// endohaptics-force-report: how good was the force feedback? Compares the bridge's per-tick log
// (estimated joint force, stylus force) with the emulator's truth log (true contact force),
// prints fit %, correlation and delay (sim::force_accuracy), the tick period distribution
// (teleop::LoopStats), and plots both with gnuplot when it is installed. The tick log's columns are
// found by name (files::read_tick_log).
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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"endohaptics force report: bridge log vs emulator truth"};
  std::string truth_path, log_path, plot_dir;
  int joint = 2;
  double skip = 0.5;
  app.add_option("--truth", truth_path, "emulator truth log (--truth-log)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--log", log_path, "bridge tick log (--log)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--joint", joint, "motor slot to compare (0 roll, 1 pitch, 2 clamp1, 3 clamp2)")
      ->check(examples::number_in(0, 3))
      ->capture_default_str();
  app.add_option("--skip", skip, "seconds at the start of the bridge log to leave out (start-up)")
      ->check(examples::number_in(0.0, 1e7))
      ->capture_default_str();
  app.add_option("--plot-dir", plot_dir, "write forces.png and period.png here (needs gnuplot)");
  CLI11_PARSE(app, argc, argv);

  try {
    const files::Log truth = read_truth(truth_path);
    const files::TickLog ticks = files::read_tick_log(log_path);
    if (ticks.dropped > 0) fmt::print("force-report: {}", ticks.report());
    if (ticks.rows() == 0) throw endohaptics::Error(log_path + ": the tick log has no rows");
    const std::string j = std::to_string(joint);
    const Eigen::VectorXd t_truth = truth.time;
    const Eigen::VectorXd f_truth = truth.signal("force" + j);
    const std::vector<double>& t_all = ticks.column("time");
    const std::vector<double>& f_all = ticks.column("motor_force" + j);
    const double t0 = t_all[0] + skip;
    std::vector<double> t_est, f_est;
    for (std::size_t i = 0; i < t_all.size(); ++i) {
      if (t_all[i] >= t0) {
        t_est.push_back(t_all[i]);
        f_est.push_back(f_all[i]);
      }
    }
    const auto a = sim::force_accuracy(to_vector(t_truth), to_vector(f_truth), t_est, f_est);
    fmt::print(
        "force feedback (motor {}) over {:.1f} s: fit {:.1f} %, correlation {:.3f}, RMSE {:.3f} N, "
        "delay of the estimate {:.0f} ms (fit {:.1f} %, correlation {:.3f} once delayed); peak "
        "true {:.2f} N, peak estimated {:.2f} N\n",
        joint, a.span, a.fit_percent, a.correlation, a.rmse, a.delay * 1e3, a.fit_percent_at_delay,
        a.correlation_at_delay, a.truth_peak, a.estimate_peak);

    // Tick-to-tick periods from the bridge log (time stamps taken as each tick ended).
    const endohaptics::teleop::LoopStats stats = files::tick_period_stats(ticks);
    const auto& periods = stats.period();
    fmt::print(
        "tick periods: {} ticks, median {:.1f} us, p1 {:.1f} us, p99 {:.1f} us, max {:.1f} us\n",
        t_all.size(), periods.quantile(0.5) * 1e6, periods.quantile(0.01) * 1e6,
        periods.quantile(0.99) * 1e6, periods.max() * 1e6);

    if (!plot_dir.empty()) {
      std::filesystem::create_directories(plot_dir);
      const std::string forces = plot_dir + "/forces.png";
      const std::string period = plot_dir + "/period.png";
      // gnuplot reads the bridge log itself: by the column numbers the reader found by name.
      const auto col = [&ticks](const std::string& name) { return ticks.index(name) + 1; };
      const std::string script = fmt::format(
          "set terminal pngcairo size 1400,600 noenhanced\n"
          "set datafile separator ','\nset datafile columnheaders\n"
          "set output '{0}'\n"
          "set title 'Force feedback, motor {4}: true contact force (emulator) vs estimate "
          "(bridge)'\n"
          "set xlabel 'time (s)'; set ylabel 'force (N)'; set grid; set key top left\n"
          "t0 = {5:.9f}\n"
          "plot '{2}' using (column('time')-t0):(column('force{4}')) with lines lw 2 title "
          "'true', "
          "'{3}' using (${6}-t0):{7} with lines lw 2 title 'estimated', "
          "'{3}' using (${6}-t0):(sqrt(${8}**2+${9}**2+${10}**2)) with lines title "
          "'stylus |F|'\n"
          "set output '{1}'\n"
          "set title 'Bridge tick period (tick to tick)'\n"
          "set xlabel 'period (us)'; set ylabel 'ticks'; set logscale y; unset key\n"
          "binwidth = 5; bin(x) = binwidth * floor(x / binwidth + 0.5)\n"
          "set style fill solid 0.6\n"
          "prev = {5:.9f}\n"
          "plot '{3}' every ::1 using (d = (${6} - prev) * 1e6, prev = ${6}, bin(d)):(1) "
          "smooth frequency with boxes\n",
          forces, period, truth_path, log_path, joint, t_all[0], col("time"),
          col("motor_force" + j), col("stylus_fx"), col("stylus_fy"), col("stylus_fz"));
      if (plot(script)) {
        fmt::print("plots: {} and {}\n", forces, period);
      } else {
        fmt::print("plots: gnuplot failed or is not installed (apt-get install gnuplot-nox)\n");
      }
    }
    // No false success: results that are not finite, or a report that could not be written.
    if (!std::isfinite(a.fit_percent) || !std::isfinite(a.correlation) || !std::isfinite(a.rmse)) {
      throw endohaptics::Error("the force accuracy is not finite (fit " +
                               fmt::format("{}", a.fit_percent) + " %, correlation " +
                               fmt::format("{}", a.correlation) +
                               "): no overlap of the logs after --skip, or a constant force");
    }
    endohaptics::workflow::require_written(stdout, "standard output");
    return 0;
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
}
