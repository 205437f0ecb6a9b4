//! @file
//! SecureTransport: protocol v2 as a Transport adapter. It carries 2016 packets (what TeleopLoop
//! and SbrioEmulator send and decode) inside v2 packets over any FilteringTransport: send seals,
//! receive keeps only authentic, fresh, in-session datagrams and hands over their 2016 payload.
//! Refusals are counted by cause; a drain with nothing authentic is reported as silence (timeout).
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstring>
#include <span>

#include "endohaptics/protocol/secure_session.hpp"
#include "endohaptics/transport/transport.hpp"

namespace endohaptics::transport {

//! v2 adapter over `Inner` (not owned) with the session rules of `Session`
//! (protocol::SecureInitiator on the PC, protocol::SecureResponder on the sbRIO). Models
//! FilteringTransport; send/receive are noexcept and allocation-free.
template <FilteringTransport Inner, typename Session>
class SecureTransport {
 public:
  //! `inner` must outlive the adapter; `session` is copied.
  SecureTransport(Inner& inner, const Session& session) : inner_(&inner), session_(session) {}

  //! Seals the 2016 packet `datagram` and sends it; error when it has the wrong size.
  TransportStatus send(std::span<const std::byte> datagram) noexcept {
    if (session_.seal(datagram, tx_) != protocol::SecureStatus::ok) return TransportStatus::error;
    const TransportStatus s = inner_->send(tx_);
    if constexpr (requires { session_.sent(); }) {
      sent_at_[session_.sent() % sent_at_.size()] = now();
    }
    return s;
  }

  //! The true round trip of the newest accepted answer: from sending the packet it acknowledges
  //! to receiving it (0 before the first, or when that packet is older than the last
  //! `round_trip_history` sent). On a delayed link this is the delay, not the time a receive
  //! waited.
  [[nodiscard]] std::chrono::nanoseconds answer_round_trip() const noexcept {
    return answer_round_trip_;
  }
  //! How many packets back answer_round_trip() can look (16 s at 1 kHz).
  static constexpr std::size_t round_trip_history = 16384;

  //! As receive(buffer, timeout, filter) with a filter that accepts every authentic payload.
  ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout) noexcept {
    AcceptAny any;
    return receive(buffer, timeout, any);
  }

  //! Receives the newest authentic, fresh datagram whose 2016 payload `filter` accepts, and
  //! writes that payload into `buffer`. Datagrams that are not authentic or not fresh never reach
  //! `filter` and are counted (counters()); when nothing authentic and fresh arrived the status
  //! is timeout (silence), whatever was read.
  template <DatagramFilter F>
  ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout,
                        F& filter) noexcept {
    Gate<F> gate{this, &filter};
    ReceiveResult r = inner_->receive(std::span<std::byte>(rx_), timeout, gate);
    counters_.wrong_size += r.oversized;
    r.oversized = 0;
    if (r.status == TransportStatus::ok) {
      if (buffer.size() < Session::receive_payload_size) {
        ++r.oversized;
        r.status = TransportStatus::rejected;
        r.size = 0;
        return r;
      }
      std::memcpy(buffer.data(), rx_.data() + Codec::header_size, Session::receive_payload_size);
      if (gate.last_unbound) buffer[Session::receive_payload_size - 1] = std::byte{0};
      r.size = Session::receive_payload_size;
    } else if (r.status == TransportStatus::rejected && !gate.filter_refused) {
      r.status = TransportStatus::timeout;  // nothing authentic and fresh arrived: silence
    }
    return r;
  }

  //! Refusals and acceptances by cause, since construction.
  [[nodiscard]] const protocol::SecureCounters& counters() const noexcept { return counters_; }
  //! The session state (ids, window).
  [[nodiscard]] const Session& session() const noexcept { return session_; }
  //! The wrapped transport.
  [[nodiscard]] Inner& inner() noexcept { return *inner_; }

 private:
  using Codec = typename Session::Codec;

  static std::chrono::nanoseconds now() noexcept {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
        std::chrono::steady_clock::now().time_since_epoch());
  }

  // The inner drain's filter: verify, then the caller's filter on the payload, then commit.
  template <typename F>
  struct Gate {
    SecureTransport* self;
    F* filter;
    bool filter_refused = false;  // the caller's filter refused an authentic, fresh payload
    bool last_unbound = false;
    bool operator()(std::span<const std::byte> datagram) noexcept {
      const auto now = SecureTransport::now();
      protocol::SecureVerified v;
      const protocol::SecureStatus s = self->session_.verify(datagram, now, v);
      const bool unbound = s == protocol::SecureStatus::unbound;
      if (s != protocol::SecureStatus::ok && !unbound) {
        self->counters_.record(s);
        return false;
      }
      std::array<std::byte, Session::receive_payload_size> payload{};
      std::memcpy(payload.data(), v.payload.data(), payload.size());
      if (unbound) payload.back() = std::byte{0};  // answered, never obeyed
      if (!(*filter)(std::span<const std::byte>(payload))) {
        self->counters_.record(protocol::SecureStatus::bad_payload);
        filter_refused = true;
        return false;
      }
      if constexpr (requires { self->session_.commit(v, now); }) {
        self->session_.commit(v, now);
      } else {
        self->session_.commit(v);
      }
      if constexpr (requires { self->session_.sent(); }) {
        const std::uint64_t ack = v.header.ack;
        const std::uint64_t sent = self->session_.sent();
        if (ack > 0 && ack <= sent && sent - ack < self->sent_at_.size()) {
          self->answer_round_trip_ = now - self->sent_at_[ack % self->sent_at_.size()];
        }
      }
      self->counters_.record(s);
      last_unbound = unbound;
      return true;
    }
  };

  Inner* inner_;
  Session session_;
  protocol::SecureCounters counters_{};
  std::array<std::byte, Session::send_packet_size> tx_{};
  // One byte longer than a v2 packet: a longer datagram is refused as a wrong size.
  std::array<std::byte, Session::receive_packet_size + 1> rx_{};
  // When each of the last round_trip_history packets was sent (by sequence modulo the size).
  std::array<std::chrono::nanoseconds, round_trip_history> sent_at_{};
  std::chrono::nanoseconds answer_round_trip_{0};
};

}  // namespace endohaptics::transport
