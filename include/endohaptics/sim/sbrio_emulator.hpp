//! @file
//! SbrioEmulator: the sbRIO's behaviour on the wire (worksheet 3.3.1, 5.3): receives setpoint
//! packets, answers each with the newest state packet of a simulated rig, lets a motor follow
//! its setpoint only while its enable bit is set, and disables every motor when no valid packet
//! arrived for `watchdog_timeout` (100 ms). The rig runs in the clock's time. Times in ns.
#pragma once

#include <array>
#include <chrono>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <type_traits>

#include "endohaptics/core/clock.hpp"
#include "endohaptics/core/error.hpp"
#include "endohaptics/protocol/packet_codec.hpp"
#include "endohaptics/transport/transport.hpp"

namespace endohaptics::sim {

//! What the emulator needs from a simulated rig (SimulatedRig, or a user's own plant).
template <typename R, int N>
concept EmulatedRig = requires(R& rig, const R& crig, const protocol::MotorSetpoint<N>& setpoint,
                               double seconds) {
  { rig.command(setpoint) }
  noexcept;
  { rig.advance(seconds) }
  noexcept;
  { crig.state() }
  noexcept->std::convertible_to<protocol::MotorState<N>>;
};

//! Emulator settings.
struct EmulatorConfig {
  //! No valid setpoint packet for this long: every motor is disabled (sbRIO watchdog).
  std::chrono::nanoseconds watchdog_timeout = std::chrono::milliseconds(100);
  //! The rig is advanced in chunks of at most this (bounds the work of one poll after a pause).
  std::chrono::nanoseconds max_advance = std::chrono::seconds(1);
  //! > 0: the rig is stopped at every multiple of this after construction and `poll`'s sampler
  //! sees it there (a truth log on an exact grid, whatever the packets' timing). 0: no grid.
  std::chrono::nanoseconds sample_period{0};

  //! Throws Error when a duration is not > 0 (naming field and value).
  void validate() const {
    if (watchdog_timeout.count() <= 0) {
      ENDOHAPTICS_THROW(Error("EmulatorConfig: watchdog_timeout must be > 0 ns, got " +
                              std::to_string(watchdog_timeout.count())));
    }
    if (max_advance.count() <= 0) {
      ENDOHAPTICS_THROW(Error("EmulatorConfig: max_advance must be > 0 ns, got " +
                              std::to_string(max_advance.count())));
    }
    if (sample_period.count() < 0) {
      ENDOHAPTICS_THROW(Error("EmulatorConfig: sample_period must be >= 0 ns (0: no grid), got " +
                              std::to_string(sample_period.count())));
    }
  }
};

//! What one poll did.
enum class PollEvent : std::uint8_t {
  idle = 0,         //!< nothing arrived before the timeout; the rig ran on
  answered,         //!< a valid setpoint packet arrived and was answered
  rejected,         //!< a datagram arrived that is not a valid setpoint packet (not answered)
  transport_error,  //!< the transport failed (receive or send)
};

//! Human-readable name of a poll event, for logs.
[[nodiscard]] constexpr std::string_view to_string(PollEvent e) noexcept {
  switch (e) {
    case PollEvent::idle:
      return "idle";
    case PollEvent::answered:
      return "answered";
    case PollEvent::rejected:
      return "rejected";
    case PollEvent::transport_error:
      return "transport error";
  }
  return "unknown event";
}

//! Running totals (monotonic).
struct EmulatorCounters {
  std::uint64_t received = 0;             //!< valid setpoint packets
  std::uint64_t answered = 0;             //!< state packets sent
  std::uint64_t rejected = 0;             //!< invalid datagrams (the three causes below)
  std::uint64_t rejected_size = 0;        //!< empty, short, long or oversized datagrams
  std::uint64_t rejected_non_finite = 0;  //!< NaN or Inf in a setpoint
  std::uint64_t rejected_mask = 0;        //!< enable bit at or above the motor count
  std::uint64_t stale_dropped = 0;     //!< older valid setpoints drained unanswered (queue of one)
  std::uint64_t transport_errors = 0;  //!< receive or send failures
  std::uint64_t watchdog_trips = 0;    //!< times the 100 ms watchdog disabled the motors
};

//! The sbRIO side. `Transport` answers the sender of the newest datagram (UdpServerTransport,
//! or an in-memory link end). All members a poll calls are noexcept and allocation-free.
template <transport::Transport Transport, typename Rig,
          endohaptics::Clock ClockT = endohaptics::SteadyClock, int N = 4>
requires EmulatedRig<Rig, N>
class SbrioEmulator {
 public:
  using Codec = protocol::PacketCodec<N>;  //!< the sbRIO protocol for N motors

  //! Parts are owned by the caller and must outlive the emulator. Throws Error on a bad config.
  SbrioEmulator(Transport& transport, Rig& rig, ClockT& clock, const EmulatorConfig& config = {})
      : transport_(&transport),
        rig_(&rig),
        clock_(&clock),
        config_((config.validate(), config)),
        last_time_(clock.now()),
        last_packet_(last_time_),
        next_sample_(last_time_) {
    rig_->command(setpoint_);  // everything disabled until the PC says otherwise
  }

  //! Waits up to `timeout` for a setpoint packet, runs the rig up to the clock's now (tripping the
  //! watchdog on the way if due), applies the packet and answers it with the rig's state.
  [[nodiscard]] PollEvent poll(std::chrono::nanoseconds timeout) noexcept {
    return poll(timeout, NoSampler{});
  }

  //! poll(timeout), and with `EmulatorConfig::sample_period` > 0 the rig is stopped at each grid
  //! instant it passes on the way to now, where `sampler(time, setpoint, rig)` sees it: the
  //! time on the grid, the setpoint the rig followed up to then (a packet that arrives is applied
  //! at the clock's now, after the instants before it). `sampler` must be noexcept.
  template <typename Sampler>
  requires std::is_nothrow_invocable_v<Sampler&, std::chrono::nanoseconds,
                                       const typename Codec::Setpoint&, const Rig&>
  [[nodiscard]] PollEvent poll(std::chrono::nanoseconds timeout, Sampler&& sampler) noexcept {
    // The newest datagram that decodes wins: junk arriving after a valid setpoint cannot
    // displace it. Every refused datagram is counted by cause.
    Decoder decoder{&counters_};
    const transport::ReceiveResult rx = transport::receive_filtered(
        *transport_, std::span<std::byte>(rx_buffer_), timeout, decoder);
    advance_to(clock_->now(), sampler);
    counters_.stale_dropped += rx.dropped;
    counters_.rejected_size += rx.oversized;
    counters_.rejected += rx.oversized;
    if (rx.status == transport::TransportStatus::timeout) return PollEvent::idle;
    if (rx.status == transport::TransportStatus::error) {
      ++counters_.transport_errors;
      return PollEvent::transport_error;
    }
    // the real sbRIO ignores what it cannot parse: no answer, no watchdog feed
    if (rx.status == transport::TransportStatus::rejected) return PollEvent::rejected;
    typename Codec::Setpoint received;
    if (Codec::decode_setpoint(std::span<const std::byte>(rx_buffer_.data(), rx.size), received) !=
        protocol::CodecStatus::ok) {
      count_rejection(counters_, protocol::CodecStatus::wrong_size);  // a plain Transport's damage
      return PollEvent::rejected;
    }
    ++counters_.received;
    setpoint_ = received;
    rig_->command(setpoint_);
    last_packet_ = last_time_;
    tripped_ = false;

    typename Codec::StateBytes tx{};
    if (Codec::encode_state(rig_->state(), tx) != protocol::CodecStatus::ok ||
        transport_->send(tx) != transport::TransportStatus::ok) {
      ++counters_.transport_errors;
      return PollEvent::transport_error;
    }
    ++counters_.answered;
    return PollEvent::answered;
  }

  //! Runs the rig up to `now` without receiving (e.g. between polls in a test).
  void advance_to(std::chrono::nanoseconds now) noexcept {
    NoSampler none;
    advance_to(now, none);
  }

  //! advance_to(now), `sampler` called at the grid instants passed (see poll).
  template <typename Sampler>
  void advance_to(std::chrono::nanoseconds now, Sampler& sampler) noexcept {
    if (!tripped_ && setpoint_.enable_mask != 0 && now - last_packet_ > config_.watchdog_timeout) {
      run_until(last_packet_ + config_.watchdog_timeout, sampler);
      setpoint_.enable_mask = 0;  // positions kept; the motors coast
      rig_->command(setpoint_);
      tripped_ = true;
      ++counters_.watchdog_trips;
    }
    run_until(now, sampler);
  }

  //! Running totals since construction.
  [[nodiscard]] const EmulatorCounters& counters() const noexcept { return counters_; }
  //! The setpoint the rig follows now (enable bits cleared by the watchdog).
  [[nodiscard]] const typename Codec::Setpoint& setpoint() const noexcept { return setpoint_; }
  //! True while the watchdog holds the motors disabled.
  [[nodiscard]] bool watchdog_tripped() const noexcept { return tripped_; }
  //! The emulated rig.
  [[nodiscard]] Rig& rig() noexcept { return *rig_; }
  //! The emulated rig.
  [[nodiscard]] const Rig& rig() const noexcept { return *rig_; }
  //! Clock time up to which the rig has run.
  [[nodiscard]] std::chrono::nanoseconds time() const noexcept { return last_time_; }

 private:
  // The sampler of the calls without one.
  struct NoSampler {
    void operator()(std::chrono::nanoseconds, const typename Codec::Setpoint&,
                    const Rig&) const noexcept {}
  };

  static void count_rejection(EmulatorCounters& c, protocol::CodecStatus status) noexcept {
    ++c.rejected;
    if (status == protocol::CodecStatus::mask_out_of_range) {
      ++c.rejected_mask;
    } else if (status == protocol::CodecStatus::wrong_size) {
      ++c.rejected_size;
    } else {
      ++c.rejected_non_finite;
    }
  }

  // The receive filter: a candidate only if it decodes as a setpoint packet.
  struct Decoder {
    EmulatorCounters* counters;
    bool operator()(std::span<const std::byte> datagram) noexcept {
      typename Codec::Setpoint scratch;
      const auto status = Codec::decode_setpoint(datagram, scratch);
      if (status == protocol::CodecStatus::ok) return true;
      count_rejection(*counters, status);
      return false;
    }
  };

  // Runs the rig to `t` in steps of at most max_advance, stopping at each grid instant (the
  // sampler sees the rig there, the first instant being the construction time).
  template <typename Sampler>
  void run_until(std::chrono::nanoseconds t, Sampler& sampler) noexcept {
    const bool grid = config_.sample_period.count() > 0;
    for (;;) {
      if (grid && next_sample_ <= last_time_) {
        sampler(last_time_, setpoint_, *rig_);
        next_sample_ += config_.sample_period;
        continue;
      }
      if (t <= last_time_) break;
      const auto target = grid ? std::min(t, next_sample_) : t;
      const auto step = std::min(target - last_time_, config_.max_advance);
      (void)rig_->advance(std::chrono::duration<double>(step).count());
      last_time_ += step;
    }
  }

  Transport* transport_;
  Rig* rig_;
  ClockT* clock_;
  EmulatorConfig config_;
  typename Codec::Setpoint setpoint_{};
  std::chrono::nanoseconds last_time_;
  std::chrono::nanoseconds last_packet_;
  std::chrono::nanoseconds next_sample_;  // the next grid instant (sample_period > 0)
  bool tripped_ = false;
  EmulatorCounters counters_{};
  // One byte longer than a setpoint packet: a long datagram never decodes as its first bytes.
  std::array<std::byte, Codec::setpoint_packet_size + 1> rx_buffer_{};
};

}  // namespace endohaptics::sim
