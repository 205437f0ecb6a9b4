//! @file
//! The v2 session rules on top of SecureCodec and the handshake (docs/protocol.md, "Sessions"):
//! SecureInitiator (the console, sends setpoints) and SecureResponder (the robot side, answers
//! them). A session starts with a HELLO / WELCOME exchange under the long-term key and runs under
//! two fresh session keys derived from both sides' nonces, so nothing recorded before it verifies
//! in it. The robot side answers nothing but a fresh HELLO before a session, obeys a setpoint only
//! if it is newer than every setpoint obeyed and acknowledges one of its own recent states (age
//! bounded by the granted round trip), and counts every refusal by cause.
#pragma once

#include <sodium.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <span>
#include <string>

#include "endohaptics/core/error.hpp"
#include "endohaptics/protocol/handshake.hpp"
#include "endohaptics/protocol/key_ring.hpp"
#include "endohaptics/protocol/replay_window.hpp"
#include "endohaptics/protocol/secure_codec.hpp"

namespace endohaptics::protocol {

//! Packets a session remembers for round trips and freshness (SecureResponder's answered states,
//! SecureTransport's send times): 16 s at 1 kHz. The longest answer lag a console may allow is
//! one less.
inline constexpr std::size_t packet_history = 16384;

//! The longest round trip a session may be configured for (HELLO carries it in µs).
inline constexpr std::chrono::seconds max_configurable_round_trip{60};

//! Datagrams handled by a v2 receiver, by outcome.
struct SecureCounters {
  std::uint64_t accepted = 0;       //!< authentic, fresh, in session
  std::uint64_t handshakes = 0;     //!< handshake steps taken (HELLO answered / WELCOME taken)
  std::uint64_t wrong_size = 0;     //!< SecureStatus::wrong_size
  std::uint64_t forged = 0;         //!< SecureStatus::forged
  std::uint64_t bad_version = 0;    //!< SecureStatus::bad_version
  std::uint64_t wrong_type = 0;     //!< SecureStatus::wrong_type
  std::uint64_t wrong_session = 0;  //!< SecureStatus::wrong_session
  std::uint64_t replayed = 0;       //!< SecureStatus::replayed
  std::uint64_t too_old = 0;        //!< SecureStatus::too_old
  std::uint64_t stale_answer = 0;   //!< SecureStatus::stale_answer
  std::uint64_t bad_payload = 0;    //!< authentic, the payload refused
  std::uint64_t no_session = 0;     //!< SecureStatus::no_session
  std::uint64_t wrong_key = 0;      //!< SecureStatus::wrong_key
  std::uint64_t wrong_rig = 0;      //!< SecureStatus::wrong_rig

  //! Counts one datagram with outcome `s`.
  constexpr void record(SecureStatus s) noexcept {
    switch (s) {
      case SecureStatus::ok:
        ++accepted;
        break;
      case SecureStatus::hello:
      case SecureStatus::welcome:
        ++handshakes;
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
      case SecureStatus::bad_payload:
      case SecureStatus::exhausted:
        ++bad_payload;
        break;
      case SecureStatus::no_session:
        ++no_session;
        break;
      case SecureStatus::wrong_key:
        ++wrong_key;
        break;
      case SecureStatus::wrong_rig:
        ++wrong_rig;
        break;
    }
  }
  //! Every refused datagram (all but accepted and handshakes).
  [[nodiscard]] constexpr std::uint64_t rejected() const noexcept {
    return wrong_size + forged + bad_version + wrong_type + wrong_session + replayed + too_old +
           stale_answer + bad_payload + no_session + wrong_key + wrong_rig;
  }
};

//! One line for logs and summaries: "accepted A, handshakes H, rejected R (forged F, ...)".
//! Allocates: not for the tick.
[[nodiscard]] inline std::string describe(const SecureCounters& c) {
  auto n = [](std::uint64_t v) { return std::to_string(v); };
  return "accepted " + n(c.accepted) + ", handshakes " + n(c.handshakes) + ", rejected " +
         n(c.rejected()) + " (forged " + n(c.forged) + ", wrong size " + n(c.wrong_size) +
         ", bad version " + n(c.bad_version) + ", wrong type " + n(c.wrong_type) +
         ", wrong session " + n(c.wrong_session) + ", replayed " + n(c.replayed) + ", too old " +
         n(c.too_old) + ", stale answer " + n(c.stale_answer) + ", bad payload " +
         n(c.bad_payload) + ", no session " + n(c.no_session) + ", wrong key " + n(c.wrong_key) +
         ", wrong rig " + n(c.wrong_rig) + ")";
}

//! What a verify step found in an authentic packet; pass it to commit() if it is used.
struct SecureVerified {
  PacketType type = PacketType::setpoint;  //!< what arrived
  SecureHeader header{};                   //!< a data packet's header
  std::span<const std::byte> payload{};    //!< a data packet's 2016 packet (inside the datagram)
  bool previous_session = false;  //!< console: a state of the session before the last handshake
  bool new_session = false;       //!< robot: the first setpoint of the pending session
  bool retransmission = false;    //!< robot: a HELLO answered already: the same WELCOME again
  std::size_t key_slot = 0;       //!< robot: the key ring slot of a HELLO's key
  Hello hello{};                  //!< robot: the HELLO
  Welcome welcome{};              //!< console: the WELCOME
};

namespace detail {

//! µs of `d`, for a handshake field (precondition: 0 < d <= max_configurable_round_trip).
[[nodiscard]] inline std::uint32_t to_us(std::chrono::nanoseconds d) noexcept {
  return static_cast<std::uint32_t>(
      std::chrono::duration_cast<std::chrono::microseconds>(d).count());
}

//! Throws Error unless 0 < `d` <= max_configurable_round_trip.
inline void check_round_trip(std::chrono::nanoseconds d, const char* who) {
  if (d < std::chrono::microseconds(1) || d > max_configurable_round_trip) {
    ENDOHAPTICS_THROW(Error(std::string(who) + ": max_round_trip must be in [1 us, " +
                            std::to_string(max_configurable_round_trip.count()) + " s], got " +
                            std::to_string(d.count()) + " ns"));
  }
}

//! A key slot for a session key (zeros until a handshake re-keys it).
[[nodiscard]] inline SecureKey blank_key() {
  return SecureKey(
      std::span<const std::byte, SecureKey::size>(std::array<std::byte, SecureKey::size>{}));
}

}  // namespace detail

//! The console side's session settings.
struct InitiatorConfig {
  RigId rig{};  //!< the robot side it talks to (make_rig_id)
  //! The longest round trip it asks the robot side to accept (a setpoint's acknowledged state's
  //! age); the robot may grant less.
  std::chrono::nanoseconds max_round_trip = std::chrono::milliseconds(200);
  //! States may answer a setpoint this many older than the newest sent (0: only the newest);
  //! below packet_history.
  std::uint64_t max_answer_lag = 0;
  //! A HELLO not answered is sent again after this long, then after twice as long each time (up
  //! to 1 s).
  std::chrono::nanoseconds hello_interval = std::chrono::milliseconds(10);
  //! A new handshake (fresh keys, seamless) after a session this old.
  std::chrono::nanoseconds rekey_after = std::chrono::minutes(2);

  //! Throws Error naming the field and its range.
  void validate() const {
    detail::check_round_trip(max_round_trip, "InitiatorConfig");
    if (max_answer_lag >= packet_history) {
      ENDOHAPTICS_THROW(Error("InitiatorConfig: max_answer_lag must be below " +
                              std::to_string(packet_history) + " packets, got " +
                              std::to_string(max_answer_lag)));
    }
    if (hello_interval < std::chrono::milliseconds(5) || hello_interval > std::chrono::seconds(1)) {
      ENDOHAPTICS_THROW(Error("InitiatorConfig: hello_interval must be in [5, 1000] ms, got " +
                              std::to_string(hello_interval.count()) + " ns"));
    }
    if (rekey_after < std::chrono::seconds(1) || rekey_after > std::chrono::hours(24)) {
      ENDOHAPTICS_THROW(Error("InitiatorConfig: rekey_after must be in [1 s, 24 h], got " +
                              std::to_string(rekey_after.count()) + " ns"));
    }
  }
};

//! The console side: asks for sessions (HELLO, resent with a doubling interval from
//! hello_interval until a WELCOME answers), seals setpoints under the session key, verifies states.
//! A new handshake starts when no state came for twice the granted round trip (at least 100 ms), or
//! the session is `rekey_after` old; setpoints keep flowing in the old session meanwhile, and
//! states of the old session are still taken until the first state of the new one arrives.
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

  //! `key`: the long-term key; `config` is validated. Throws Error.
  SecureInitiator(const SecureKey& key, const InitiatorConfig& config)
      : key_(key),
        config_((config.validate(), config)),
        send_key_(detail::blank_key()),
        receive_key_(detail::blank_key()),
        previous_key_(detail::blank_key()) {}
  SecureInitiator(SecureInitiator&&) noexcept = default;             //!< moves the key slots
  SecureInitiator& operator=(SecureInitiator&&) noexcept = default;  //!< moves the key slots
  SecureInitiator(const SecureInitiator&) = delete;             //!< session keys are never shared
  SecureInitiator& operator=(const SecureInitiator&) = delete;  //!< session keys never shared

  //! At `now`: true when a HELLO is due, written into `out` (send it). Starts a handshake when
  //! there is no session, when the session has been silent for rehandshake_after(), or when it
  //! is rekey_after old; an attempt not answered within max(1 s, 4 round trips) starts afresh.
  [[nodiscard]] bool hello_due(std::chrono::nanoseconds now,
                               std::span<std::byte, HandshakeCodec::packet_size> out) noexcept {
    const bool needed = !established_ || now - last_state_at_ > rehandshake_after() ||
                        now - established_at_ > config_.rekey_after;
    const auto give_up =
        std::max<std::chrono::nanoseconds>(std::chrono::seconds(1), 4 * config_.max_round_trip);
    if ((needed && !attempting_) || (attempting_ && now - attempt_started_ > give_up)) {
      start_attempt(now);
    }
    if (!attempting_ || (hello_sent_ && now - hello_sent_at_ < hello_wait_)) return false;
    std::memcpy(out.data(), hello_bytes_.data(), out.size());
    if (hello_sent_) {  // each resend waits twice as long, up to 1 s (a slow link is not flooded)
      hello_wait_ = std::min<std::chrono::nanoseconds>(2 * hello_wait_, std::chrono::seconds(1));
    }
    hello_sent_ = true;
    hello_sent_at_ = now;
    return true;
  }

  //! Seals the 2016 setpoint `payload` as the next setpoint of the session into `out`;
  //! no_session before the first WELCOME (nothing to send: the robot obeys nothing unsealed).
  [[nodiscard]] SecureStatus seal(std::span<const std::byte> payload,
                                  std::span<std::byte> out) noexcept {
    if (!established_) return SecureStatus::no_session;
    if (sent_ == std::numeric_limits<std::uint64_t>::max()) return SecureStatus::exhausted;
    const SecureHeader h{PacketType::setpoint, session_, sent_ + 1, peer_session_, window_.top()};
    const SecureStatus s = Codec::seal(send_key_, h, payload, out);
    if (s == SecureStatus::ok) ++sent_;
    return s;
  }

  //! Checks a datagram (a state, or a WELCOME) without changing anything: ok (a state: use it),
  //! welcome (commit it: a new session), or the refusal.
  [[nodiscard]] SecureStatus verify(std::span<const std::byte> bytes, std::chrono::nanoseconds now,
                                    SecureVerified& out) const noexcept {
    (void)now;
    if (bytes.size() == HandshakeCodec::packet_size) return verify_welcome(bytes, out);
    if (bytes.size() != receive_packet_size) return SecureStatus::wrong_size;
    if (!established_) return SecureStatus::no_session;
    SecureVerified v;
    SecureStatus s = Codec::open(receive_key_, PacketType::state, bytes, v.header, v.payload);
    if (s == SecureStatus::ok) {
      s = check_state(v.header, session_, peer_session_, sent_, window_);
      if (s == SecureStatus::ok && sent_ - v.header.ack > config_.max_answer_lag) {
        s = SecureStatus::stale_answer;
      }
    } else if (s == SecureStatus::forged && previous_valid_) {
      s = Codec::open(previous_key_, PacketType::state, bytes, v.header, v.payload);
      if (s == SecureStatus::ok) {
        s = check_state(v.header, previous_session_, previous_peer_, previous_sent_,
                        previous_window_);
        v.previous_session = true;
      }
    }
    if (s == SecureStatus::ok) {
      v.type = PacketType::state;
      out = v;
    }
    return s;
  }

  //! Takes what verify() returned ok or welcome for, at `now`.
  void commit(const SecureVerified& v, std::chrono::nanoseconds now) noexcept {
    if (v.type == PacketType::welcome) {
      begin_session(v.welcome, now);
      return;
    }
    if (v.previous_session) {
      previous_window_.accept(v.header.sequence);
      return;
    }
    window_.accept(v.header.sequence);
    last_state_at_ = now;
    if (previous_valid_) {  // the new session answers: nothing of the old one is taken any more
      previous_valid_ = false;
      previous_key_.wipe();
    }
  }

  //! verify() then commit() on ok; the 2016 state packet is copied into `payload` (untouched
  //! unless ok). A WELCOME is committed and reported as welcome (no payload).
  [[nodiscard]] SecureStatus open(std::span<const std::byte> bytes,
                                  std::span<std::byte, receive_payload_size> payload,
                                  std::chrono::nanoseconds now) noexcept {
    SecureVerified v;
    const SecureStatus s = verify(bytes, now, v);
    if (s != SecureStatus::ok && s != SecureStatus::welcome) return s;
    commit(v, now);
    if (s == SecureStatus::ok) std::memcpy(payload.data(), v.payload.data(), receive_payload_size);
    return s;
  }

  //! True once a WELCOME opened a session (setpoints are sealed from then on).
  [[nodiscard]] bool established() const noexcept { return established_; }
  //! True while a HELLO awaits its WELCOME.
  [[nodiscard]] bool attempting() const noexcept { return attempting_; }
  //! This side's session id (0 before the first session).
  [[nodiscard]] std::uint64_t session() const noexcept { return session_; }
  //! The robot side's session id (0 before the first session).
  [[nodiscard]] std::uint64_t peer_session() const noexcept { return peer_session_; }
  //! Sequence number of the newest setpoint sealed in this session (0: none).
  [[nodiscard]] std::uint64_t sent() const noexcept { return sent_; }
  //! The replay window over the session's state sequence numbers.
  [[nodiscard]] const ReplayWindow& window() const noexcept { return window_; }
  //! Sessions opened so far.
  [[nodiscard]] std::uint64_t sessions() const noexcept { return sessions_; }
  //! The round trip the robot granted this session (0 before the first).
  [[nodiscard]] std::chrono::nanoseconds granted_round_trip() const noexcept { return granted_; }
  //! Silence (no state accepted) after which a new handshake starts: twice the granted round
  //! trip, at least 100 ms.
  [[nodiscard]] std::chrono::nanoseconds rehandshake_after() const noexcept {
    return std::max<std::chrono::nanoseconds>(std::chrono::milliseconds(100), 2 * granted_);
  }
  //! The long-term key's id.
  [[nodiscard]] const KeyId& key_id() const noexcept { return key_.id(); }
  //! The settings.
  [[nodiscard]] const InitiatorConfig& config() const noexcept { return config_; }

 private:
  // The session rules of a state under `session` / `peer`: answers one of this side's setpoints,
  // newer than every state taken (strictly in order).
  static SecureStatus check_state(const SecureHeader& h, std::uint64_t session, std::uint64_t peer,
                                  std::uint64_t sent, const ReplayWindow& window) noexcept {
    if (h.peer_session != session || h.session != peer || h.ack == 0 || h.ack > sent) {
      return SecureStatus::wrong_session;
    }
    if (const WindowStatus w = window.check(h.sequence); w != WindowStatus::ok) {
      return w == WindowStatus::replayed ? SecureStatus::replayed : SecureStatus::too_old;
    }
    if (h.sequence < window.top()) return SecureStatus::too_old;
    return SecureStatus::ok;
  }

  SecureStatus verify_welcome(std::span<const std::byte> bytes,
                              SecureVerified& out) const noexcept {
    KeyId id{};
    if (const SecureStatus s = HandshakeCodec::peek_key_id(bytes, PacketType::welcome, id);
        s != SecureStatus::ok) {
      return s;
    }
    if (id != key_.id()) return SecureStatus::wrong_key;
    Welcome w;
    if (const SecureStatus s = HandshakeCodec::decode(key_, bytes, w); s != SecureStatus::ok) {
      return s;
    }
    if (w.rig != config_.rig) return SecureStatus::wrong_rig;
    if (!attempting_ || w.console_nonce != nonce_) {
      // A WELCOME to a HELLO sent again (answered once already), or to an earlier attempt.
      return w.console_nonce == last_nonce_ ? SecureStatus::replayed : SecureStatus::wrong_session;
    }
    if (w.max_round_trip_us == 0 || w.max_round_trip_us > detail::to_us(config_.max_round_trip)) {
      return SecureStatus::bad_payload;  // granted more than asked, or nothing
    }
    out.type = PacketType::welcome;
    out.welcome = w;
    return SecureStatus::welcome;
  }

  void start_attempt(std::chrono::nanoseconds now) noexcept {
    fresh_nonce(nonce_);
    const auto wall = std::chrono::duration_cast<std::chrono::nanoseconds>(
                          std::chrono::system_clock::now().time_since_epoch())
                          .count();
    timestamp_ = std::max<std::uint64_t>(timestamp_ + 1, static_cast<std::uint64_t>(wall));
    const Hello hello{key_.id(), config_.rig, timestamp_, nonce_,
                      detail::to_us(config_.max_round_trip)};
    HandshakeCodec::encode(key_, hello, hello_bytes_);
    attempting_ = true;
    attempt_started_ = now;
    hello_sent_ = false;
    hello_wait_ = config_.hello_interval;
  }

  void begin_session(const Welcome& w, std::chrono::nanoseconds now) noexcept {
    if (established_) {  // the old session's answers in flight are still taken, until the new's
      swap(previous_key_, receive_key_);
      previous_valid_ = true;
      previous_session_ = session_;
      previous_peer_ = peer_session_;
      previous_sent_ = sent_;
      previous_window_ = window_;
    }
    derive_session_key(key_, PacketType::setpoint, config_.rig, nonce_, w.robot_nonce, send_key_);
    derive_session_key(key_, PacketType::state, config_.rig, nonce_, w.robot_nonce, receive_key_);
    session_ = session_id_of(nonce_);
    peer_session_ = session_id_of(w.robot_nonce);
    sent_ = 0;
    window_.reset();
    granted_ = std::chrono::microseconds(w.max_round_trip_us);
    established_ = true;
    established_at_ = now;
    last_state_at_ = now;
    last_nonce_ = nonce_;
    attempting_ = false;
    ++sessions_;
  }

  SecureKey key_;
  InitiatorConfig config_;
  // The session's keys (locked memory, re-keyed in place by each handshake).
  SecureKey send_key_;
  SecureKey receive_key_;
  SecureKey previous_key_;  // the session before the last handshake: its states in flight
  bool established_ = false;
  std::uint64_t session_ = 0;
  std::uint64_t peer_session_ = 0;
  std::uint64_t sent_ = 0;
  ReplayWindow window_{};
  std::chrono::nanoseconds established_at_{0};
  std::chrono::nanoseconds last_state_at_{0};
  std::chrono::nanoseconds granted_{0};
  std::uint64_t sessions_ = 0;
  bool previous_valid_ = false;
  std::uint64_t previous_session_ = 0;
  std::uint64_t previous_peer_ = 0;
  std::uint64_t previous_sent_ = 0;
  ReplayWindow previous_window_{};
  // The handshake attempt.
  bool attempting_ = false;
  bool hello_sent_ = false;
  Nonce nonce_{};
  Nonce last_nonce_{};  // of the attempt that opened the session
  std::uint64_t timestamp_ = 0;
  std::chrono::nanoseconds attempt_started_{0};
  std::chrono::nanoseconds hello_sent_at_{0};
  std::chrono::nanoseconds hello_wait_{0};
  HandshakeCodec::Bytes hello_bytes_{};
};

//! The robot side's session settings.
struct ResponderConfig {
  RigId rig{};  //!< this robot side's identity (make_rig_id)
  //! The longest round trip it grants: a setpoint is obeyed only if the state it acknowledges
  //! answered a setpoint received at most this long ago (the WELCOME: twice this long).
  std::chrono::nanoseconds max_round_trip = std::chrono::milliseconds(200);
  //! A session with nothing obeyed for this long ends (its keys wiped; a new HELLO is needed).
  std::chrono::nanoseconds expiry = std::chrono::milliseconds(100);

  //! Throws Error naming the field and its range.
  void validate() const {
    detail::check_round_trip(max_round_trip, "ResponderConfig");
    if (expiry < std::chrono::microseconds(1) || expiry > std::chrono::seconds(60)) {
      ENDOHAPTICS_THROW(Error("ResponderConfig: expiry must be in [1 us, 60 s], got " +
                              std::to_string(expiry.count()) + " ns"));
    }
  }
};

//! The robot side: silent until an authentic, fresh HELLO for its rig under a key it holds,
//! which it answers with a WELCOME no larger (a pending session). The first setpoint verifying
//! under the pending session's key makes it the session (the one before ends). It obeys a
//! setpoint only if its sequence number is above every setpoint obeyed and it acknowledges one of
//! its recent states (age bounded by the granted round trip); it answers obeyed setpoints only.
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

  //! `keys`: the long-term keys it accepts (at least one); `config` is validated. Throws Error.
  SecureResponder(const KeyRing& keys, const ResponderConfig& config)
      : keys_(keys),
        config_((config.validate(), config)),
        send_key_(detail::blank_key()),
        receive_key_(detail::blank_key()),
        pending_send_key_(detail::blank_key()),
        pending_receive_key_(detail::blank_key()) {
    if (keys.size() == 0) ENDOHAPTICS_THROW(Error("SecureResponder: no key to accept"));
  }
  //! One long-term key.
  SecureResponder(const SecureKey& key, const ResponderConfig& config)
      : SecureResponder(KeyRing(key), config) {}
  SecureResponder(SecureResponder&&) noexcept = default;             //!< moves the key slots
  SecureResponder& operator=(SecureResponder&&) noexcept = default;  //!< moves the key slots
  SecureResponder(const SecureResponder&) = delete;             //!< session keys are never shared
  SecureResponder& operator=(const SecureResponder&) = delete;  //!< session keys never shared

  //! Checks a datagram received at `now` without changing anything: ok (a setpoint: obey it),
  //! hello (commit it, then send take_reply()), or the refusal.
  [[nodiscard]] SecureStatus verify(std::span<const std::byte> bytes, std::chrono::nanoseconds now,
                                    SecureVerified& out) const noexcept {
    if (bytes.size() == HandshakeCodec::packet_size) return verify_hello(bytes, now, out);
    if (bytes.size() != receive_packet_size) return SecureStatus::wrong_size;
    const bool live = live_at(now);
    const bool pending = pending_ && now - welcome_at_pending_ <= 2 * pending_granted_;
    if (!live && !pending) return SecureStatus::no_session;
    SecureVerified v;
    SecureStatus s = SecureStatus::forged;
    if (live) {
      s = Codec::open(receive_key_, PacketType::setpoint, bytes, v.header, v.payload);
      if (s == SecureStatus::ok) s = check_setpoint(v.header, now);
    }
    if (s == SecureStatus::forged && pending) {
      s = Codec::open(pending_receive_key_, PacketType::setpoint, bytes, v.header, v.payload);
      if (s == SecureStatus::ok) {
        const SecureHeader& h = v.header;
        if (h.session != pending_peer_ || h.peer_session != pending_session_ || h.ack != 0) {
          s = SecureStatus::wrong_session;
        } else if (h.sequence == 0) {
          s = SecureStatus::too_old;
        }
        v.new_session = true;
      }
    }
    if (s == SecureStatus::ok) {
      v.type = PacketType::setpoint;
      out = v;
    }
    return s;
  }

  //! The shortest gap between two WELCOMEs answering the same HELLO.
  static constexpr std::chrono::milliseconds min_welcome_gap{5};
  //! WELCOMEs sent again for one HELLO resent (its first answer lost) at most.
  static constexpr int max_welcome_resends = 4;

  //! Takes what verify() returned ok or hello for, at `now`.
  void commit(const SecureVerified& v, std::chrono::nanoseconds now) noexcept {
    if (v.type == PacketType::hello) {
      answer_hello(v, now);
      return;
    }
    if (v.new_session) {
      promote();
    } else if (!live_at(now)) {
      return;  // verify() refuses this; a caller that committed anyway changes nothing
    }
    window_.accept(v.header.sequence);
    last_obeyed_ = now;
    answer_sequence_ = v.header.sequence;
    answer_received_at_ = now;
  }

  //! Ends a session silent for the expiry and drops a pending session older than twice its
  //! granted round trip, wiping their keys (SecureTransport calls it on every receive).
  void expire(std::chrono::nanoseconds now) noexcept {
    if (bound_ && !live_at(now)) end_session();
    if (pending_ && now - welcome_at_pending_ > 2 * pending_granted_) drop_pending();
  }

  //! The WELCOME to send after a committed HELLO (empty when none is due); taken once.
  [[nodiscard]] std::span<const std::byte> take_reply() noexcept {
    if (!reply_due_) return {};
    reply_due_ = false;
    return welcome_bytes_;
  }

  //! Seals the 2016 state `payload` as the answer to the setpoint committed last; no_session
  //! when there is none (nothing is answered outside a session).
  [[nodiscard]] SecureStatus seal(std::span<const std::byte> payload,
                                  std::span<std::byte> out) noexcept {
    if (!bound_) return SecureStatus::no_session;
    if (sent_ == std::numeric_limits<std::uint64_t>::max()) return SecureStatus::exhausted;
    const SecureHeader h{PacketType::state, session_, sent_ + 1, peer_session_, answer_sequence_};
    const SecureStatus s = Codec::seal(send_key_, h, payload, out);
    if (s != SecureStatus::ok) return s;
    ++sent_;
    answered_[static_cast<std::size_t>(sent_ % answered_.size())] = {sent_, answer_received_at_};
    return s;
  }

  //! verify() then commit() on ok or hello; a setpoint is copied into `payload` (untouched
  //! otherwise).
  [[nodiscard]] SecureStatus open(std::span<const std::byte> bytes,
                                  std::span<std::byte, receive_payload_size> payload,
                                  std::chrono::nanoseconds now) noexcept {
    SecureVerified v;
    const SecureStatus s = verify(bytes, now, v);
    if (s != SecureStatus::ok && s != SecureStatus::hello) return s;
    commit(v, now);
    if (s == SecureStatus::ok) std::memcpy(payload.data(), v.payload.data(), receive_payload_size);
    return s;
  }

  //! Ends every session and handshake under the key `id` and stops accepting it; false when the
  //! ring does not hold it.
  bool revoke(const KeyId& id) noexcept {
    const auto slot = keys_.find(id);
    if (!slot) return false;
    if (bound_ && key_slot_ == *slot) end_session();
    if (pending_ && pending_slot_ == *slot) drop_pending();
    highest_timestamp_[*slot] = 0;
    return keys_.revoke(id);
  }

  //! True while a session is live at `now` (a setpoint obeyed within the expiry).
  [[nodiscard]] bool live_at(std::chrono::nanoseconds now) const noexcept {
    return bound_ && now - last_obeyed_ <= config_.expiry;
  }
  //! True while a session holds keys (it may have expired; the next commit ends it).
  [[nodiscard]] bool bound() const noexcept { return bound_; }
  //! This side's session id (0: none).
  [[nodiscard]] std::uint64_t session() const noexcept { return session_; }
  //! The console's session id (0: none).
  [[nodiscard]] std::uint64_t peer_session() const noexcept { return peer_session_; }
  //! The replay window over the session's setpoint sequence numbers.
  [[nodiscard]] const ReplayWindow& window() const noexcept { return window_; }
  //! Sessions opened so far.
  [[nodiscard]] std::uint64_t sessions() const noexcept { return sessions_; }
  //! The round trip granted to the session (0: none).
  [[nodiscard]] std::chrono::nanoseconds granted_round_trip() const noexcept { return granted_; }
  //! The settings.
  [[nodiscard]] const ResponderConfig& config() const noexcept { return config_; }
  //! The keys it accepts.
  [[nodiscard]] const KeyRing& keys() const noexcept { return keys_; }

 private:
  // A state sealed in this session (every slot `ack` can name, ack <= sent_ and
  // sent_ - ack < packet_history, was written by this session: sequences restart at 1).
  struct Answered {
    std::uint64_t sequence = 0;           // the state's sequence number
    std::chrono::nanoseconds received{};  // when the setpoint it answers arrived
  };

  // A setpoint of the live session: from the console of this session, newer than every setpoint
  // obeyed, acknowledging a state of this session young enough.
  SecureStatus check_setpoint(const SecureHeader& h, std::chrono::nanoseconds now) const noexcept {
    if (h.session != peer_session_ || h.peer_session != session_)
      return SecureStatus::wrong_session;
    if (const WindowStatus w = window_.check(h.sequence); w != WindowStatus::ok) {
      return w == WindowStatus::replayed ? SecureStatus::replayed : SecureStatus::too_old;
    }
    if (h.sequence < window_.top()) return SecureStatus::too_old;  // strictly in order
    if (!fresh(h.ack, now)) return SecureStatus::stale_answer;
    return SecureStatus::ok;
  }

  // Does acknowledging state `ack` of the session show the setpoint was sent within the granted
  // round trip? State 0 is the WELCOME (twice the round trip: it reached the console one way,
  // its first state takes a second round trip).
  [[nodiscard]] bool fresh(std::uint64_t ack, std::chrono::nanoseconds now) const noexcept {
    if (ack == 0) return now - welcome_at_ <= 2 * granted_;
    if (ack > sent_ || sent_ - ack >= answered_.size()) return false;
    const Answered& a = answered_[static_cast<std::size_t>(ack % answered_.size())];
    return a.sequence == ack && now - a.received <= granted_;
  }

  SecureStatus verify_hello(std::span<const std::byte> bytes, std::chrono::nanoseconds now,
                            SecureVerified& out) const noexcept {
    KeyId id{};
    if (const SecureStatus s = HandshakeCodec::peek_key_id(bytes, PacketType::hello, id);
        s != SecureStatus::ok) {
      return s;
    }
    const auto slot = keys_.find(id);
    if (!slot) return SecureStatus::wrong_key;
    Hello hello;
    if (const SecureStatus s = HandshakeCodec::decode(keys_.at(*slot), bytes, hello);
        s != SecureStatus::ok) {
      return s;
    }
    if (hello.rig != config_.rig) return SecureStatus::wrong_rig;
    if (hello.max_round_trip_us == 0) return SecureStatus::bad_payload;
    const std::uint64_t highest = highest_timestamp_[*slot];
    bool again = false;
    if (hello.timestamp <= highest) {
      // Only the HELLO the pending session answered may come again (the console resends it
      // until a WELCOME arrives), while that session may still open; any other is a recording.
      again = hello.timestamp == highest && pending_ && pending_slot_ == *slot &&
              hello.nonce == pending_nonce_ && now - welcome_at_pending_ <= 2 * pending_granted_;
      if (!again) return SecureStatus::replayed;
    }
    out.type = PacketType::hello;
    out.hello = hello;
    out.key_slot = *slot;
    out.retransmission = again;
    return SecureStatus::hello;
  }

  void answer_hello(const SecureVerified& v, std::chrono::nanoseconds now) noexcept {
    if (v.retransmission) {
      // The same WELCOME again, at most max_welcome_resends times, min_welcome_gap apart, and
      // only while the session may open (twice the granted round trip from the first WELCOME):
      // a replayed HELLO cannot make this side a reflector.
      if (now - welcome_sent_at_ >= min_welcome_gap && welcome_resends_ < max_welcome_resends) {
        reply_due_ = true;
        welcome_sent_at_ = now;
        ++welcome_resends_;
      }
      return;
    }
    reply_due_ = true;
    welcome_sent_at_ = now;
    welcome_resends_ = 0;
    const SecureKey& key = keys_.at(v.key_slot);
    highest_timestamp_[v.key_slot] = v.hello.timestamp;
    Nonce robot{};
    fresh_nonce(robot);
    pending_ = true;
    pending_slot_ = v.key_slot;
    pending_nonce_ = v.hello.nonce;
    pending_granted_ = std::min<std::chrono::nanoseconds>(
        std::chrono::microseconds(v.hello.max_round_trip_us), config_.max_round_trip);
    pending_session_ = session_id_of(robot);
    pending_peer_ = session_id_of(v.hello.nonce);
    welcome_at_pending_ = now;
    derive_session_key(key, PacketType::setpoint, config_.rig, v.hello.nonce, robot,
                       pending_receive_key_);
    derive_session_key(key, PacketType::state, config_.rig, v.hello.nonce, robot,
                       pending_send_key_);
    const Welcome w{key.id(), config_.rig, v.hello.nonce, robot, detail::to_us(pending_granted_)};
    HandshakeCodec::encode(key, w, welcome_bytes_);
    sodium_memzero(robot.data(), robot.size());
  }

  void promote() noexcept {
    swap(send_key_, pending_send_key_);
    swap(receive_key_, pending_receive_key_);
    pending_send_key_.wipe();  // the session before, if any: gone
    pending_receive_key_.wipe();
    pending_ = false;
    reply_due_ = false;
    bound_ = true;
    key_slot_ = pending_slot_;
    session_ = pending_session_;
    peer_session_ = pending_peer_;
    granted_ = pending_granted_;
    welcome_at_ = welcome_at_pending_;
    window_.reset();
    sent_ = 0;
    answer_sequence_ = 0;
    ++sessions_;
  }

  void drop_pending() noexcept {
    pending_ = false;
    reply_due_ = false;
    pending_send_key_.wipe();
    pending_receive_key_.wipe();
  }

  void end_session() noexcept {
    bound_ = false;
    send_key_.wipe();
    receive_key_.wipe();
    session_ = peer_session_ = 0;
    window_.reset();
    sent_ = 0;
  }

  KeyRing keys_;
  ResponderConfig config_;
  std::array<std::uint64_t, KeyRing::max_keys> highest_timestamp_{};
  // The session.
  SecureKey send_key_;
  SecureKey receive_key_;
  bool bound_ = false;
  std::size_t key_slot_ = 0;
  std::uint64_t session_ = 0;
  std::uint64_t peer_session_ = 0;
  std::chrono::nanoseconds granted_{0};
  std::chrono::nanoseconds welcome_at_{0};
  ReplayWindow window_{};
  std::chrono::nanoseconds last_obeyed_{0};
  std::uint64_t sent_ = 0;
  std::uint64_t answer_sequence_ = 0;
  std::chrono::nanoseconds answer_received_at_{0};
  std::uint64_t sessions_ = 0;
  // The state each of the last packet_history states answered, and when its setpoint arrived.
  std::array<Answered, packet_history> answered_{};
  // The pending session (a WELCOME sent, no setpoint under its key yet).
  SecureKey pending_send_key_;
  SecureKey pending_receive_key_;
  bool pending_ = false;
  std::size_t pending_slot_ = 0;
  Nonce pending_nonce_{};
  std::uint64_t pending_session_ = 0;
  std::uint64_t pending_peer_ = 0;
  std::chrono::nanoseconds pending_granted_{0};
  std::chrono::nanoseconds welcome_at_pending_{0};  // the first WELCOME: the session's age
  std::chrono::nanoseconds welcome_sent_at_{0};     // the last WELCOME sent
  int welcome_resends_ = 0;
  HandshakeCodec::Bytes welcome_bytes_{};
  bool reply_due_ = false;
};

}  // namespace endohaptics::protocol
