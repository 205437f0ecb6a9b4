// The whole loop on UDP loopback: TeleopLoop (UdpTransport, scripted operator, 2016 estimator
// paced at 1 kHz, cylindrical mapping) against SbrioEmulator + SimulatedRig (UdpServerTransport)
// in another thread. Pacing quality at 1 kHz side by side with the machine's bare
// clock_nanosleep pacing (the floor any loop on this machine sits on), and the rate with
// `--rate max` (period 0). Figures are user counters: rate_hz, loss_pct, p99_period_err_us,
// max_period_err_us, deadline_misses. Arg: ticks per run. The `_v2` variants run the same loop
// over protocol v2 (SecureTransport on both sides, docs/protocol.md) in the same run.
#include <benchmark/benchmark.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sched.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <endohaptics/estimation/force_estimator.hpp>
#include <endohaptics/estimation/paced_estimator.hpp>
#include <endohaptics/kinematics/cylindrical_mapper.hpp>
#include <endohaptics/protocol/secure_session.hpp>
#include <endohaptics/sim/sbrio_emulator.hpp>
#include <endohaptics/sim/scripted_operator.hpp>
#include <endohaptics/sim/simulated_rig.hpp>
#include <endohaptics/teleop/realtime.hpp>
#include <endohaptics/teleop/teleop_loop.hpp>
#include <endohaptics/transport/secure_transport.hpp>
#include <endohaptics/transport/udp_server_transport.hpp>
#include <endohaptics/transport/udp_transport.hpp>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <thread>
#include <type_traits>

#include "cpu_pinning.hpp"
#include "loopback_emulator.hpp"
#include "smoke_pass.hpp"

namespace loopback_bench {

namespace {

namespace transport = endohaptics::transport;
namespace sim = endohaptics::sim;
namespace tp = endohaptics::teleop;
namespace est = endohaptics::estimation;
namespace protocol = endohaptics::protocol;
using loopback_emulator::bench_key;
using loopback_emulator::ClientV2;
using loopback_emulator::console_config;
using loopback_emulator::EmulatorThread;
using loopback_emulator::robot_config;
using std::chrono::nanoseconds;

// Ticks per run: a tenth under the smoke pass (smoke_pass.hpp; the runs' names show the count).
std::int64_t run_ticks(std::int64_t full) { return bench::smoke_scaled<std::int64_t>(full, 10); }

// The loop's figures as the benchmark's counters.
void report(benchmark::State& st, const tp::LoopStats& s) {
  st.counters["rate_hz"] = s.rate();
  st.counters["loss_pct"] = s.loss_percent();
  st.counters["p99_period_err_us"] = s.period_error().quantile(0.99) * 1e6;
  st.counters["max_period_err_us"] = s.period_error().max() * 1e6;
  st.counters["deadline_misses"] = static_cast<double>(s.deadline_misses());
  st.counters["p99_round_trip_us"] = s.round_trip().quantile(0.99) * 1e6;
}

// fifo: SCHED_FIFO for the loop (80) and the emulator (70) when permitted (root); the
// `fifo_applied` counter says whether it was. V2: protocol v2 on both sides.
template <bool V2 = false>
void run_loop(benchmark::State& st, nanoseconds period, nanoseconds busy_tail, bool fifo = false,
              nanoseconds spin = nanoseconds(0)) {
  const auto ticks = static_cast<std::uint64_t>(st.range(0));
  const auto rt = tp::apply_realtime({.fifo_priority = fifo ? 80 : 0, .timer_slack_ns = 1});
  for (auto _ : st) {
    st.PauseTiming();
    auto emulator =
        std::make_unique<EmulatorThread<V2>>(sim::Environment::tissue, rt.fifo ? 70 : 0);
    transport::UdpTransport udp({.local_address = "127.0.0.1",
                                 .remote_address = "127.0.0.1",
                                 .remote_port = emulator->port(),
                                 .receive_spin = spin});
    std::optional<ClientV2> v2;
    if constexpr (V2) {
      v2.emplace(udp, protocol::SecureInitiator<4>(bench_key(), console_config()));
    }
    auto& transport = [&]() -> auto& {
      if constexpr (V2) {
        return *v2;
      } else {
        return udp;
      }
    }
    ();
    endohaptics::SteadyClock clock;
    sim::ScriptedOperator<endohaptics::SteadyClock> hand(clock);
    est::ForceEstimator<est::rate::Decimate> estimator;
    est::PacedEstimator paced(estimator, clock, std::chrono::milliseconds(1));
    endohaptics::kinematics::CylindricalMapper<> mapper;
    tp::TeleopLoopConfig config;
    config.period = period;
    tp::TeleopLoop loop(transport, hand, paced, mapper, clock, config);
    std::uint64_t n = 0;
    // Warm-up until the link is up, then measure on fresh statistics.
    loop.run([&] { return n >= 200; }, [&](const tp::TickResult&) { ++n; });
    tp::LoopStats stats(period);
    n = 0;
    st.ResumeTiming();
    loop.run([&] { return n >= ticks; },
             [&](const tp::TickResult& r) {
               ++n;
               stats.record_tick_start(clock.now());
               stats.record_exchange(r.exchange, r.round_trip, 0);
             },
             busy_tail);
    st.PauseTiming();
    report(st, stats);
    emulator.reset();
    st.ResumeTiming();
  }
  st.SetItemsProcessed(static_cast<std::int64_t>(ticks) * st.iterations());
  st.counters["fifo_applied"] = rt.fifo ? 1 : 0;
  if (rt.fifo) {  // back to normal scheduling for the benchmarks that follow
    sched_param normal{};
    (void)::sched_setscheduler(0, SCHED_OTHER, &normal);
  }
}

void BM_Loopback_1kHz(benchmark::State& st) {
  run_loop(st, std::chrono::milliseconds(1), nanoseconds(0));
}
void BM_Loopback_1kHz_busy_tail_200us(benchmark::State& st) {
  run_loop(st, std::chrono::milliseconds(1), std::chrono::microseconds(200));
}
void BM_Loopback_1kHz_fifo_busy_tail_200us(benchmark::State& st) {
  run_loop(st, std::chrono::milliseconds(1), std::chrono::microseconds(200), true);
}
void BM_Loopback_max_rate(benchmark::State& st) { run_loop(st, nanoseconds(0), nanoseconds(0)); }
void BM_Loopback_max_rate_v2(benchmark::State& st) {
  run_loop<true>(st, nanoseconds(0), nanoseconds(0));
}
void BM_Loopback_1kHz_v2(benchmark::State& st) {
  run_loop<true>(st, std::chrono::milliseconds(1), nanoseconds(0));
}

// The v2 handshake on loopback: from a new console's first send (its HELLO) to the first state
// of the session, against the emulator thread: HELLO, WELCOME, the first setpoint, its state.
void BM_Loopback_v2_handshake(benchmark::State& st) {
  auto emulator = std::make_unique<EmulatorThread<true>>(sim::Environment::tissue);
  const auto setpoint = [] {
    protocol::PacketCodec<4>::SetpointBytes b{};
    (void)protocol::PacketCodec<4>::encode_setpoint({}, b);
    return b;
  }();
  std::uint64_t sends = 0;
  for (auto _ : st) {
    st.PauseTiming();
    transport::UdpTransport udp({.local_address = "127.0.0.1",
                                 .remote_address = "127.0.0.1",
                                 .remote_port = emulator->port()});
    ClientV2 client(udp, protocol::SecureInitiator<4>(bench_key(), console_config()));
    std::array<std::byte, 64> state{};
    st.ResumeTiming();
    for (;;) {
      (void)client.send(setpoint);
      ++sends;
      if (client.receive(state, std::chrono::milliseconds(20)).status ==
          transport::TransportStatus::ok) {
        break;
      }
    }
  }
  st.counters["sends_per_handshake"] =
      static_cast<double>(sends) / static_cast<double>(st.iterations());
}

// How each end of a ping-pong waits for its datagram.
enum class Wait {
  blocking,  // recv in a blocking socket (no deadline: the floor)
  ppoll,     // ppoll with a 1 ms timeout, then a non-blocking read (UdpTransport before timerfds)
  transport  // detail::ReadableWait with a 1 ms deadline, then a non-blocking read (the transports)
};

// The wire's floor for `--rate max`: a raw POSIX UDP ping-pong on 127.0.0.1 between this thread
// and an echo thread (17 bytes out, 49 back, the 2016 sizes). With Wait::blocking each end blocks
// in recv: the rate the loop would reach if the loop, the emulator and the transports cost
// nothing. rate_hz here and in BM_Loopback_max_rate, same run, give the ratio
// docs/performance.md tracks. The other waits show what a deadline costs per round trip, both
// ends waiting as the transports do (same reads and sends, only the wait differs).
void ping_pong(benchmark::State& st, Wait wait) {
  const auto ticks = st.range(0);
  const auto open_socket = [] {
    const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (fd < 0 || ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
      throw std::runtime_error("cannot open a UDP socket on 127.0.0.1");
    }
    return fd;
  };
  const int server = open_socket();
  const int client = open_socket();
  sockaddr_in server_address{};
  socklen_t length = sizeof server_address;
  (void)::getsockname(server, reinterpret_cast<sockaddr*>(&server_address), &length);
  (void)::connect(client, reinterpret_cast<sockaddr*>(&server_address), sizeof server_address);
  const timeval wake{0, 100000};  // the echo thread looks at `stop` at least every 100 ms
  (void)::setsockopt(server, SOL_SOCKET, SO_RCVTIMEO, &wake, sizeof wake);
  // Waits as `wait` says for `fd` to be readable, at most 1 ms (ReadableWait: `timer`'s).
  const auto readable = [wait](int fd, transport::detail::ReadableWait& timer) {
    if (wait == Wait::blocking) return true;
    if (wait == Wait::transport) {
      return timer.until(fd, transport::detail::monotonic_now() + std::chrono::milliseconds(1)) ==
             transport::TransportStatus::ok;
    }
    pollfd pfd{fd, POLLIN, 0};
    const timespec one_ms{0, 1000000};
    return ::ppoll(&pfd, 1, &one_ms, nullptr) > 0;
  };
  const int read_flags = wait == Wait::blocking ? 0 : MSG_DONTWAIT;
  std::atomic<bool> stop{false};
  std::thread echo([&] {
    (void)tp::apply_realtime({.timer_slack_ns = 1});  // as EmulatorThread
    transport::detail::ReadableWait timer;
    std::array<char, 64> in{};
    const std::array<char, 49> state{};
    sockaddr_in from{};
    while (!stop.load(std::memory_order_relaxed)) {
      if (!readable(server, timer)) continue;
      socklen_t n = sizeof from;
      if (::recvfrom(server, in.data(), in.size(), read_flags, reinterpret_cast<sockaddr*>(&from),
                     &n) > 0) {
        (void)::sendto(server, state.data(), state.size(), 0, reinterpret_cast<sockaddr*>(&from),
                       n);
      }
    }
  });
  (void)tp::apply_realtime({.timer_slack_ns = 1});  // as run_loop
  transport::detail::ReadableWait timer;
  const std::array<char, 17> setpoint{};
  std::array<char, 64> in{};
  std::int64_t done = 0;
  for (auto _ : st) {
    for (std::int64_t i = 0; i < ticks; ++i) {
      if (::send(client, setpoint.data(), setpoint.size(), 0) < 0) {
        st.SkipWithError("the ping-pong failed");
        break;
      }
      while (!readable(client, timer)) {
      }
      if (::recv(client, in.data(), in.size(), read_flags) <= 0) {
        st.SkipWithError("the ping-pong failed");
        break;
      }
      ++done;
    }
  }
  stop.store(true);
  echo.join();
  ::close(client);
  ::close(server);
  st.counters["rate_hz"] =
      benchmark::Counter(static_cast<double>(done), benchmark::Counter::kIsRate);
  st.SetItemsProcessed(done);
}

// Both ends on one CPU (the _one_cpu variants): the calling thread is pinned to the first CPU it
// may use, the other end's thread (started inside) inherits that, and the old mask comes back at
// the end. Where the two ends run decides a loopback rate more than anything they do
// (docs/performance.md: a wake-up on another virtual CPU costs an inter-processor interrupt), so
// the _one_cpu pair compares the loop with the wire placed alike.

void BM_Baseline_udp_ping_pong(benchmark::State& st) { ping_pong(st, Wait::blocking); }
void BM_Baseline_udp_ping_pong_one_cpu(benchmark::State& st) {
  const bench::PinnedTo pin(bench::allowed_cpus().first);
  ping_pong(st, Wait::blocking);
}
void BM_Loopback_max_rate_one_cpu(benchmark::State& st) {
  const bench::PinnedTo pin(bench::allowed_cpus().first);
  run_loop(st, nanoseconds(0), nanoseconds(0));
}
// The same two placements with the loop's transport spinning 50 us before it blocks
// (UdpConfig::receive_spin: non-blocking reads, yielding between them): what the spin buys where
// the wake-up of a blocked thread is what costs.
void BM_Loopback_max_rate_one_cpu_spin(benchmark::State& st) {
  const bench::PinnedTo pin(bench::allowed_cpus().first);
  run_loop(st, nanoseconds(0), nanoseconds(0), false, std::chrono::microseconds(50));
}
void BM_Loopback_max_rate_spin(benchmark::State& st) {
  run_loop(st, nanoseconds(0), nanoseconds(0), false, std::chrono::microseconds(50));
}
void BM_Baseline_udp_ping_pong_ppoll(benchmark::State& st) { ping_pong(st, Wait::ppoll); }
void BM_Baseline_udp_ping_pong_transport_wait(benchmark::State& st) {
  ping_pong(st, Wait::transport);
}
// Both ends waiting as the transports do, on one CPU: the wire with the loop's wait and none of
// its work, beside BM_Loopback_max_rate_one_cpu.
void BM_Baseline_udp_ping_pong_transport_wait_one_cpu(benchmark::State& st) {
  const bench::PinnedTo pin(bench::allowed_cpus().first);
  ping_pong(st, Wait::transport);
}

// The floor: a bare absolute-deadline clock_nanosleep loop at 1 kHz on the same machine, its
// period error measured the same way (LoopStats).
void BM_Baseline_clock_nanosleep_1kHz(benchmark::State& st) {
  const auto ticks = st.range(0);
  (void)tp::apply_realtime({.timer_slack_ns = 1});
  for (auto _ : st) {
    endohaptics::SteadyClock clock;
    tp::LoopStats stats(std::chrono::milliseconds(1));
    auto next = clock.now();
    for (std::int64_t i = 0; i < ticks; ++i) {
      stats.record_tick_start(clock.now());
      next += std::chrono::milliseconds(1);
      clock.sleep_until(next);
    }
    report(st, stats);
  }
  st.SetItemsProcessed(ticks * st.iterations());
}

}  // namespace

BENCHMARK(BM_Baseline_clock_nanosleep_1kHz)
    ->Arg(run_ticks(3000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Loopback_1kHz)
    ->Arg(run_ticks(3000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Loopback_1kHz_busy_tail_200us)
    ->Arg(run_ticks(3000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Loopback_1kHz_fifo_busy_tail_200us)
    ->Arg(run_ticks(3000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Loopback_1kHz_v2)
    ->Arg(run_ticks(3000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Loopback_v2_handshake)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_Baseline_udp_ping_pong)
    ->Arg(run_ticks(60000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Baseline_udp_ping_pong_ppoll)
    ->Arg(run_ticks(60000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Baseline_udp_ping_pong_transport_wait)
    ->Arg(run_ticks(60000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Loopback_max_rate)
    ->Arg(run_ticks(60000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Baseline_udp_ping_pong_one_cpu)
    ->Arg(run_ticks(60000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Baseline_udp_ping_pong_transport_wait_one_cpu)
    ->Arg(run_ticks(60000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Loopback_max_rate_one_cpu_spin)
    ->Arg(run_ticks(60000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Loopback_max_rate_spin)
    ->Arg(run_ticks(60000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Loopback_max_rate_one_cpu)
    ->Arg(run_ticks(60000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Loopback_max_rate_v2)
    ->Arg(run_ticks(60000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace loopback_bench
