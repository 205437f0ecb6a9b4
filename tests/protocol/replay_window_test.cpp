#include "endohaptics/protocol/replay_window.hpp"

#include <doctest/doctest.h>

#include <cstdint>
#include <random>
#include <set>

namespace protocol_replay_window_test {

namespace {

using endohaptics::protocol::ReplayWindow;
using endohaptics::protocol::WindowStatus;

// A reference model of RFC 4303 3.4.3 kept as a set of every accepted number: a sequence number is
// acceptable when it is > 0, not accepted before, and top - seq < 64.
struct Reference {
  std::set<std::uint64_t> seen;
  std::uint64_t top = 0;
  WindowStatus check(std::uint64_t s) const {
    if (s == 0) return WindowStatus::too_old;
    if (s > top) return WindowStatus::ok;
    if (top - s >= 64) return WindowStatus::too_old;
    return seen.count(s) != 0 ? WindowStatus::replayed : WindowStatus::ok;
  }
  void accept(std::uint64_t s) {
    seen.insert(s);
    if (s > top) top = s;
  }
};

}  // namespace

TEST_CASE("ReplayWindow: in-order sequence numbers are accepted once each") {
  ReplayWindow w;
  for (std::uint64_t s = 1; s <= 200; ++s) {
    REQUIRE(w.check_and_accept(s) == WindowStatus::ok);
    REQUIRE(w.check(s) == WindowStatus::replayed);
  }
  CHECK(w.top() == 200);
  CHECK(w.bitmap() == ~std::uint64_t{0});
}

TEST_CASE("ReplayWindow: zero is never valid") {
  ReplayWindow w;
  CHECK(w.check(0) == WindowStatus::too_old);
  REQUIRE(w.check_and_accept(5) == WindowStatus::ok);
  CHECK(w.check(0) == WindowStatus::too_old);
}

TEST_CASE("ReplayWindow: window edges (RFC 4303: top - 63 is inside, top - 64 is too old)") {
  ReplayWindow w;
  REQUIRE(w.check_and_accept(100) == WindowStatus::ok);
  CHECK(w.check(100 - 63) == WindowStatus::ok);
  CHECK(w.check(100 - 64) == WindowStatus::too_old);
  CHECK(w.check(1) == WindowStatus::too_old);
  REQUIRE(w.check_and_accept(37) == WindowStatus::ok);
  CHECK(w.check(37) == WindowStatus::replayed);
  // Sliding by one moves 37 out of the window: too old, not replayed.
  REQUIRE(w.check_and_accept(101) == WindowStatus::ok);
  CHECK(w.check(37) == WindowStatus::too_old);
  CHECK(w.check(38) == WindowStatus::ok);
}

TEST_CASE("ReplayWindow: reordered packets inside the window are accepted, then refused") {
  ReplayWindow w;
  for (std::uint64_t s : {5u, 3u, 4u, 1u, 2u}) REQUIRE(w.check_and_accept(s) == WindowStatus::ok);
  for (std::uint64_t s = 1; s <= 5; ++s) CHECK(w.check(s) == WindowStatus::replayed);
  CHECK(w.top() == 5);
}

TEST_CASE("ReplayWindow: a jump of 64 or more clears the bitmap") {
  ReplayWindow w;
  REQUIRE(w.check_and_accept(10) == WindowStatus::ok);
  REQUIRE(w.check_and_accept(10 + 64) == WindowStatus::ok);
  CHECK(w.bitmap() == 1u);
  CHECK(w.check(10) == WindowStatus::too_old);
  CHECK(w.check(11) == WindowStatus::ok);
  REQUIRE(w.check_and_accept(UINT64_MAX) == WindowStatus::ok);
  CHECK(w.check(UINT64_MAX) == WindowStatus::replayed);
  CHECK(w.check(UINT64_MAX - 63) == WindowStatus::ok);
  CHECK(w.check(UINT64_MAX - 64) == WindowStatus::too_old);
}

TEST_CASE("ReplayWindow: check changes nothing") {
  ReplayWindow w;
  REQUIRE(w.check_and_accept(70) == WindowStatus::ok);
  const ReplayWindow before = w;
  for (std::uint64_t s : {0u, 1u, 6u, 7u, 69u, 70u, 71u, 1000u}) (void)w.check(s);
  CHECK(w == before);
  // A refused check_and_accept changes nothing either.
  CHECK(w.check_and_accept(70) == WindowStatus::replayed);
  CHECK(w.check_and_accept(6) == WindowStatus::too_old);
  CHECK(w == before);
}

TEST_CASE("ReplayWindow: agrees with a reference model on random traffic") {
  std::mt19937_64 rng(4303);
  ReplayWindow w;
  Reference ref;
  std::uint64_t next = 1;
  for (int i = 0; i < 20000; ++i) {
    // Mostly forward, with reordering, duplicates and old packets.
    std::uint64_t s;
    switch (rng() % 4) {
      case 0:
        s = next++;
        break;
      case 1:
        s = next + rng() % 8;
        break;
      case 2:
        s = next > 80 ? next - rng() % 80 : 1 + rng() % next;
        break;
      default:
        s = ref.top > 0 ? ref.top - rng() % 3 : 1;
        break;
    }
    const WindowStatus expected = ref.check(s);
    REQUIRE(w.check(s) == expected);
    if (expected == WindowStatus::ok) {
      w.accept(s);
      ref.accept(s);
    }
    if (s >= next) next = s + 1;
  }
}

TEST_CASE("ReplayWindow: usable in constant expressions") {
  constexpr auto w = [] {
    ReplayWindow r;
    (void)r.check_and_accept(3);
    (void)r.check_and_accept(1);
    return r;
  }();
  static_assert(w.top() == 3 && w.bitmap() == 0b101);
  static_assert(w.check(2) == WindowStatus::ok && w.check(1) == WindowStatus::replayed);
  CHECK(w.top() == 3);
}

}  // namespace protocol_replay_window_test
