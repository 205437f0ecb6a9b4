// endohaptics-sbrio-emulator: behaves like the 2016 sbRIO on the wire (UDP, binary protocol)
// with a simulated EndoWrist behind it, so the bridge can run without the lab. The truth log
// holds what no real rig can give: the true contact force at the tool. Options and run:
// emulator_app.hpp.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "emulator_app.hpp"

int main(int argc, char** argv) {
  CLI::App app{"endohaptics sbRIO emulator: a simulated EndoWrist behind the 2016 UDP protocol"};
  emulator::Options options;
  emulator::add_options(app, options);
  CLI11_PARSE(app, argc, argv);
  try {
    return emulator::run(options, app.count("--rig") > 0);
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
}
