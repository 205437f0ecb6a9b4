//! @file
//! InMemoryTransport: a pair of connected endpoints exchanging datagrams through fixed-capacity
//! queues, for deterministic tests and simulation without sockets. Single-threaded; an optional
//! responder answers synchronously inside `send` (an emulated sbRIO in the same thread).
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cstddef>
#include <cstring>
#include <span>
#include <type_traits>
#include <utility>

#include "endohaptics/transport/transport.hpp"

namespace endohaptics::transport {

//! Bounded FIFO of datagrams of at most MaxDatagram bytes; when full, the oldest is overwritten
//! (and counted), as a kernel socket buffer drops on overflow.
template <std::size_t MaxDatagram = 128, std::size_t Capacity = 16>
class DatagramQueue {
  static_assert(MaxDatagram > 0 && Capacity > 0);

 public:
  //! Queues a copy. Longer datagrams are truncated to MaxDatagram and counted.
  void push(std::span<const std::byte> datagram) noexcept {
    if (size_ == Capacity) {
      head_ = (head_ + 1) % Capacity;
      --size_;
      ++overflowed_;
    }
    Slot& slot = slots_[(head_ + size_) % Capacity];
    slot.size = std::min(datagram.size(), MaxDatagram);
    slot.truncated = datagram.size() > MaxDatagram;
    if (slot.size) std::memcpy(slot.bytes.data(), datagram.data(), slot.size);
    ++size_;
  }

  //! Pops the oldest into `out`; returns its length (0 and false when empty).
  bool pop(std::span<std::byte> out, std::size_t& size, bool& truncated) noexcept {
    if (size_ == 0) return false;
    const Slot& slot = slots_[head_];
    truncated = slot.truncated || slot.size > out.size();
    size = std::min(slot.size, out.size());
    if (size) std::memcpy(out.data(), slot.bytes.data(), size);
    head_ = (head_ + 1) % Capacity;
    --size_;
    return true;
  }

  //! Datagrams currently queued.
  [[nodiscard]] std::size_t size() const noexcept { return size_; }
  //! Datagrams overwritten because the queue was full, since construction.
  [[nodiscard]] std::size_t overflowed() const noexcept { return overflowed_; }
  //! Discards every queued datagram (the overflow count is kept).
  void clear() noexcept { head_ = size_ = 0; }

 private:
  struct Slot {
    std::array<std::byte, MaxDatagram> bytes{};
    std::size_t size = 0;
    bool truncated = false;
  };
  std::array<Slot, Capacity> slots_{};
  std::size_t head_ = 0;
  std::size_t size_ = 0;
  std::size_t overflowed_ = 0;
};

//! One endpoint: sends into `tx`, receives from `rx` (the peer's tx). Single-threaded.
template <std::size_t MaxDatagram = 128, std::size_t Capacity = 16>
class InMemoryTransport {
 public:
  using Queue = DatagramQueue<MaxDatagram, Capacity>;  //!< queue type of `tx` and `rx`

  //! Receives read at most default_max_drain datagrams each.
  InMemoryTransport(Queue& tx, Queue& rx) noexcept : tx_(&tx), rx_(&rx) {}
  //! Receives read at most `max_drain` datagrams each; throws Error unless 1..max_drain_limit.
  InMemoryTransport(Queue& tx, Queue& rx, std::size_t max_drain)
      : tx_(&tx), rx_(&rx), max_drain_(detail::checked_max_drain(max_drain, "InMemoryTransport")) {}

  //! Queues a copy into `tx` (never blocks; a full queue drops its oldest); error when closed.
  TransportStatus send(std::span<const std::byte> datagram) noexcept {
    if (closed_) return TransportStatus::error;
    tx_->push(datagram);
    return TransportStatus::ok;
  }

  //! Returns the newest queued datagram, discarding older ones, after reading at most max_drain
  //! of them (the rest stay queued). Never waits: an empty queue is a timeout at once (simulated
  //! time is the caller's business).
  ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout) noexcept {
    AcceptAny any;
    return receive(buffer, timeout, any);
  }

  //! As receive(buffer, timeout), returning the newest datagram `filter` accepts; refused and
  //! oversized ones (truncated by the queue, or longer than `buffer`) are counted.
  template <DatagramFilter F>
  ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds, F& filter) noexcept {
    if (closed_) {
      ReceiveResult result;
      result.status = TransportStatus::error;
      return result;
    }
    std::array<std::byte, MaxDatagram> scratch;  // NOLINT: written by pop before it is read
    detail::NewestAccepted<F> drain(buffer, filter);
    std::size_t size = 0;
    bool truncated = false;
    for (std::size_t reads = 0; reads < max_drain_ && rx_->pop(scratch, size, truncated); ++reads) {
      drain.offer(std::span<const std::byte>(scratch.data(), size), truncated ? size + 1 : size);
    }
    return drain.finish(TransportStatus::timeout);
  }

  //! Simulates a dead socket: every call fails until reopened.
  void close() noexcept { closed_ = true; }
  //! Undoes close(): send and receive work again.
  void reopen() noexcept { closed_ = false; }

  //! Datagrams one receive reads at most.
  [[nodiscard]] std::size_t max_drain() const noexcept { return max_drain_; }

 private:
  Queue* tx_;
  Queue* rx_;
  std::size_t max_drain_ = default_max_drain;
  bool closed_ = false;
};

//! Two connected endpoints owning their queues: `a` and `b`. Not movable (endpoints point in).
template <std::size_t MaxDatagram = 128, std::size_t Capacity = 16>
class InMemoryLink {
 public:
  using Endpoint = InMemoryTransport<MaxDatagram, Capacity>;  //!< type of `a` and `b`
  using Queue = typename Endpoint::Queue;                     //!< one direction's queue

  //! Both endpoints read at most default_max_drain datagrams per receive.
  InMemoryLink() noexcept : a_(a_to_b_, b_to_a_), b_(b_to_a_, a_to_b_) {}
  //! Both endpoints read at most `max_drain` datagrams per receive (Error unless in range).
  explicit InMemoryLink(std::size_t max_drain)
      : a_(a_to_b_, b_to_a_, max_drain), b_(b_to_a_, a_to_b_, max_drain) {}
  InMemoryLink(const InMemoryLink&) = delete;
  InMemoryLink& operator=(const InMemoryLink&) = delete;

  //! Endpoint a: sends into a_to_b(), receives from b_to_a().
  Endpoint& a() noexcept { return a_; }
  //! Endpoint b: sends into b_to_a(), receives from a_to_b().
  Endpoint& b() noexcept { return b_; }
  //! Datagrams sent by a and not yet received by b.
  Queue& a_to_b() noexcept { return a_to_b_; }
  //! Datagrams sent by b and not yet received by a.
  Queue& b_to_a() noexcept { return b_to_a_; }

 private:
  Queue a_to_b_;
  Queue b_to_a_;
  Endpoint a_;
  Endpoint b_;
};

//! An endpoint whose peer answers synchronously: `send` hands the datagram to
//! `responder(datagram, reply)` where `reply` is a Transport-like sink (`reply.send(bytes)`).
//! This is how tests put an emulated sbRIO behind a TeleopLoop in one thread.
template <typename Responder, std::size_t MaxDatagram = 128, std::size_t Capacity = 16>
class RespondingTransport {
 public:
  using Queue = DatagramQueue<MaxDatagram, Capacity>;  //!< queue type holding the replies

  //! Takes ownership of `responder`, called as `responder(datagram, reply)` on each send.
  explicit RespondingTransport(Responder responder) noexcept(
      std::is_nothrow_move_constructible_v<Responder>)
      : responder_(std::move(responder)) {}

  //! Hands `datagram` to the responder, which may queue replies; error when closed.
  TransportStatus send(std::span<const std::byte> datagram) noexcept {
    if (closed_) return TransportStatus::error;
    Reply reply{&replies_};
    responder_(datagram, reply);
    return TransportStatus::ok;
  }

  //! Returns the newest queued reply like InMemoryTransport::receive (never waits; reads at most
  //! default_max_drain replies); error when closed.
  ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout) noexcept {
    AcceptAny any;
    return receive(buffer, timeout, any);
  }

  //! As receive(buffer, timeout), returning the newest reply `filter` accepts.
  template <DatagramFilter F>
  ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout,
                        F& filter) noexcept {
    InMemoryTransport<MaxDatagram, Capacity> view(unused_, replies_);
    if (closed_) view.close();
    return view.receive(buffer, timeout, filter);
  }

  //! The owned responder (e.g. to inspect or reconfigure an emulated sbRIO).
  Responder& responder() noexcept { return responder_; }
  //! Simulates a dead socket: send and receive fail until reopened.
  void close() noexcept { closed_ = true; }
  //! Undoes close(): send and receive work again.
  void reopen() noexcept { closed_ = false; }

  //! What the responder writes its answers into.
  struct Reply {
    Queue* queue;  //!< the transport's reply queue (not owned)
    //! Queues `datagram` as a reply for the next receive; always ok.
    TransportStatus send(std::span<const std::byte> datagram) noexcept {
      queue->push(datagram);
      return TransportStatus::ok;
    }
  };

 private:
  Responder responder_;
  Queue replies_;
  Queue unused_;
  bool closed_ = false;
};

}  // namespace endohaptics::transport
