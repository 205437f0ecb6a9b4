//! @file
//! DelayLine: one direction of a network with a fixed delay plus uniform jitter, in any clock's
//! time: datagrams go in stamped with their send time and come out, in order, once due (jitter
//! bunches them, never reorders them). Fixed capacity, seeded, noexcept and allocation-free.
//! It carries a tag (e.g. a true force, sim::ClosedLoop) along with each datagram. Times in ns.
//! DelayedSendTransport puts one on a Transport's send path, with loss (the emulator's --delay).
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

#include "endohaptics/core/clock.hpp"
#include "endohaptics/core/error.hpp"
#include "endohaptics/transport/transport.hpp"

namespace endohaptics::sim {

//! Delay and jitter of one direction.
struct DelaySettings {
  std::chrono::nanoseconds delay{0};   //!< every datagram is held at least this long
  std::chrono::nanoseconds jitter{0};  //!< plus a uniform extra in [0, jitter]

  //! Throws Error unless both are >= 0 and at most 10 s.
  void validate() const {
    constexpr auto limit = std::chrono::seconds(10);
    if (delay.count() < 0 || delay > limit || jitter.count() < 0 || jitter > limit) {
      ENDOHAPTICS_THROW(Error("DelaySettings: delay and jitter must be in [0, 10] s, got " +
                              std::to_string(delay.count()) + " ns and " +
                              std::to_string(jitter.count()) + " ns"));
    }
  }
};

//! A FIFO of at most Capacity datagrams of at most MaxDatagram bytes, each with a due time and a
//! Tag. A full line drops the newest datagram (counted).
template <typename Tag = char, std::size_t MaxDatagram = 64, std::size_t Capacity = 2048>
class DelayLine {
 public:
  //! Throws Error on invalid settings.
  DelayLine(const DelaySettings& settings, std::uint64_t seed)
      : settings_((settings.validate(), settings)), rng_(seed) {}

  //! Queues a copy of `datagram` sent at `now`; false (counted) when the line is full or the
  //! datagram is longer than MaxDatagram.
  bool push(std::span<const std::byte> datagram, std::chrono::nanoseconds now,
            const Tag& tag = Tag{}) noexcept {
    if (size_ == Capacity || datagram.size() > MaxDatagram) {
      ++dropped_;
      return false;
    }
    auto due = now + settings_.delay;
    if (settings_.jitter.count() > 0) {
      due += std::chrono::nanoseconds(static_cast<std::int64_t>(
          uniform_(rng_) * static_cast<double>(settings_.jitter.count())));
    }
    due = std::max(due, last_due_);  // in order: jitter delays, never overtakes
    last_due_ = due;
    Slot& slot = slots_[(head_ + size_) % Capacity];
    slot.due = due;
    slot.size = datagram.size();
    slot.tag = tag;
    if (slot.size > 0) std::memcpy(slot.bytes.data(), datagram.data(), slot.size);
    ++size_;
    return true;
  }

  //! True when a datagram is queued; `due` is then the oldest one's due time.
  [[nodiscard]] bool next_due(std::chrono::nanoseconds& due) const noexcept {
    if (size_ == 0) return false;
    due = slots_[head_].due;
    return true;
  }

  //! Pops the oldest datagram if it is due at `now`: copies it to `out` (cut to its size) and
  //! its tag; returns its length in `size`. False when nothing is due.
  bool pop_due(std::chrono::nanoseconds now, std::span<std::byte> out, std::size_t& size,
               Tag& tag) noexcept {
    if (size_ == 0 || slots_[head_].due > now) return false;
    const Slot& slot = slots_[head_];
    size = std::min(slot.size, out.size());
    if (size > 0) std::memcpy(out.data(), slot.bytes.data(), size);
    tag = slot.tag;
    head_ = (head_ + 1) % Capacity;
    --size_;
    return true;
  }

  [[nodiscard]] std::size_t size() const noexcept { return size_; }  //!< datagrams in flight
  //! Datagrams refused because the line was full or they were too long.
  [[nodiscard]] std::uint64_t dropped() const noexcept { return dropped_; }
  //! The settings in effect.
  [[nodiscard]] const DelaySettings& settings() const noexcept { return settings_; }

 private:
  struct Slot {
    std::chrono::nanoseconds due{0};
    std::array<std::byte, MaxDatagram> bytes{};
    std::size_t size = 0;
    Tag tag{};
  };
  DelaySettings settings_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::array<Slot, Capacity> slots_{};
  std::size_t head_ = 0;
  std::size_t size_ = 0;
  std::chrono::nanoseconds last_due_{0};
  std::uint64_t dropped_ = 0;
};

//! A Transport whose sends go through a DelayLine (delay, jitter) after a seeded loss draw, on a
//! clock: each call first hands the inner transport every datagram that has come due, and a
//! receive waits no longer than until the next one is due. Receives are passed through. Wraps
//! `Inner` (not owned). Models Transport (and FilteringTransport when Inner does).
template <transport::Transport Inner, endohaptics::Clock ClockT, std::size_t MaxDatagram = 128>
class DelayedSendTransport {
 public:
  //! Throws Error on invalid settings or a loss outside [0, 1].
  DelayedSendTransport(Inner& inner, ClockT& clock, const DelaySettings& settings, double loss,
                       std::uint64_t seed)
      : inner_(&inner),
        clock_(&clock),
        line_(settings, seed),
        loss_(check_loss(loss)),
        rng_(seed + 1) {}

  //! Drops the datagram with the loss probability (still ok, as UDP), else queues it; ok, or
  //! error when the line is full.
  transport::TransportStatus send(std::span<const std::byte> datagram) noexcept {
    flush();
    if (loss_ > 0.0 && uniform_(rng_) < loss_) {
      ++lost_;
      return transport::TransportStatus::ok;
    }
    if (!line_.push(datagram, clock_->now())) return transport::TransportStatus::error;
    flush();  // no delay: out at once
    return transport::TransportStatus::ok;
  }
  //! The inner transport's receive, waiting at most until the next queued datagram is due.
  transport::ReceiveResult receive(std::span<std::byte> buffer,
                                   std::chrono::nanoseconds timeout) noexcept {
    const auto wait = flush_and_wait(timeout);
    const transport::ReceiveResult r = inner_->receive(buffer, wait);
    flush();
    return r;
  }
  //! As above, through the inner transport's filtered drain.
  template <transport::DatagramFilter F>
  requires transport::FilteringTransport<Inner> transport::ReceiveResult receive(
      std::span<std::byte> buffer, std::chrono::nanoseconds timeout, F& filter)
  noexcept {
    const auto wait = flush_and_wait(timeout);
    const transport::ReceiveResult r = inner_->receive(buffer, wait, filter);
    flush();
    return r;
  }

  //! Datagrams the loss draw dropped.
  [[nodiscard]] std::uint64_t lost() const noexcept { return lost_; }
  //! Datagrams refused because the line was full or too long.
  [[nodiscard]] std::uint64_t overflowed() const noexcept { return line_.dropped(); }
  //! Datagrams in flight.
  [[nodiscard]] std::size_t in_flight() const noexcept { return line_.size(); }

 private:
  static double check_loss(double loss) {
    if (!(loss >= 0.0 && loss <= 1.0)) {
      ENDOHAPTICS_THROW(Error("DelayedSendTransport: loss must be in [0, 1], got " +
                              endohaptics::detail::format_number(loss)));
    }
    return loss;
  }
  void flush() noexcept {
    const auto now = clock_->now();
    std::size_t size = 0;
    char tag = 0;
    while (line_.pop_due(now, scratch_, size, tag)) {
      (void)inner_->send(std::span<const std::byte>(scratch_.data(), size));
    }
  }
  std::chrono::nanoseconds flush_and_wait(std::chrono::nanoseconds timeout) noexcept {
    flush();
    std::chrono::nanoseconds due{0};
    if (line_.next_due(due)) {
      timeout = std::clamp(due - clock_->now(), std::chrono::nanoseconds(0), timeout);
    }
    return timeout;
  }

  Inner* inner_;
  ClockT* clock_;
  DelayLine<char, MaxDatagram> line_;
  double loss_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::array<std::byte, MaxDatagram> scratch_{};
  std::uint64_t lost_ = 0;
};

}  // namespace endohaptics::sim
