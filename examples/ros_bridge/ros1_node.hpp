//! @file
//! endohaptics-ros-bridge's ROS 1 side (roscpp): `RosStylus`, a teleop::HapticDevice fed by a
//! subscription (the CRTK stylus pose, or the 2016 phantom_omni driver's TF and joint states), and
//! `RosPublisher`, a tick observer whose thread publishes what the loop did. The loop thread only
//! copies fixed-size values into lock-free hand-offs (teleop::LatestValue from the subscriber,
//! an SPSC ring to the publisher): it never waits on ROS, never locks, never allocates.
//! What the topics carry: ros_conversion.hpp (no ROS there); docs/ros.md.
#pragma once

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <phantom_omni/OmniFeedback.h>
#include <ros/network.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <std_msgs/Float64MultiArray.h>
#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <boost/lockfree/spsc_queue.hpp>
#include <chrono>
#include <cstdint>
#include <endohaptics/core/clock.hpp>
#include <endohaptics/teleop/haptic_device.hpp>
#include <endohaptics/teleop/latest_value.hpp>
#include <endohaptics/teleop/loop_stats.hpp>
#include <endohaptics/teleop/realtime.hpp>
#include <string>
#include <thread>
#include <vector>

#include "../teleop_bridge/touch_frame.hpp"
#include "ros_conversion.hpp"

namespace ros_bridge {

using std::chrono::nanoseconds;

//! A ROS program's own command line: argv without ROS's arguments (remappings `name:=value`,
//! `__name:=...`; ros::removeROSArgs), for its option parser. argv() points into `args`.
struct ProgramArguments {
  std::vector<std::string> args;      //!< the arguments left for the program
  std::vector<const char*> pointers;  //!< their C strings, for argv()
  [[nodiscard]] int argc() const noexcept { return static_cast<int>(pointers.size()); }
  [[nodiscard]] const char* const* argv() const noexcept { return pointers.data(); }
};

//! argv without ROS's arguments. ros::init later takes the whole command line.
inline ProgramArguments program_arguments(int argc, const char* const* argv) {
  ProgramArguments p;
  ros::removeROSArgs(argc, argv, p.args);
  for (const auto& a : p.args) p.pointers.push_back(a.c_str());
  return p;
}

//! Where the stylus comes from.
enum class InputKind : std::uint8_t {
  crtk,          //!< a CRTK device: <touch>/measured_cp (PoseStamped, Touch frame, m)
  phantom_omni,  //!< the 2016 phantom_omni driver: TF base -> tip, /omni1_joint_states
};

//! Settings of RosStylus.
struct StylusConfig {
  InputKind kind = InputKind::crtk;  //!< which driver
  //! A sample older than this (by arrival) is a lost operator: read() reports
  //! DeviceStatus::error and the loop takes the safe state (SafetyConfig::policy).
  nanoseconds timeout = std::chrono::milliseconds(100);
  std::string frame;  //!< CRTK: the frame_id required of measured_cp (empty: any)
  Eigen::Vector3d hd_origin = bridge::default_hd_origin();  //!< the Touch frame's origin
  Topics topics;                                            //!< CRTK names
  PhantomOmniTopics omni;                                   //!< the 2016 driver's names
};

//! Counts of the stylus messages, by what became of them (any thread may read them).
struct StylusCounters {
  std::atomic<std::uint64_t> used{0};          //!< handed to the loop
  std::atomic<std::uint64_t> non_finite{0};    //!< NaN or Inf
  std::atomic<std::uint64_t> wrong_frame{0};   //!< not the frame asked for
  std::atomic<std::uint64_t> invalid{0};       //!< stamp 0
  std::atomic<std::uint64_t> out_of_order{0};  //!< older than the newest used
  std::atomic<std::uint64_t> no_chain{0};      //!< TF: base -> tip not complete yet
  std::atomic<std::uint64_t> joint_states{0};  //!< phantom_omni joint states heard
  std::atomic<std::uint64_t> stale_ticks{0};   //!< loop ticks that found the input too old
  std::atomic<std::uint64_t> losses{0};        //!< times the input went stale

  //! Counts one message's fate.
  void count(InputError e) noexcept {
    switch (e) {
      case InputError::none:
        used.fetch_add(1, std::memory_order_relaxed);
        break;
      case InputError::non_finite:
        non_finite.fetch_add(1, std::memory_order_relaxed);
        break;
      case InputError::wrong_frame:
        wrong_frame.fetch_add(1, std::memory_order_relaxed);
        break;
      case InputError::invalid:
        invalid.fetch_add(1, std::memory_order_relaxed);
        break;
      case InputError::out_of_order:
        out_of_order.fetch_add(1, std::memory_order_relaxed);
        break;
    }
  }
};

//! A stylus message as RosStylus hands it to the loop.
struct StylusMessage {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  //!< mapping frame, m
  std::int64_t stamp_ns = 0;                           //!< the message's stamp
  nanoseconds arrived{0};                              //!< SteadyClock, when it arrived
};

//! A teleop::HapticDevice whose stylus comes from a ROS subscription. The callbacks run on the
//! spinner's thread (one: the single producer); read() and command_force() on the loop's.
class RosStylus {
 public:
  //! Subscribes on `nh`. The object must outlive the subscriptions (keep it beside the node).
  RosStylus(ros::NodeHandle& nh, StylusConfig config) : config_(std::move(config)) {
    if (config_.kind == InputKind::crtk) {
      subscribers_[0] = nh.subscribe(config_.topics.stylus_pose(), 16, &RosStylus::on_pose, this,
                                     ros::TransportHints().tcpNoDelay());
    } else {
      subscribers_[0] = nh.subscribe(config_.omni.tf, 64, &RosStylus::on_tf, this,
                                     ros::TransportHints().tcpNoDelay());
      subscribers_[1] = nh.subscribe(config_.omni.joint_states, 16, &RosStylus::on_joint_states,
                                     this, ros::TransportHints().tcpNoDelay());
    }
  }

  //! Loop thread: the newest sample while it is fresh (ok), not_ready before the first one,
  //! error once it is older than the timeout (the loop then holds and releases: a lost operator).
  endohaptics::teleop::DeviceStatus read(endohaptics::teleop::StylusSample& s) noexcept {
    StylusMessage latest;
    bool fresh = false;
    if (!latest_.read(latest, &fresh)) return endohaptics::teleop::DeviceStatus::not_ready;
    if (clock_.now() - latest.arrived > config_.timeout) {
      counters_.stale_ticks.fetch_add(1, std::memory_order_relaxed);
      if (!stale_) counters_.losses.fetch_add(1, std::memory_order_relaxed);
      stale_ = true;
      used_stamp_ = 0;
      used_fresh_ = false;
      return endohaptics::teleop::DeviceStatus::error;
    }
    stale_ = false;
    s.position = latest.position;
    s.buttons = 0;
    used_stamp_ = latest.stamp_ns;
    used_fresh_ = fresh;
    return endohaptics::teleop::DeviceStatus::ok;
  }

  //! Loop thread: the force goes out with the tick (RosPublisher), nothing to do here.
  endohaptics::teleop::DeviceStatus command_force(const Eigen::Vector3d&) noexcept {
    return endohaptics::teleop::DeviceStatus::ok;
  }

  //! Loop thread: the stamp of the message the last read() used (0: none), and whether that
  //! read was its first.
  [[nodiscard]] std::int64_t used_stamp() const noexcept { return used_stamp_; }
  //! True when the last read() took a message no read() had taken before.
  [[nodiscard]] bool used_fresh() const noexcept { return used_fresh_; }
  //! What became of the messages.
  [[nodiscard]] const StylusCounters& counters() const noexcept { return counters_; }
  //! The settings.
  [[nodiscard]] const StylusConfig& config() const noexcept { return config_; }

 private:
  void on_pose(const geometry_msgs::PoseStamped::ConstPtr& m) {
    Eigen::Vector3d p;
    const std::int64_t stamp = static_cast<std::int64_t>(m->header.stamp.toNSec());
    const InputError e = stylus_position(*m, config_.frame, stamp, newest_stamp_, p);
    counters_.count(e);
    if (e != InputError::none) return;
    newest_stamp_ = stamp;
    latest_.publish({bridge::touch_to_mapping_position(p, config_.hd_origin), stamp, clock_.now()});
  }

  // The 2016 node looked up /base -> /tip on TF: the tip's origin in the base frame, taken as
  // the mapping frame (docs/ros.md says how to check that on the rig).
  void on_tf(const tf2_msgs::TFMessage::ConstPtr& m) {
    bool touched_tip_chain = false;
    std::int64_t stamp = 0;
    for (const auto& t : m->transforms) {
      const auto& tr = t.transform.translation;
      const auto& q = t.transform.rotation;
      const InputError e =
          chain_.update(t.header.frame_id, t.child_frame_id, Eigen::Vector3d(tr.x, tr.y, tr.z),
                        Eigen::Quaterniond(q.w, q.x, q.y, q.z));
      if (e != InputError::none) {
        counters_.count(e);
        return;
      }
      touched_tip_chain = true;
      stamp = std::max(stamp, static_cast<std::int64_t>(t.header.stamp.toNSec()));
    }
    if (!touched_tip_chain) return;
    Eigen::Vector3d p;
    if (!chain_.lookup(config_.omni.base_frame, config_.omni.tip_frame, p)) {
      counters_.no_chain.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    if (stamp == 0) {
      counters_.count(InputError::invalid);
      return;
    }
    if (stamp < newest_stamp_) {
      counters_.count(InputError::out_of_order);
      return;
    }
    counters_.count(InputError::none);
    newest_stamp_ = stamp;
    latest_.publish({p, stamp, clock_.now()});
  }

  void on_joint_states(const sensor_msgs::JointState::ConstPtr&) {
    counters_.joint_states.fetch_add(1, std::memory_order_relaxed);
  }

  StylusConfig config_;
  endohaptics::SteadyClock clock_;
  endohaptics::teleop::LatestValue<StylusMessage> latest_;
  StylusCounters counters_;
  TfChain chain_;                  // spinner thread only
  std::int64_t newest_stamp_ = 0;  // spinner thread only
  std::array<ros::Subscriber, 2> subscribers_;
  // Loop thread only.
  std::int64_t used_stamp_ = 0;
  bool used_fresh_ = false;
  bool stale_ = false;
};

//! Figures of RosPublisher's thread (read them after stop()).
struct PublisherCounters {
  std::uint64_t ticks = 0;          //!< ticks published
  std::uint64_t dropped = 0;        //!< ticks the ring had no room for (loop side)
  std::uint64_t round_trips = 0;    //!< fresh stylus messages timed to the wire
  double round_trip_mean_ms = 0.0;  //!< their mean, ms (stylus message stamp -> setpoint sent)
  double round_trip_p99_ms = 0.0;   //!< their 99th percentile, ms (10 us bins)
  double round_trip_max_ms = 0.0;   //!< the largest, ms
};

//! The loop's figures at the end of a second, for the loop-statistics topic.
struct LoopFigures {
  double t = 0.0;                           //!< s since the first tick
  endohaptics::teleop::LoopSnapshot stats;  //!< the cumulative counters then
};

//! The tick observer that publishes: on_tick (loop thread) copies the tick into a ring and, once
//! a second, the loop's figures into a LatestValue; the thread started by start() publishes them.
class RosPublisher {
 public:
  //! Advertises on `nh`. `omni_feedback`: also publish phantom_omni/OmniFeedback.
  RosPublisher(ros::NodeHandle& nh, Topics topics, bool omni_feedback,
               const PhantomOmniTopics& omni = {}, std::size_t ring = 4096)
      : topics_(std::move(topics)), queue_(ring) {
    endohaptics::teleop::prefault_ring(queue_, TickMessage{});  // no page fault in on_tick
    measured_js_ = nh.advertise<sensor_msgs::JointState>(topics_.measured_js(), 100);
    setpoint_js_ = nh.advertise<sensor_msgs::JointState>(topics_.setpoint_js(), 100);
    measured_jf_ = nh.advertise<sensor_msgs::JointState>(topics_.measured_jf(), 100);
    servo_cf_ = nh.advertise<geometry_msgs::WrenchStamped>(topics_.stylus_force(), 100);
    tick_log_ = nh.advertise<std_msgs::Float64MultiArray>(topics_.tick_log(), 100);
    state_ = nh.advertise<std_msgs::String>(topics_.operating_state(), 10, /*latch*/ true);
    stats_ = nh.advertise<std_msgs::String>(topics_.loop_stats(), 10);
    if (omni_feedback) {
      omni_feedback_ = nh.advertise<phantom_omni::OmniFeedback>(omni.force_feedback, 100);
    }
  }

  RosPublisher(const RosPublisher&) = delete;             //!< owns a thread
  RosPublisher& operator=(const RosPublisher&) = delete;  //!< owns a thread
  ~RosPublisher() { stop(); }

  //! Loop thread: hands the tick over (noexcept, no allocation, no lock); a full ring drops it
  //! and counts. `stylus`: the device, for the stamp of the message the tick used.
  template <typename Loop>
  void on_tick(const endohaptics::teleop::TickResult& r, nanoseconds now, const Loop& loop,
               const RosStylus& stylus) noexcept {
    const TickMessage m = tick_message(r, now, stylus.used_stamp(), stylus.used_fresh());
    if (!queue_.push(m)) dropped_.fetch_add(1, std::memory_order_relaxed);
    if (now >= next_second_) {
      if (next_second_.count() == 0) {
        next_second_ = now;
      } else {
        LoopFigures f;
        f.stats = loop.stats().snapshot();
        f.t = std::chrono::duration<double>(now - started_).count();
        figures_.publish(f);
      }
      if (started_.count() == 0) started_ = now;
      next_second_ += std::chrono::seconds(1);
    }
  }

  //! Starts the publishing thread (before the loop thread turns real-time: it stays
  //! SCHED_OTHER, with the CPUs the starting thread had).
  void start() {
    thread_ = std::thread([this] { run(); });
  }

  //! Publishes what is left and joins the thread.
  void stop() {
    if (!thread_.joinable()) return;
    done_.store(true);
    thread_.join();
  }

  //! The thread's figures (after stop()).
  [[nodiscard]] PublisherCounters counters() const noexcept {
    PublisherCounters c = counters_;
    c.dropped = dropped_.load(std::memory_order_relaxed);
    return c;
  }

 private:
  void run() {
    sensor_msgs::JointState js, sp, jf;
    geometry_msgs::WrenchStamped cf;
    std_msgs::Float64MultiArray row;
    phantom_omni::OmniFeedback feedback;
    std_msgs::String state;
    std::string last_state;
    endohaptics::teleop::LoopSnapshot previous;
    std::array<std::uint32_t, round_trip_bins> histogram{};
    double round_trip_sum = 0.0;
    auto next_state = std::chrono::steady_clock::now();
    for (;;) {
      const bool last = done_.load();
      TickMessage m;
      while (queue_.pop(m)) {
        ros::Time wall;
        wall.fromNSec(static_cast<std::uint64_t>(m.wall_ns));
        const auto& r = m.record;
        fill_joint_state(js, m.valid_state() ? wall : ros::Time(), &r.position, &r.velocity,
                         &r.current);
        measured_js_.publish(js);
        fill_joint_state(sp, wall, &r.setpoint, nullptr, nullptr);
        setpoint_js_.publish(sp);
        fill_joint_state(jf, m.valid_state() ? wall : ros::Time(), nullptr, nullptr,
                         &r.motor_force);
        measured_jf_.publish(jf);
        const Eigen::Vector3d f_touch = bridge::mapping_to_touch_force(r.stylus_force);
        cf.header.stamp = wall;
        fill_vector3(cf.wrench.force, f_touch);
        fill_vector3(cf.wrench.torque, Eigen::Vector3d::Zero());
        servo_cf_.publish(cf);
        if (omni_feedback_) {
          fill_vector3(feedback.force, f_touch);
          fill_vector3(feedback.position, Eigen::Vector3d::Zero());  // as the 2016 node sent it
          omni_feedback_.publish(feedback);
        }
        fill_tick_log<std_msgs::Float64MultiArray, std_msgs::MultiArrayDimension>(
            row, r, counters_.ticks % 1000 == 0);
        tick_log_.publish(row);
        const std::string_view s = operating_state(r);
        if (s != last_state || std::chrono::steady_clock::now() >= next_state) {
          last_state = std::string(s);
          state.data = last_state;
          state_.publish(state);
          next_state = std::chrono::steady_clock::now() + std::chrono::seconds(1);
        }
        // Stylus message in -> setpoint on the wire: the tick sent it one round trip before it
        // ended (wall_ns); same clock on every host of a test, NTP across machines.
        if (m.input_fresh && m.input_stamp_ns > 0) {
          const double ms =
              (static_cast<double>(m.wall_ns - m.input_stamp_ns) - r.round_trip * 1e9) * 1e-6;
          ++counters_.round_trips;
          round_trip_sum += ms;
          counters_.round_trip_max_ms = std::max(counters_.round_trip_max_ms, ms);
          const auto bin =
              static_cast<std::size_t>(std::clamp(ms * 100.0, 0.0, double{round_trip_bins - 1}));
          ++histogram[bin];
        }
        ++counters_.ticks;
      }
      LoopFigures f;
      bool fresh = false;
      if (figures_.read(f, &fresh) && fresh) {
        const endohaptics::teleop::LoopWindow w = f.stats.since(previous);
        previous = f.stats;
        std_msgs::String line;
        line.data = fmt::format(
            "t {:.1f} s  rate {:.1f} Hz  period err mean {:.1f} us  deadline misses {}  "
            "round trip {:.1f} us  loss {:.3f} %  published {}  dropped {}",
            f.t, w.rate, w.period_error_mean * 1e6, w.deadline_misses, w.round_trip_mean * 1e6,
            w.loss_percent, counters_.ticks, dropped_.load(std::memory_order_relaxed));
        stats_.publish(line);
      }
      if (last) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));  // a batch per wake-up
    }
    if (counters_.round_trips > 0) {
      counters_.round_trip_mean_ms = round_trip_sum / static_cast<double>(counters_.round_trips);
      std::uint64_t seen = 0;
      for (std::size_t b = 0; b < histogram.size(); ++b) {
        seen += histogram[b];
        if (static_cast<double>(seen) >= 0.99 * static_cast<double>(counters_.round_trips)) {
          counters_.round_trip_p99_ms = static_cast<double>(b + 1) * 0.01;
          break;
        }
      }
    }
  }

  static constexpr std::size_t round_trip_bins = 10000;  // 10 us each, up to 100 ms

  Topics topics_;
  ros::Publisher measured_js_, setpoint_js_, measured_jf_, servo_cf_, tick_log_, state_, stats_,
      omni_feedback_;
  boost::lockfree::spsc_queue<TickMessage> queue_;
  endohaptics::teleop::LatestValue<LoopFigures> figures_;
  std::atomic<std::uint64_t> dropped_{0};
  std::atomic<bool> done_{false};
  std::thread thread_;
  PublisherCounters counters_;  // the thread's; read after stop()
  // Loop thread only.
  nanoseconds next_second_{0};
  nanoseconds started_{0};
};

//! The tick observer run_bridge calls: the publisher, told which device the tick read.
struct RosTickObserver {
  RosPublisher* publisher;  //!< publishes
  const RosStylus* stylus;  //!< the device, for the stamp of the stylus message used

  //! Loop thread: noexcept, no allocation, no lock.
  template <typename Loop>
  void on_tick(const endohaptics::teleop::TickResult& r, nanoseconds now,
               const Loop& loop) noexcept {
    publisher->on_tick(r, now, loop, *stylus);
  }
};

}  // namespace ros_bridge
