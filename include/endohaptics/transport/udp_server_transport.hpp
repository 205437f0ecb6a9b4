//! @file
//! UdpServerTransport: the sbRIO side of the link (worksheet 3.3.1), for the emulator and for
//! tests: a bound, unconnected UDP socket that answers whoever sent the newest datagram.
//! Same receive semantics as UdpTransport (deadline by ppoll, queue of one). POSIX only.
#pragma once

#include <sys/socket.h>

#include <array>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/address.hpp>
#include <boost/asio/ip/udp.hpp>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <span>
#include <string>

#include "endohaptics/core/error.hpp"
#include "endohaptics/transport/transport.hpp"
#include "endohaptics/transport/udp_transport.hpp"

namespace endohaptics::transport {

//! Where the server listens. Default: the sbRIO's port on every interface.
struct UdpServerConfig {
  std::string bind_address = "0.0.0.0";  //!< local IPv4/IPv6 address to bind; 0.0.0.0: all
  std::uint16_t port = 61556;            //!< 0: any free port (see local_endpoint())
  //! Datagrams one receive reads at most (1..max_drain_limit); the rest wait for the next call.
  std::size_t max_drain = default_max_drain;
  //! Answer only the sender of the first accepted datagram from then on; datagrams from any other
  //! address or port are read, counted (foreign_datagrams()) and never offered to the filter. For
  //! the unauthenticated 2016 protocol, where the source is the only check there is.
  bool pin_first_peer = false;
};

//! Server (sbRIO) side of the UDP link: bound, unconnected socket that replies to the sender of
//! the newest datagram received. Non-copyable; models Transport.
class UdpServerTransport {
 public:
  //! Opens and binds the socket. Throws Error naming the address on failure, or the field and
  //! value of an invalid max_drain.
  explicit UdpServerTransport(const UdpServerConfig& config)
      : socket_(io_),
        max_drain_(detail::checked_max_drain(config.max_drain, "UdpServerTransport")),
        pin_(config.pin_first_peer) {
    namespace ip = boost::asio::ip;
    boost::system::error_code ec;
    const ip::address local = ip::make_address(config.bind_address, ec);
    if (ec) {
      ENDOHAPTICS_THROW(
          Error("UdpServerTransport: invalid bind address '" + config.bind_address + "'"));
    }
    socket_.open(local.is_v6() ? ip::udp::v6() : ip::udp::v4(), ec);
    if (ec) {
      ENDOHAPTICS_THROW(Error("UdpServerTransport: cannot open a UDP socket: " + ec.message()));
    }
    socket_.bind(ip::udp::endpoint(local, config.port), ec);
    if (ec) {
      ENDOHAPTICS_THROW(Error("UdpServerTransport: cannot bind " + config.bind_address + ":" +
                              std::to_string(config.port) + ": " + ec.message()));
    }
  }

  UdpServerTransport(const UdpServerTransport&) = delete;
  UdpServerTransport& operator=(const UdpServerTransport&) = delete;

  //! Sends to the sender of the newest datagram received; error before any was received.
  TransportStatus send(std::span<const std::byte> datagram) noexcept {
    if (peer_size_ == 0) return TransportStatus::error;
    for (;;) {
      const ssize_t n = ::sendto(socket_.native_handle(), datagram.data(), datagram.size(),
                                 MSG_DONTWAIT | MSG_NOSIGNAL,
                                 reinterpret_cast<const sockaddr*>(&peer_),  // NOLINT: socket API
                                 peer_size_);
      if (n >= 0) return TransportStatus::ok;
      if (errno == EINTR) continue;
      // A full buffer drops like the wire would; a vanished peer (ICMP) is not our error either.
      return errno == EAGAIN || errno == EWOULDBLOCK || errno == ECONNREFUSED
                 ? TransportStatus::ok
                 : TransportStatus::error;
    }
  }

  //! Waits up to `timeout`, drains the socket (at most max_drain datagrams), returns the newest
  //! one read and remembers its sender as the peer `send` answers.
  ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout) noexcept {
    AcceptAny any;
    return receive(buffer, timeout, any);
  }

  //! As receive(buffer, timeout), returning the newest datagram `filter` accepts; only its sender
  //! becomes the peer (a refused datagram never redirects the answers).
  template <DatagramFilter F>
  ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout,
                        F& filter) noexcept {
    sockaddr_storage from{};
    const bool pinned = pin_ && peer_size_ != 0;
    const ReceiveResult r =
        detail::receive_newest(socket_.native_handle(), buffer, timeout, &from, max_drain_,
                               scratch_, filter, pinned ? &peer_ : nullptr, &foreign_);
    if (r.status == TransportStatus::ok) {
      peer_ = from;
      peer_size_ = from.ss_family == AF_INET6 ? sizeof(sockaddr_in6) : sizeof(sockaddr_in);
    }
    return r;
  }

  //! The bound local endpoint (useful with port = 0).
  [[nodiscard]] boost::asio::ip::udp::endpoint local_endpoint() const {
    return socket_.local_endpoint();
  }

  //! True once a datagram has been received (there is someone to answer).
  [[nodiscard]] bool has_peer() const noexcept { return peer_size_ != 0; }

  //! Datagrams one receive reads at most.
  [[nodiscard]] std::size_t max_drain() const noexcept { return max_drain_; }

  //! Datagrams from other senders than the pinned peer (UdpServerConfig::pin_first_peer).
  [[nodiscard]] std::size_t foreign_datagrams() const noexcept { return foreign_; }

 private:
  boost::asio::io_context io_;
  boost::asio::ip::udp::socket socket_;
  std::size_t max_drain_;
  std::array<std::byte, detail::max_datagram_bytes> scratch_{};
  sockaddr_storage peer_{};
  socklen_t peer_size_ = 0;
  bool pin_ = false;
  std::size_t foreign_ = 0;
};

static_assert(FilteringTransport<UdpServerTransport>);

}  // namespace endohaptics::transport
