//! @file
//! The v2 session rules on top of SecureCodec: SecureInitiator (the PC, sends setpoints) and
//! SecureResponder (the sbRIO, answers them): random session ids per run, sequence numbers from 1,
//! the RFC 4303 replay window, session binding by echo (no packet of an earlier run is ever
//! accepted), and counters of every refusal by cause. See docs/protocol.md, "Protocol v2".
#pragma once

#include <sodium.h>

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>

#include "endohaptics/core/error.hpp"
#include "endohaptics/protocol/replay_window.hpp"
#include "endohaptics/protocol/secure_codec.hpp"

namespace endohaptics::protocol {

//! A fresh random non-zero 64-bit session id (libsodium's randombytes_buf). Configuration time,
//! or rarely (the sbRIO side after a session expired). Throws Error if libsodium cannot start.
[[nodiscard]] inline std::uint64_t random_session_id() {
  if (sodium_init() < 0) ENDOHAPTICS_THROW(Error("libsodium failed to initialise"));
  std::uint64_t id = 0;
  while (id == 0) randombytes_buf(&id, sizeof(id));
  return id;
}

//! Datagrams refused by a v2 receiver, by cause (and the accepted ones).
struct SecureCounters {
  std::uint64_t accepted = 0;       //!< authentic, fresh, in session
  std::uint64_t wrong_size = 0;     //!< SecureStatus::wrong_size
  std::uint64_t forged = 0;         //!< SecureStatus::forged
  std::uint64_t bad_version = 0;    //!< SecureStatus::bad_version
  std::uint64_t wrong_type = 0;     //!< SecureStatus::wrong_type
  std::uint64_t wrong_session = 0;  //!< SecureStatus::wrong_session
  std::uint64_t replayed = 0;       //!< SecureStatus::replayed
  std::uint64_t too_old = 0;        //!< SecureStatus::too_old
  std::uint64_t stale_answer = 0;   //!< SecureStatus::stale_answer
  std::uint64_t unbound = 0;        //!< SecureStatus::unbound (delivered with motors disabled)
  std::uint64_t bad_payload = 0;    //!< authentic, the 2016 payload refused by the receiver

  //! Counts one datagram with outcome `s`.
  constexpr void record(SecureStatus s) noexcept {
    switch (s) {
      case SecureStatus::ok:
        ++accepted;
        break;
      case SecureStatus::wrong_size:
        ++wrong_size;
        break;
      case SecureStatus::forged:
        ++forged;
        break;
      case SecureStatus::bad_version:
        ++bad_version;
        break;
      case SecureStatus::wrong_type:
        ++wrong_type;
        break;
      case SecureStatus::wrong_session:
        ++wrong_session;
        break;
      case SecureStatus::replayed:
        ++replayed;
        break;
      case SecureStatus::too_old:
        ++too_old;
        break;
      case SecureStatus::stale_answer:
        ++stale_answer;
        break;
      case SecureStatus::unbound:
        ++unbound;
        break;
      case SecureStatus::bad_payload:
      case SecureStatus::exhausted:
        ++bad_payload;
        break;
    }
  }
  //! Every refused datagram (all but accepted and unbound).
  [[nodiscard]] constexpr std::uint64_t rejected() const noexcept {
    return wrong_size + forged + bad_version + wrong_type + wrong_session + replayed + too_old +
           stale_answer + bad_payload;
  }
};

//! One line for logs and summaries: "accepted A, unbound U, rejected R (forged F, wrong size W,
//! ...)". Allocates: not for the tick.
[[nodiscard]] inline std::string describe(const SecureCounters& c) {
  auto n = [](std::uint64_t v) { return std::to_string(v); };
  return "accepted " + n(c.accepted) + ", unbound " + n(c.unbound) + ", rejected " +
         n(c.rejected()) + " (forged " + n(c.forged) + ", wrong size " + n(c.wrong_size) +
         ", bad version " + n(c.bad_version) + ", wrong type " + n(c.wrong_type) +
         ", wrong session " + n(c.wrong_session) + ", replayed " + n(c.replayed) + ", too old " +
         n(c.too_old) + ", stale answer " + n(c.stale_answer) + ", bad payload " +
         n(c.bad_payload) + ")";
}

//! What a verify step found in an authentic packet; pass it to commit() if it is used.
struct SecureVerified {
  SecureHeader header{};                 //!< the packet's header
  std::span<const std::byte> payload{};  //!< the 2016 packet inside the datagram
  bool new_peer_session = false;         //!< commit binds to header.session afresh
  bool renew_own_session = false;        //!< responder: the bound session expired
};

//! The PC side: seals setpoints, verifies states. Binds to the sbRIO's session from the first
//! authentic state that echoes this run's session id; follows the sbRIO to a new session (it
//! restarted, or the binding expired) only for a state answering a newer setpoint than any
//! accepted before, so no state of an earlier sbRIO session is ever accepted again.
template <int NumMotors = 4>
class SecureInitiator {
 public:
  using Codec = SecureCodec<NumMotors>;  //!< the v2 codec
  //! 2016 payload bytes sent (a setpoint) and received (a state).
  static constexpr std::size_t send_payload_size = Codec::Legacy::setpoint_packet_size;
  static constexpr std::size_t receive_payload_size = Codec::Legacy::state_packet_size;  //!< bytes
  static constexpr std::size_t send_packet_size = Codec::setpoint_packet_size;  //!< v2 bytes
  static constexpr std::size_t receive_packet_size = Codec::state_packet_size;  //!< v2 bytes
  static constexpr PacketType receive_type = PacketType::state;  //!< what it verifies

  //! `session`: this run's id, non-zero (random_session_id()). `max_answer_lag`: states may
  //! answer a setpoint this many older than the newest sent (0: only the newest). Throws Error.
  SecureInitiator(const SecureKey& key, std::uint64_t session, std::uint64_t max_answer_lag = 0)
      : key_(key), session_(session), max_answer_lag_(max_answer_lag) {
    if (session == 0) ENDOHAPTICS_THROW(Error("SecureInitiator: session id must be non-zero"));
  }

  //! Seals the 2016 setpoint `payload` as the next setpoint of this session into `out`.
  [[nodiscard]] SecureStatus seal(std::span<const std::byte> payload,
                                  std::span<std::byte> out) noexcept {
    if (sent_ == std::numeric_limits<std::uint64_t>::max()) return SecureStatus::exhausted;
    const SecureHeader h{PacketType::setpoint, session_, sent_ + 1, peer_session_, window_.top()};
    const SecureStatus s = Codec::seal(key_, h, payload, out);
    if (s == SecureStatus::ok) ++sent_;
    return s;
  }

  //! Checks a datagram as a state packet without changing anything.
  [[nodiscard]] SecureStatus verify(std::span<const std::byte> bytes,
                                    std::chrono::nanoseconds /*now*/,
                                    SecureVerified& out) const noexcept {
    SecureVerified v;
    if (const SecureStatus s = Codec::open(key_, PacketType::state, bytes, v.header, v.payload);
        s != SecureStatus::ok) {
      return s;
    }
    const SecureHeader& h = v.header;
    if (h.peer_session != session_ || h.ack > sent_ || h.ack == 0) {
      return SecureStatus::wrong_session;  // not an answer to this run's setpoints
    }
    if (peer_session_ != 0 && h.session == peer_session_) {
      if (const WindowStatus w = window_.check(h.sequence); w != WindowStatus::ok) {
        return w == WindowStatus::replayed ? SecureStatus::replayed : SecureStatus::too_old;
      }
      // Strictly in order: a state older than the newest accepted is a step back in time.
      if (h.sequence < window_.top()) return SecureStatus::too_old;
    } else {
      // A new sbRIO session: only from a state answering a newer setpoint than any accepted.
      if (h.ack <= highest_ack_) return SecureStatus::wrong_session;
      if (h.sequence == 0) return SecureStatus::too_old;
      v.new_peer_session = true;
    }
    if (sent_ - h.ack > max_answer_lag_) return SecureStatus::stale_answer;
    out = v;
    return SecureStatus::ok;
  }

  //! Accepts what verify() returned ok for: binds, slides the window.
  void commit(const SecureVerified& v) noexcept {
    if (v.new_peer_session) {
      peer_session_ = v.header.session;
      window_.reset();
    }
    window_.accept(v.header.sequence);
    if (v.header.ack > highest_ack_) highest_ack_ = v.header.ack;
  }

  //! verify() then commit() on ok; the 2016 state packet is copied into `payload` (untouched
  //! unless ok).
  [[nodiscard]] SecureStatus open(std::span<const std::byte> bytes,
                                  std::span<std::byte, receive_payload_size> payload,
                                  std::chrono::nanoseconds now = {}) noexcept {
    SecureVerified v;
    const SecureStatus s = verify(bytes, now, v);
    if (s != SecureStatus::ok) return s;
    commit(v);
    std::memcpy(payload.data(), v.payload.data(), receive_payload_size);
    return s;
  }

  //! This run's session id.
  [[nodiscard]] std::uint64_t session() const noexcept { return session_; }
  //! The sbRIO session bound (0: none yet).
  [[nodiscard]] std::uint64_t peer_session() const noexcept { return peer_session_; }
  //! Sequence number of the newest setpoint sealed (0: none).
  [[nodiscard]] std::uint64_t sent() const noexcept { return sent_; }
  //! The replay window over the bound sbRIO session's sequence numbers.
  [[nodiscard]] const ReplayWindow& window() const noexcept { return window_; }

 private:
  SecureKey key_;
  std::uint64_t session_;
  std::uint64_t max_answer_lag_;
  std::uint64_t sent_ = 0;
  std::uint64_t peer_session_ = 0;
  std::uint64_t highest_ack_ = 0;
  ReplayWindow window_{};
};

//! The sbRIO side: verifies setpoints, seals states. Unbound (at start, and after `expiry`
//! without an accepted setpoint), it answers any authentic setpoint as `unbound` (delivered with
//! every motor disabled) with a state carrying its session id; it binds to the first setpoint
//! that echoes that id and then obeys only that session, in sequence (replay window). Expiry
//! draws a new session id, so nothing sent before can bind again.
template <int NumMotors = 4>
class SecureResponder {
 public:
  using Codec = SecureCodec<NumMotors>;  //!< the v2 codec
  //! 2016 payload bytes sent (a state) and received (a setpoint).
  static constexpr std::size_t send_payload_size = Codec::Legacy::state_packet_size;
  static constexpr std::size_t receive_payload_size = Codec::Legacy::setpoint_packet_size;  //!< B
  static constexpr std::size_t send_packet_size = Codec::state_packet_size;        //!< v2 bytes
  static constexpr std::size_t receive_packet_size = Codec::setpoint_packet_size;  //!< v2 bytes
  static constexpr PacketType receive_type = PacketType::setpoint;  //!< what it verifies

  //! `session`: non-zero (random_session_id()); `expiry`: a bound session silent this long is
  //! dropped (> 0); `max_round_trip`: a binding setpoint must acknowledge a state answering a
  //! setpoint received at most this long ago (> 0; 0: the expiry), so a link whose round trip
  //! exceeds the expiry still binds. Throws Error.
  SecureResponder(const SecureKey& key, std::uint64_t session,
                  std::chrono::nanoseconds expiry = std::chrono::milliseconds(100),
                  std::chrono::nanoseconds max_round_trip = std::chrono::nanoseconds(0))
      : key_(key),
        session_(session),
        expiry_(expiry),
        max_round_trip_(max_round_trip.count() == 0 ? expiry : max_round_trip) {
    if (session == 0) ENDOHAPTICS_THROW(Error("SecureResponder: session id must be non-zero"));
    if (expiry.count() <= 0) {
      ENDOHAPTICS_THROW(
          Error("SecureResponder: expiry must be > 0 ns, got " + std::to_string(expiry.count())));
    }
    if (max_round_trip.count() < 0) {
      ENDOHAPTICS_THROW(Error("SecureResponder: max_round_trip must be >= 0 ns, got " +
                              std::to_string(max_round_trip.count())));
    }
  }

  //! Checks a datagram received at `now` as a setpoint without changing anything. ok: obey it;
  //! unbound: answer it, with every motor disabled.
  [[nodiscard]] SecureStatus verify(std::span<const std::byte> bytes, std::chrono::nanoseconds now,
                                    SecureVerified& out) const noexcept {
    SecureVerified v;
    if (const SecureStatus s = Codec::open(key_, PacketType::setpoint, bytes, v.header, v.payload);
        s != SecureStatus::ok) {
      return s;
    }
    const SecureHeader& h = v.header;
    const bool expired = bound_ && now - last_accepted_ > expiry_;
    v.renew_own_session = expired;
    if (bound_ && !expired) {
      if (h.session != peer_session_ || h.peer_session != session_) {
        return SecureStatus::wrong_session;
      }
      if (const WindowStatus w = window_.check(h.sequence); w != WindowStatus::ok) {
        return w == WindowStatus::replayed ? SecureStatus::replayed : SecureStatus::too_old;
      }
      // Commands strictly in order: a setpoint older than the newest obeyed (held back on the
      // link, reordered) would send the tool back; it is counted, never executed.
      if (h.sequence < window_.top()) return SecureStatus::too_old;
      out = v;
      return SecureStatus::ok;
    }
    if (h.sequence == 0) return SecureStatus::too_old;
    // Binds only on a setpoint that echoes this (unbound) session and acknowledges one of its
    // recent states, answered at most `expiry` ago: a setpoint held back by an attacker on the
    // link and delivered later (after the PC stopped) cannot bind; it is answered unbound.
    if (!expired && h.peer_session == session_ && answered_recently(h.ack, now)) {
      v.new_peer_session = true;
      out = v;
      return SecureStatus::ok;
    }
    out = v;
    return SecureStatus::unbound;
  }

  //! Accepts what verify() returned ok or unbound for at `now`.
  void commit(const SecureVerified& v, std::chrono::nanoseconds now) noexcept {
    if (v.renew_own_session) renew();
    answer_session_ = v.header.session;
    answer_sequence_ = v.header.sequence;
    answered_at_[(sent_ + 1) % answered_at_.size()] = now;  // the next state answers it
    if (v.renew_own_session || (!bound_ && !v.new_peer_session)) return;  // unbound: answer only
    if (v.new_peer_session) {
      bound_ = true;
      peer_session_ = v.header.session;
      window_.reset();
    }
    window_.accept(v.header.sequence);
    last_accepted_ = now;
  }

  //! Seals the 2016 state `payload` as the answer to the setpoint committed last.
  [[nodiscard]] SecureStatus seal(std::span<const std::byte> payload,
                                  std::span<std::byte> out) noexcept {
    if (sent_ == std::numeric_limits<std::uint64_t>::max()) return SecureStatus::exhausted;
    const SecureHeader h{PacketType::state, session_, sent_ + 1, answer_session_, answer_sequence_};
    const SecureStatus s = Codec::seal(key_, h, payload, out);
    if (s == SecureStatus::ok) ++sent_;
    return s;
  }

  //! verify() then commit() on ok or unbound; the setpoint is copied into `payload`, with the
  //! enable mask cleared when unbound (untouched otherwise).
  [[nodiscard]] SecureStatus open(std::span<const std::byte> bytes,
                                  std::span<std::byte, receive_payload_size> payload,
                                  std::chrono::nanoseconds now) noexcept {
    SecureVerified v;
    const SecureStatus s = verify(bytes, now, v);
    if (s != SecureStatus::ok && s != SecureStatus::unbound) return s;
    commit(v, now);
    std::memcpy(payload.data(), v.payload.data(), receive_payload_size);
    if (s == SecureStatus::unbound) payload[receive_payload_size - 1] = std::byte{0};
    return s;
  }

  //! This side's current session id.
  [[nodiscard]] std::uint64_t session() const noexcept { return session_; }
  //! True while bound to a PC session.
  [[nodiscard]] bool bound() const noexcept { return bound_; }
  //! The PC session bound (meaningful while bound()).
  [[nodiscard]] std::uint64_t peer_session() const noexcept { return peer_session_; }
  //! The replay window over the bound PC session's sequence numbers.
  [[nodiscard]] const ReplayWindow& window() const noexcept { return window_; }
  //! The longest round trip a binding setpoint may have taken (its acknowledged state's age).
  [[nodiscard]] std::chrono::nanoseconds max_round_trip() const noexcept { return max_round_trip_; }

 private:
  // True when state `ack` of this session is among the last answered_at_.size() states and the
  // setpoint it answered was committed at most `max_round_trip` before `now`.
  [[nodiscard]] bool answered_recently(std::uint64_t ack,
                                       std::chrono::nanoseconds now) const noexcept {
    if (ack == 0 || ack > sent_ || sent_ - ack >= answered_at_.size()) return false;
    return now - answered_at_[ack % answered_at_.size()] <= max_round_trip_;
  }

  void renew() noexcept {
    bound_ = false;
    peer_session_ = 0;
    window_.reset();
    sent_ = 0;
    // randombytes_buf cannot fail once libsodium is initialised (the key's constructor did).
    std::uint64_t id = 0;
    while (id == 0 || id == session_) randombytes_buf(&id, sizeof(id));
    session_ = id;
  }

  SecureKey key_;
  std::uint64_t session_;
  std::chrono::nanoseconds expiry_;
  std::chrono::nanoseconds max_round_trip_;
  bool bound_ = false;
  std::uint64_t peer_session_ = 0;
  ReplayWindow window_{};
  std::chrono::nanoseconds last_accepted_{0};
  std::uint64_t sent_ = 0;
  std::uint64_t answer_session_ = 0;
  std::uint64_t answer_sequence_ = 0;
  // When the setpoint answered by each of the last 4096 states was committed (by sequence mod
  // 4096: 4 s of states at 1 kHz, longer than any round trip the bridge accepts): a binding
  // setpoint must acknowledge one of them, answered within `max_round_trip`.
  std::array<std::chrono::nanoseconds, 4096> answered_at_{};
};

}  // namespace endohaptics::protocol
