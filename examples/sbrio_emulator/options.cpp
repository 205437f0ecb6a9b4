// endohaptics-sbrio-emulator's options (examples/program_options.hpp: one translation unit with
// every program's).
#include "options.hpp"

#include "../cli_numbers.hpp"
#include "../parse_command_line.hpp"
#include "../robot_side_options.hpp"

namespace emulator {

namespace {

//! The emulator's options.
void add_options(CLI::App& app, Options& o) {
  app.add_option("--bind", o.bind, "address to listen on")->capture_default_str();
  app.add_option("--port", o.port, "UDP port to listen on (0: any free port, printed)")
      ->check(examples::number_in<std::uint16_t>(0, 65535))
      ->capture_default_str();
  app.add_option("--motors", o.motors, "number of motors (the EndoWrist has 4)")
      ->check(examples::number_in(4, 4))
      ->capture_default_str();
  app.add_option("--environment", o.environment, "what the tool touches: free|loadcell|tissue")
      ->check(CLI::IsMember({"free", "loadcell", "tissue"}))
      ->capture_default_str();
  app.add_option(
      "--truth-log", o.truth_path,
      "CSV: time, setpoints, positions, velocities, currents, true external forces (N, along "
      "+setpoint)");
  app.add_option("--truth-period-ms", o.truth_period_ms,
                 "truth log row period (rows on an exact grid of the emulator's time)")
      ->check(examples::number_in(0.01, 1000.0))
      ->capture_default_str();
  app.add_option("--duration", o.duration, "seconds to run (0: until SIGINT/SIGTERM)")
      ->check(examples::number_in(0.0, 1e7))
      ->capture_default_str();
  app.add_option("--watchdog-ms", o.watchdog_ms,
                 "disable the motors after this long without packets")
      ->check(examples::number_in(1.0, 10000.0))
      ->capture_default_str();
  app.add_flag("--quiet", o.quiet, "print only the final summary");
  app.add_option("--delay", o.delay_ms, "ms every answer is held on the send path (one way)")
      ->check(examples::number_in(0.0, 5000.0))
      ->capture_default_str();
  app.add_option("--jitter", o.jitter_ms, "ms of extra uniform delay per answer, [0, jitter]")
      ->check(examples::number_in(0.0, 5000.0))
      ->capture_default_str();
  app.add_option("--loss", o.loss, "probability an answer is lost on the send path")
      ->check(examples::number_in(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--protocol", o.wire,
                 "wire protocol: 2 (authenticated, needs --key) or 2016 (unauthenticated; the "
                 "first peer's address and port are pinned)")
      ->check(CLI::IsMember({"2", "2016"}))
      ->capture_default_str();
  examples::add_robot_side_v2_options(app, o.key_paths, o.rig_name, o.max_round_trip_ms,
                                      "protocol v2: ", "the watchdog + --delay + --jitter");
  app.add_option("--peer", o.peer,
                 "protocol 2016: obey only the console at HOST:PORT (default: the first one "
                 "heard, released after --watchdog-ms of its silence)");
  app.add_option("--generate-key", o.generate_key,
                 "write a new random key file (mode 0600; refuses an existing file) and exit");
}

}  // namespace

examples::Parsed parse_options(int argc, const char* const* argv, Options& o) {
  CLI::App app{"endohaptics sbRIO emulator: a simulated EndoWrist behind the 2016 UDP protocol"};
  add_options(app, o);
  return examples::parse_command_line(app, argc, argv);
}

}  // namespace emulator
