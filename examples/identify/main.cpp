// endohaptics-identify: identifies a force model from logs (worksheet 4.2): reads each log and
// prints what the reader dropped, resamples to --ts, low-pass/offset as 4.2.1 for the fit,
// identifies with N4SID/MOESP/CVA (or all three), optionally with input dead zones, and chooses
// method, dead zones and order by the causal score (x0 from the inputs, warm-up excluded, inputs
// filtered forward only, output as logged), refusing unstable and near-integrating models.
// Joint force models (--method stall_hold, push_load_observer, bidirectional_load_observer:
// workflow/joint_models.hpp) are further families; with several, the family is chosen by an inner
// cross-validation on the training files (workflow::choose_family). Each format has recommended
// defaults (workflow/format_defaults.hpp). Writes a JSON model. The whole run is
// workflow::run_identify (workflow/identify_request.hpp); this program parses, calls and prints
// (identify_print.hpp). Results: docs/identification_results.md.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <endohaptics/workflow/command_line.hpp>
#include <endohaptics/workflow/identify_request.hpp>
#include <exception>
#include <string>

#include "../cli_numbers.hpp"
#include "../workflow_cli.hpp"
#include "identify_print.hpp"

namespace wf = endohaptics::workflow;
namespace limits = endohaptics::workflow::limits;
using examples::number_in;

int main(int argc, char** argv) {
  CLI::App app{"endohaptics identify: subspace (+ dead zone) model from logs"};
  examples::LogWorkflowOptions o;
  wf::IdentifyRequest q;
  std::string order = "auto", method = "moesp", deadzone = "none", out_path;
  double max_time_constant = 0.0;
  examples::add_signal_options(app, examples::Tool::identify, o);
  app.add_option("--order", order,
                 "model order N, or auto (select_order, then every order 1..max-order by the "
                 "causal score) [format]")
      ->check(number_in(1, limits::max_order, {"auto"}));
  app.add_option("--max-order", q.max_order, "largest order --order auto considers")
      ->check(number_in(1, limits::max_order))
      ->capture_default_str();
  app.add_option("--method", method,
                 "n4sid, moesp, cva, best (all three, highest causal score), static, stall_hold, "
                 "push_load_observer or bidirectional_load_observer, or a comma list of them "
                 "(every family fitted, the best by an inner cross-validation on the training "
                 "files chosen) [format]");
  app.add_option("--deadzone", deadzone,
                 "input dead zone: auto, none or half width (or one per input, comma-separated) "
                 "[format]");
  examples::add_preprocessing_options(app, examples::Tool::identify, o);
  examples::add_scoring_options(app, examples::Tool::identify, o);
  app.add_option("--max-time-constant", max_time_constant,
                 "s; models with a slower mode are refused as near-integrating, as are those "
                 "slower than the longest segment [format: 2 for endowrist-2016 and "
                 "umn-mis-2018, none for csv]")
      ->check(number_in(1e-6, 1e6));
  app.add_option("--free-threshold", q.free_threshold,
                 "auto, none or a value (output units): the estimate reads 0 up to it and is "
                 "unchanged beyond twice it (auto: the 99th percentile of |estimate| where the "
                 "training output is 0)")
      ->check(number_in(0.0, endohaptics::files::ModelFile::max_parameter, {"auto", "none"}));
  app.add_option("--current-play", q.current_play,
                 "input 0's units (A): the subspace family's input 0 passes a play (backlash) "
                 "operator of this half width before the fit and wherever that model runs (the "
                 "static friction of a joint pressed into an object: its current falls through "
                 "that band while the force stays); a joint model chosen beside it is written "
                 "without a play; 0: none")
      ->check(number_in(0.0, endohaptics::files::ModelFile::max_parameter))
      ->capture_default_str();
  app.add_option("--current-play-slide", q.current_play_slide,
                 "input 0's units (A), in [0, --current-play]: the play's half width while the "
                 "joint slides (its Coulomb friction, where it is below the static friction of "
                 "--current-play: stuck, the current crosses the wider band; sliding, the "
                 "narrower); default: the same, a plain play")
      ->check(number_in(0.0, endohaptics::files::ModelFile::max_parameter));
  app.add_option("--current-play-viscous", q.current_play_viscous,
                 "input 0's units per input 1's (A per rad/s), signed as the logged signals: this "
                 "times input 1 is the viscous friction's current, which the play takes off "
                 "while the joint slides, and whose sign says it moves (-F_mu for a rig that "
                 "reports the current negated); default 0")
      ->check(number_in(-endohaptics::files::ModelFile::max_parameter,
                        endohaptics::files::ModelFile::max_parameter))
      ->capture_default_str();
  app.add_flag("--nested-constants", q.nested_joint_constants,
               "the family choice searches a joint family's constants again inside each of its "
               "cross-validation folds, so the inner score sees nothing of the fold's held-out "
               "files (about the folds' count times the search's cost)");
  app.add_option("--out", out_path, "write the model here (JSON)");
  CLI11_PARSE(app, argc, argv);

  try {
    using examples::given;
    q.logs = o.logs;
    q.format = o.format;
    q.inputs = o.inputs;
    q.outputs = o.outputs;
    if (given(app, "--order")) q.order = order;
    if (given(app, "--method")) q.method = method;
    if (given(app, "--deadzone")) q.deadzone = deadzone;
    if (given(app, "--ts")) q.sample_time = o.ts;
    q.preprocessing = o.pre;
    if (given(app, "--lowpass")) q.lowpass = o.pre.cutoff;
    q.offset = o.offset;
    q.input_offset = o.input_offset;
    q.x0 = o.x0;
    q.warmup = o.warmup;
    if (given(app, "--max-time-constant")) q.max_time_constant = max_time_constant;
    q.drop_non_finite = o.drop_non_finite;

    const wf::IdentifyReport report =
        wf::run_identify(q, {.text = [](const std::string& s) { fmt::print("{}", s); },
                             .prepared = identify_print::prepared,
                             .subspace_fitted = identify_print::subspace_fitted,
                             .progress = identify_print::progress_on_terminal()});
    identify_print::chosen(report);
    // No false success: a fit that is not finite (a diverging model, a constant output) fails.
    wf::check_scores(report);
    identify_print::means(report);
    if (!out_path.empty()) {
      endohaptics::files::save_model(out_path, report.model);
      fmt::print("model written to {}\n", out_path);
    }
    wf::require_written(stdout, "standard output");
  } catch (const std::exception& e) {
    fmt::print(stderr, "endohaptics-identify: error: {}\n", e.what());
    return 1;
  }
  return 0;
}
