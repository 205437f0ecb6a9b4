//! @file
//! UdpTransport: the PC side of the sbRIO link (worksheet 3.3.1) on a connected UDP socket set up
//! with Boost.Asio; receive waits until a deadline with nanosecond resolution (ppoll and a
//! timerfd, ReadableWait), then drains the socket so only the newest datagram is returned (the
//! sbRIO's queue-of-one, worksheet 3.1.3). Linux.
#pragma once

#include <netinet/in.h>
#include <poll.h>
#include <sched.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/address.hpp>
#include <boost/asio/ip/udp.hpp>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <ctime>
#include <span>
#include <string>

#include "endohaptics/core/error.hpp"
#include "endohaptics/transport/transport.hpp"

namespace endohaptics::transport {

namespace detail {

//! CLOCK_MONOTONIC now, ns (the clock of every receive deadline and of ReadableWait's timer).
inline std::chrono::nanoseconds monotonic_now() noexcept {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::chrono::seconds(ts.tv_sec) + std::chrono::nanoseconds(ts.tv_nsec);
}

//! Waits until a socket is readable or an absolute deadline passes, exactly (to the timer's
//! resolution) but without arming a timer on every call. ppoll with a timeout starts and cancels
//! a high-resolution timer per call: on the 2-core VM of docs/performance.md a loopback
//! ping-pong with such a wait at both ends took 2.0-2.2x as long per round trip as one with
//! blocking reads (BM_Baseline_udp_ping_pong_ppoll), about 6 us per wait. Here one timerfd per
//! socket is armed at a deadline and left armed: a later wait whose deadline is no earlier than
//! the armed expiry waits on the socket and the timerfd with no timeout of its own (at --rate max
//! a new deadline is 1 ms after each send, so the timer is armed about once per millisecond, not
//! once per round trip). When the timer fires before this wait's deadline, it is re-armed at the
//! deadline and the wait goes on: a wait never ends after its deadline, nor before it without a
//! datagram. Without a timerfd (creation refused) every wait is a ppoll with its own timeout.
//!
//! Optionally (set_spin, default 0: off) a wait first polls the socket without blocking for up to
//! `spin` (never past its deadline), yielding the CPU between polls, and blocks only if nothing
//! came: a datagram that arrives during the spin costs no wake-up of a blocked thread, at the
//! price of the CPU the spin burns (a relay whose peer answers within microseconds;
//! docs/performance.md, the sbRIO gateway).
class ReadableWait {
 public:
  ReadableWait() noexcept : timer_(::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC)) {}
  ~ReadableWait() {
    if (timer_ >= 0) ::close(timer_);
  }
  ReadableWait(const ReadableWait&) = delete;
  ReadableWait& operator=(const ReadableWait&) = delete;

  //! Waits until `fd` is readable (ok), the CLOCK_MONOTONIC time `deadline` (ns) passes (timeout;
  //! a deadline already passed still looks once) or the wait fails (error).
  TransportStatus until(int fd, std::chrono::nanoseconds deadline) noexcept {
    if (spin_.count() > 0) {
      const TransportStatus spun = spin_until(fd, deadline);
      if (spun != TransportStatus::timeout) return spun;
    }
    for (;;) {
      const auto now = monotonic_now();
      if (now >= deadline) return poll_until(fd, now);
      if (timer_ < 0) return poll_until(fd, deadline);
      // The armed expiry still ahead and no later than the deadline: it wakes this wait in time.
      if (!(armed_ > now && armed_ <= deadline)) {
        const auto s = std::chrono::duration_cast<std::chrono::seconds>(deadline);
        const itimerspec at{
            {0, 0},
            {static_cast<std::time_t>(s.count()), static_cast<long>((deadline - s).count())}};
        // Re-arming also clears an expiry that was not read: the timerfd is readable only
        // once the new expiry passes.
        if (::timerfd_settime(timer_, TFD_TIMER_ABSTIME, &at, nullptr) != 0) {
          return poll_until(fd, deadline);
        }
        armed_ = deadline;
      }
      std::array<pollfd, 2> fds{pollfd{fd, POLLIN, 0}, pollfd{timer_, POLLIN, 0}};
      const int ready = ::ppoll(fds.data(), fds.size(), nullptr, nullptr);
      if (ready < 0 && errno != EINTR) return TransportStatus::error;
      if (ready > 0 && fds[0].revents != 0) return TransportStatus::ok;
      // The timer fired (or a signal came): look at the clock again.
    }
  }

  //! How long a wait polls without blocking before it blocks (0: it blocks at once). The caller
  //! keeps it in [0, max_receive_spin] (checked_receive_spin).
  void set_spin(std::chrono::nanoseconds spin) noexcept {
    spin_ = std::max(spin, std::chrono::nanoseconds(0));
  }
  //! The spin set.
  [[nodiscard]] std::chrono::nanoseconds spin() const noexcept { return spin_; }
  //! Waits (with a spin set) that ended without blocking: the datagram was there at the first poll
  //! or came during the spin (no blocking wait, no wake-up; the first kind would not have slept
  //! without the spin either).
  [[nodiscard]] std::uint64_t spin_hits() const noexcept { return spin_hits_; }
  //! Waits (with a spin set) whose spin ended without a datagram, so they blocked.
  [[nodiscard]] std::uint64_t spin_misses() const noexcept { return spin_misses_; }

 private:
  // Polls `fd` without blocking until it is readable (ok), the spin or the deadline has passed
  // (timeout: block from here) or the poll fails (error). A deadline already passed is left to
  // the blocking path, which still looks once.
  TransportStatus spin_until(int fd, std::chrono::nanoseconds deadline) noexcept {
    const auto now = monotonic_now();
    if (now >= deadline) return TransportStatus::timeout;
    const auto end = spin_ < deadline - now ? now + spin_ : deadline;
    for (;;) {
      pollfd pfd{fd, POLLIN, 0};
      const int ready = ::poll(&pfd, 1, 0);
      if (ready > 0) {
        ++spin_hits_;
        return TransportStatus::ok;
      }
      if (ready < 0 && errno != EINTR) return TransportStatus::error;
      if (monotonic_now() >= end) break;
      // A thread woken on this CPU (often the very peer that is to answer: the kernel places a
      // woken receiver beside its sender) runs now, not when the spin ends. Without it a spin on
      // two shared cores was slower than no spin at all (docs/performance.md).
      ::sched_yield();
    }
    ++spin_misses_;
    return TransportStatus::timeout;
  }

  // ppoll on `fd` alone until the CLOCK_MONOTONIC time `deadline` (looks once when it has
  // passed): ok, timeout or error.
  static TransportStatus poll_until(int fd, std::chrono::nanoseconds deadline) noexcept {
    for (;;) {
      const auto left = std::max(deadline - monotonic_now(), std::chrono::nanoseconds(0));
      timespec ts{static_cast<std::time_t>(left.count() / 1'000'000'000),
                  static_cast<long>(left.count() % 1'000'000'000)};
      pollfd pfd{fd, POLLIN, 0};
      const int ready = ::ppoll(&pfd, 1, &ts, nullptr);
      if (ready > 0) return TransportStatus::ok;
      if (ready == 0) return TransportStatus::timeout;
      if (errno != EINTR) return TransportStatus::error;
    }
  }

  int timer_;
  std::chrono::nanoseconds armed_{0};  // CLOCK_MONOTONIC expiry the timer is armed for (0: none)
  std::chrono::nanoseconds spin_{0};   // the non-blocking poll before each blocking wait
  std::uint64_t spin_hits_ = 0;
  std::uint64_t spin_misses_ = 0;
};

//! Largest datagram a UDP transport reads whole; longer ones are refused as oversized (every
//! packet of the protocol is < 100 bytes).
inline constexpr std::size_t max_datagram_bytes = 2048;

//! True when `a` and `b` are the same IPv4/IPv6 address and port.
inline bool same_sender(const sockaddr_storage& a, const sockaddr_storage& b) noexcept {
  if (a.ss_family != b.ss_family) return false;
  if (a.ss_family == AF_INET) {
    const auto& x = reinterpret_cast<const sockaddr_in&>(a);  // NOLINT: socket API
    const auto& y = reinterpret_cast<const sockaddr_in&>(b);  // NOLINT: socket API
    return x.sin_port == y.sin_port && x.sin_addr.s_addr == y.sin_addr.s_addr;
  }
  if (a.ss_family == AF_INET6) {
    const auto& x = reinterpret_cast<const sockaddr_in6&>(a);  // NOLINT: socket API
    const auto& y = reinterpret_cast<const sockaddr_in6&>(b);  // NOLINT: socket API
    return x.sin6_port == y.sin6_port &&
           std::memcmp(&x.sin6_addr, &y.sin6_addr, sizeof(x.sin6_addr)) == 0;
  }
  return false;
}

//! The buffers one drain reads into: `batch` datagrams per recvmmsg call (one system call reads
//! whatever is queued, up to the batch: the loop's receive costs a wait and one read, not a read
//! per datagram plus one that finds the queue empty). Part of each UDP transport (no allocation).
struct DrainScratch {
  static constexpr std::size_t batch = 8;  //!< datagrams per recvmmsg call
  //! One buffer per datagram of a batch.
  std::array<std::array<std::byte, max_datagram_bytes>, batch> data{};
  std::array<sockaddr_storage, batch> senders{};  //!< their senders (unconnected sockets)
  std::array<iovec, batch> iov{};                 //!< recvmmsg's vectors
  std::array<mmsghdr, batch> messages{};          //!< recvmmsg's headers
  ReadableWait wait;                              //!< the wait before each read
};

//! Waits up to `timeout`, then drains `fd`, reading at most `max_drain` (>= 1) datagrams into
//! `scratch`, and keeps in `buffer` the newest one `filter` accepts; the rest stay queued. With
//! `from` != nullptr, that datagram's sender is written there (unconnected sockets). With `pin`
//! != nullptr (and `from`), datagrams from any other sender are read, counted in `*foreign` and
//! never offered to `filter`.
template <typename F>
ReceiveResult receive_newest(int fd, std::span<std::byte> buffer, std::chrono::nanoseconds timeout,
                             sockaddr_storage* from, std::size_t max_drain, DrainScratch& scratch,
                             F& filter, const sockaddr_storage* pin = nullptr,
                             std::size_t* foreign = nullptr) noexcept {
  const auto start = monotonic_now();
  // A timeout too long to add (nanoseconds::max(): wait for ever) ends at the clock's end.
  const auto deadline = timeout > std::chrono::nanoseconds::max() - start
                            ? std::chrono::nanoseconds::max()
                            : start + std::max(timeout, std::chrono::nanoseconds(0));
  NewestAccepted<F> drain(buffer, filter);
  TransportStatus none = TransportStatus::timeout;  // readable but nothing (e.g. bad checksum)
  std::size_t reads = 0;
  // Until a datagram is accepted or the deadline passes: junk that wakes the wait does not end
  // it (the valid answer may be a moment behind). At most max_drain reads in all.
  for (;;) {
    const TransportStatus waited = scratch.wait.until(fd, deadline);
    if (waited == TransportStatus::error) {
      if (!drain.any()) none = TransportStatus::error;
      break;
    }
    if (waited != TransportStatus::ok) break;  // timeout
    bool accepted = false;
    while (reads < max_drain) {
      const auto want = static_cast<unsigned>(std::min(max_drain - reads, DrainScratch::batch));
      for (unsigned i = 0; i < want; ++i) {
        scratch.iov[i] = {scratch.data[i].data(), scratch.data[i].size()};
        msghdr& h = scratch.messages[i].msg_hdr;
        h = msghdr{};
        h.msg_iov = &scratch.iov[i];
        h.msg_iovlen = 1;
        if (from != nullptr) {
          h.msg_name = &scratch.senders[i];
          h.msg_namelen = sizeof(sockaddr_storage);
        }
      }
      const int got =
          ::recvmmsg(fd, scratch.messages.data(), want, MSG_DONTWAIT | MSG_TRUNC, nullptr);
      if (got < 0) {
        if (errno == EINTR) continue;
        if (errno != EAGAIN && errno != EWOULDBLOCK && !drain.any()) none = TransportStatus::error;
        break;
      }
      for (int i = 0; i < got; ++i) {
        const auto k = static_cast<std::size_t>(i);
        ++reads;
        if (pin != nullptr && from != nullptr && !same_sender(*pin, scratch.senders[k])) {
          if (foreign != nullptr) ++*foreign;
          continue;
        }
        // MSG_TRUNC: msg_len is the real length, also of a datagram longer than its buffer.
        if (drain.offer(scratch.data[k], scratch.messages[k].msg_len)) {
          accepted = true;
          if (from != nullptr) *from = scratch.senders[k];
        }
      }
      if (static_cast<unsigned>(got) < want) break;  // the queue is empty
    }
    if (accepted || reads >= max_drain || none == TransportStatus::error) break;
    if (monotonic_now() >= deadline) break;
  }
  return drain.finish(none);
}

}  // namespace detail

//! Where to bind and whom to talk to. Defaults: the 2016 rig's sbRIO (worksheet appendix B).
struct UdpConfig {
  std::string local_address = "0.0.0.0";        //!< local IPv4/IPv6 address to bind; 0.0.0.0: any
  std::uint16_t local_port = 0;                 //!< 0: any free port
  std::string remote_address = "169.254.4.42";  //!< the sbRIO's address
  std::uint16_t remote_port = 61556;            //!< the sbRIO's UDP port
  int receive_buffer_bytes = 0;                 //!< SO_RCVBUF; 0 keeps the system default
  //! Datagrams one receive reads at most (1..max_drain_limit); the rest wait for the next call.
  std::size_t max_drain = default_max_drain;
  //! Each receive first polls the socket without blocking for up to this long (never past its
  //! timeout), then blocks: 0 (the default) blocks at once. In [0, max_receive_spin]. Spinning
  //! saves the wake-up of a blocked thread when the answer comes within the spin, and burns the
  //! CPU meanwhile (detail::ReadableWait).
  std::chrono::nanoseconds receive_spin{0};
};

//! PC side of the UDP link to the sbRIO: bound and connected socket, non-blocking sends and
//! deadline-bounded receives returning the newest datagram. Non-copyable; models Transport.
class UdpTransport {
 public:
  //! Opens, binds and connects the socket. Throws Error naming the address on failure, or the
  //! field and value of an invalid max_drain.
  explicit UdpTransport(const UdpConfig& config)
      : socket_(io_), max_drain_(detail::checked_max_drain(config.max_drain, "UdpTransport")) {
    namespace ip = boost::asio::ip;
    boost::system::error_code ec;
    scratch_.wait.set_spin(detail::checked_receive_spin(config.receive_spin, "UdpTransport"));
    const ip::address local = ip::make_address(config.local_address, ec);
    if (ec)
      ENDOHAPTICS_THROW(
          Error("UdpTransport: invalid local address '" + config.local_address + "'"));
    socket_.open(local.is_v6() ? ip::udp::v6() : ip::udp::v4(), ec);
    if (ec) ENDOHAPTICS_THROW(Error("UdpTransport: cannot open a UDP socket: " + ec.message()));
    if (config.receive_buffer_bytes > 0) {
      socket_.set_option(boost::asio::socket_base::receive_buffer_size(config.receive_buffer_bytes),
                         ec);
    }
    socket_.bind(ip::udp::endpoint(local, config.local_port), ec);
    if (ec) {
      ENDOHAPTICS_THROW(Error("UdpTransport: cannot bind " + config.local_address + ":" +
                              std::to_string(config.local_port) + ": " + ec.message()));
    }
    connect(config.remote_address, config.remote_port);
  }

  //! (Re)connects to the peer. Connected, the kernel drops datagrams from anyone else and
  //! reports ICMP "port unreachable" (peer not running) as an error on the next call.
  //! Throws Error naming the address on failure.
  void connect(const std::string& address, std::uint16_t port) {
    namespace ip = boost::asio::ip;
    boost::system::error_code ec;
    const ip::address remote = ip::make_address(address, ec);
    if (ec) ENDOHAPTICS_THROW(Error("UdpTransport: invalid remote address '" + address + "'"));
    socket_.connect(ip::udp::endpoint(remote, port), ec);
    if (ec) {
      ENDOHAPTICS_THROW(Error("UdpTransport: cannot reach " + address + ":" + std::to_string(port) +
                              ": " + ec.message()));
    }
  }

  UdpTransport(const UdpTransport&) = delete;
  UdpTransport& operator=(const UdpTransport&) = delete;

  //! Sends `datagram` without blocking. A full send buffer counts as ok (dropped, as on the
  //! wire); error on any other failure, e.g. ECONNREFUSED when the peer is not listening.
  TransportStatus send(std::span<const std::byte> datagram) noexcept {
    for (;;) {
      const ssize_t n = ::send(socket_.native_handle(), datagram.data(), datagram.size(),
                               MSG_DONTWAIT | MSG_NOSIGNAL);
      if (n >= 0) return TransportStatus::ok;
      if (errno == EINTR) continue;
      // Full send buffer: UDP may drop, like the wire would. Anything else is an error
      // (ECONNREFUSED from an earlier ICMP: the peer is not listening).
      return errno == EAGAIN || errno == EWOULDBLOCK ? TransportStatus::ok : TransportStatus::error;
    }
  }

  //! Waits up to `timeout` for a datagram, then drains the socket (at most max_drain datagrams)
  //! and returns the newest one read.
  ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout) noexcept {
    AcceptAny any;
    return receive(buffer, timeout, any);
  }

  //! As receive(buffer, timeout), returning the newest datagram `filter` accepts (junk arriving
  //! after a valid packet cannot displace it); refused and oversized ones are counted.
  template <DatagramFilter F>
  ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout,
                        F& filter) noexcept {
    return detail::receive_newest(socket_.native_handle(), buffer, timeout, nullptr, max_drain_,
                                  scratch_, filter);
  }

  //! Datagrams one receive reads at most.
  [[nodiscard]] std::size_t max_drain() const noexcept { return max_drain_; }
  //! The receive's non-blocking poll before it blocks (UdpConfig::receive_spin), and how often it
  //! found a datagram, already there or during the spin (hits), or ran out and blocked (misses).
  [[nodiscard]] const detail::ReadableWait& receive_wait() const noexcept { return scratch_.wait; }

  //! The bound local endpoint (useful with local_port = 0).
  [[nodiscard]] boost::asio::ip::udp::endpoint local_endpoint() const {
    return socket_.local_endpoint();
  }

 private:
  boost::asio::io_context io_;
  boost::asio::ip::udp::socket socket_;
  std::size_t max_drain_;
  detail::DrainScratch scratch_{};
};

static_assert(FilteringTransport<UdpTransport>);

}  // namespace endohaptics::transport
