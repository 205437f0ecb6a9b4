//! @file
//! ReplayWindow: the anti-replay sliding window of RFC 4303 section 3.4.3 (IPsec ESP) for 64-bit
//! sequence numbers and a window of 64: a bitmap of the 64 highest sequence numbers, so
//! duplicates, replays and packets older than the window are refused. Check before use, accept
//! only after the packet is authenticated. See docs/protocol.md, "Protocol v2".
#pragma once

#include <cstdint>
#include <string_view>

namespace endohaptics::protocol {

//! Outcome of ReplayWindow::check.
enum class WindowStatus : std::uint8_t {
  ok = 0,    //!< new: newer than the highest seen, or inside the window and not yet seen
  replayed,  //!< inside the window and already accepted (a duplicate or a replay)
  too_old,   //!< 64 or more below the highest accepted sequence number, or 0 (never valid)
};

//! Human-readable name of a window status.
[[nodiscard]] constexpr std::string_view to_string(WindowStatus status) noexcept {
  switch (status) {
    case WindowStatus::ok:
      return "ok";
    case WindowStatus::replayed:
      return "duplicate or replay";
    case WindowStatus::too_old:
      return "older than the replay window";
  }
  return "unknown status";
}

//! RFC 4303 3.4.3 sliding window, size 64: `top` is the highest sequence number accepted, bit
//! i of `bitmap` is set when `top - i` was accepted. Sequence numbers start at 1; 0 is refused.
//! All members are constexpr, noexcept and allocation-free.
class ReplayWindow {
 public:
  static constexpr std::uint64_t size = 64;  //!< sequence numbers the bitmap covers

  //! May `sequence` be accepted? Changes nothing (call accept() once the packet is authentic).
  [[nodiscard]] constexpr WindowStatus check(std::uint64_t sequence) const noexcept {
    if (sequence == 0) return WindowStatus::too_old;
    if (sequence > top_) return WindowStatus::ok;
    const std::uint64_t behind = top_ - sequence;
    if (behind >= size) return WindowStatus::too_old;
    return ((bitmap_ >> behind) & 1u) != 0 ? WindowStatus::replayed : WindowStatus::ok;
  }

  //! Marks `sequence` as accepted, sliding the window when it is the new highest.
  //! Precondition: check(sequence) == WindowStatus::ok.
  constexpr void accept(std::uint64_t sequence) noexcept {
    if (sequence > top_) {
      const std::uint64_t shift = sequence - top_;
      bitmap_ = shift >= size ? 0 : bitmap_ << shift;
      bitmap_ |= 1u;
      top_ = sequence;
    } else {
      bitmap_ |= std::uint64_t{1} << (top_ - sequence);
    }
  }

  //! check(), then accept() when ok: the one call for a packet already authenticated.
  [[nodiscard]] constexpr WindowStatus check_and_accept(std::uint64_t sequence) noexcept {
    const WindowStatus s = check(sequence);
    if (s == WindowStatus::ok) accept(sequence);
    return s;
  }

  //! Forgets everything (a new session).
  constexpr void reset() noexcept { *this = ReplayWindow{}; }

  //! Highest sequence number accepted (0: none yet).
  [[nodiscard]] constexpr std::uint64_t top() const noexcept { return top_; }
  //! Bit i: `top() - i` was accepted.
  [[nodiscard]] constexpr std::uint64_t bitmap() const noexcept { return bitmap_; }

  //! Member-wise equality (tests: "state untouched").
  friend constexpr bool operator==(const ReplayWindow&, const ReplayWindow&) = default;

 private:
  std::uint64_t top_ = 0;
  std::uint64_t bitmap_ = 0;
};

}  // namespace endohaptics::protocol
