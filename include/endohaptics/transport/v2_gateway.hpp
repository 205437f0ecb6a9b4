//! @file
//! V2Gateway: the robot side of protocol v2 as a relay in front of an unchanged 2016 sbRIO. It
//! takes authentic, fresh setpoints from a v2 transport (SecureTransport with SecureResponder),
//! relays their 2016 payload to the sbRIO over a point-to-point link, and seals the sbRIO's
//! answer back to the console. When no setpoint was relayed for the watchdog time (silence, or
//! nothing but forgeries and replays, which never get through) it sends the 2016 "all disabled"
//! setpoint to the sbRIO itself, once a period. Nothing from the network reaches the sbRIO unless
//! the v2 layer accepted it, and nothing it relays leaves the robot side's own envelope: every
//! position within the joint range, and each motor's path a token bucket of the rate limit (over
//! any time T, at most max_setpoint_rate x T plus one burst, from the sbRIO's measured position
//! after silence), behind the console's same limits: a console with the key but a bug, or a
//! stolen key, can command neither a jump nor, by sending faster, a faster motion. Every call of
//! step() is noexcept and allocation-free.
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <span>
#include <string>

#include "endohaptics/core/clock.hpp"
#include "endohaptics/core/error.hpp"
#include "endohaptics/protocol/motor_order.hpp"
#include "endohaptics/protocol/packet_codec.hpp"
#include "endohaptics/transport/transport.hpp"

namespace endohaptics::transport {

//! The gateway's timing.
struct GatewayConfig {
  //! No setpoint relayed for this long: the gateway disables every motor itself (its sbRIO-side
  //! watchdog, ahead of the sbRIO's own).
  std::chrono::nanoseconds watchdog = std::chrono::milliseconds(100);
  //! While silent, one "all disabled" setpoint per period (the sbRIO loop's rate).
  std::chrono::nanoseconds period = std::chrono::milliseconds(1);
  //! How long a relayed setpoint waits for the sbRIO's answer before it is given up (counted).
  std::chrono::nanoseconds answer_timeout = std::chrono::milliseconds(2);
  //! rad: every relayed position is kept in [-joint_range, joint_range] (motor side, every
  //! motor; a tool the sbRIO measures outside it is brought back at max_setpoint_rate, never
  //! further out); at most pi.
  double joint_range = protocol::endowrist_joint_range;
  //! rad/s: each motor's relayed positions move at most this fast: over any time T their path
  //! (the sum of the steps) is at most max_setpoint_rate x T plus one burst(); in (0, 1000].
  double max_setpoint_rate = protocol::endowrist_max_joint_rate;
  //! How much a console's setpoints may run ahead of the rate by their timing alone: the
  //! console's longest tick beyond one `period`, plus how much more one setpoint may take to be
  //! relayed than another (the network, the hosts' scheduling, the gateway's own waits: up to
  //! answer_timeout for an sbRIO answer that does not come). A console within the same rate whose
  //! timing stays within it is never limited; one that sends a burst (a key holder sending faster
  //! than its rate allows) gets at most burst() ahead of the rate. In [0, 100 ms].
  std::chrono::nanoseconds jitter = std::chrono::milliseconds(10);
  //! Largest jitter: a link whose latency varies more is no teleoperation link.
  static constexpr std::chrono::nanoseconds max_jitter = std::chrono::milliseconds(100);

  //! rad: the most a motor's path may run ahead of max_setpoint_rate x time, the token bucket's
  //! size: the rate times (period + jitter). The bucket starts full, and a rest of period +
  //! jitter fills it again (the first step after silence, from where the sbRIO measured the
  //! motor, may take it all when the watchdog is at least that long).
  [[nodiscard]] double burst() const noexcept {
    return max_setpoint_rate * std::chrono::duration<double>(period + jitter).count();
  }

  //! Throws Error naming the field, its value and its range.
  void validate() const {
    const auto check = [](std::chrono::nanoseconds v, std::chrono::nanoseconds lo,
                          std::chrono::nanoseconds hi, const char* field,
                          const std::string& range) {
      if (v < lo || v > hi) {
        ENDOHAPTICS_THROW(Error(std::string("GatewayConfig: ") + field + " must be in " + range +
                                ", got " + std::to_string(v.count()) + " ns"));
      }
    };
    using std::chrono::microseconds;
    using std::chrono::milliseconds;
    check(watchdog, milliseconds(1), std::chrono::seconds(10), "watchdog", "[1 ms, 10 s]");
    check(period, microseconds(100), milliseconds(100), "period", "[0.1, 100] ms");
    check(answer_timeout, microseconds(10), milliseconds(100), "answer_timeout", "[0.01, 100] ms");
    check(jitter, std::chrono::nanoseconds(0), max_jitter, "jitter", "[0, 100] ms");
    const auto check_number = [](double v, double lo, double hi, const char* field,
                                 const char* range) {
      if (!(v > lo && v <= hi)) {  // NaN fails too
        ENDOHAPTICS_THROW(Error(std::string("GatewayConfig: ") + field + " must be in " + range +
                                ", got " + std::to_string(v)));
      }
    };
    check_number(joint_range, 0.0, std::numbers::pi, "joint_range", "(0, pi] rad");
    check_number(max_setpoint_rate, 0.0, 1000.0, "max_setpoint_rate", "(0, 1000] rad/s");
    if (period > watchdog) {
      ENDOHAPTICS_THROW(Error("GatewayConfig: period (" + std::to_string(period.count()) +
                              " ns) must not exceed watchdog (" + std::to_string(watchdog.count()) +
                              " ns)"));
    }
  }
};

//! Running totals of a gateway (monotonic).
struct GatewayCounters {
  std::uint64_t relayed = 0;         //!< authentic, fresh setpoints relayed to the sbRIO
  std::uint64_t returned = 0;        //!< sbRIO states sealed back to the console
  std::uint64_t disabled = 0;        //!< "all disabled" setpoints sent on silence
  std::uint64_t sbrio_refused = 0;   //!< sbRIO datagrams that are no 2016 state (size, NaN, mask)
  std::uint64_t unanswered = 0;      //!< relayed setpoints the sbRIO did not answer in time
  std::uint64_t watchdog_trips = 0;  //!< times relaying stopped for the watchdog time
  std::uint64_t network_errors = 0;  //!< v2 side receive or send failures
  std::uint64_t sbrio_errors = 0;    //!< sbRIO side receive or send failures
  //! relayed setpoints the gateway moved back into its envelope (range or rate) on a motor they
  //! enable
  std::uint64_t limited = 0;
};

//! What one step did.
struct GatewayStep {
  bool relayed = false;   //!< a setpoint went to the sbRIO
  bool returned = false;  //!< the sbRIO's answer went back to the console
  bool disabled = false;  //!< an "all disabled" setpoint went to the sbRIO
  bool error = false;     //!< a transport failed
};

//! The gateway between a v2 `Network` (it must authenticate: SecureTransport over the console's
//! socket, with SecureResponder) and the 2016 `Link` to the sbRIO (a connected UdpTransport).
//! Both are owned by the caller and must outlive it.
template <FilteringTransport Network, FilteringTransport Link,
          endohaptics::Clock ClockT = endohaptics::SteadyClock, int N = 4>
requires requires(const Network& n) {
  { n.counters().rejected() } -> std::convertible_to<std::uint64_t>;
}
class V2Gateway {
 public:
  using Codec = protocol::PacketCodec<N>;  //!< the 2016 protocol for N motors

  //! Throws Error on a bad config.
  V2Gateway(Network& network, Link& link, ClockT& clock, const GatewayConfig& config = {})
      : network_(&network),
        link_(&link),
        clock_(&clock),
        config_((config.validate(), config)),
        next_disabled_(clock.now()),
        budget_at_(clock.now()) {
    budget_.fill(config_.burst() + wire_tolerance);  // full: a rest before the first setpoint
  }

  //! One round: waits up to `max_wait` (less while silent: the next disabled setpoint is due
  //! sooner) for a v2 setpoint and relays it; takes the sbRIO's answer (waiting up to the
  //! answer timeout after a relay) and seals it back; on silence sends the disabled setpoint
  //! when one is due.
  [[nodiscard]] GatewayStep step(std::chrono::nanoseconds max_wait) noexcept {
    GatewayStep out;
    auto now = clock_->now();
    auto wait = std::max(max_wait, std::chrono::nanoseconds(0));
    if (silent_at(now)) wait = std::clamp(next_disabled_ - now, std::chrono::nanoseconds(0), wait);
    SetpointFilter accept;
    const ReceiveResult r = network_->receive(std::span<std::byte>(setpoint_rx_), wait, accept);
    if (r.status == TransportStatus::ok && r.size == Codec::setpoint_packet_size) {
      // An answer still due to a disabled setpoint must not pass for this setpoint's.
      if (disabled_outstanding_) take_state(std::chrono::nanoseconds(0), out);
      relay(out);
    } else if (r.status == TransportStatus::error) {
      ++counters_.network_errors;
      out.error = true;
    }
    now = clock_->now();
    take_state(awaiting_ ? std::max(relayed_at_ + config_.answer_timeout - now,
                                    std::chrono::nanoseconds(0))
                         : std::chrono::nanoseconds(0),
               out);
    now = clock_->now();
    if (silent_at(now)) {
      if (obeyed_ && !tripped_) {
        tripped_ = true;
        ++counters_.watchdog_trips;
      }
      if (now >= next_disabled_) send_disabled(now, out);
    }
    return out;
  }

  //! Running totals since construction.
  [[nodiscard]] const GatewayCounters& counters() const noexcept { return counters_; }
  //! True while nothing was relayed for the watchdog time (or never): the motors are disabled.
  [[nodiscard]] bool silent() const noexcept { return silent_at(clock_->now()); }
  //! The "all disabled" setpoint sent now: enable mask 0, positions held (hold_position()).
  [[nodiscard]] typename Codec::Setpoint disabled_setpoint() const noexcept {
    typename Codec::Setpoint s;
    s.position = hold_position();
    s.enable_mask = 0;
    return s;
  }
  //! Where a disabled setpoint holds the motors: the sbRIO's newest measured positions (the tool
  //! where it is, also while it coasts: whatever the loop does with a disabled motor's setpoint,
  //! nothing pulls it back to where the console last commanded); before any state, the last
  //! relayed setpoint; before that, zero.
  [[nodiscard]] typename Codec::Setpoint::Vector hold_position() const noexcept {
    if (have_measured_) return measured_;
    return last_relayed_.position;
  }
  //! The settings.
  [[nodiscard]] const GatewayConfig& config() const noexcept { return config_; }

  //! rad: what a motor's bucket holds beyond GatewayConfig::burst(), for the float32 wire: a
  //! console's path is rounded to floats (under 2.4e-7 rad apart below pi), so a console exactly
  //! at its bound may be a few of them past it at a window's two ends. A fixed amount, not one
  //! per setpoint: however fast setpoints come, it is never gained twice.
  static constexpr double wire_tolerance = 1e-6;

 private:
  // The v2 side's payload filter: a decodable 2016 setpoint (bad payloads are counted there).
  struct SetpointFilter {
    bool operator()(std::span<const std::byte> datagram) const noexcept {
      typename Codec::Setpoint scratch;
      return Codec::decode_setpoint(datagram, scratch) == protocol::CodecStatus::ok;
    }
  };
  // The sbRIO side's filter: a decodable 2016 state.
  struct StateFilter {
    bool operator()(std::span<const std::byte> datagram) const noexcept {
      typename Codec::State scratch;
      return Codec::decode_state(datagram, scratch) == protocol::CodecStatus::ok;
    }
  };

  [[nodiscard]] bool silent_at(std::chrono::nanoseconds now) const noexcept {
    return !obeyed_ || now - last_obeyed_ >= config_.watchdog;
  }

  // Each motor's token bucket (rad): how far its next relayed position may move, before the time
  // since the last relayed setpoint was limited refills it at the rate, up to burst().
  using Budget = std::array<double, static_cast<std::size_t>(N)>;

  // `setpoint` kept in the envelope at `now`, motor by motor, and each motor's bucket after it
  // (`budget`): the joint range, and a step from a reference of at most what the bucket holds
  // (what the steps before left of it, refilled at the rate for the time since, at most
  // burst()). The reference is the last relayed setpoint's position if the motor was enabled in
  // it; else (after silence, or a motor that was released) where the sbRIO measured it; with
  // nothing measured, the last relayed position; with neither (nothing relayed, nothing
  // measured) the range alone. A motor the setpoint releases is sent at hold_position(), as in
  // the gateway's own disabled setpoint. A tool measured outside the range is brought back at the
  // rate, never by a jump to the range's edge. True if a motor this setpoint enables was moved.
  [[nodiscard]] bool limit(typename Codec::Setpoint& setpoint, std::chrono::nanoseconds now,
                           Budget& budget) const noexcept {
    const bool fresh = !silent_at(now);
    const double range = config_.joint_range;
    const double burst = config_.burst() + wire_tolerance;
    const double refill =
        config_.max_setpoint_rate *
        std::chrono::duration<double>(std::max(now - budget_at_, std::chrono::nanoseconds(0)))
            .count();
    const typename Codec::Setpoint::Vector hold = hold_position();
    bool moved = false;
    for (int i = 0; i < N; ++i) {
      const auto m = static_cast<std::size_t>(i);
      const auto bit = static_cast<std::uint8_t>(1u << static_cast<unsigned>(i));
      // The bucket goes on through silences and releases (refilled by a silence as by any rest):
      // a console that releases a motor between setpoints gains nothing by it.
      double step = std::min(burst, budget_[m] + refill);
      double ref = 0.0;
      if (fresh && (last_relayed_.enable_mask & bit) != 0) {
        ref = last_relayed_.position[i];
      } else if (have_measured_) {
        ref = measured_[i];
      } else if (obeyed_) {
        ref = last_relayed_.position[i];
      } else {
        step = 2.0 * range;  // no reference: the range alone
      }
      if ((setpoint.enable_mask & bit) == 0) {
        // A motor this setpoint releases is held where the gateway's own disabled setpoint holds
        // it (hold_position(): where the sbRIO measured it): what the console sends for it never
        // reaches the sbRIO (whatever its loop does with a disabled motor's setpoint), and its
        // bucket refills.
        setpoint.position[i] = hold[i];
        budget[m] = std::min(step, burst);
        continue;
      }
      const double lo = std::max(std::min(-range, ref), ref - step);
      const double hi = std::min(std::max(range, ref), ref + step);
      // What the wire carries (float32), kept inside [lo, hi] itself: rounded out of it, it is
      // taken one float towards the reference (a float, from the wire, inside [lo, hi]).
      auto wire = static_cast<float>(std::clamp(setpoint.position[i], lo, hi));
      if (wire < lo || wire > hi) wire = std::nextafter(wire, static_cast<float>(ref));
      const double kept = wire;
      // What the step left; a first setpoint (the range alone) leaves a full bucket.
      budget[m] = (obeyed_ || have_measured_) ? std::max(step - std::abs(kept - ref), 0.0) : burst;
      if (kept != setpoint.position[i]) {
        setpoint.position[i] = kept;
        moved = moved || (setpoint.enable_mask & bit) != 0;
      }
    }
    return moved;
  }

  void relay(GatewayStep& out) noexcept {
    const auto received =
        std::span<const std::byte>(setpoint_rx_.data(), Codec::setpoint_packet_size);
    typename Codec::Setpoint decoded;
    if (Codec::decode_setpoint(received, decoded) != protocol::CodecStatus::ok) return;  // filtered
    Budget budget{};
    const auto limited_at = clock_->now();
    const bool limited = limit(decoded, limited_at, budget);
    // What is sent is what was kept (re-encoded: a released motor's position may have moved too).
    if (Codec::encode_setpoint(decoded, limited_tx_) != protocol::CodecStatus::ok) return;
    const auto bytes = std::span<const std::byte>(limited_tx_);
    if (link_->send(bytes) != TransportStatus::ok) {
      ++counters_.sbrio_errors;
      out.error = true;
      return;
    }
    if (limited) ++counters_.limited;
    const auto now = clock_->now();
    last_relayed_ = decoded;
    budget_ = budget;
    // The send's own time is refilled by the next setpoint, not lost; never back in time.
    budget_at_ = std::max(budget_at_, limited_at);
    ++counters_.relayed;
    obeyed_ = true;
    tripped_ = false;
    last_obeyed_ = now;
    if (awaiting_) ++counters_.unanswered;  // the previous one's answer never came
    awaiting_ = true;
    relayed_at_ = now;
    out.relayed = true;
  }

  // Reads the sbRIO's newest state (waiting up to `wait`); answers the awaited setpoint with it.
  void take_state(std::chrono::nanoseconds wait, GatewayStep& out) noexcept {
    StateFilter accept;
    const ReceiveResult s = link_->receive(std::span<std::byte>(state_rx_), wait, accept);
    counters_.sbrio_refused += s.rejected + s.oversized;
    if (s.status == TransportStatus::ok && s.size == Codec::state_packet_size) {
      const auto bytes = std::span<const std::byte>(state_rx_.data(), Codec::state_packet_size);
      typename Codec::State state;
      if (Codec::decode_state(bytes, state) == protocol::CodecStatus::ok) {
        measured_ = state.position;
        have_measured_ = true;
      }
      disabled_outstanding_ = false;
      if (awaiting_) {
        awaiting_ = false;
        if (network_->send(bytes) == TransportStatus::ok) {
          ++counters_.returned;
          out.returned = true;
        } else {
          ++counters_.network_errors;
          out.error = true;
        }
      }
      return;
    }
    if (s.status == TransportStatus::error) {
      ++counters_.sbrio_errors;
      out.error = true;
    }
    if (awaiting_ && clock_->now() - relayed_at_ >= config_.answer_timeout) {
      awaiting_ = false;
      ++counters_.unanswered;
    }
  }

  void send_disabled(std::chrono::nanoseconds now, GatewayStep& out) noexcept {
    typename Codec::SetpointBytes bytes{};
    if (Codec::encode_setpoint(disabled_setpoint(), bytes) != protocol::CodecStatus::ok ||
        link_->send(bytes) != TransportStatus::ok) {
      ++counters_.sbrio_errors;
      out.error = true;
    } else {
      ++counters_.disabled;
      disabled_outstanding_ = true;
      out.disabled = true;
    }
    // Once a period from now on; a late step does not send a burst to catch up.
    next_disabled_ += config_.period;
    if (next_disabled_ <= now) next_disabled_ = now + config_.period;
  }

  Network* network_;
  Link* link_;
  ClockT* clock_;
  GatewayConfig config_;
  GatewayCounters counters_{};
  bool obeyed_ = false;                // a setpoint was relayed once
  bool tripped_ = false;               // silent since the last relayed setpoint
  bool awaiting_ = false;              // the setpoint relayed last awaits the sbRIO's answer
  bool disabled_outstanding_ = false;  // a disabled setpoint was sent and not answered yet
  bool have_measured_ = false;
  std::chrono::nanoseconds last_obeyed_{0};
  std::chrono::nanoseconds relayed_at_{0};
  std::chrono::nanoseconds next_disabled_{0};
  typename Codec::Setpoint last_relayed_{};
  Budget budget_{};  // each motor's token bucket after the last relayed setpoint (rad)
  std::chrono::nanoseconds budget_at_{0};  // when budget_ was taken (the limit, before the send)
  typename Codec::Setpoint::Vector measured_ = Codec::Setpoint::Vector::Zero();
  // One byte longer than the packets: a longer datagram never decodes as its first bytes.
  std::array<std::byte, Codec::setpoint_packet_size + 1> setpoint_rx_{};
  std::array<std::byte, Codec::state_packet_size + 1> state_rx_{};
  typename Codec::SetpointBytes limited_tx_{};  // the setpoint relayed, as kept in the envelope
};

}  // namespace endohaptics::transport
