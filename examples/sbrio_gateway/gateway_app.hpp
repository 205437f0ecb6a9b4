// endohaptics-sbrio-gateway's options and run: protocol v2's robot side in front of a 2016 sbRIO
// (transport/v2_gateway.hpp): the console's link (UDP + SecureTransport), the point-to-point link
// to the sbRIO, the relay loop until --duration or a signal, the counters. Header-only: the armhf
// cross build compiles the gateway as one translation unit.
#pragma once

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <endohaptics/protocol/key_file.hpp>
#include <endohaptics/protocol/secure_session.hpp>
#include <endohaptics/teleop/realtime.hpp>
#include <endohaptics/transport/secure_transport.hpp>
#include <endohaptics/transport/udp_server_transport.hpp>
#include <endohaptics/transport/udp_transport.hpp>
#include <endohaptics/transport/v2_gateway.hpp>
#include <endohaptics/workflow/command_line.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "../cli_numbers.hpp"
#include "../robot_side_options.hpp"

namespace gateway {

namespace protocol = endohaptics::protocol;
namespace transport = endohaptics::transport;

inline std::atomic<bool> g_stop{false};
extern "C" inline void on_signal(int) { g_stop.store(true); }

inline std::chrono::nanoseconds from_ms(double ms) {
  return std::chrono::nanoseconds(static_cast<std::int64_t>(ms * 1e6 + 0.5));
}
inline std::chrono::nanoseconds from_us(double us) {
  return std::chrono::nanoseconds(static_cast<std::int64_t>(us * 1e3 + 0.5));
}

//! The command line's settings.
struct Options {
  std::string listen = "0.0.0.0:61557";
  std::string sbrio = "169.254.4.42:61556";
  std::vector<std::string> key_paths;
  std::string rig_name = std::string(protocol::default_rig_name);
  double watchdog_ms = 100.0;
  double max_round_trip_ms = 0.0;
  double joint_range = protocol::endowrist_joint_range;
  double max_setpoint_rate = protocol::endowrist_max_joint_rate;
  double jitter_ms =
      std::chrono::duration<double, std::milli>(transport::GatewayConfig{}.jitter).count();
  double spin_us = 0.0;
  double listen_spin_us = 0.0;
  bool stats = false;
  double duration = 0.0;
};

//! The gateway's options.
inline void add_options(CLI::App& app, Options& o) {
  app.add_option("--listen", o.listen,
                 "HOST:PORT the consoles' protocol v2 datagrams arrive at (port 0: any free "
                 "port, printed)")
      ->capture_default_str();
  app.add_option("--sbrio", o.sbrio,
                 "HOST:PORT of the sbRIO on the point-to-point link (plain 2016 wire; only its "
                 "datagrams are taken)")
      ->capture_default_str();
  app.add_option("--watchdog-ms", o.watchdog_ms,
                 "no setpoint relayed for this long: send the sbRIO the all-disabled setpoint, "
                 "once a millisecond")
      ->check(examples::number_in(1.0, 10000.0))
      ->capture_default_str();
  examples::add_robot_side_v2_options(app, o.key_paths, o.rig_name, o.max_round_trip_ms, "",
                                      "the watchdog");
  app.add_option("--joint-range", o.joint_range,
                 "rad: every relayed position is kept in [-this, this] on every motor, whatever "
                 "the console sends (the robot side's own envelope)")
      ->check(examples::number_in(1e-3, 3.14159))
      ->capture_default_str();
  app.add_option("--max-setpoint-rate", o.max_setpoint_rate,
                 "rad/s: each motor's relayed positions move at most this fast, over any time "
                 "ahead of the rate by one burst at most (rate x (1 ms + --jitter-ms)), from the "
                 "sbRIO's measured position after silence")
      ->check(examples::number_in(1e-3, 1000.0))
      ->capture_default_str();
  app.add_option("--jitter-ms", o.jitter_ms,
                 "ms the console's setpoints may run ahead of --max-setpoint-rate by their "
                 "timing: its longest tick beyond 1 ms plus how much later one setpoint may be "
                 "relayed than another (network, scheduling)")
      ->check(examples::number_in(
          0.0,
          std::chrono::duration<double, std::milli>(transport::GatewayConfig::max_jitter).count()))
      ->capture_default_str();
  app.add_option("--spin-us", o.spin_us,
                 "us each wait for the sbRIO's answer polls the link without blocking before it "
                 "blocks (0: blocks at once): no wake-up when the answer comes within it, this "
                 "much CPU burnt when it does not; for a gateway with a CPU to spare")
      ->check(examples::number_in(0.0, 1000.0))
      ->capture_default_str();
  app.add_option("--listen-spin-us", o.listen_spin_us,
                 "us each wait for a console's setpoint polls without blocking before it blocks "
                 "(0: blocks at once); helps only a console faster than one setpoint per "
                 "--listen-spin-us (--rate max), otherwise burns that much CPU per setpoint")
      ->check(examples::number_in(0.0, 1000.0))
      ->capture_default_str();
  app.add_flag("--stats", o.stats, "print the counters every second");
  app.add_option("--duration", o.duration, "seconds to run (0: until SIGINT/SIGTERM)")
      ->check(examples::number_in(0.0, 1e7))
      ->capture_default_str();
}

//! Relays until --duration or SIGINT/SIGTERM, then prints the counters; the exit status (3: no
//! setpoint was relayed).
inline int run(const Options& o) {
  if (o.key_paths.empty()) {
    throw endohaptics::Error(
        "--key FILE is required (the key the console holds; make one with endohaptics-bridge "
        "--generate-key FILE)");
  }
  const auto [listen_host, listen_port] =
      endohaptics::workflow::parse_endpoint(o.listen, "--listen", true);
  const auto [sbrio_host, sbrio_port] =
      endohaptics::workflow::parse_endpoint(o.sbrio, "--sbrio", false);
  transport::GatewayConfig gateway_config;
  gateway_config.watchdog = from_ms(o.watchdog_ms);
  gateway_config.joint_range = o.joint_range;
  gateway_config.max_setpoint_rate = o.max_setpoint_rate;
  gateway_config.jitter = from_ms(o.jitter_ms);
  gateway_config.validate();
  protocol::ResponderConfig session;
  session.rig = protocol::make_rig_id(o.rig_name);
  session.max_round_trip =
      o.max_round_trip_ms > 0 ? from_ms(o.max_round_trip_ms) : gateway_config.watchdog;
  session.expiry = gateway_config.watchdog;  // a silent console's session ends with the motors
  std::string ids;
  const protocol::KeyRing keys = protocol::load_key_ring(o.key_paths, &ids);

  transport::UdpServerConfig network_config;
  network_config.bind_address = listen_host;
  network_config.port = listen_port;
  network_config.receive_spin = from_us(o.listen_spin_us);
  transport::UdpServerTransport network(network_config);
  transport::SecureTransport<transport::UdpServerTransport, protocol::SecureResponder<4>> secure(
      network, protocol::SecureResponder<4>(keys, session));
  transport::UdpConfig link_config;
  // The link's own address family: an IPv6 sbRIO needs an IPv6 socket.
  link_config.local_address = sbrio_host.find(':') != std::string::npos ? "::" : "0.0.0.0";
  link_config.remote_address = sbrio_host;
  link_config.remote_port = sbrio_port;
  link_config.receive_spin = from_us(o.spin_us);
  transport::UdpTransport link(link_config);
  endohaptics::SteadyClock clock;
  transport::V2Gateway gateway(secure, link, clock, gateway_config);

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  (void)endohaptics::teleop::apply_realtime({.timer_slack_ns = 1});  // prompt receive timeouts
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // a supervising script sees the port at once
  const auto endpoint = network.local_endpoint();
  fmt::print(
      "sbrio-gateway: protocol v2 on {}:{} (rig '{}', keys {}; round trips up to {:.0f} ms) -> "
      "2016 sbRIO {}:{}; watchdog {} ms; setpoints kept in +-{} rad, {} rad/s (bursts of "
      "{:.1f} mrad)\n",
      endpoint.address().to_string(), endpoint.port(), o.rig_name, ids,
      std::chrono::duration<double, std::milli>(session.max_round_trip).count(), sbrio_host,
      sbrio_port, o.watchdog_ms, o.joint_range, o.max_setpoint_rate, gateway_config.burst() * 1e3);
  const bool spinning = o.spin_us > 0 || o.listen_spin_us > 0;
  if (spinning) {
    fmt::print(
        "sbrio-gateway: receives spin before they block: {} us for the sbRIO's answer, {} us for "
        "a console's setpoint\n",
        o.spin_us, o.listen_spin_us);
  }
  const auto start = clock.now();
  auto next_report = start + std::chrono::seconds(1);
  bool was_silent = true;
  const auto print_counters = [&](std::string_view prefix) {
    const auto& c = gateway.counters();
    fmt::print(
        "sbrio-gateway: {}{} setpoints relayed, {} states returned, {} disabled setpoints sent "
        "on silence, {} sbRIO datagrams refused, {} unanswered, {} watchdog trips, {} "
        "transport errors (v2 {}, sbRIO {}); v2 refused {}; {} relayed setpoints moved into the "
        "envelope\n",
        prefix, c.relayed, c.returned, c.disabled, c.sbrio_refused, c.unanswered, c.watchdog_trips,
        c.network_errors + c.sbrio_errors, c.network_errors, c.sbrio_errors,
        secure.counters().rejected(), c.limited);
    if (spinning) {
      const auto& l = link.receive_wait();
      const auto& n = network.receive_wait();
      fmt::print(
          "sbrio-gateway: spins: sbRIO link {} found without blocking (already there or within "
          "the spin), {} blocked after it; consoles' side {} found, {} blocked\n",
          l.spin_hits(), l.spin_misses(), n.spin_hits(), n.spin_misses());
    }
  };
  // 1 ms receives at most: a signal ends the run well within 1 s.
  while (!g_stop.load()) {
    const auto now = clock.now();
    if (o.duration > 0 && now - start >= std::chrono::duration<double>(o.duration)) break;
    (void)gateway.step(std::chrono::milliseconds(1));
    if (gateway.silent() != was_silent) {
      was_silent = !was_silent;
      fmt::print("sbrio-gateway: {}\n", was_silent
                                            ? "silence: sending the sbRIO all-disabled setpoints"
                                            : "relaying setpoints from " + network.peer_name());
    }
    if (o.stats && now >= next_report) {
      next_report += std::chrono::seconds(1);
      print_counters("");
    }
  }
  fmt::print("sbrio-gateway: protocol v2 datagrams: {}\n", protocol::describe(secure.counters()));
  print_counters(fmt::format("done after {:.1f} s: ",
                             std::chrono::duration<double>(clock.now() - start).count()));
  endohaptics::workflow::require_written(stdout, "standard output");
  if (gateway.counters().relayed == 0) {
    fmt::print(stderr,
               "error: no setpoint was relayed: no console with a matching key and rig reached "
               "{} (v2 refused {})\n",
               o.listen, secure.counters().rejected());
    return 3;
  }
  return 0;
}

}  // namespace gateway
