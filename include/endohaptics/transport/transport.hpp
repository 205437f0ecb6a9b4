//! @file
//! The `Transport` concept: how a TeleopLoop exchanges datagrams with the sbRIO (worksheet 3.3.1:
//! send, then receive with a deadline, single thread). Implementations: UdpTransport,
//! InMemoryTransport, FaultInjectingTransport, or a user's own.
#pragma once

#include <chrono>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "endohaptics/core/error.hpp"

namespace endohaptics::transport {

//! Default bound on the datagrams one `receive` reads (UdpConfig, UdpServerConfig,
//! InMemoryTransport): a flood cannot keep the tick inside `receive`; what is left stays queued
//! for the next call. A read costs about a microsecond, so 64 reads stay well inside a 1 ms tick.
inline constexpr std::size_t default_max_drain = 64;
//! Largest drain bound a transport accepts.
inline constexpr std::size_t max_drain_limit = 4096;

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

}  // namespace detail

//! Outcome of a send or receive.
enum class TransportStatus : std::uint8_t {
  ok = 0,     //!< sent, or a datagram was received into the buffer
  timeout,    //!< receive: nothing arrived before the deadline
  truncated,  //!< receive: the datagram was larger than the caller's buffer (content dropped)
  error,      //!< the operating system refused the operation (socket closed, unreachable, ...)
};

//! Short human-readable description of `status` (for logs and error messages).
[[nodiscard]] constexpr std::string_view to_string(TransportStatus status) noexcept {
  switch (status) {
    case TransportStatus::ok:
      return "ok";
    case TransportStatus::timeout:
      return "timeout";
    case TransportStatus::truncated:
      return "datagram larger than buffer";
    case TransportStatus::error:
      return "transport error";
  }
  return "unknown status";
}

//! What a receive produced: status, bytes written into the caller's buffer, and how many older
//! datagrams were discarded so that only the newest is returned (queue of one, worksheet 3.1.3).
//! A receive reads at most its transport's `max_drain` datagrams: under a flood it returns the
//! newest of those, and the rest are read (and counted) by the next call.
struct ReceiveResult {
  TransportStatus status = TransportStatus::timeout;  //!< outcome of the receive
  std::size_t size = 0;     //!< bytes of the returned datagram (valid when status is ok)
  std::size_t dropped = 0;  //!< stale datagrams discarded before the returned one
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

}  // namespace endohaptics::transport
