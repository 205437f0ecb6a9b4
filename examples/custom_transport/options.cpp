// endohaptics-custom-transport's options (examples/program_options.hpp).
#include "options.hpp"

#include "../cli_numbers.hpp"
#include "../parse_command_line.hpp"

namespace custom_transport {

examples::Parsed parse_options(int argc, const char* const* argv, Options& o) {
  CLI::App app{"endohaptics: a TeleopLoop over a user-defined transport and device"};
  app.add_option("--ticks", o.ticks, "ticks to run (simulated 1 kHz)")
      ->check(examples::number_in(1, 10000000));
  return examples::parse_command_line(app, argc, argv);
}

}  // namespace custom_transport
