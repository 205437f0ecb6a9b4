#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <endohaptics/teleop/latest_value.hpp>
#include <thread>

namespace teleop_latest_value_test {

namespace {

namespace tp = endohaptics::teleop;
using endohaptics::test::allocations_during;

// A value whose parts must always agree: a torn read (half of one publish, half of another)
// breaks the relation.
struct Sample {
  std::uint64_t sequence = 0;
  double x = 0.0;
  std::array<std::uint64_t, 6> copies{};
};

Sample make(std::uint64_t n) {
  Sample s;
  s.sequence = n;
  s.x = static_cast<double>(n) * 0.5;
  s.copies.fill(n);
  return s;
}

bool whole(const Sample& s) {
  if (s.x != static_cast<double>(s.sequence) * 0.5) return false;
  for (const auto c : s.copies) {
    if (c != s.sequence) return false;
  }
  return true;
}

}  // namespace

TEST_CASE("LatestValue: nothing before the first publish, then always the newest") {
  tp::LatestValue<Sample> v;
  Sample out = make(99);
  bool fresh = true;
  CHECK_FALSE(v.read(out, &fresh));
  CHECK_FALSE(fresh);
  CHECK(out.sequence == 99);  // untouched

  v.publish(make(1));
  REQUIRE(v.read(out, &fresh));
  CHECK(fresh);
  CHECK(out.sequence == 1);
  REQUIRE(v.read(out, &fresh));  // the same value again, not fresh
  CHECK_FALSE(fresh);
  CHECK(out.sequence == 1);

  for (std::uint64_t n = 2; n <= 10; ++n) v.publish(make(n));  // overwrites: only the newest
  REQUIRE(v.read(out, &fresh));
  CHECK(fresh);
  CHECK(out.sequence == 10);
  CHECK(v.published() == 10);
}

TEST_CASE("LatestValue: publish and read allocate nothing") {
  tp::LatestValue<Sample> v;
  Sample out;
  const long allocations = allocations_during([&] {
    for (std::uint64_t n = 1; n <= 10000; ++n) {
      v.publish(make(n));
      (void)v.read(out);
    }
  });
  CHECK(allocations == 0);
  CHECK(out.sequence == 10000);
}

TEST_CASE("allocations_on_this_thread_during counts this thread's allocations, not another's") {
  std::atomic<bool> go{false}, done{false};
  std::thread other([&] {
    while (!go.load()) std::this_thread::yield();
    for (int i = 0; i < 100; ++i) {
      auto* p = new std::uint64_t(static_cast<std::uint64_t>(i));  // NOLINT: counted on purpose
      delete p;
    }
    done.store(true);
  });
  const long mine = endohaptics::test::allocations_on_this_thread_during([&] {
    go.store(true);
    while (!done.load()) std::this_thread::yield();
  });
  other.join();
  CHECK(mine == 0);
  const long counted = endohaptics::test::allocations_on_this_thread_during([] {
    auto* p = new std::uint64_t(1);  // NOLINT: counted on purpose
    delete p;
  });
  CHECK(counted == 1);
}

TEST_CASE("LatestValue: two threads, no torn value, never older than one read before") {
  tp::LatestValue<Sample> v;
  constexpr std::uint64_t count = 200000;
  std::atomic<bool> done{false};
  std::thread producer([&] {
    for (std::uint64_t n = 1; n <= count; ++n) v.publish(make(n));
    done.store(true);
  });
  std::uint64_t reads = 0, torn = 0, backwards = 0, last = 0;
  Sample out;
  for (;;) {
    const bool finished = done.load();
    if (v.read(out)) {
      ++reads;
      if (!whole(out)) ++torn;
      if (out.sequence < last) ++backwards;
      last = out.sequence;
    }
    if (finished) break;
  }
  producer.join();
  (void)v.read(out);
  CHECK(reads > 0);
  CHECK(torn == 0);
  CHECK(backwards == 0);
  CHECK(out.sequence == count);  // the last publish is seen once the producer is done
}

}  // namespace teleop_latest_value_test
