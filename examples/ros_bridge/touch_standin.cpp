// endohaptics-ros-touch-standin: plays the operator's side of a ROS teleoperation for tests and
// demos without a Touch: the library's scripted operator (sim::ScriptedOperator, the bridge's
// --device sim) published as a CRTK device (<touch>/measured_cp, rendering <touch>/servo_cf) or
// as the 2016 phantom_omni driver (TF base -> tip, /omni1_joint_states, rendering
// omni1_force_feedback). --stop-after stops the stylus (a lost operator), --bad-every sends
// refused messages (NaN, wrong frame). docs/ros.md.
#include <fmt/format.h>

#include <atomic>
#include <csignal>
#include <endohaptics/core/clock.hpp>
#include <endohaptics/sim/scripted_operator.hpp>
#include <limits>
#include <optional>

#include "../teleop_bridge/touch_frame.hpp"
#include "ros1_node.hpp"
#include "standin_options.hpp"

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop.store(true); }

// The newest force the bridge asked for (Touch frame), from the spinner thread.
struct ForceInbox {
  endohaptics::teleop::LatestValue<Eigen::Vector3d> latest;
  std::atomic<std::uint64_t> received{0};
  void take(const Eigen::Vector3d& f) {
    latest.publish(f);
    received.fetch_add(1, std::memory_order_relaxed);
  }
};

}  // namespace

int main(int argc, char** argv) {
  int ros_argc = argc;  // ros::init takes it by reference
  const ros_bridge::ProgramArguments cli = ros_bridge::program_arguments(argc, argv);
  touch_standin::Options o;
  const examples::Parsed parsed = touch_standin::parse_options(cli.argc(), cli.argv(), o);
  if (parsed.exit_code) return *parsed.exit_code;
  const auto& [mode, rate, duration, stop_after, bad_every, frame, topics] = o;
  const ros_bridge::PhantomOmniTopics omni;

  try {
    ros::init(ros_argc, argv, "touch_standin",
              ros::init_options::NoSigintHandler | ros::init_options::NoRosout);
    if (!ros::master::check()) {
      fmt::print(stderr, "error: no ROS master at {}\n", ros::master::getURI());
      return 1;
    }
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    ros::NodeHandle nh;
    ForceInbox inbox;
    ros::Publisher pose_pub, tf_pub, joints_pub;
    ros::Subscriber force_sub;
    const bool crtk = mode == "crtk";
    if (crtk) {
      pose_pub = nh.advertise<geometry_msgs::PoseStamped>(topics.stylus_pose(), 100);
      force_sub = nh.subscribe<geometry_msgs::WrenchStamped>(
          topics.stylus_force(), 100,
          [&inbox](const geometry_msgs::WrenchStamped::ConstPtr& m) {
            const auto& f = m->wrench.force;
            inbox.take(Eigen::Vector3d(f.x, f.y, f.z));
          },
          ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
    } else {
      tf_pub = nh.advertise<tf2_msgs::TFMessage>(omni.tf, 100);
      joints_pub = nh.advertise<sensor_msgs::JointState>(omni.joint_states, 100);
      force_sub = nh.subscribe<phantom_omni::OmniFeedback>(
          omni.force_feedback, 100,
          [&inbox](const phantom_omni::OmniFeedback::ConstPtr& m) {
            inbox.take(Eigen::Vector3d(m->force.x, m->force.y, m->force.z));
          },
          ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
    }
    ros::AsyncSpinner spinner(1);
    spinner.start();

    endohaptics::SteadyClock clock;
    endohaptics::sim::ScriptedOperator<endohaptics::SteadyClock> stylus(clock);
    const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / rate));
    const auto start = clock.now();
    auto next = start;
    std::uint64_t published = 0, bad = 0;
    double max_force = 0.0;
    geometry_msgs::PoseStamped pose;
    pose.header.frame_id = frame;
    pose.pose.orientation.w = 1.0;
    tf2_msgs::TFMessage tf;
    tf.transforms.resize(2);
    // base -> arm (fixed) -> tip: the bridge composes the chain as tf did for the 2016 node.
    const Eigen::Vector3d arm(0.0, 0.0, 0.1);
    tf.transforms[0].header.frame_id = "base";
    tf.transforms[0].child_frame_id = "arm";
    ros_bridge::fill_vector3(tf.transforms[0].transform.translation, arm);
    tf.transforms[0].transform.rotation.w = 1.0;
    tf.transforms[1].header.frame_id = "arm";
    tf.transforms[1].child_frame_id = "tip";
    tf.transforms[1].transform.rotation.w = 1.0;
    sensor_msgs::JointState joints;
    joints.name = {"waist", "shoulder", "elbow", "wrist1", "wrist2", "wrist3"};
    joints.position.assign(6, 0.0);
    fmt::print("standin: {} at {} Hz, ROS master {}, this node {}\n", mode, rate,
               ros::master::getURI(), ros::network::getHost());
    std::fflush(stdout);
    // --stop-after counts from the first subscriber (the bridge may take a while to connect on
    // a loaded machine: the operator's motion is what is timed, not the stand-in's start).
    const ros::Publisher& stylus_pub = crtk ? pose_pub : tf_pub;
    std::optional<std::chrono::nanoseconds> heard_at;
    while (!g_stop.load() && ros::ok()) {
      const auto now = clock.now();
      const double t = std::chrono::duration<double>(now - start).count();
      if (duration > 0 && t >= duration) break;
      if (!heard_at && stylus_pub.getNumSubscribers() > 0) heard_at = now;
      const double moving = heard_at ? std::chrono::duration<double>(now - *heard_at).count() : 0.0;
      Eigen::Vector3d f_touch;
      if (inbox.latest.read(f_touch)) {
        max_force = std::max(max_force, f_touch.norm());
        (void)stylus.command_force(bridge::touch_to_mapping_force(f_touch));
      }
      endohaptics::teleop::StylusSample s;
      (void)stylus.read(s);
      if (stop_after <= 0 || moving < stop_after) {
        const ros::Time stamp = ros::Time::now();
        ++published;
        const bool make_bad =
            bad_every > 0 && published % static_cast<std::uint64_t>(bad_every) == 0;
        const bool make_wrong_frame =
            bad_every > 1 && published % static_cast<std::uint64_t>(bad_every) ==
                                 static_cast<std::uint64_t>(bad_every / 2);
        if (crtk) {
          pose.header.stamp = stamp;
          ros_bridge::fill_vector3(pose.pose.position,
                                   bridge::mapping_to_touch_position(s.position));
          if (make_bad) pose.pose.position.x = std::numeric_limits<double>::quiet_NaN();
          pose.header.frame_id = make_wrong_frame ? "somewhere_else" : frame;
          bad += make_bad || make_wrong_frame ? 1 : 0;
          pose_pub.publish(pose);
        } else {
          for (auto& x : tf.transforms) x.header.stamp = stamp;
          ros_bridge::fill_vector3(tf.transforms[1].transform.translation, s.position - arm);
          if (make_bad)
            tf.transforms[1].transform.translation.x = std::numeric_limits<double>::quiet_NaN();
          bad += make_bad ? 1 : 0;
          tf_pub.publish(tf);
          joints.header.stamp = stamp;
          joints_pub.publish(joints);
        }
      }
      next += period;
      clock.sleep_until(next);
    }
    spinner.stop();
    fmt::print(
        "standin: published {} stylus messages ({} made bad), received {} force commands, "
        "max |force| {:.3f} N\n",
        published, bad, inbox.received.load(), max_force);
    ros::shutdown();
    return inbox.received.load() > 0 ? 0 : 4;
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
}
