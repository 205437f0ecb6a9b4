// endohaptics-codec-loopback's options (examples/program_options.hpp).
#include "options.hpp"

#include "../cli_numbers.hpp"
#include "../parse_command_line.hpp"

namespace codec_loopback {

examples::Parsed parse_options(int argc, const char* const* argv, Options& o) {
  CLI::App app{"endohaptics codec round trip over UDP loopback"};
  app.add_option("--count", o.count, "number of round trips")
      ->check(examples::number_in(1, 1000000));
  return examples::parse_command_line(app, argc, argv);
}

}  // namespace codec_loopback
