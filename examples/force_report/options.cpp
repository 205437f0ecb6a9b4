// endohaptics-force-report's options (examples/program_options.hpp).
#include "options.hpp"

#include "../cli_numbers.hpp"
#include "../parse_command_line.hpp"

namespace force_report {

examples::Parsed parse_options(int argc, const char* const* argv, Options& o) {
  CLI::App app{"endohaptics force report: bridge log vs emulator truth"};
  app.add_option("--truth", o.truth_paths, "emulator truth log (--truth-log); repeat per run")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--log", o.log_paths, "bridge tick log (--log); repeat per run, same order")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--label", o.labels, "name of each run in the summary lines (default: run N)");
  app.add_option("--joint", o.joint, "motor slot to compare (0 roll, 1 pitch, 2 clamp1, 3 clamp2)")
      ->check(examples::number_in(0, 3))
      ->capture_default_str();
  app.add_option("--skip", o.skip, "seconds at the start of the bridge log to leave out (start-up)")
      ->check(examples::number_in(0.0, 1e7))
      ->capture_default_str();
  app.add_option("--plot-dir", o.plot_dir,
                 "write forces.png (every run) and period.png (the last) here (needs gnuplot; "
                 "a plot that fails is an error)");
  CLI::Option* all = app.add_flag("--all-joints", o.all_joints,
                                  "end with every rendered joint's line and the stylus line of "
                                  "each run (the stylus force against the ideal one) instead "
                                  "of the --joint line");
  app.add_option("--config", o.config_paths,
                 "the bridge's --config of the runs (one for all, or one per run; default: the "
                 "default configuration): the mapping of the ideal stylus force")
      ->check(CLI::ExistingFile)
      ->needs(all);
  app.add_option("--free-log", o.free_paths,
                 "bridge tick log of a run in free space (emulator --environment free), one per "
                 "run: the free-motion RMS (default: the run's ticks without contact)")
      ->check(CLI::ExistingFile)
      ->needs(all);
  return examples::parse_command_line(app, argc, argv);
}

}  // namespace force_report
