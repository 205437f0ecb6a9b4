// endohaptics-ros-bridge: endohaptics-bridge's loop (bridge_app.hpp; the same link options,
// link_options.hpp) with the operator and the observers on ROS 1: the stylus from a CRTK device
// (<touch>/measured_cp) or the 2016 phantom_omni driver (TF base -> tip), the EndoWrist's joint
// states, setpoints, estimated forces, operating state and loop figures published, the stylus
// force on <touch>/servo_cf (and omni1_force_feedback for the 2016 driver). docs/ros.md.
#include <endohaptics/core/error.hpp>

#include "../teleop_bridge/bridge_app.hpp"
#include "options.hpp"
#include "ros1_node.hpp"

int main(int argc, char** argv) {
  int ros_argc = argc;  // ros::init takes it by reference
  const ros_bridge::ProgramArguments cli = ros_bridge::program_arguments(argc, argv);
  ros_bridge::Options ros_opt;
  const examples::Parsed parsed = ros_bridge::parse_options(cli.argc(), cli.argv(), ros_opt);
  if (parsed.exit_code) return *parsed.exit_code;
  bridge::Options& opt = ros_opt.link;
  const std::string& input = ros_opt.input;
  const double input_timeout_ms = ros_opt.input_timeout_ms;
  ros_bridge::StylusConfig stylus_config;
  stylus_config.frame = ros_opt.frame;
  stylus_config.topics = ros_opt.topics;

  try {
    if (bridge::check_options(parsed, opt)) return 0;
    stylus_config.kind =
        input == "crtk" ? ros_bridge::InputKind::crtk : ros_bridge::InputKind::phantom_omni;
    stylus_config.timeout = std::chrono::duration_cast<std::chrono::nanoseconds>(
        std::chrono::duration<double, std::milli>(input_timeout_ms));
    opt.device = "ros " + input;
    const endohaptics::files::BridgeConfig cfg = bridge::load_config(opt);

    // With --cpu, ROS's threads (roscpp's own, the spinner, the publisher) and their network
    // work stay off the loop's CPU: set before they exist, they inherit it.
    if (opt.cpu >= 0) {
      for (const auto& m : endohaptics::teleop::avoid_cpu(opt.cpu)) {
        fmt::print("ros-bridge: realtime: {}\n", m);
      }
    }
    ros::init(ros_argc, argv, "endohaptics_bridge",
              ros::init_options::NoSigintHandler | ros::init_options::NoRosout);
    if (!ros::master::check()) {
      throw endohaptics::Error("no ROS master at " + ros::master::getURI() +
                               " (start roscore there, or set ROS_MASTER_URI)");
    }
    bridge::stop_on_signals();  // after ros::init: ours, not roscpp's
    ros::NodeHandle nh;
    ros_bridge::RosStylus stylus(nh, stylus_config);
    ros_bridge::RosPublisher publisher(nh, stylus_config.topics,
                                       stylus_config.kind == ros_bridge::InputKind::phantom_omni,
                                       stylus_config.omni);
    // Both threads start before the loop thread turns real-time (bridge_app.hpp): they stay
    // SCHED_OTHER on every CPU.
    ros::AsyncSpinner spinner(1);
    spinner.start();
    publisher.start();
    fmt::print("ros-bridge: ROS master {}, this node {} ({}), input {}, input timeout {} ms\n",
               ros::master::getURI(), ros::this_node::getName(), ros::network::getHost(), input,
               input_timeout_ms);
    fmt::print("ros-bridge: {} is phantom_omni/OmniFeedback md5 {}\n",
               stylus_config.omni.force_feedback,
               ros::message_traits::MD5Sum<phantom_omni::OmniFeedback>::value());
    std::fflush(stdout);
    endohaptics::SteadyClock clock;
    const int status = bridge::run_bridge(stylus, clock, opt, cfg,
                                          ros_bridge::RosTickObserver{&publisher, &stylus});
    publisher.stop();
    spinner.stop();
    const auto& c = stylus.counters();
    fmt::print(
        "ros-bridge: input: used {} messages, refused non-finite {}, wrong frame {}, invalid "
        "(stamp 0) {}, out of order {}, TF chain incomplete {}; joint states {}; lost {} times "
        "({} ticks stale)\n",
        c.used.load(), c.non_finite.load(), c.wrong_frame.load(), c.invalid.load(),
        c.out_of_order.load(), c.no_chain.load(), c.joint_states.load(), c.losses.load(),
        c.stale_ticks.load());
    const auto p = publisher.counters();
    fmt::print(
        "ros-bridge: published {} ticks, {} dropped (ring full); stylus message -> setpoint on "
        "the wire: {} samples, mean {:.3f} ms, p99 {:.2f} ms, max {:.3f} ms\n",
        p.ticks, p.dropped, p.round_trips, p.round_trip_mean_ms, p.round_trip_p99_ms,
        p.round_trip_max_ms);
    ros::shutdown();
    return status;
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
}
