// endohaptics-sbrio-gateway's price (transport::V2Gateway, docs/performance.md): one v2 exchange
// (a sealed setpoint out, the sealed state that answers it back) on UDP loopback, console ->
// gateway -> 2016 emulator and back, against the direct link console -> v2 emulator in the same
// run (each exchange waits for its answer: the round trip, real time); and the gateway's CPU per
// packet in one thread over in-memory transports, against the v2 robot side answering directly.
#include <benchmark/benchmark.h>

#include <pthread.h>
#include <array>
#include <atomic>
#include <chrono>
#include <ctime>
#include <endohaptics/protocol/secure_session.hpp>
#include <endohaptics/sim/sbrio_emulator.hpp>
#include <endohaptics/sim/simulated_rig.hpp>
#include <endohaptics/teleop/realtime.hpp>
#include <endohaptics/transport/in_memory_transport.hpp>
#include <endohaptics/transport/secure_transport.hpp>
#include <endohaptics/transport/udp_server_transport.hpp>
#include <endohaptics/transport/udp_transport.hpp>
#include <endohaptics/transport/v2_gateway.hpp>
#include <optional>
#include <thread>
#include <type_traits>

#include "loopback_emulator.hpp"

namespace gateway_bench {

namespace {

namespace transport = endohaptics::transport;
namespace sim = endohaptics::sim;
namespace protocol = endohaptics::protocol;
using Legacy = protocol::PacketCodec<4>;
using RobotV2 = loopback_emulator::ServerV2;
using ConsoleV2 = loopback_emulator::ClientV2;
using loopback_emulator::bench_key;
using loopback_emulator::console_config;
using loopback_emulator::loopback_server;
using loopback_emulator::robot_config;

Legacy::SetpointBytes setpoint_bytes() {
  Legacy::Setpoint s;
  s.enable_mask = 0x0F;
  Legacy::SetpointBytes b{};
  (void)Legacy::encode_setpoint(s, b);
  return b;
}

// The emulated sbRIO with nothing touching the tool: protocol v2 itself (`V2`), or the 2016 wire
// (behind the gateway).
template <bool V2>
struct EmulatorThread : loopback_emulator::EmulatorThread<V2> {
  EmulatorThread() : loopback_emulator::EmulatorThread<V2>(sim::Environment::free_space) {}
};

// The gateway's sockets: each receive on the sbRIO link (`link_spin`) and on the consoles' side
// (`network_spin`) polls that long before it blocks (0: blocks at once, the default).
struct Spin {
  std::chrono::nanoseconds link{0};
  std::chrono::nanoseconds network{0};
};

transport::UdpServerConfig gateway_server(std::chrono::nanoseconds spin) {
  transport::UdpServerConfig c = loopback_server();
  c.receive_spin = spin;
  return c;
}

// endohaptics-sbrio-gateway's loop in its own thread: v2 on 127.0.0.1, the 2016 emulator behind.
class GatewayThread {
 public:
  explicit GatewayThread(std::uint16_t sbrio_port, Spin spin = {})
      : server_(gateway_server(spin.network)),
        secure_(server_, protocol::SecureResponder<4>(bench_key(), robot_config())),
        link_({.local_address = "127.0.0.1",
               .remote_address = "127.0.0.1",
               .remote_port = sbrio_port,
               .receive_spin = spin.link}),
        gateway_(secure_, link_, clock_),
        thread_([this] {
          (void)endohaptics::teleop::apply_realtime({.timer_slack_ns = 1});
          while (!stop_.load(std::memory_order_relaxed)) {
            (void)gateway_.step(std::chrono::milliseconds(1));
          }
        }) {}
  GatewayThread(const GatewayThread&) = delete;
  GatewayThread& operator=(const GatewayThread&) = delete;
  ~GatewayThread() {
    stop_.store(true);
    thread_.join();
  }
  [[nodiscard]] std::uint16_t port() const { return server_.local_endpoint().port(); }
  [[nodiscard]] const transport::GatewayCounters& counters() const { return gateway_.counters(); }
  // The gateway thread's CPU time so far (user and system), read from another thread.
  [[nodiscard]] std::chrono::nanoseconds cpu() {
    clockid_t id{};
    timespec ts{};
    if (::pthread_getcpuclockid(thread_.native_handle(), &id) != 0 ||
        ::clock_gettime(id, &ts) != 0) {
      return std::chrono::nanoseconds(-1);
    }
    return std::chrono::seconds(ts.tv_sec) + std::chrono::nanoseconds(ts.tv_nsec);
  }
  // Receives on each side that the spin ended (no blocking wait), and that blocked after it.
  [[nodiscard]] std::uint64_t spin_hits() const {
    return link_.receive_wait().spin_hits() + server_.receive_wait().spin_hits();
  }
  [[nodiscard]] std::uint64_t spin_misses() const {
    return link_.receive_wait().spin_misses() + server_.receive_wait().spin_misses();
  }

 private:
  transport::UdpServerTransport server_;
  RobotV2 secure_;
  transport::UdpTransport link_;
  endohaptics::SteadyClock clock_;
  transport::V2Gateway<RobotV2, transport::UdpTransport> gateway_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Round trips of a v2 console to the robot side at `port`: each iteration one exchange (a
// setpoint, then wait for the state that answers it). The handshake happens before timing. With a
// gateway: its thread's CPU per exchange over the timed loop.
void round_trips(benchmark::State& st, std::uint16_t port, GatewayThread* gateway = nullptr) {
  (void)endohaptics::teleop::apply_realtime({.timer_slack_ns = 1});
  transport::UdpTransport udp(
      {.local_address = "127.0.0.1", .remote_address = "127.0.0.1", .remote_port = port});
  ConsoleV2 console(udp, protocol::SecureInitiator<4>(bench_key(), console_config()));
  const auto setpoint = setpoint_bytes();
  std::array<std::byte, 64> state{};
  const auto exchange = [&] {
    for (int attempt = 0; attempt < 100; ++attempt) {
      (void)console.send(setpoint);
      if (console.receive(state, std::chrono::milliseconds(20)).status ==
          transport::TransportStatus::ok) {
        return true;
      }
    }
    return false;
  };
  if (!exchange()) {
    st.SkipWithError("no answer from the robot side");
    return;
  }
  std::int64_t retries = 0;
  const auto cpu_before = gateway != nullptr ? gateway->cpu() : std::chrono::nanoseconds(0);
  const auto hits_before = gateway != nullptr ? gateway->spin_hits() : 0;
  const auto misses_before = gateway != nullptr ? gateway->spin_misses() : 0;
  for (auto _ : st) {
    (void)console.send(setpoint);
    while (console.receive(state, std::chrono::milliseconds(20)).status !=
           transport::TransportStatus::ok) {
      ++retries;
      (void)console.send(setpoint);
    }
  }
  st.counters["resends"] = static_cast<double>(retries);
  st.SetItemsProcessed(st.iterations());
  if (gateway != nullptr && st.iterations() > 0) {
    const auto n = static_cast<double>(st.iterations());
    // The gateway thread's CPU (user + system) per exchange, µs: what a spin costs.
    st.counters["gw_cpu_us"] =
        std::chrono::duration<double, std::micro>(gateway->cpu() - cpu_before).count() / n;
    // Per exchange: receives a spin answered (no wake-up), and spins that ran out and blocked.
    st.counters["spin_hits"] = static_cast<double>(gateway->spin_hits() - hits_before) / n;
    st.counters["spin_misses"] = static_cast<double>(gateway->spin_misses() - misses_before) / n;
  }
}

void BM_Gateway_round_trip_direct_v2(benchmark::State& st) {
  EmulatorThread<true> emulator;
  round_trips(st, emulator.port());
}

void via_gateway(benchmark::State& st, Spin spin) {
  EmulatorThread<false> emulator;
  GatewayThread gateway(emulator.port(), spin);
  round_trips(st, gateway.port(), &gateway);
  st.counters["relayed"] = static_cast<double>(gateway.counters().relayed);
  // Answers later than the gateway's answer timeout (2 ms): given up, the console resends.
  st.counters["unanswered"] = static_cast<double>(gateway.counters().unanswered);
}

void BM_Gateway_round_trip_via_gateway(benchmark::State& st) { via_gateway(st, {}); }

// The gateway spinning up to range(0) µs before each blocking receive: on the sbRIO link only
// (range(1) == 1: while an answer is awaited), or on both sides (2).
void BM_Gateway_round_trip_via_gateway_spin(benchmark::State& st) {
  const auto spin = std::chrono::microseconds(st.range(0));
  via_gateway(st, {.link = spin, .network = st.range(1) == 2 ? spin : std::chrono::nanoseconds(0)});
}

// What a relay cannot save: one loopback hop's system calls in one thread, no wake-up (a send,
// then the receive that finds the datagram queued: its wait and its read). The gateway adds two
// such hops to each exchange, wherever its threads run and however they wait.
void BM_Gateway_loopback_hop(benchmark::State& st) {
  transport::UdpServerTransport server(loopback_server());
  transport::UdpTransport client({.local_address = "127.0.0.1",
                                  .remote_address = "127.0.0.1",
                                  .remote_port = server.local_endpoint().port()});
  const auto setpoint = setpoint_bytes();
  std::array<std::byte, 64> buffer{};
  for (auto _ : st) {
    (void)client.send(setpoint);
    if (server.receive(buffer, std::chrono::milliseconds(20)).status !=
        transport::TransportStatus::ok) {
      st.SkipWithError("the datagram did not arrive");
      break;
    }
  }
  st.SetItemsProcessed(st.iterations());
}

// The CPU per packet, one thread, no sockets: the console's send, the robot side's work, the
// console's receive. Direct: the v2 robot side answers itself (verify, seal); via the gateway:
// V2Gateway::step (verify, decode, relay, take the sbRIO's answer, seal) with a 2016 sbRIO that
// answers in its send. The difference is the gateway's own cost per packet.
using Link = transport::InMemoryLink<128, 16>;
using ConsoleMem = transport::SecureTransport<Link::Endpoint, protocol::SecureInitiator<4>>;
using RobotMem = transport::SecureTransport<Link::Endpoint, protocol::SecureResponder<4>>;

struct FixedState {
  template <typename Reply>
  void operator()(std::span<const std::byte>, Reply& reply) noexcept {
    static const Legacy::StateBytes state = [] {
      Legacy::StateBytes b{};
      (void)Legacy::encode_state({}, b);
      return b;
    }();
    (void)reply.send(state);
  }
};

template <typename Step>
void in_memory(benchmark::State& st, Link& link, ConsoleMem& console, Step robot_step) {
  const auto setpoint = setpoint_bytes();
  std::array<std::byte, 64> state{};
  (void)console.send(setpoint);  // the HELLO
  robot_step();
  (void)console.receive(state, std::chrono::nanoseconds(0));
  for (auto _ : st) {
    (void)console.send(setpoint);
    robot_step();
    if (console.receive(state, std::chrono::nanoseconds(0)).status !=
        transport::TransportStatus::ok) {
      st.SkipWithError("no answer");
      break;
    }
  }
  (void)link;
  st.SetItemsProcessed(st.iterations());
}

void BM_Gateway_cpu_direct_v2(benchmark::State& st) {
  Link link;
  ConsoleMem console(link.a(), protocol::SecureInitiator<4>(bench_key(), console_config()));
  RobotMem robot(link.b(), protocol::SecureResponder<4>(bench_key(), robot_config()));
  std::array<std::byte, 32> in{};
  Legacy::StateBytes state{};
  (void)Legacy::encode_state({}, state);
  in_memory(st, link, console, [&] {
    if (robot.receive(in, std::chrono::nanoseconds(0)).status == transport::TransportStatus::ok) {
      (void)robot.send(state);
    }
  });
}

void BM_Gateway_cpu_via_gateway(benchmark::State& st) {
  Link link;
  ConsoleMem console(link.a(), protocol::SecureInitiator<4>(bench_key(), console_config()));
  RobotMem robot(link.b(), protocol::SecureResponder<4>(bench_key(), robot_config()));
  transport::RespondingTransport<FixedState> sbrio{FixedState{}};
  endohaptics::SteadyClock clock;
  transport::V2Gateway<RobotMem, transport::RespondingTransport<FixedState>> gateway(robot, sbrio,
                                                                                     clock);
  in_memory(st, link, console, [&] { (void)gateway.step(std::chrono::nanoseconds(0)); });
}

}  // namespace

BENCHMARK(BM_Gateway_round_trip_direct_v2)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_Gateway_round_trip_via_gateway)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_Gateway_round_trip_via_gateway_spin)
    ->ArgsProduct({{20, 50, 200}, {1, 2}})
    ->ArgNames({"spin_us", "sides"})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();
BENCHMARK(BM_Gateway_loopback_hop)->UseRealTime();
BENCHMARK(BM_Gateway_cpu_direct_v2);
BENCHMARK(BM_Gateway_cpu_via_gateway);

}  // namespace gateway_bench
