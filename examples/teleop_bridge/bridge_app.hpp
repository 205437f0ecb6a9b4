//! @file
//! The bridge's link and loop, shared by endohaptics-bridge and endohaptics-ros-bridge: the
//! options' checks for the sbRIO link and the loop (--sbrio, --key, --protocol, --rate, --duration,
//! --config, --log, ...: options.hpp, link_options.hpp), and the loop itself (UDP or protocol v2
//! transport, the force estimator, the mapping, per-second figures, the verdict). A program adds
//! its own device and, optionally, a tick observer (`on_tick(result, now, loop)`, called on the
//! loop thread: noexcept, no allocation, no lock).
#pragma once

#include <fmt/format.h>

#include <atomic>
#include <boost/lockfree/spsc_queue.hpp>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <endohaptics/estimation/force_estimator.hpp>
#include <endohaptics/estimation/paced_estimator.hpp>
#include <endohaptics/files/bridge_config.hpp>
#include <endohaptics/kinematics/cylindrical_mapper.hpp>
#include <endohaptics/protocol/key_file.hpp>
#include <endohaptics/protocol/secure_session.hpp>
#include <endohaptics/teleop/link_diagnosis.hpp>
#include <endohaptics/teleop/realtime.hpp>
#include <endohaptics/teleop/teleop_loop.hpp>
#include <endohaptics/teleop/tick_recorder.hpp>
#include <endohaptics/transport/secure_transport.hpp>
#include <endohaptics/transport/udp_transport.hpp>
#include <endohaptics/workflow/bridge_assembly.hpp>
#include <endohaptics/workflow/command_line.hpp>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <tuple>

#include "options.hpp"

namespace bridge {

namespace tp = endohaptics::teleop;
namespace est = endohaptics::estimation;
namespace transport = endohaptics::transport;
namespace files = endohaptics::files;
namespace protocol = endohaptics::protocol;
using std::chrono::nanoseconds;

//! A tick observer that does nothing (endohaptics-bridge's).
struct NoTickObserver {
  template <typename Loop>
  void on_tick(const tp::TickResult&, nanoseconds, const Loop&) noexcept {}
};

inline std::atomic<bool> g_stop{false};
extern "C" inline void on_signal(int) { g_stop.store(true); }

// The end of one second of the loop: a ~100-byte copy made on the loop thread (no allocation,
// no LoopStats of its own); the printer thread turns two of them into the second's figures.
struct Window {
  double t = 0.0;  // s since start
  tp::LoopSnapshot stats;
  std::uint64_t link_losses = 0;
  std::uint64_t recoveries = 0;
  tp::LinkState link = tp::LinkState::waiting;
  double clamp_force = 0.0;       // N, the estimate for clamp 1 at the end of the window
  protocol::SecureCounters v2{};  // v2 datagrams accepted and refused by cause, so far
  std::uint8_t active = 0;        // the active mask of the newest state
  std::uint8_t enabled = 0;       // the enable mask sent last
  bool diagnose_only = false;     // the early look (0.9 s): warn if nothing obeyed yet, no line
};

// What the protocol layer refused, for the link's diagnosis.
inline tp::LinkEvidence evidence(bool v2, const protocol::SecureCounters& c, std::uint8_t enabled,
                                 std::uint8_t active) {
  return {.authenticated = v2,
          .forged = c.forged,
          .wrong_size = c.wrong_size,
          .wrong_session = c.wrong_session,
          .late = c.stale_answer,
          .sessions = c.handshakes,
          .enable_mask = enabled,
          .last_active = active};
}

// The longest an answer may take on this link (workflow::bridge_answer_allowance).
inline double answer_allowance_s(const Options& opt, double tick_s) {
  return endohaptics::workflow::bridge_answer_allowance(opt.max_answer_lag, tick_s);
}

// The loop's settings from the options (workflow/bridge_assembly.hpp assembles the loop).
inline endohaptics::workflow::BridgeLoopSettings loop_settings(const Options& opt) {
  return {.rate = opt.rate,
          .tdpa = opt.passivity == "tdpa",
          .passivity_round_trip_ms = opt.passivity_round_trip,
          .max_answer_lag = opt.max_answer_lag};
}

// "HOST:PORT" of --sbrio or --local (IPv6: "[addr]:port"), the port in 1..65535.
inline std::pair<std::string, std::uint16_t> parse_endpoint(const std::string& s,
                                                            const std::string& option = "--sbrio") {
  endohaptics::workflow::Endpoint e = endohaptics::workflow::parse_endpoint(s, option, false);
  return {std::move(e.host), e.port};
}

// The v2 counters of `transport` (none for the 2016 protocol).
template <typename Transport>
protocol::SecureCounters v2_counters(const Transport& transport) {
  if constexpr (requires { transport.counters(); }) {
    return transport.counters();
  } else {
    return {};
  }
}

template <typename Transport, typename Device, typename Observer>
int run_loop(Transport& transport, Device& device, endohaptics::SteadyClock& clock,
             const Options& opt, const files::BridgeConfig& cfg, const std::string& host,
             std::uint16_t port, Observer& observer) {
  // The 2016 models run at their own rates (rate::Decimate) on a 1 kHz grid; PacedEstimator
  // keeps that grid whatever the loop rate (--rate max) and through lost packets. The clamp model
  // file may be of any kind the library runs (estimation::BridgeJointModel).
  endohaptics::workflow::BridgeAssembly bridge(transport, device, clock, cfg, loop_settings(opt));
  auto& loop = bridge.loop();
  const auto& paced = bridge.paced();

  // Per-tick log and per-second windows leave the loop thread through lock-free rings.
  std::unique_ptr<tp::TickRecorder> recorder;
  std::FILE* log = nullptr;
  if (!opt.log_path.empty()) {
    log = endohaptics::workflow::open_output(opt.log_path, "the log '" + opt.log_path + "'");
    recorder = std::make_unique<tp::TickRecorder>();
    tp::TickRecorder::write_header(log);
  }
  boost::lockfree::spsc_queue<Window> windows(64);
  std::atomic<bool> done{false};
  std::string log_error;  // set by the writer thread when the log cannot be written
  // Started before apply_realtime and reset explicitly: the writer never runs SCHED_FIFO or on
  // the loop's CPU.
  const std::string peer = fmt::format("{}:{}", host, port);
  std::thread writer([&] {
    for (const auto& m : tp::leave_realtime()) fmt::print("bridge: log writer: {}\n", m);
    bool warned = false;
    tp::LoopSnapshot previous;
    auto print_window = [&previous, &opt](const Window& w) {
      const tp::LoopWindow s = w.stats.since(previous);
      previous = w.stats;
      fmt::print(
          "bridge: t {:5.1f} s  rate {:7.1f} Hz  period err mean {:6.1f} us  deadline misses {}"
          "  round trip {:6.1f} us  loss {:6.3f} %  decode errors {}  state faults {}  rejected {}"
          "  link {}  (lost {}, recovered {})  clamp1 {:+.2f} N{}\n",
          w.t, s.rate, s.period_error_mean * 1e6, s.deadline_misses, s.round_trip_mean * 1e6,
          s.loss_percent, s.decode_errors, s.state_faults, s.rejected, to_string(w.link),
          w.link_losses, w.recoveries, w.clamp_force,
          opt.protocol == "2016" ? std::string()
                                 : "  v2 rejected " + std::to_string(w.v2.rejected()) +
                                       " (forged " + std::to_string(w.v2.forged) + ")");
    };
    for (;;) {
      const bool last = done.load();
      if (recorder && log_error.empty()) {
        try {
          recorder->drain(log);
        } catch (const std::exception& e) {
          log_error = "writing the log '" + opt.log_path + "' failed: " + e.what();  // full disk
        }
      }
      Window w;
      while (windows.pop(w)) {
        // Within the first second: say so if nothing obeyed yet, and the likely cause.
        if (!warned) {
          const tp::LinkDiagnosis d =
              tp::diagnose_link(w.stats.since(tp::LoopSnapshot{}),
                                evidence(opt.protocol != "2016", w.v2, w.enabled, w.active), peer);
          if (!d.up()) {
            fmt::print("bridge: WARNING: no obeyed state after {:.1f} s: {}\n", w.t, d.message);
            std::fflush(stdout);  // now, not at exit: a supervisor reads it while we run
          }
          warned = true;
        }
        if (opt.stats && !w.diagnose_only) {
          print_window(w);
          std::fflush(stdout);
        }
      }
      if (last) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });

  // Timer slack 1 ns always (Linux's 50 us default is 50 us of lateness on every period);
  // SCHED_FIFO, pinning and mlockall when asked.
  const auto realtime =
      tp::apply_realtime({opt.fifo_priority, opt.cpu, opt.fifo_priority > 0, /*slack*/ 1});
  for (const auto& m : realtime.messages) fmt::print("bridge: realtime: {}\n", m);

  fmt::print("bridge: sbRIO {}:{}, rate {}, device {} (force models paced at 1 kHz)\n", host, port,
             opt.rate == "max" ? "max" : opt.rate + " Hz", opt.device);
  fmt::print("bridge: force models: {}\n", bridge.force_models_description());
  std::fflush(stdout);
  const auto start = clock.now();
  const auto end = opt.duration > 0 ? start + std::chrono::duration_cast<nanoseconds>(
                                                  std::chrono::duration<double>(opt.duration))
                                    : nanoseconds::max();
  auto next_window = start + std::chrono::seconds(1);
  // The early look at the link, so a dead or refusing robot is named within the first second.
  auto early_look = start + std::chrono::milliseconds(900);
  std::uint8_t last_active = 0, last_enabled = 0;
  loop.run([&] { return g_stop.load(std::memory_order_relaxed) || clock.now() >= end; },
           [&](const tp::TickResult& r) {
             const auto now = clock.now();
             if (recorder) (void)recorder->push(tp::TickRecord::from(r, now));
             observer.on_tick(r, now, loop);
             last_active = r.measured.active_mask;
             last_enabled = r.enable_mask;
             if (now >= next_window || now >= early_look) {
               Window w;
               w.diagnose_only = now < next_window;
               if (w.diagnose_only) {
                 early_look = nanoseconds::max();
               } else {
                 next_window += std::chrono::seconds(1);
               }
               w.t = std::chrono::duration<double>(now - start).count();
               w.stats = loop.stats().snapshot();
               w.link_losses = loop.watchdog().link_losses();
               w.recoveries = loop.watchdog().recoveries();
               w.link = r.link;
               w.clamp_force = r.motor_force[2];
               w.v2 = v2_counters(transport);
               w.active = r.measured.active_mask;
               w.enabled = r.enable_mask;
               (void)windows.push(w);
             }
           },
           nanoseconds(static_cast<std::int64_t>(opt.busy_wait_us * 1e3)));
  loop.shutdown();  // zero force on the device, one packet with every motor disabled
  done.store(true);
  writer.join();
  if (log != nullptr) {
    try {
      endohaptics::workflow::close_written(log, "the log '" + opt.log_path + "'");
    } catch (const std::exception& e) {
      if (log_error.empty()) log_error = e.what();
    }
  }

  const auto& s = loop.stats();
  fmt::print("bridge: final statistics after {:.2f} s\n{}",
             std::chrono::duration<double>(clock.now() - start).count(), s.to_table());
  fmt::print("bridge: link losses {}, recoveries {}, watchdog misses {}\n",
             loop.watchdog().link_losses(), loop.watchdog().recoveries(),
             loop.watchdog().total_misses());
  const auto& pc = paced.counters();
  fmt::print("bridge: estimator steps {}, held {}, skipped periods {}, rejected {}\n", pc.steps,
             pc.held, pc.skipped, pc.rejected);
  if (recorder && log_error.empty()) {
    fmt::print("bridge: log {} rows written to {}, {} dropped (ring full)\n", recorder->written(),
               opt.log_path, recorder->dropped());
  }
  const double complete =
      s.ticks() ? 100.0 * static_cast<double>(s.received()) / static_cast<double>(s.ticks()) : 0.0;
  fmt::print(
      "bridge: summary ticks={} received={} complete={:.2f}% decode_errors={} state_faults={} "
      "rejected={} stale_dropped={} link_losses={} recoveries={}\n",
      s.ticks(), s.received(), complete, s.decode_errors(), s.state_faults(), s.rejected().total(),
      s.stale_dropped(), loop.watchdog().link_losses(), loop.watchdog().recoveries());
  if (opt.protocol != "2016") {
    fmt::print("bridge: protocol v2 states: {}\n", protocol::describe(v2_counters(transport)));
  }
  // The verdict: "up" only if the robot obeyed (a valid state showing the enabled motors
  // active); otherwise the likely cause, and a non-zero exit.
  const tp::LinkDiagnosis verdict = tp::diagnose_link(
      s.snapshot().since(tp::LoopSnapshot{}),
      evidence(opt.protocol != "2016", v2_counters(transport), last_enabled, last_active), peer);
  if (verdict.up()) {
    fmt::print(
        "bridge: link: up: the robot obeyed {} of {} exchanges ({} answered but did not "
        "obey), ended {}\n",
        s.received(), s.exchanges(), s.not_obeyed(), to_string(loop.watchdog().state()));
  } else {
    fmt::print("bridge: link: never up ({}): {}\n", to_string(verdict.problem), verdict.message);
  }
  // No false success: a log that could not be written (full disk) fails the run.
  if (!log_error.empty()) throw endohaptics::Error(log_error);
  endohaptics::workflow::require_written(stdout, "standard output");
  return verdict.up() ? 0 : 3;
}

// The link: v2 (SecureTransport over UDP, key from --key) or the unauthenticated 2016 wire.
template <typename Device, typename Observer = NoTickObserver>
int run_bridge(Device& device, endohaptics::SteadyClock& clock, const Options& opt,
               const files::BridgeConfig& cfg, Observer&& observer = Observer{}) {
  const auto [host, port] = parse_endpoint(opt.sbrio);
  transport::UdpConfig udp;
  udp.remote_address = host;
  udp.remote_port = port;
  udp.local_address = host.find(':') != std::string::npos ? "::" : "0.0.0.0";
  if (!opt.local.empty()) {  // a fixed source, for a robot side that obeys one console (--peer)
    std::tie(udp.local_address, udp.local_port) = parse_endpoint(opt.local, "--local");
  }
  if (opt.protocol == "2016") {
    fmt::print(
        "bridge: WARNING: --protocol 2016: unauthenticated; anyone who can send UDP to this "
        "host can spoof the robot's state (docs/protocol.md)\n");
    fmt::print(
        "bridge: states are taken from {}:{} only (a connected socket: the kernel drops "
        "datagrams from any other source)\n",
        host, port);
    transport::UdpTransport transport(udp);
    return run_loop(transport, device, clock, opt, cfg, host, port, observer);
  }
  if (opt.key_path.empty()) {
    throw endohaptics::Error(
        "protocol v2 needs --key FILE (the key the sbRIO holds; make one with --generate-key "
        "FILE), or --protocol 2016 for the unauthenticated 2016 wire");
  }
  const protocol::SecureKey key = protocol::load_key_file(opt.key_path);
  protocol::InitiatorConfig session;
  session.rig = protocol::make_rig_id(opt.rig);
  session.max_answer_lag = static_cast<std::uint64_t>(opt.max_answer_lag);
  const double tick_s = opt.rate == "max" ? 1e-3 : 1.0 / std::stod(opt.rate);
  session.max_round_trip =
      std::min<nanoseconds>(protocol::max_configurable_round_trip,
                            std::chrono::duration_cast<nanoseconds>(
                                std::chrono::duration<double>(answer_allowance_s(opt, tick_s))));
  transport::UdpTransport udp_transport(udp);
  transport::SecureTransport secure(udp_transport, protocol::SecureInitiator<4>(key, session));
  fmt::print(
      "bridge: protocol v2 (authenticated, key {} id {}, rig '{}'; asks for round trips up to "
      "{:.0f} ms)\n",
      opt.key_path, protocol::to_hex(key.id()), opt.rig,
      std::chrono::duration<double, std::milli>(session.max_round_trip).count());
  return run_loop(secure, device, clock, opt, cfg, host, port, observer);
}

//! Refuses options that cannot apply, with the reason; writes a key file and returns true when
//! --generate-key asked for one (the program then exits 0).
inline bool check_options(const examples::Parsed& parsed, const Options& opt) {
  // Options that cannot apply are refused with the reason, never ignored.
  if (opt.protocol == "2016" && !opt.key_path.empty()) {
    throw endohaptics::Error("--key applies to protocol v2; --protocol 2016 has no key");
  }
  if (opt.protocol == "2016" && parsed.was_given("--max-answer-lag")) {
    throw endohaptics::Error(
        "--max-answer-lag applies to protocol v2 (its states name the setpoint they answer); "
        "the 2016 wire cannot tell");
  }
  if (opt.protocol == "2016" && parsed.was_given("--rig")) {
    throw endohaptics::Error(
        "--rig applies to protocol v2 (the session keys bind the robot side's name); the 2016 "
        "wire has no session");
  }
  if (opt.passivity != "tdpa" && parsed.was_given("--passivity-round-trip")) {
    throw endohaptics::Error("--passivity-round-trip applies to --passivity tdpa only");
  }
  if (!opt.generate_key.empty()) {
    protocol::generate_key_file(opt.generate_key);
    fmt::print("bridge: wrote a new key to {} (32 bytes, mode 0600)\n", opt.generate_key);
    return true;
  }
  return false;
}

//! SIGINT and SIGTERM stop the loop (g_stop): zero force, motors disabled, final figures.
inline void stop_on_signals() {
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
}

//! The configuration from --config, or the defaults; --instrument chooses the model set (over
//! estimator.instrument), checked as the configuration is.
inline files::BridgeConfig load_config(const Options& opt) {
  files::BridgeConfig cfg =
      opt.config_path.empty() ? files::BridgeConfig{} : files::load_bridge_config(opt.config_path);
  if (!opt.instrument.empty()) {
    if (cfg.model_sets.empty()) {
      throw endohaptics::Error("--instrument " + opt.instrument +
                               ": needs a --config whose estimator.model_sets names the folder "
                               "of model sets");
    }
    cfg.instrument = opt.instrument;
    files::validate_bridge_config(
        cfg, opt.config_path.empty() ? "--instrument" : opt.config_path + " with --instrument");
  }
  return cfg;
}

}  // namespace bridge
