// endohaptics-ros-bridge's command line (options.cpp; examples/program_options.hpp): the bridges'
// link and loop options and the ROS stylus's.
#pragma once

#include <string>

#include "../program_options.hpp"
#include "../teleop_bridge/options.hpp"
#include "ros_conversion.hpp"

namespace ros_bridge {

//! The command line's settings.
struct Options {
  bridge::Options link;             //!< the sbRIO link and the loop, as endohaptics-bridge's
  std::string input = "crtk";       //!< crtk or phantom-omni
  double input_timeout_ms = 100.0;  //!< a stylus older than this is a lost operator
  std::string frame;                //!< CRTK: the frame_id measured_cp must carry (empty: any)
  Topics topics;                    //!< the touch and robot namespaces
};

//! Reads the command line (ROS's own arguments already removed) into `opt`.
[[nodiscard]] examples::Parsed parse_options(int argc, const char* const* argv, Options& opt);

}  // namespace ros_bridge
