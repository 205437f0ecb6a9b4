// endohaptics-force-report: how good was the force feedback? For each run (--truth/--log pairs)
// compares the bridge's tick log with the emulator's truth log: fit %, correlation, RMSE, delay,
// peaks and tick periods, one plot panel per run, then one summary line per run; with
// --all-joints also every motor, and the stylus force against the ideal one (eq. 5.8 on the true
// forces, --config as the bridge ran) and in free motion (--free-log). Runs, scores, lines and
// plots are workflow/force_report.hpp's.
#include <fmt/format.h>

#include <cstdio>
#include <endohaptics/files/bridge_config.hpp>
#include <endohaptics/files/tick_log.hpp>
#include <endohaptics/workflow/command_line.hpp>
#include <endohaptics/workflow/force_report.hpp>
#include <endohaptics/workflow/gnuplot.hpp>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "options.hpp"

namespace files = endohaptics::files;
namespace wf = endohaptics::workflow;

int main(int argc, char** argv) {
  force_report::Options o;
  const examples::Parsed parsed = force_report::parse_options(argc, argv, o);
  if (parsed.exit_code) return *parsed.exit_code;
  const auto& [truth_paths, log_paths, labels, config_paths, free_paths, plot_dir, joint, skip,
               all_joints] = o;

  try {
    wf::check_run_options(truth_paths.size(), log_paths.size(), labels.size(), config_paths.size(),
                          free_paths.size());
    std::vector<wf::ForceRun> runs;
    std::vector<wf::RunScores> scores;
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
      fmt::print("{}", wf::run_details(run, joint));
      wf::require_finite_accuracy(run);  // no false success
      if (!all_joints) continue;
      const files::BridgeConfig config =
          config_paths.empty()
              ? files::BridgeConfig{}
              : files::load_bridge_config(config_paths[std::min(r, config_paths.size() - 1)]);
      wf::RunScores& s =
          scores.emplace_back(wf::score_run(run.label, truth, run.ticks, config, skip));
      if (!free_paths.empty())
        wf::free_motion_rms(s.stylus, files::read_tick_log(free_paths[r]), skip);
      fmt::print("{}", wf::stylus_details(run.label, s.stylus));
    }
    if (!plot_dir.empty()) {  // asked for: a plot that fails fails the run
      std::filesystem::create_directories(plot_dir);
      const std::filesystem::path forces = std::filesystem::path(plot_dir) / "forces.png";
      const std::filesystem::path period = std::filesystem::path(plot_dir) / "period.png";
      wf::write_png(wf::forces_figure(runs, joint), forces);
      wf::write_png(wf::period_figure(runs.back()), period);
      fmt::print("plots: {} and {}\n", forces.string(), period.string());
    }
    // Last: one line per run at --joint, side by side; with --all-joints instead each run's
    // rendered joints and its stylus line ("LABEL, " in front with several runs).
    for (std::size_t r = 0; r < runs.size() && !all_joints; ++r) {
      fmt::print("{}\n", wf::summary_line(runs[r].label, runs[r].accuracy));
    }
    for (const wf::RunScores& s : scores) {
      for (const wf::JointScore& j : s.joints) {
        if (j.rendered) fmt::print("{}\n", wf::joint_line(s.label, j));
      }
      fmt::print("{}\n", wf::stylus_line(scores.size() > 1 ? s.label : "", s.stylus));
    }
    wf::require_written(stdout, "standard output");
    return 0;
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
}
