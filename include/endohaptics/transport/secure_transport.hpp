//! @file
//! SecureTransport: protocol v2 as a Transport adapter. It carries 2016 packets (what TeleopLoop
//! and SbrioEmulator send and decode) inside v2 packets over any FilteringTransport, and runs the
//! session's handshake underneath: on the console side send() also sends the HELLO when one is
//! due (and sends no setpoint before a session: the robot would obey none), receive() takes the
//! WELCOME; on the robot side receive() answers a fresh HELLO with its WELCOME. receive() hands
//! over only authentic, fresh, in-session payloads. Refusals are counted by cause; a drain with
//! nothing to hand over is reported as silence (timeout).
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cstddef>
#include <cstring>
#include <span>
#include <utility>

#include "endohaptics/protocol/secure_session.hpp"
#include "endohaptics/transport/transport.hpp"

namespace endohaptics::transport {

//! v2 adapter over `Inner` (not owned) with the session rules of `Session`
//! (protocol::SecureInitiator on the console, protocol::SecureResponder on the robot side).
//! Models FilteringTransport; send/receive are noexcept and allocation-free.
template <FilteringTransport Inner, typename Session>
class SecureTransport {
 public:
  //! `inner` must outlive the adapter; `session` is moved in (its keys are never copied).
  SecureTransport(Inner& inner, Session session) : inner_(&inner), session_(std::move(session)) {}

  //! Console side: sends the HELLO when one is due, then seals the 2016 packet `datagram` and
  //! sends it (before the first session it is held back: ok, nothing sent, counted in
  //! held_before_session()). error when it has the wrong size or the transport fails.
  TransportStatus send(std::span<const std::byte> datagram) noexcept {
    const auto t = now();
    if constexpr (requires { session_.hello_due(t, hello_); }) {
      if (session_.hello_due(t, hello_)) (void)inner_->send(hello_);
    }
    const protocol::SecureStatus sealed =
        session_.seal(datagram, std::span<std::byte>(tx_.data(), Session::send_packet_size));
    if (sealed == protocol::SecureStatus::no_session) {
      ++held_;
      return TransportStatus::ok;
    }
    if (sealed != protocol::SecureStatus::ok) return TransportStatus::error;
    const TransportStatus s =
        inner_->send(std::span<const std::byte>(tx_.data(), Session::send_packet_size));
    if constexpr (requires { session_.hello_due(t, hello_); }) {
      sent_at_[static_cast<std::size_t>(session_.sent() % sent_at_.size())] = t;
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
  //! How many packets back answer_round_trip() can look.
  static constexpr std::size_t round_trip_history = protocol::packet_history;

  //! As receive(buffer, timeout, filter) with a filter that accepts every authentic payload.
  ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout) noexcept {
    AcceptAny any;
    return receive(buffer, timeout, any);
  }

  //! Receives the newest authentic, fresh datagram whose 2016 payload `filter` accepts, and
  //! writes that payload into `buffer`. Datagrams that are not authentic or not fresh never reach
  //! `filter` and are counted (counters()); handshake packets are taken (and a HELLO answered)
  //! without reaching it. When nothing authentic and fresh arrived the status is timeout
  //! (silence), whatever was read.
  template <DatagramFilter F>
  ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout,
                        F& filter) noexcept {
    if constexpr (requires { session_.expire(now()); }) session_.expire(now());
    Gate<F> gate{this, &filter};
    ReceiveResult r = inner_->receive(std::span<std::byte>(rx_), timeout, gate);
    counters_.wrong_size += r.oversized;
    r.oversized = 0;
    if (r.status == TransportStatus::ok && gate.last_handshake) {
      // A handshake step was the newest datagram taken (the drain returns at once: a session
      // opens one round trip after the HELLO). Robot side: the inner transport answers the
      // HELLO's sender. Either way nothing for the caller: silence.
      if constexpr (requires { session_.take_reply(); }) {
        if (const auto reply = session_.take_reply(); !reply.empty()) (void)inner_->send(reply);
      }
      r.status = TransportStatus::timeout;
      r.size = 0;
      return r;
    }
    if (r.status == TransportStatus::ok) {
      if (buffer.size() < Session::receive_payload_size) {
        ++r.oversized;
        r.status = TransportStatus::rejected;
        r.size = 0;
        return r;
      }
      std::memcpy(buffer.data(), rx_.data() + Codec::header_size, Session::receive_payload_size);
      r.size = Session::receive_payload_size;
    } else if (r.status == TransportStatus::rejected && !gate.filter_refused) {
      r.status = TransportStatus::timeout;  // nothing authentic and fresh arrived: silence
    }
    return r;
  }

  //! Refusals and acceptances by cause, since construction.
  [[nodiscard]] const protocol::SecureCounters& counters() const noexcept { return counters_; }
  //! Console side: setpoints not sent because no session was open yet.
  [[nodiscard]] std::uint64_t held_before_session() const noexcept { return held_; }
  //! The session state (ids, window).
  [[nodiscard]] const Session& session() const noexcept { return session_; }
  //! The session state, for revocation (SecureResponder::revoke).
  [[nodiscard]] Session& session() noexcept { return session_; }
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
    bool last_handshake = false;  // the newest datagram taken is a HELLO or a WELCOME
    bool operator()(std::span<const std::byte> datagram) noexcept {
      const auto now = SecureTransport::now();
      protocol::SecureVerified v;
      const protocol::SecureStatus s = self->session_.verify(datagram, now, v);
      if (s != protocol::SecureStatus::ok) self->counters_.record(s);
      if (s == protocol::SecureStatus::welcome || s == protocol::SecureStatus::hello) {
        self->session_.commit(v, now);  // a session opens (console), or is offered (robot)
        last_handshake = true;
        return true;
      }
      if (s != protocol::SecureStatus::ok) return false;
      std::array<std::byte, Session::receive_payload_size> payload{};
      std::memcpy(payload.data(), v.payload.data(), payload.size());
      if (!(*filter)(std::span<const std::byte>(payload))) {
        self->counters_.record(protocol::SecureStatus::bad_payload);
        filter_refused = true;
        return false;
      }
      self->counters_.record(protocol::SecureStatus::ok);
      self->session_.commit(v, now);
      if constexpr (requires { self->session_.hello_due(now, self->hello_); }) {
        const std::uint64_t ack = v.header.ack;
        const std::uint64_t sent = self->session_.sent();
        if (!v.previous_session && ack > 0 && ack <= sent && sent - ack < self->sent_at_.size()) {
          self->answer_round_trip_ =
              now - self->sent_at_[static_cast<std::size_t>(ack % self->sent_at_.size())];
        }
      }
      last_handshake = false;
      return true;
    }
  };

  static constexpr std::size_t largest_packet =
      std::max({Session::send_packet_size, Session::receive_packet_size,
                protocol::HandshakeCodec::packet_size});

  Inner* inner_;
  Session session_;
  protocol::SecureCounters counters_{};
  std::uint64_t held_ = 0;
  std::array<std::byte, Session::send_packet_size> tx_{};
  protocol::HandshakeCodec::Bytes hello_{};
  // One byte longer than the longest v2 packet: a longer datagram is refused as a wrong size.
  std::array<std::byte, largest_packet + 1> rx_{};
  // When each of the last round_trip_history packets was sent (by sequence modulo the size).
  std::array<std::chrono::nanoseconds, round_trip_history> sent_at_{};
  std::chrono::nanoseconds answer_round_trip_{0};
};

}  // namespace endohaptics::transport
