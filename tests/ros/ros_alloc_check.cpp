// The ROS bridge's loop allocates nothing on its thread while ROS traffic flows (docs/ros.md): a
// TeleopLoop with the ROS stylus (RosStylus, fed by a subscription) and the publishing observer
// (RosPublisher) over an in-memory sbRIO, paced at 1 kHz; every heap allocation of the loop
// thread is counted (tests/alloc_counter.hpp) over 2000 ticks while a stylus stand-in publishes at
// 1 kHz, the bridge's topics are published and a `rostopic hz` subscribes (tests/ros/ros_e2e.py
// alloc starts roscore and both). Prints "PASS: ..." and exits 0, or says what failed.
#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <fmt/format.h>

#include <chrono>
#include <endohaptics/kinematics/cylindrical_mapper.hpp>
#include <endohaptics/teleop/teleop_loop.hpp>
#include <endohaptics/transport/in_memory_transport.hpp>
#include <thread>

#include "ros1_node.hpp"

namespace {

using Codec = endohaptics::protocol::PacketCodec<4>;

// An sbRIO that obeys at once: enabled motors go 5 % of the way to their setpoint per exchange.
struct ObeyingSbrio {
  Codec::State state;
  template <typename Reply>
  void operator()(std::span<const std::byte> in, Reply& reply) noexcept {
    Codec::Setpoint sp;
    if (Codec::decode_setpoint(in, sp) != endohaptics::protocol::CodecStatus::ok) return;
    for (int i = 0; i < 4; ++i) {
      if ((sp.enable_mask & (1u << i)) != 0) {
        state.position[i] += 0.05 * (sp.position[i] - state.position[i]);
      }
      state.current[i] = 2.0 * (sp.position[i] - state.position[i]);
    }
    state.active_mask = sp.enable_mask;
    Codec::StateBytes out{};
    if (Codec::encode_state(state, out) == endohaptics::protocol::CodecStatus::ok) {
      (void)reply.send(out);
    }
  }
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "endohaptics_alloc_test",
            ros::init_options::NoSigintHandler | ros::init_options::NoRosout);
  if (!ros::master::check()) {
    fmt::print("FAIL: no ROS master at {}\n", ros::master::getURI());
    return 1;
  }
  ros::NodeHandle nh;
  ros_bridge::RosStylus stylus(nh, ros_bridge::StylusConfig{});
  ros_bridge::RosPublisher publisher(nh, ros_bridge::Topics{}, false);
  ros::AsyncSpinner spinner(1);
  spinner.start();
  publisher.start();
  endohaptics::SteadyClock clock;
  endohaptics::transport::RespondingTransport<ObeyingSbrio> link{ObeyingSbrio{}};
  endohaptics::teleop::NoForceEstimator estimator;
  endohaptics::kinematics::CylindricalMapper<> mapper;
  endohaptics::teleop::TeleopLoop loop(link, stylus, estimator, mapper, clock);
  ros_bridge::RosTickObserver observer{&publisher, &stylus};

  // Wait (at most 10 s) for the stand-in's stylus, then 1000 ticks to warm up.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (stylus.counters().used.load() < 100 && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  constexpr std::uint64_t warm_up = 1000, counted = 2000;
  std::uint64_t ticks = 0, ok = 0;
  const auto run = [&](std::uint64_t n) {
    const std::uint64_t end = ticks + n;
    loop.run([&] { return ticks >= end; },
             [&](const endohaptics::teleop::TickResult& r) {
               ++ticks;
               if (r.status == endohaptics::teleop::TickStatus::ok) ++ok;
               observer.on_tick(r, clock.now(), loop);
             });
  };
  run(warm_up);
  const std::uint64_t used_before = stylus.counters().used.load();
  ok = 0;
  const long allocations =
      endohaptics::test::allocations_on_this_thread_during([&] { run(counted); });
  const std::uint64_t used = stylus.counters().used.load() - used_before;
  publisher.stop();
  spinner.stop();
  const auto p = publisher.counters();
  fmt::print(
      "loop thread: {} heap allocations in {} ticks ({} ok) at 1 kHz, while {} stylus messages "
      "arrived and {} ticks were published ({} dropped)\n",
      allocations, counted, ok, used, p.ticks, p.dropped);
  ros::shutdown();
  // What is proven is the allocations: the counted ticks must have run with ROS traffic flowing
  // both ways (on a loaded machine some ticks miss their stylus message; that is not the test).
  if (allocations != 0 || ok < counted / 2 || used < counted / 4 || p.dropped != 0) {
    fmt::print("FAIL: allocations {}, ok ticks {}, stylus messages {}, dropped {}\n", allocations,
               ok, used, p.dropped);
    return 1;
  }
  fmt::print("PASS: 0 heap allocations on the loop thread in {} ticks with ROS traffic\n", counted);
  return 0;
}
