// endohaptics-replay's command line (options.cpp; examples/program_options.hpp).
#pragma once

#include <endohaptics/workflow/replay_request.hpp>
#include <string>

#include "../program_options.hpp"

namespace replay {

//! The command line's settings: the replay asked for (the preprocessing an option does not set
//! is the model file's) and the plot's path.
struct Options {
  endohaptics::workflow::ReplayRequest request;
  std::string plot_path;  //!< --plot (empty: none)
};

//! Reads the command line into `opt`.
[[nodiscard]] examples::Parsed parse_options(int argc, const char* const* argv, Options& opt);

}  // namespace replay
