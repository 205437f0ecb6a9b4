//! @file
//! UdpServerTransport: the sbRIO side of the link (worksheet 3.3.1), for the emulator and for
//! tests: a bound, unconnected UDP socket that answers whoever sent the newest datagram.
//! Same receive semantics as UdpTransport (deadline by ppoll, queue of one). POSIX only.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <array>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/address.hpp>
#include <boost/asio/ip/udp.hpp>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
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
  //! With pin_first_peer: the pin is released once the pinned peer has sent nothing accepted for
  //! this long (> 0; the robot side's watchdog: its motors are off by then), so a restarted
  //! console (a new source port) can take over; 0 keeps the first peer for ever.
  std::chrono::nanoseconds repin_after{0};
  //! The only peer to obey, "HOST:PORT" (IPv4 or IPv6 literal; for IPv6 "[addr]:port" or
  //! "addr:port" with the last colon before the port); empty: pin per pin_first_peer. Datagrams
  //! from anyone else are counted (foreign_datagrams()) and never answered, from the start.
  std::string peer{};
  //! Each receive first polls the socket without blocking for up to this long, then blocks; 0
  //! (the default) blocks at once. In [0, max_receive_spin] (UdpConfig::receive_spin).
  std::chrono::nanoseconds receive_spin{0};
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
        pin_(config.pin_first_peer || !config.peer.empty()),
        fixed_peer_(!config.peer.empty()),
        repin_after_(config.repin_after) {
    namespace ip = boost::asio::ip;
    boost::system::error_code ec;
    scratch_.wait.set_spin(detail::checked_receive_spin(config.receive_spin, "UdpServerTransport"));
    if (config.repin_after.count() < 0) {
      ENDOHAPTICS_THROW(Error("UdpServerTransport: repin_after must be >= 0 ns, got " +
                              std::to_string(config.repin_after.count())));
    }
    if (fixed_peer_) set_fixed_peer(config.peer);
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
    const auto now = std::chrono::steady_clock::now();
    if (pinned_ && !fixed_peer_ && repin_after_.count() > 0 &&
        now - last_from_peer_ > repin_after_) {
      pinned_ = false;  // the pinned console has been silent past the watchdog: free the robot
      ++releases_;
    }
    const ReceiveResult r =
        detail::receive_newest(socket_.native_handle(), buffer, timeout, &from, max_drain_,
                               scratch_, filter, pinned_ ? &peer_ : nullptr, &foreign_);
    if (r.status == TransportStatus::ok) {
      if (pin_ && !pinned_) {
        pinned_ = true;
        ++pins_;
      }
      last_from_peer_ = std::chrono::steady_clock::now();
      peer_ = from;
      peer_size_ = from.ss_family == AF_INET6 ? sizeof(sockaddr_in6) : sizeof(sockaddr_in);
    }
    return r;
  }

  //! The peer answered now (and, when pinned, the only one obeyed), "HOST:PORT"; empty: none yet.
  //! Allocates: not for a tick.
  [[nodiscard]] std::string peer_name() const {
    if (peer_size_ == 0) return {};
    char host[INET6_ADDRSTRLEN] = {};
    std::uint16_t port = 0;
    if (peer_.ss_family == AF_INET6) {
      const auto& a = reinterpret_cast<const sockaddr_in6&>(peer_);  // NOLINT: socket API
      ::inet_ntop(AF_INET6, &a.sin6_addr, host, sizeof host);
      port = ntohs(a.sin6_port);
      return "[" + std::string(host) + "]:" + std::to_string(port);
    }
    const auto& a = reinterpret_cast<const sockaddr_in&>(peer_);  // NOLINT: socket API
    ::inet_ntop(AF_INET, &a.sin_addr, host, sizeof host);
    port = ntohs(a.sin_port);
    return std::string(host) + ":" + std::to_string(port);
  }
  //! True while only one peer is obeyed (a configured peer, or the first one heard).
  [[nodiscard]] bool pinned() const noexcept { return pinned_; }
  //! Times a peer was pinned (the first console, and each one after a release).
  [[nodiscard]] std::uint64_t pins() const noexcept { return pins_; }
  //! Times the pin was released because the pinned peer fell silent (UdpServerConfig::repin_after).
  [[nodiscard]] std::uint64_t releases() const noexcept { return releases_; }

  //! The bound local endpoint (useful with port = 0).
  [[nodiscard]] boost::asio::ip::udp::endpoint local_endpoint() const {
    return socket_.local_endpoint();
  }

  //! True once a datagram has been received (there is someone to answer).
  [[nodiscard]] bool has_peer() const noexcept { return peer_size_ != 0; }

  //! Datagrams one receive reads at most.
  [[nodiscard]] std::size_t max_drain() const noexcept { return max_drain_; }
  //! The receive's non-blocking poll before it blocks (UdpServerConfig::receive_spin), and how
  //! often it found a datagram (hits) or ran out and blocked (misses).
  [[nodiscard]] const detail::ReadableWait& receive_wait() const noexcept { return scratch_.wait; }

  //! Datagrams from other senders than the pinned peer (UdpServerConfig::pin_first_peer).
  [[nodiscard]] std::size_t foreign_datagrams() const noexcept { return foreign_; }

 private:
  // Parses "HOST:PORT" (IPv6 may be bracketed) into peer_; throws Error naming the text.
  void set_fixed_peer(const std::string& text) {
    namespace ip = boost::asio::ip;
    const auto colon = text.rfind(':');
    const auto bad = [&text](const std::string& why) {
      ENDOHAPTICS_THROW(
          Error("UdpServerTransport: peer must be HOST:PORT (an IP address and a port "
                "1..65535), got '" +
                text.substr(0, 80) + "': " + why));
    };
    if (colon == std::string::npos || colon == 0 || colon + 1 == text.size()) bad("no port");
    std::string host = text.substr(0, colon);
    if (host.size() >= 2 && host.front() == '[' && host.back() == ']') {
      host = host.substr(1, host.size() - 2);
    }
    const std::string port_text = text.substr(colon + 1);
    unsigned long port = 0;
    for (const char c : port_text) {
      if (c < '0' || c > '9' || port > 65535) bad("the port is not a number in 1..65535");
      port = port * 10 + static_cast<unsigned long>(c - '0');
    }
    if (port == 0 || port > 65535 || port_text.size() > 5) {
      bad("the port is not a number in 1..65535");
    }
    boost::system::error_code ec;
    const ip::address address = ip::make_address(host, ec);
    if (ec) bad("not an IP address");
    const ip::udp::endpoint endpoint(address, static_cast<std::uint16_t>(port));
    std::memcpy(&peer_, endpoint.data(), endpoint.size());
    peer_size_ = static_cast<socklen_t>(endpoint.size());
    pinned_ = true;
    pins_ = 1;
  }

  boost::asio::io_context io_;
  boost::asio::ip::udp::socket socket_;
  std::size_t max_drain_;
  detail::DrainScratch scratch_{};
  sockaddr_storage peer_{};
  socklen_t peer_size_ = 0;
  bool pin_ = false;         // obey one peer at a time
  bool fixed_peer_ = false;  // that peer is configured (UdpServerConfig::peer), never released
  std::chrono::nanoseconds repin_after_{0};
  bool pinned_ = false;
  std::uint64_t pins_ = 0;
  std::uint64_t releases_ = 0;
  std::chrono::steady_clock::time_point last_from_peer_{};
  std::size_t foreign_ = 0;
};

static_assert(FilteringTransport<UdpServerTransport>);

}  // namespace endohaptics::transport
