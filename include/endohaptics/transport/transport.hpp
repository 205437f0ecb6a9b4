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
#include <string_view>

namespace endohaptics::transport {

//! Outcome of a send or receive.
enum class TransportStatus : std::uint8_t {
  ok = 0,
  timeout,    //!< receive: nothing arrived before the deadline
  truncated,  //!< receive: the datagram was larger than the caller's buffer (content dropped)
  error,      //!< the operating system refused the operation (socket closed, unreachable, ...)
};

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
struct ReceiveResult {
  TransportStatus status = TransportStatus::timeout;
  std::size_t size = 0;     //!< bytes of the returned datagram (valid when status is ok)
  std::size_t dropped = 0;  //!< stale datagrams discarded before the returned one
};

//! A datagram transport usable from the real-time tick: both calls are noexcept, allocation-free
//! and bounded in time. `receive` waits at most `timeout` for a datagram, then drains whatever
//! else is queued and returns the newest one.
template <typename T>
concept Transport = requires(T& transport, std::span<const std::byte> datagram,
                             std::span<std::byte> buffer, std::chrono::nanoseconds timeout) {
  { transport.send(datagram) }
  noexcept->std::same_as<TransportStatus>;
  { transport.receive(buffer, timeout) }
  noexcept->std::same_as<ReceiveResult>;
};

}  // namespace endohaptics::transport
