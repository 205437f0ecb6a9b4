// endohaptics-sbrio-emulator's options and run: the 2016 sbRIO's wire (UDP, or protocol v2 around
// it) in front of a simulated EndoWrist (sim/sbrio_emulator.hpp, sim/simulated_rig.hpp), answers
// delayed and lost on the send path when asked (sim/delay_line.hpp), the truth log
// (sim/truth_log.hpp), the counters.
#pragma once

#include <fmt/format.h>
#include <fmt/os.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <endohaptics/protocol/key_file.hpp>
#include <endohaptics/protocol/secure_session.hpp>
#include <endohaptics/sim/delay_line.hpp>
#include <endohaptics/sim/sbrio_emulator.hpp>
#include <endohaptics/sim/simulated_rig.hpp>
#include <endohaptics/sim/truth_log.hpp>
#include <endohaptics/teleop/realtime.hpp>
#include <endohaptics/transport/secure_transport.hpp>
#include <endohaptics/transport/udp_server_transport.hpp>
#include <endohaptics/workflow/command_line.hpp>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "options.hpp"

namespace emulator {

namespace sim = endohaptics::sim;
namespace transport = endohaptics::transport;
namespace tp = endohaptics::teleop;
namespace protocol = endohaptics::protocol;

inline std::atomic<bool> g_stop{false};
extern "C" inline void on_signal(int) { g_stop.store(true); }

struct TruthLog {
  std::FILE* file = nullptr;
  ~TruthLog() {
    if (file != nullptr) std::fclose(file);
  }
};

// Options the emulator's run needs.
struct RunOptions {
  std::string truth_path;
  double truth_period_ms = 1.0;
  double duration = 0.0;
  double watchdog_ms = 100.0;
  int motors = 4;
  std::string environment;
  bool quiet = false;
  double delay_ms = 0.0;   // --delay: on the send path (answers), docs/passivity.md
  double jitter_ms = 0.0;  // --jitter
  double loss = 0.0;       // --loss
};

// The send path: every answer goes through a delay line with loss (pass-through with all three
// at 0), below protocol v2, so a delayed state still names the setpoint it answered when it was
// made (above v2 it would be sealed when it leaves, naming the newest setpoint: a stale answer
// passed off as fresh).
using Delayed = sim::DelayedSendTransport<transport::UdpServerTransport, endohaptics::SteadyClock>;

// Datagrams the v2 layer refused (none for the 2016 wire).
template <typename Transport>
inline std::uint64_t refused(const Transport& transport) {
  if constexpr (requires { transport.counters(); }) {
    return transport.counters().rejected();
  } else {
    return 0;
  }
}

// Serves setpoints through `transport` (v2 SecureTransport over `delayed`, or `delayed` itself)
// until the duration or a signal; `udp` is the socket underneath.
template <typename Transport>
int serve(Transport& transport, Delayed& delayed, transport::UdpServerTransport& udp,
          sim::SimulatedRig<4>& rig, endohaptics::SteadyClock& clock,
          const sim::EmulatorConfig& config, const RunOptions& opts) {
  const auto& [truth_path, truth_period_ms, duration, watchdog_ms, motors, environment, quiet,
               delay_ms, jitter_ms, loss] = opts;
  // The truth log's rows on an exact grid of the rig's time (not when packets happen to arrive),
  // so identification sees uniformly sampled signals whatever the UDP timing.
  sim::EmulatorConfig grid_config = config;
  if (!truth_path.empty()) {
    grid_config.sample_period =
        std::chrono::nanoseconds(static_cast<long>(std::llround(truth_period_ms * 1e6)));
  }
  sim::SbrioEmulator emulator(transport, rig, clock, grid_config);
  TruthLog truth;
  if (!truth_path.empty()) {
    truth.file =
        endohaptics::workflow::open_output(truth_path, "the truth log '" + truth_path + "'");
    std::fputs(std::string(sim::truth_log_header).c_str(), truth.file);
  }
  // Line buffering so a supervising script sees the port as soon as it is bound.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  const auto endpoint = udp.local_endpoint();
  fmt::print("sbrio-emulator: listening on {}:{} ({} motors, environment {}, watchdog {} ms)\n",
             endpoint.address().to_string(), endpoint.port(), motors, environment, watchdog_ms);
  if (delay_ms > 0 || jitter_ms > 0 || loss > 0) {
    fmt::print("sbrio-emulator: answers delayed {} ms + [0, {}] ms jitter, {:.0f} % lost\n",
               delay_ms, jitter_ms, 100 * loss);
  }

  // The 2016 wire obeys one console at a time (pinned); v2 authenticates instead.
  constexpr bool pin_mode = !requires { transport.counters(); };
  std::uint64_t pins_seen = 0, releases_seen = 0;
  const auto announce_peer = [&] {  // whom a 2016 emulator obeys, whenever that changes
    if (udp.releases() != releases_seen) {
      releases_seen = udp.releases();
      fmt::print(
          "sbrio-emulator: the pinned console fell silent for {} ms: the next console heard "
          "is obeyed\n",
          watchdog_ms);
    }
    if (udp.pins() != pins_seen && udp.pinned()) {
      pins_seen = udp.pins();
      fmt::print("sbrio-emulator: obeying {} only\n", udp.peer_name());
    }
  };
  const auto start = clock.now();
  // One row per grid instant (a write error is reported when the file is closed; running out of
  // memory for a row's text ends the program, as anywhere else here).
  const auto write_row = [&](std::chrono::nanoseconds t, const auto& setpoint,
                             const sim::SimulatedRig<4>& r) noexcept {
    if (truth.file == nullptr) return;
    const std::string row = sim::truth_log_row(std::chrono::duration<double>(t).count(), setpoint,
                                               r.truth(), r.state());
    std::fputs(row.c_str(), truth.file);
  };
  auto next_report = start + std::chrono::seconds(1);
  bool was_tripped = false;
  while (!g_stop.load()) {
    const auto now = clock.now();
    if (duration > 0 && now - start >= std::chrono::duration<double>(duration)) break;
    (void)emulator.poll(std::chrono::milliseconds(1), write_row);
    if (pin_mode) announce_peer();
    if (emulator.watchdog_tripped() != was_tripped) {
      was_tripped = emulator.watchdog_tripped();
      if (!quiet) {
        fmt::print("sbrio-emulator: {}\n", was_tripped
                                               ? "watchdog: no packets, motors disabled"
                                               : "packets again, motors follow their setpoints");
      }
    }
    const auto t = emulator.time();
    if (!quiet && t >= next_report) {
      next_report += std::chrono::seconds(1);
      const auto& c = emulator.counters();
      fmt::print("sbrio-emulator: {} packets answered, {} rejected, clamp force {:.2f} N{}\n",
                 c.answered, c.rejected + refused(transport), rig.truth().contact_force[2],
                 pin_mode ? fmt::format(", obeying {}, {} datagrams from others ignored",
                                        udp.pinned() ? udp.peer_name() : "nobody yet",
                                        udp.foreign_datagrams())
                          : std::string());
    }
  }
  const auto& c = emulator.counters();
  std::uint64_t sessions = 0;
  if constexpr (requires { transport.counters(); }) {
    sessions = transport.session().sessions();
    fmt::print("sbrio-emulator: protocol v2 datagrams: {}\n",
               protocol::describe(transport.counters()));
  } else {
    fmt::print(
        "sbrio-emulator: protocol 2016: obeyed {} ({} pinned, {} released after silence); {} "
        "datagrams from other senders ignored\n",
        udp.pinned() ? udp.peer_name() : "nobody", udp.pins(), udp.releases(),
        udp.foreign_datagrams());
  }
  // One count of refusals: the v2 layer's (never reached the emulator) and the 2016 payload's.
  fmt::print(
      "sbrio-emulator: done after {:.1f} s: {} setpoint packets obeyed, {} v2 sessions, {} "
      "rejected (protocol v2 {}; 2016 payload: wrong size {}, non-finite {}, bad mask {}), {} "
      "stale dropped, {} transport errors, {} watchdog trips\n",
      std::chrono::duration<double>(clock.now() - start).count(), c.received, sessions,
      c.rejected + refused(transport), refused(transport), c.rejected_size, c.rejected_non_finite,
      c.rejected_mask, c.stale_dropped, c.transport_errors, c.watchdog_trips);
  if (delay_ms > 0 || jitter_ms > 0 || loss > 0) {
    fmt::print("sbrio-emulator: send path: {} answers lost, {} refused by a full delay line\n",
               delayed.lost(), delayed.overflowed());
  }
  // No false success: a truth log that could not be written (full disk) fails the run.
  if (truth.file != nullptr) {
    std::FILE* file = std::exchange(truth.file, nullptr);
    endohaptics::workflow::close_written(file, "the truth log '" + truth_path + "'");
  }
  endohaptics::workflow::require_written(stdout, "standard output");
  return 0;
}

//! Refuses options that cannot apply, then serves setpoints until --duration or SIGINT/SIGTERM
//! (or writes a key with --generate-key); the exit status. `rig_given`: --rig was on the command
//! line.
inline int run(const Options& o, bool rig_given) {
  const auto& [bind, port, motors, environment, truth_path, truth_period_ms, duration, watchdog_ms,
               quiet, delay_ms, jitter_ms, loss, wire, key_paths, rig_name, generate_key, peer,
               max_round_trip_ms] = o;
  const std::map<std::string, sim::Environment> environments{
      {"free", sim::Environment::free_space},
      {"loadcell", sim::Environment::load_cell},
      {"tissue", sim::Environment::tissue}};
  if (!generate_key.empty()) {
    protocol::generate_key_file(generate_key);
    fmt::print("sbrio-emulator: wrote a new key to {} (32 bytes, mode 0600)\n", generate_key);
    return 0;
  }
  if (wire != "2016" && key_paths.empty()) {
    throw endohaptics::Error(
        "protocol v2 needs --key FILE (the key the bridge holds; make one with --generate-key "
        "FILE), or --protocol 2016 for the unauthenticated 2016 wire");
  }
  // Options that cannot apply are refused, never ignored.
  if (wire == "2016" && !key_paths.empty()) {
    throw endohaptics::Error("--key applies to protocol v2; --protocol 2016 has no key");
  }
  if (wire == "2016" && rig_given) {
    throw endohaptics::Error("--rig applies to protocol v2; --protocol 2016 has no session");
  }
  if (wire == "2016" && max_round_trip_ms > 0) {
    throw endohaptics::Error(
        "--max-round-trip applies to protocol v2 (session binding); --protocol 2016 has none");
  }
  if (wire != "2016" && !peer.empty()) {
    throw endohaptics::Error(
        "--peer applies to --protocol 2016; protocol v2 obeys the console holding the key");
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  (void)endohaptics::teleop::apply_realtime({.timer_slack_ns = 1});  // prompt poll timeouts
  transport::UdpServerConfig udp;
  udp.bind_address = bind;
  udp.port = port;
  udp.pin_first_peer = wire == "2016";  // v2 authenticates instead
  udp.peer = peer;
  // A console silent for the watchdog time has lost the robot (its motors are off): the next
  // console heard may take over (a restarted bridge has a new source port).
  udp.repin_after = std::chrono::nanoseconds(static_cast<std::int64_t>(watchdog_ms * 1e6));
  transport::UdpServerTransport udp_transport(udp);
  endohaptics::SteadyClock clock;
  sim::SimulatedRig<4> rig(sim::endowrist_2016_rig<4>(environments.at(environment)));
  sim::EmulatorConfig config;
  config.watchdog_timeout = std::chrono::microseconds(static_cast<long>(watchdog_ms * 1e3));
  // v2: a PC session silent for the watchdog time is dropped (the motors are off by then).
  const auto ms = [](double v) {
    return std::chrono::nanoseconds(static_cast<std::int64_t>(v * 1e6 + 0.5));
  };
  Delayed delayed(udp_transport, clock, sim::DelaySettings{ms(delay_ms), ms(jitter_ms)}, loss, 1);
  std::optional<transport::SecureTransport<Delayed, protocol::SecureResponder<4>>> secure;
  if (wire == "2016") {
    fmt::print(
        "sbrio-emulator: WARNING: --protocol 2016: unauthenticated; setpoints are obeyed from "
        "{}, others are counted\n",
        peer.empty() ? fmt::format("the first console heard only (released after {} ms of its "
                                   "silence)",
                                   watchdog_ms)
                     : "only " + udp_transport.peer_name() + " (--peer)");
  } else {
    // The round trip granted: the watchdog plus the delay this emulator adds to its answers
    // (else no setpoint would be fresh beyond it), or --max-round-trip.
    protocol::ResponderConfig session;
    session.rig = protocol::make_rig_id(rig_name);
    session.max_round_trip = max_round_trip_ms > 0
                                 ? ms(max_round_trip_ms)
                                 : config.watchdog_timeout + ms(delay_ms) + ms(jitter_ms);
    session.expiry = config.watchdog_timeout;  // a silent console's session ends with the motors
    std::string ids;
    const protocol::KeyRing keys = protocol::load_key_ring(key_paths, &ids);
    secure.emplace(delayed, protocol::SecureResponder<4>(keys, session));
    fmt::print(
        "sbrio-emulator: protocol v2: rig '{}', keys {}; answers only a fresh handshake; round "
        "trips up to {:.0f} ms\n",
        rig_name, ids, std::chrono::duration<double, std::milli>(session.max_round_trip).count());
  }
  const RunOptions opts{truth_path,  truth_period_ms, duration, watchdog_ms, motors,
                        environment, quiet,           delay_ms, jitter_ms,   loss};
  return secure ? serve(*secure, delayed, udp_transport, rig, clock, config, opts)
                : serve(delayed, delayed, udp_transport, rig, clock, config, opts);
}

}  // namespace emulator
