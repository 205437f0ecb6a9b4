// endohaptics-identify's options (examples/program_options.hpp).
#include "options.hpp"

#include <endohaptics/files/model_file.hpp>

#include "../cli_numbers.hpp"
#include "../parse_command_line.hpp"
#include "../workflow_cli.hpp"

namespace identify {

namespace wf = endohaptics::workflow;
namespace limits = endohaptics::workflow::limits;
using examples::number_in;

examples::Parsed parse_options(int argc, const char* const* argv, Options& opt) {
  CLI::App app{"endohaptics identify: subspace (+ dead zone) model from logs"};
  examples::LogWorkflowOptions o;
  wf::IdentifyRequest& q = opt.request;
  std::string order, method, deadzone;
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
  app.add_option("--out", opt.out_path, "write the model here (JSON)");
  examples::Parsed parsed = examples::parse_command_line(app, argc, argv);
  // The request: what was given, and for the rest the request's own defaults (the format's).
  examples::copy_shared_settings(o, q);
  if (parsed.was_given("--order")) q.order = order;
  if (parsed.was_given("--method")) q.method = method;
  if (parsed.was_given("--deadzone")) q.deadzone = deadzone;
  if (parsed.was_given("--ts")) q.sample_time = o.ts;
  q.preprocessing = o.pre;
  if (parsed.was_given("--lowpass")) q.lowpass = o.pre.cutoff;
  q.offset = o.offset;
  q.input_offset = o.input_offset;
  if (parsed.was_given("--max-time-constant")) q.max_time_constant = max_time_constant;
  return parsed;
}

}  // namespace identify
