//! @file
//! FaultInjectingTransport: a Transport decorator that drops, delays, duplicates, reorders,
//! corrupts and truncates datagrams at configurable rates from a seeded generator, so the loop's
//! safety can be tested against every fault of an unreliable UDP link (worksheet 3.2.1, 3.4).
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <random>
#include <span>
#include <string>

#include "endohaptics/core/error.hpp"
#include "endohaptics/transport/transport.hpp"

namespace endohaptics::transport {

//! Probabilities in [0, 1] of each fault, per datagram.
struct FaultRates {
  double drop_send = 0.0;     //!< outgoing datagram never sent
  double drop_receive = 0.0;  //!< incoming datagram lost (reported as timeout)
  double delay = 0.0;         //!< incoming datagram held back and delivered at a later receive
  double duplicate = 0.0;     //!< outgoing datagram sent twice
  double corrupt = 0.0;       //!< 1-3 random bits flipped in an incoming datagram
  double truncate = 0.0;      //!< incoming datagram cut to a random shorter length
  double reorder = 0.0;       //!< the held-back datagram is delivered instead of a newer one
};

//! Exact counts of the faults injected so far.
struct FaultCounters {
  std::uint64_t dropped_send = 0;     //!< outgoing datagrams silently not sent
  std::uint64_t dropped_receive = 0;  //!< incoming datagrams discarded as if lost
  std::uint64_t delayed = 0;          //!< incoming datagrams held back for a later receive
  std::uint64_t duplicated = 0;       //!< outgoing datagrams sent a second time
  std::uint64_t corrupted = 0;        //!< incoming datagrams with 1-3 bits flipped
  std::uint64_t truncated = 0;        //!< incoming datagrams cut to a shorter length
  std::uint64_t reordered = 0;        //!< held-back datagrams delivered in place of a newer one
};

//! Wraps the Transport `Inner` (not owned; must outlive this) and injects the faults of
//! FaultRates. Held-back datagrams are kept up to MaxDatagram bytes. Models Transport.
template <Transport Inner, std::size_t MaxDatagram = 128>
class FaultInjectingTransport {
 public:
  //! Throws Error when a rate is not a probability.
  FaultInjectingTransport(Inner& inner, const FaultRates& rates, std::uint64_t seed)
      : inner_(&inner), rates_(rates), rng_(seed) {
    for (const double p : {rates.drop_send, rates.drop_receive, rates.delay, rates.duplicate,
                           rates.corrupt, rates.truncate, rates.reorder}) {
      if (!(p >= 0.0 && p <= 1.0)) {
        ENDOHAPTICS_THROW(
            Error("FaultInjectingTransport: every fault rate must be in [0, 1], got " +
                  std::to_string(p)));
      }
    }
  }

  //! Sends through the inner transport, unless dropped (still reports ok, as UDP would) or
  //! duplicated (sent twice). Otherwise returns the inner transport's status.
  TransportStatus send(std::span<const std::byte> datagram) noexcept {
    if (happens(rates_.drop_send)) {
      ++counters_.dropped_send;
      return TransportStatus::ok;  // UDP: the sender never knows
    }
    const TransportStatus status = inner_->send(datagram);
    if (status == TransportStatus::ok && happens(rates_.duplicate)) {
      ++counters_.duplicated;
      return inner_->send(datagram);
    }
    return status;
  }

  //! Receives through the inner transport, then may drop, delay, reorder, corrupt or truncate
  //! the datagram; a held-back datagram is delivered when nothing usable arrives.
  ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout) noexcept {
    AcceptAny any;
    return receive(buffer, timeout, any);
  }

  //! As receive(buffer, timeout) with the inner transport's filtered drain; what the faults
  //! changed (a late, reordered, corrupted or truncated datagram) is shown to `filter` again, so
  //! damage is refused as it would be at the receiver.
  template <DatagramFilter F>
  ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout,
                        F& filter) noexcept {
    ReceiveResult result = receive_filtered(*inner_, buffer, timeout, filter);
    if (result.status != TransportStatus::ok)
      return refilter(buffer, deliver_held(buffer, result), filter);

    if (happens(rates_.drop_receive)) {
      ++counters_.dropped_receive;
      return refilter(buffer, deliver_held(buffer, nothing(result)), filter);
    }
    if (!held_ && happens(rates_.delay)) {  // hold this one back for a later receive
      ++counters_.delayed;
      hold(buffer.first(result.size));
      return nothing(result);
    }
    if (held_ && happens(rates_.reorder)) {  // an older datagram overtakes the newer one
      ++counters_.reordered;
      std::array<std::byte, MaxDatagram> newer{};
      const std::size_t n = std::min(result.size, MaxDatagram);
      std::memcpy(newer.data(), buffer.data(), n);
      result = deliver_held(buffer, result);
      hold(std::span<const std::byte>(newer.data(), n));
      return refilter(buffer, damage(buffer, result), filter);
    }
    const std::uint64_t before = counters_.corrupted + counters_.truncated;
    result = damage(buffer, result);
    if (counters_.corrupted + counters_.truncated == before) return result;  // untouched
    return refilter(buffer, result, filter);
  }

  //! Faults injected since construction.
  [[nodiscard]] const FaultCounters& counters() const noexcept { return counters_; }
  //! The fault rates currently in effect.
  [[nodiscard]] const FaultRates& rates() const noexcept { return rates_; }
  //! Changes the rates at run time (e.g. to simulate a link dying and recovering).
  //! Precondition: every rate in [0, 1].
  void set_rates(const FaultRates& rates) noexcept { rates_ = rates; }

 private:
  bool happens(double p) noexcept { return p > 0.0 && uniform_(rng_) < p; }

  void hold(std::span<const std::byte> datagram) noexcept {
    held_size_ = std::min(datagram.size(), MaxDatagram);
    std::memcpy(held_data_.data(), datagram.data(), held_size_);
    held_ = true;
  }

  // `r` with nothing delivered (a timeout, its counts kept).
  static ReceiveResult nothing(ReceiveResult r) noexcept {
    r.status = TransportStatus::timeout;
    r.size = 0;
    return r;
  }

  // When nothing usable arrived but a datagram is held back, the late one arrives now (a copy
  // too long for `buffer` is refused as oversized).
  ReceiveResult deliver_held(std::span<std::byte> buffer, ReceiveResult fallback) noexcept {
    if (!held_ || fallback.status == TransportStatus::error) return fallback;
    held_ = false;
    if (held_size_ > buffer.size()) {
      ++fallback.oversized;
      fallback.status = TransportStatus::rejected;
      fallback.size = 0;
      return fallback;
    }
    std::memcpy(buffer.data(), held_data_.data(), held_size_);
    fallback.status = TransportStatus::ok;
    fallback.size = held_size_;
    return fallback;
  }

  // Shows a delivered datagram to the filter once more: refused means status rejected.
  template <typename F>
  static ReceiveResult refilter(std::span<std::byte> buffer, ReceiveResult r, F& filter) noexcept {
    if (r.status == TransportStatus::ok &&
        !filter(std::span<const std::byte>(buffer.data(), r.size))) {
      r.status = TransportStatus::rejected;
      r.size = 0;
      ++r.rejected;
    }
    return r;
  }

  ReceiveResult damage(std::span<std::byte> buffer, ReceiveResult result) noexcept {
    if (result.status != TransportStatus::ok || result.size == 0) return result;
    if (happens(rates_.corrupt)) {
      ++counters_.corrupted;
      const int flips = 1 + static_cast<int>(rng_() % 3);
      for (int i = 0; i < flips; ++i) {
        buffer[rng_() % result.size] ^= std::byte{static_cast<unsigned char>(1u << (rng_() % 8))};
      }
    }
    if (happens(rates_.truncate)) {
      ++counters_.truncated;
      result.size = static_cast<std::size_t>(rng_() % result.size);
    }
    return result;
  }

  Inner* inner_;
  FaultRates rates_;
  FaultCounters counters_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::array<std::byte, MaxDatagram> held_data_{};
  std::size_t held_size_ = 0;
  bool held_ = false;
};

}  // namespace endohaptics::transport
