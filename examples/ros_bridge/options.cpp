// endohaptics-ros-bridge's options (examples/program_options.hpp).
#include "options.hpp"

#include "../cli_numbers.hpp"
#include "../parse_command_line.hpp"
#include "../teleop_bridge/link_options.hpp"

namespace ros_bridge {

examples::Parsed parse_options(int argc, const char* const* argv, Options& opt) {
  CLI::App app{
      "endohaptics ROS bridge: a ROS stylus <-> sbRIO teleoperation with sensorless force "
      "feedback; joint states, setpoints, forces and loop figures on ROS topics"};
  bridge::add_link_options(app, opt.link);
  app.add_option("--input", opt.input,
                 "stylus: crtk (<touch>/measured_cp, geometry_msgs/PoseStamped, Touch frame) or "
                 "phantom-omni (the 2016 driver: TF base -> tip, /omni1_joint_states)")
      ->check(CLI::IsMember({"crtk", "phantom-omni"}))
      ->capture_default_str();
  app.add_option("--input-timeout", opt.input_timeout_ms,
                 "ms: a stylus older than this is a lost operator (the setpoint is held, the "
                 "motors released per safety.policy)")
      ->check(examples::number_in(1.0, 500.0))
      ->capture_default_str();
  app.add_option("--input-frame", opt.frame,
                 "crtk: the frame_id measured_cp must carry (default: any)");
  app.add_option("--touch-namespace", opt.topics.touch, "the CRTK stylus's namespace")
      ->capture_default_str();
  app.add_option("--robot-namespace", opt.topics.robot, "the namespace of the EndoWrist's topics")
      ->capture_default_str();
  return examples::parse_command_line(app, argc, argv);
}

}  // namespace ros_bridge
