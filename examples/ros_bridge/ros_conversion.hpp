//! @file
//! What endohaptics-ros-bridge reads and publishes, without the middleware: the topic names, the
//! record the loop hands to the publishing thread, the operating state, the checks on a stylus
//! message and the TF chain of the 2016 phantom_omni driver, and the filling of messages. The
//! `fill_*` templates take any message type with the ROS field names (ROS 1's sensor_msgs::
//! JointState, ROS 2's sensor_msgs::msg::JointState ...); the stamp comes from a callable, the one
//! thing that differs. A ROS 2 port is one new file beside ros1_node.hpp (docs/ros.md).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <endohaptics/protocol/motor_order.hpp>
#include <endohaptics/teleop/teleop_loop.hpp>
#include <endohaptics/teleop/tick_recorder.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace ros_bridge {

namespace tp = endohaptics::teleop;

//! The topics (CRTK names, as the dVRK 2.x and sawSensablePhantom use them). `robot` and `touch`
//! are the namespaces (--robot-namespace, --touch-namespace).
struct Topics {
  std::string robot = "/EW";     //!< the EndoWrist's namespace
  std::string touch = "/touch";  //!< the CRTK stylus's namespace

  //! Motor positions, velocities and currents (as effort), protocol motor order; stamp 0 while
  //! no valid state (CRTK: invalid data).
  [[nodiscard]] std::string measured_js() const { return robot + "/measured_js"; }
  //! The setpoints sent to the sbRIO (position, rad).
  [[nodiscard]] std::string setpoint_js() const { return robot + "/setpoint_js"; }
  //! The estimated force per joint (effort; N, roll N m), from the loop's estimator.
  [[nodiscard]] std::string measured_jf() const { return robot + "/measured_jf"; }
  //! "waiting", "link up", "link lost", "safe" (std_msgs/String, on change and every second).
  [[nodiscard]] std::string operating_state() const { return robot + "/operating_state"; }
  //! One line of loop figures every second (std_msgs/String).
  [[nodiscard]] std::string loop_stats() const { return robot + "/loop_stats"; }
  //! Every tick-log column of every tick (std_msgs/Float64MultiArray; the column names in
  //! layout.dim[0].label once a second): what bag_to_tick_log.py turns into the bridge's --log.
  [[nodiscard]] std::string tick_log() const { return robot + "/tick_log"; }
  //! The CRTK stylus pose the bridge follows (geometry_msgs/PoseStamped, Touch frame, m).
  [[nodiscard]] std::string stylus_pose() const { return touch + "/measured_cp"; }
  //! The force the stylus should render (geometry_msgs/WrenchStamped, Touch frame, N).
  [[nodiscard]] std::string stylus_force() const { return touch + "/servo_cf"; }
};

//! The 2016 phantom_omni driver's names (as the 2016 node used them).
struct PhantomOmniTopics {
  std::string joint_states = "/omni1_joint_states";     //!< sensor_msgs/JointState
  std::string force_feedback = "omni1_force_feedback";  //!< phantom_omni/OmniFeedback
  std::string tf = "/tf";                               //!< tf2_msgs/TFMessage
  std::string base_frame = "base";                      //!< the 2016 node's "/base"
  std::string tip_frame = "tip";                        //!< the 2016 node's "/tip"
};

//! One tick as the loop hands it to the publishing thread (fixed size: no allocation).
struct TickMessage {
  tp::TickRecord record;            //!< the tick-log row (time: the loop clock, s)
  std::int64_t wall_ns = 0;         //!< system time at the end of the tick (the stamps)
  std::int64_t input_stamp_ns = 0;  //!< stamp of the stylus message this tick used (0: none)
  bool input_fresh = false;         //!< that message was first used in this tick

  //! The loop has a valid state (false: the measured messages are stamped 0).
  [[nodiscard]] bool valid_state() const noexcept { return tp::holds_valid_state(record.link); }
};

//! The message for tick result `r`, stamped `now` on the loop clock and with the system time at
//! the call; `input_stamp_ns` and `input_fresh` say which stylus message the tick used. Loop
//! thread: noexcept, no allocation.
[[nodiscard]] inline TickMessage tick_message(const tp::TickResult& r, std::chrono::nanoseconds now,
                                              std::int64_t input_stamp_ns,
                                              bool input_fresh) noexcept {
  TickMessage m;
  m.record = tp::TickRecord::from(r, now);
  m.wall_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                  std::chrono::system_clock::now().time_since_epoch())
                  .count();
  m.input_stamp_ns = input_stamp_ns;
  m.input_fresh = input_fresh;
  return m;
}

//! The operating state published on `operating_state`: "waiting" before the first valid state,
//! "link up" (up, degraded, recovering), "link lost" while the lost link holds the motors,
//! "safe" when they are released (a lost link or a lost operator).
[[nodiscard]] inline std::string_view operating_state(const tp::TickRecord& r) noexcept {
  if (r.link == tp::LinkState::waiting) return "waiting";
  if (r.enable_mask == 0) return "safe";
  if (r.link == tp::LinkState::lost) return "link lost";
  return "link up";
}

//! The joint names, protocol motor order ("roll", "pitch", "clamp1", "clamp2").
[[nodiscard]] inline std::array<std::string, tp::loop_motors> joint_names() {
  std::array<std::string, tp::loop_motors> names;
  for (int j = 0; j < tp::loop_motors; ++j) {
    names[static_cast<std::size_t>(j)] =
        std::string(endohaptics::protocol::to_string(static_cast<endohaptics::protocol::Motor>(j)));
  }
  return names;
}

//! Fills a JointState: names once, then the given vectors (null: left empty).
template <typename JointState, typename Stamp>
void fill_joint_state(JointState& m, const Stamp& stamp, const tp::MotorVector* position,
                      const tp::MotorVector* velocity, const tp::MotorVector* effort) {
  m.header.stamp = stamp;
  if (m.name.size() != tp::loop_motors) {
    const auto names = joint_names();
    m.name.assign(names.begin(), names.end());
  }
  const auto copy = [](auto& out, const tp::MotorVector* v) {
    if (v == nullptr) {
      out.clear();
      return;
    }
    out.resize(tp::loop_motors);
    for (int j = 0; j < tp::loop_motors; ++j) out[static_cast<std::size_t>(j)] = (*v)[j];
  };
  copy(m.position, position);
  copy(m.velocity, velocity);
  copy(m.effort, effort);
}

//! Fills a 3-vector message (geometry_msgs Vector3).
template <typename Vector3>
void fill_vector3(Vector3& v, const Eigen::Vector3d& x) {
  v.x = x.x();
  v.y = x.y();
  v.z = x.z();
}

//! Fills a Float64MultiArray with the tick-log row `r`. `named`: the column names go in
//! layout.dim[0].label (teleop::tick_log_columns, comma-separated); otherwise the label is empty
//! (the bridge names one message a second: 0.4 kB less per tick; bag_to_tick_log.py takes the
//! names from any one).
template <typename Float64MultiArray, typename Dimension>
void fill_tick_log(Float64MultiArray& m, const tp::TickRecord& r, bool named) {
  if (m.layout.dim.empty()) m.layout.dim.push_back(Dimension{});
  auto& d = m.layout.dim.front();
  d.label.clear();
  if (named) {
    for (const auto c : tp::tick_log_columns) {
      if (!d.label.empty()) d.label += ',';
      d.label += std::string(c);
    }
  }
  d.size = static_cast<std::uint32_t>(tp::tick_log_columns.size());
  d.stride = d.size;
  const auto row = r.values();
  m.data.assign(row.begin(), row.end());
}

//! Why a stylus message was not used (each counted by cause).
enum class InputError : std::uint8_t {
  none = 0,
  non_finite,   //!< NaN or Inf in the position or orientation
  wrong_frame,  //!< header.frame_id is not the one asked for
  invalid,      //!< header.stamp 0 (CRTK: invalid data)
  out_of_order  //!< stamped before the newest message used
};

//! The input error's name for messages ("non-finite", "wrong frame", ...).
[[nodiscard]] constexpr std::string_view to_string(InputError e) noexcept {
  switch (e) {
    case InputError::none:
      return "none";
    case InputError::non_finite:
      return "non-finite";
    case InputError::wrong_frame:
      return "wrong frame";
    case InputError::invalid:
      return "invalid (stamp 0)";
    case InputError::out_of_order:
      return "out of order";
  }
  return "unknown";
}

//! A frame name without the leading '/' ROS 1's tf allowed ("/base" and "base" are one frame).
[[nodiscard]] inline std::string_view bare_frame(std::string_view f) noexcept {
  while (!f.empty() && f.front() == '/') f.remove_prefix(1);
  return f;
}

//! Checks a stylus pose message (a PoseStamped's header and pose) and gives its position (m).
//! `frame`: the frame_id asked for (empty: any). `newest_ns`: the stamp of the newest message
//! used so far (0: none).
template <typename PoseStamped>
[[nodiscard]] InputError stylus_position(const PoseStamped& m, std::string_view frame,
                                         std::int64_t stamp_ns, std::int64_t newest_ns,
                                         Eigen::Vector3d& position) {
  const auto& p = m.pose.position;
  const auto& q = m.pose.orientation;
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !std::isfinite(q.x) ||
      !std::isfinite(q.y) || !std::isfinite(q.z) || !std::isfinite(q.w)) {
    return InputError::non_finite;
  }
  if (!frame.empty() && bare_frame(m.header.frame_id) != bare_frame(frame)) {
    return InputError::wrong_frame;
  }
  if (stamp_ns == 0) return InputError::invalid;
  if (stamp_ns < newest_ns) return InputError::out_of_order;
  position = Eigen::Vector3d(p.x, p.y, p.z);
  return InputError::none;
}

//! The newest transform of every frame heard on /tf, and the chain from a base frame to a tip
//! frame through them (what tf's lookupTransform("/base", "/tip") gave the 2016 node). Used on
//! the subscribing thread only.
class TfChain {
 public:
  //! Records `parent` -> `child` (translation m, rotation as a unit quaternion w, x, y, z).
  //! Returns InputError::non_finite (and keeps the previous one) for a non-finite transform.
  [[nodiscard]] InputError update(std::string_view parent, std::string_view child,
                                  const Eigen::Vector3d& translation,
                                  const Eigen::Quaterniond& rotation) {
    if (!translation.allFinite() || !rotation.coeffs().allFinite() || rotation.norm() < 1e-9) {
      return InputError::non_finite;
    }
    const std::string c(bare_frame(child));
    for (auto& l : links_) {
      if (l.child == c) {
        l.parent = std::string(bare_frame(parent));
        l.transform = make(translation, rotation);
        return InputError::none;
      }
    }
    if (links_.size() < max_links) {
      links_.push_back({std::string(bare_frame(parent)), c, make(translation, rotation)});
    }
    return InputError::none;
  }

  //! The tip frame's origin in the base frame; false when the chain is incomplete (or longer than
  //! max_links: a cycle).
  [[nodiscard]] bool lookup(std::string_view base, std::string_view tip,
                            Eigen::Vector3d& position) const {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    std::string_view frame = bare_frame(tip);
    const std::string_view b = bare_frame(base);
    for (std::size_t hops = 0; frame != b; ++hops) {
      if (hops >= max_links) return false;
      const Link* l = find(frame);
      if (l == nullptr) return false;
      t = l->transform * t;
      frame = l->parent;
    }
    position = t.translation();
    return true;
  }

  static constexpr std::size_t max_links = 32;  //!< frames remembered (the Omni has 7)

 private:
  struct Link {
    std::string parent;
    std::string child;
    Eigen::Isometry3d transform;
  };
  static Eigen::Isometry3d make(const Eigen::Vector3d& t, const Eigen::Quaterniond& q) {
    Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
    m.linear() = q.normalized().toRotationMatrix();
    m.translation() = t;
    return m;
  }
  [[nodiscard]] const Link* find(std::string_view child) const {
    for (const auto& l : links_) {
      if (l.child == child) return &l;
    }
    return nullptr;
  }
  std::vector<Link> links_;
};

}  // namespace ros_bridge
