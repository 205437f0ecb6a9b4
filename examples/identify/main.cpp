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

#include <cstdio>
#include <endohaptics/workflow/command_line.hpp>
#include <endohaptics/workflow/identify_request.hpp>
#include <exception>
#include <string>

#include "identify_print.hpp"
#include "options.hpp"

namespace wf = endohaptics::workflow;

int main(int argc, char** argv) {
  identify::Options opt;
  const examples::Parsed parsed = identify::parse_options(argc, argv, opt);
  if (parsed.exit_code) return *parsed.exit_code;

  try {
    const wf::IdentifyRequest& q = opt.request;
    const wf::IdentifyReport report =
        wf::run_identify(q, {.text = [](const std::string& s) { fmt::print("{}", s); },
                             .prepared = identify_print::prepared,
                             .subspace_fitted = identify_print::subspace_fitted,
                             .progress = identify_print::progress_on_terminal()});
    identify_print::chosen(report);
    // No false success: a fit that is not finite (a diverging model, a constant output) fails.
    wf::check_scores(report);
    identify_print::means(report);
    if (!opt.out_path.empty()) {
      endohaptics::files::save_model(opt.out_path, report.model);
      fmt::print("model written to {}\n", opt.out_path);
    }
    wf::require_written(stdout, "standard output");
  } catch (const std::exception& e) {
    fmt::print(stderr, "endohaptics-identify: error: {}\n", e.what());
    return 1;
  }
  return 0;
}
