//! @file
//! The `Transport` concept: how a TeleopLoop exchanges datagrams with the sbRIO (worksheet 3.3.1:
//! send, then receive with a deadline, single thread). Implementations: UdpTransport,
//! InMemoryTransport, FaultInjectingTransport, or a user's own.
#pragma once

#include <chrono>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>

#include "endohaptics/core/error.hpp"

namespace endohaptics::transport {

//! Default bound on the datagrams one `receive` reads (UdpConfig, UdpServerConfig,
//! InMemoryTransport): a flood cannot keep the tick inside `receive`; what is left stays queued
//! for the next call. A read costs about a microsecond, so 64 reads stay well inside a 1 ms tick.
inline constexpr std::size_t default_max_drain = 64;
//! Largest drain bound a transport accepts.
inline constexpr std::size_t max_drain_limit = 4096;
//! Longest receive spin (UdpConfig::receive_spin) a transport accepts: one 1 kHz period; a
//! longer one is a busy poll, and a blocking wait is the better tool for it.
inline constexpr std::chrono::nanoseconds max_receive_spin = std::chrono::milliseconds(1);

namespace detail {

//! `max_drain` if it is in 1..max_drain_limit; otherwise throws Error naming `who`'s field.
inline std::size_t checked_max_drain(std::size_t max_drain, std::string_view who) {
  if (max_drain < 1 || max_drain > max_drain_limit) {
    ENDOHAPTICS_THROW(Error(std::string(who) + ": max_drain must be 1.." +
                            std::to_string(max_drain_limit) + " datagrams per receive, got " +
                            std::to_string(max_drain)));
  }
  return max_drain;
}

//! `spin` if it is in [0, max_receive_spin]; otherwise throws Error naming `who`'s field.
inline std::chrono::nanoseconds checked_receive_spin(std::chrono::nanoseconds spin,
                                                     std::string_view who) {
  if (spin.count() < 0 || spin > max_receive_spin) {
    ENDOHAPTICS_THROW(Error(std::string(who) + ": receive_spin must be in [0, " +
                            std::to_string(max_receive_spin.count()) +
                            "] ns (0: block at once), got " + std::to_string(spin.count()) +
                            " ns"));
  }
  return spin;
}

}  // namespace detail

//! Outcome of a send or receive.
enum class TransportStatus : std::uint8_t {
  ok = 0,    //!< sent, or an accepted datagram was received into the buffer
  timeout,   //!< receive: nothing arrived before the deadline
  rejected,  //!< receive: datagrams arrived, but the filter refused each (or each was too long)
  error,     //!< the operating system refused the operation (socket closed, unreachable, ...)
};

//! Short human-readable description of `status` (for logs and error messages).
[[nodiscard]] constexpr std::string_view to_string(TransportStatus status) noexcept {
  switch (status) {
    case TransportStatus::ok:
      return "ok";
    case TransportStatus::timeout:
      return "timeout";
    case TransportStatus::rejected:
      return "every datagram rejected";
    case TransportStatus::error:
      return "transport error";
  }
  return "unknown status";
}

//! What a receive produced: status, bytes written into the caller's buffer, and what else the
//! drain read: older accepted datagrams discarded so that only the newest is returned (queue of
//! one, worksheet 3.1.3), datagrams the filter refused, datagrams too long for the buffer. A
//! receive reads at most its transport's `max_drain` datagrams: under a flood it returns the
//! newest accepted one of those, and the rest are read (and counted) by the next call.
struct ReceiveResult {
  TransportStatus status = TransportStatus::timeout;  //!< outcome of the receive
  std::size_t size = 0;       //!< bytes of the returned datagram (valid when status is ok)
  std::size_t dropped = 0;    //!< accepted datagrams discarded for a newer accepted one
  std::size_t rejected = 0;   //!< datagrams the filter refused (it may count why itself)
  std::size_t oversized = 0;  //!< datagrams longer than the buffer: refused unseen by the filter
};

//! A receive filter: called with each datagram a drain reads (noexcept, allocation-free); true
//! keeps it as the candidate to return, false refuses it. The newest *accepted* datagram wins, so
//! junk arriving after a valid packet cannot displace it (TeleopLoop and SbrioEmulator pass their
//! decoder).
template <typename F>
concept DatagramFilter = std::is_nothrow_invocable_r_v<bool, F&, std::span<const std::byte>>;

//! The filter that accepts every datagram (the two-argument `receive`).
struct AcceptAny {
  //! Always true.
  constexpr bool operator()(std::span<const std::byte>) const noexcept { return true; }
};

//! A datagram transport usable from the real-time tick: both calls are noexcept, allocation-free
//! and bounded in time. `receive` waits at most `timeout` for a datagram, then drains what else is
//! queued, up to a bounded number of datagrams, and returns the newest one it read.
template <typename T>
concept Transport = requires(T& transport, std::span<const std::byte> datagram,
                             std::span<std::byte> buffer, std::chrono::nanoseconds timeout) {
  { transport.send(datagram) }
  noexcept->std::same_as<TransportStatus>;
  { transport.receive(buffer, timeout) }
  noexcept->std::same_as<ReceiveResult>;
};

//! A Transport whose drain takes a filter: `receive(buffer, timeout, filter)` returns the newest
//! datagram the filter accepted (UdpTransport, UdpServerTransport, InMemoryTransport, ...).
template <typename T>
concept FilteringTransport = Transport<T> &&
    requires(T& transport, std::span<std::byte> buffer, std::chrono::nanoseconds timeout,
             AcceptAny& filter) {
  { transport.receive(buffer, timeout, filter) }
  noexcept->std::same_as<ReceiveResult>;
};

//! Receives the newest datagram `filter` accepts: through the transport's own filtered drain when
//! it has one, otherwise its newest datagram, refused (status `rejected`) when the filter says so
//! (a plain Transport cannot look behind its newest datagram).
template <Transport T, DatagramFilter F>
[[nodiscard]] ReceiveResult receive_filtered(T& transport, std::span<std::byte> buffer,
                                             std::chrono::nanoseconds timeout, F& filter) noexcept {
  if constexpr (FilteringTransport<T>) {
    return transport.receive(buffer, timeout, filter);
  } else {
    ReceiveResult r = transport.receive(buffer, timeout);
    if (r.status == TransportStatus::ok &&
        !filter(std::span<const std::byte>(buffer.data(), r.size))) {
      r.status = TransportStatus::rejected;
      r.rejected += 1;
    }
    return r;
  }
}

namespace detail {

//! Bookkeeping of one filtered drain: offer() each datagram read (its bytes and real length);
//! the newest accepted one is copied into the caller's buffer; finish() sets the status.
template <typename F>
class NewestAccepted {
 public:
  //! `buffer`: the caller's; `filter`: called on each offered datagram that fits.
  NewestAccepted(std::span<std::byte> buffer, F& filter) noexcept
      : buffer_(buffer), filter_(&filter) {}

  //! One datagram of `length` bytes, the first `bytes.size()` of which are in `bytes`. True
  //! when it was accepted (and is now in the buffer).
  bool offer(std::span<const std::byte> bytes, std::size_t length) noexcept {
    any_ = true;
    if (length > bytes.size() || length > buffer_.size()) {
      ++result_.oversized;
      return false;
    }
    const auto datagram = bytes.first(length);
    if (!(*filter_)(datagram)) {
      ++result_.rejected;
      return false;
    }
    if (have_) ++result_.dropped;
    have_ = true;
    if (length > 0 && datagram.data() != buffer_.data()) {
      std::memmove(buffer_.data(), datagram.data(), length);
    }
    result_.size = length;
    return true;
  }

  //! True once some datagram was offered.
  [[nodiscard]] bool any() const noexcept { return any_; }
  //! The result: ok with the newest accepted, rejected when some were read but none accepted,
  //! otherwise `none_status` (timeout, or error when the read itself failed).
  [[nodiscard]] ReceiveResult finish(TransportStatus none_status) noexcept {
    result_.status = have_ ? TransportStatus::ok : any_ ? TransportStatus::rejected : none_status;
    if (!have_) result_.size = 0;
    return result_;
  }

 private:
  std::span<std::byte> buffer_;
  F* filter_;
  ReceiveResult result_{};
  bool any_ = false;
  bool have_ = false;
};

}  // namespace detail

}  // namespace endohaptics::transport
