// What the loopback benchmarks share (loopback_bench.cpp, gateway_bench.cpp): the benchmark key
// and v2 session settings, the emulator's socket on 127.0.0.1, and the emulated sbRIO polling in
// its own thread, over the 2016 wire or protocol v2.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <endohaptics/protocol/secure_session.hpp>
#include <endohaptics/sim/sbrio_emulator.hpp>
#include <endohaptics/sim/simulated_rig.hpp>
#include <endohaptics/teleop/realtime.hpp>
#include <endohaptics/transport/secure_transport.hpp>
#include <endohaptics/transport/udp_server_transport.hpp>
#include <endohaptics/transport/udp_transport.hpp>
#include <optional>
#include <thread>
#include <type_traits>

namespace loopback_emulator {

namespace transport = endohaptics::transport;
namespace sim = endohaptics::sim;
namespace protocol = endohaptics::protocol;

//! The robot side of protocol v2 on UDP, and the console side.
using ServerV2 =
    transport::SecureTransport<transport::UdpServerTransport, protocol::SecureResponder<4>>;
using ClientV2 = transport::SecureTransport<transport::UdpTransport, protocol::SecureInitiator<4>>;

//! The benchmark key (a fixed pattern; the programs load theirs from a file).
inline protocol::SecureKey bench_key() {
  std::array<std::byte, protocol::SecureKey::size> k{};
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = std::byte{static_cast<std::uint8_t>(3 * i)};
  return protocol::SecureKey(k);
}

//! The benchmarks' v2 session settings (the rig name both sides use).
inline protocol::InitiatorConfig console_config() {
  protocol::InitiatorConfig c;
  c.rig = protocol::make_rig_id("bench");
  return c;
}
inline protocol::ResponderConfig robot_config() {
  protocol::ResponderConfig c;
  c.rig = protocol::make_rig_id("bench");
  return c;
}

//! The emulator's socket: 127.0.0.1, any free port, every other setting its default.
inline transport::UdpServerConfig loopback_server() {
  transport::UdpServerConfig c;
  c.bind_address = "127.0.0.1";
  c.port = 0;
  return c;
}

//! The emulated sbRIO in its own thread, on 127.0.0.1, any free port, touching `environment`;
//! over protocol v2 when `V2`, else the 2016 wire; SCHED_FIFO at `fifo_priority` when not 0 and
//! permitted.
template <bool V2>
class EmulatorThread {
 public:
  using Link = std::conditional_t<V2, ServerV2, transport::UdpServerTransport>;
  explicit EmulatorThread(sim::Environment environment, int fifo_priority = 0)
      : server_(loopback_server()),
        link_(make_link()),
        rig_(sim::endowrist_2016_rig<4>(environment)),
        emulator_(*link_, rig_, clock_),
        thread_([this, fifo_priority] {
          (void)endohaptics::teleop::apply_realtime(
              {.fifo_priority = fifo_priority, .timer_slack_ns = 1});
          while (!stop_.load(std::memory_order_relaxed)) {
            (void)emulator_.poll(std::chrono::milliseconds(1));
          }
        }) {}
  EmulatorThread(const EmulatorThread&) = delete;
  EmulatorThread& operator=(const EmulatorThread&) = delete;
  ~EmulatorThread() {
    stop_.store(true);
    thread_.join();
  }
  [[nodiscard]] std::uint16_t port() const { return server_.local_endpoint().port(); }

 private:
  Link* make_link() {
    if constexpr (V2) {
      return &v2_.emplace(server_, protocol::SecureResponder<4>(bench_key(), robot_config()));
    } else {
      return &server_;
    }
  }
  transport::UdpServerTransport server_;
  std::optional<ServerV2> v2_;
  Link* link_;
  endohaptics::SteadyClock clock_;
  sim::SimulatedRig<4> rig_;
  sim::SbrioEmulator<Link, sim::SimulatedRig<4>> emulator_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace loopback_emulator
