// endohaptics-codec-loopback's command line (options.cpp; examples/program_options.hpp).
#pragma once

#include "../program_options.hpp"

namespace codec_loopback {

struct Options {
  int count = 5;  //!< round trips
};

//! Reads the command line into `o`.
[[nodiscard]] examples::Parsed parse_options(int argc, const char* const* argv, Options& o);

}  // namespace codec_loopback
