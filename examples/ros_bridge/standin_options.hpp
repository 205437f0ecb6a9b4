// endohaptics-ros-touch-standin's command line (standin_options.cpp;
// examples/program_options.hpp).
#pragma once

#include <string>

#include "../program_options.hpp"
#include "ros_conversion.hpp"

namespace touch_standin {

//! The command line's settings.
struct Options {
  std::string mode = "crtk";  //!< crtk or phantom-omni
  double rate = 1000.0;       //!< Hz
  double duration = 0.0;      //!< s (0: until SIGINT)
  double stop_after = 0.0;    //!< s after the first subscriber: the stylus stops (0: never)
  int bad_every = 0;          //!< every Nth message NaN, every Nth shifted by N/2 in a wrong frame
  std::string frame = "touch";  //!< CRTK: the frame_id of measured_cp
  ros_bridge::Topics topics;    //!< the CRTK namespace
};

//! Reads the command line (ROS's own arguments already removed) into `o`.
[[nodiscard]] examples::Parsed parse_options(int argc, const char* const* argv, Options& o);

}  // namespace touch_standin
