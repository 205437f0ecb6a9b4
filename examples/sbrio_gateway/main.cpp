// endohaptics-sbrio-gateway: protocol v2's robot side on a small computer beside the sbRIO. It
// terminates v2 towards the console and relays plain 2016 setpoints to the unchanged LabVIEW loop
// over a point-to-point link, and the sbRIO's states back, sealed; on silence it disables the
// motors itself (transport/v2_gateway.hpp, docs/rig.md). Options and run: gateway_app.hpp.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "gateway_app.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "endohaptics sbRIO gateway: protocol v2's robot side in front of a 2016 sbRIO (relays "
      "authenticated setpoints, disables the motors on silence)"};
  gateway::Options options;
  gateway::add_options(app, options);
  CLI11_PARSE(app, argc, argv);
  try {
    return gateway::run(options);
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
}
