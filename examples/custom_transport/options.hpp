// endohaptics-custom-transport's command line (options.cpp; examples/program_options.hpp).
#pragma once

#include "../program_options.hpp"

namespace custom_transport {

struct Options {
  int ticks = 2000;  //!< ticks to run (simulated 1 kHz)
};

//! Reads the command line into `o`.
[[nodiscard]] examples::Parsed parse_options(int argc, const char* const* argv, Options& o);

}  // namespace custom_transport
