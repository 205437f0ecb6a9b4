// endohaptics-bridge's options (examples/program_options.hpp).
#include "options.hpp"

#include "../parse_command_line.hpp"
#include "link_options.hpp"

namespace bridge {

examples::Parsed parse_options(int argc, const char* const* argv, Options& opt) {
  CLI::App app{"endohaptics bridge: stylus <-> sbRIO teleoperation with sensorless force feedback"};
  add_link_options(app, opt);
  app.add_option("--device", opt.device,
                 "haptic device: sim (scripted operator), arm-model (the table 5.1 arm holding a "
                 "simulated stylus, pressing clamp 1 into the emulator's contact and holding) or "
                 "openhaptics")
      ->check(CLI::IsMember({"sim", "arm-model", "openhaptics"}))
      ->capture_default_str();
  return examples::parse_command_line(app, argc, argv);
}

}  // namespace bridge
