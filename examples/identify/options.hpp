// endohaptics-identify's command line (options.cpp; examples/program_options.hpp).
#pragma once

#include <endohaptics/workflow/identify_request.hpp>
#include <string>

#include "../program_options.hpp"

namespace identify {

//! The command line's settings: the identification asked for (an option not given leaves the
//! request's default, the format's where it has one) and where to write the model.
struct Options {
  endohaptics::workflow::IdentifyRequest request;
  std::string out_path;  //!< --out (empty: not written)
};

//! Reads the command line into `opt`.
[[nodiscard]] examples::Parsed parse_options(int argc, const char* const* argv, Options& opt);

}  // namespace identify
