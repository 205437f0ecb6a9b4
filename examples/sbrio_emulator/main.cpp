// endohaptics-sbrio-emulator: behaves like the 2016 sbRIO on the wire (UDP, binary protocol)
// with a simulated EndoWrist behind it, so the bridge can run without the lab. The truth log
// holds what no real rig can give: the true contact force at the tool. Options: options.cpp;
// the run: emulator_app.hpp.
#include <fmt/format.h>

#include <cstdio>
#include <exception>

#include "emulator_app.hpp"

int main(int argc, char** argv) {
  emulator::Options options;
  const examples::Parsed parsed = emulator::parse_options(argc, argv, options);
  if (parsed.exit_code) return *parsed.exit_code;
  try {
    return emulator::run(options, parsed.was_given("--rig"));
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
}
