// endohaptics-ros-touch-standin's options (examples/program_options.hpp).
#include "standin_options.hpp"

#include "../cli_numbers.hpp"
#include "../parse_command_line.hpp"

namespace touch_standin {

examples::Parsed parse_options(int argc, const char* const* argv, Options& o) {
  CLI::App app{"endohaptics ROS touch stand-in: a scripted operator on ROS topics"};
  app.add_option("--mode", o.mode, "crtk or phantom-omni")
      ->check(CLI::IsMember({"crtk", "phantom-omni"}))
      ->capture_default_str();
  app.add_option("--rate", o.rate, "Hz")
      ->check(examples::number_in(1.0, 5000.0))
      ->capture_default_str();
  app.add_option("--duration", o.duration, "s (0: until SIGINT)")
      ->check(examples::number_in(0.0, 1e7));
  app.add_option("--stop-after", o.stop_after,
                 "s after the first subscriber connected: stop publishing the stylus then (0: "
                 "never)")
      ->check(examples::number_in(0.0, 1e7));
  app.add_option(
         "--bad-every", o.bad_every,
         "every Nth stylus message NaN, every Nth (shifted by N/2) in a wrong frame (0: none)")
      ->check(examples::number_in(0, 1000000));
  app.add_option("--frame", o.frame, "crtk: frame_id of measured_cp")->capture_default_str();
  app.add_option("--touch-namespace", o.topics.touch, "the CRTK namespace")->capture_default_str();
  return examples::parse_command_line(app, argc, argv);
}

}  // namespace touch_standin
