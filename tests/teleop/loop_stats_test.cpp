#include <doctest/doctest.h>

#include <endohaptics/teleop/loop_stats.hpp>
#include <type_traits>
#include <vector>

namespace teleop_loop_stats_test {

using endohaptics::teleop::DurationStats;
using endohaptics::teleop::LoopSnapshot;
using endohaptics::teleop::LoopStats;
using endohaptics::teleop::LoopWindow;
using endohaptics::teleop::TickOutcome;
using namespace std::chrono_literals;

TEST_CASE("duration stats: mean, sample std, min, max and histogram quantiles") {
  DurationStats<100, 1000> s;  // 1 us bins up to 100 us
  for (int i = 1; i <= 100; ++i) s.add(std::chrono::microseconds(i) - 500ns);  // 0.5 .. 99.5 us
  CHECK(s.count() == 100);
  CHECK(s.mean() == doctest::Approx(50e-6).epsilon(1e-12));
  // sample std of 1..100 = sqrt(100 * 101 / 12) = 29.011491975882016 (us)
  CHECK(s.stddev() == doctest::Approx(29.011491975882016e-6).epsilon(1e-9));
  CHECK(s.min() == doctest::Approx(0.5e-6));
  CHECK(s.max() == doctest::Approx(99.5e-6));
  CHECK(s.quantile(0.99) == doctest::Approx(99e-6));  // 99th value lies in bin [98, 99) us
  CHECK(s.quantile(0.5) == doctest::Approx(50e-6));
  s.add(1s);  // overflow: counted in max, quantile 1.0 bounded by max
  CHECK(s.overflow() == 1);
  CHECK(s.max() == doctest::Approx(1.0));
  CHECK(s.quantile(1.0) == doctest::Approx(1.0));
}

TEST_CASE("loop stats: rate, period error, deadline misses and loss are exact") {
  LoopStats stats(1ms);
  std::chrono::nanoseconds t{0};
  for (int i = 0; i < 1001; ++i) {
    stats.record_tick_start(t);
    const bool lost = i % 50 == 0;  // 21 of 1001
    stats.record_exchange(lost ? TickOutcome::timeout : TickOutcome::received, 200us, 0);
    t += (i % 100 == 99) ? 1500us : 1000us;  // 10 late periods of 1.5 ms
  }
  CHECK(stats.ticks() == 1001);
  CHECK(stats.timeouts() == 21);
  CHECK(stats.received() == 980);
  CHECK(stats.loss_percent() == doctest::Approx(100.0 * 21 / 1001));
  CHECK(stats.deadline_misses() == 10);
  // 1000 periods in 1000 * 1 ms + 10 * 0.5 ms = 1.005 s
  CHECK(stats.rate() == doctest::Approx(1000 / 1.005));
  CHECK(stats.period().max() == doctest::Approx(1.5e-3));
  CHECK(stats.period_error().mean() == doctest::Approx(10 * 0.5e-3 / 1000));
  CHECK(stats.round_trip().mean() == doctest::Approx(200e-6));
  const std::string table = stats.to_table();
  CHECK(table.find("loss 2.098 %") != std::string::npos);
  stats.reset();
  CHECK(stats.ticks() == 0);
}

namespace {

// Tick i of a test sequence: start time, outcome, round trip and stale datagrams (varied).
struct Tick {
  std::chrono::nanoseconds start;
  TickOutcome outcome;
  std::chrono::nanoseconds round_trip;
  std::size_t stale;
};

std::vector<Tick> ticks_for_windows() {
  std::vector<Tick> ticks;
  std::chrono::nanoseconds t{5s};
  for (int i = 0; i < 2001; ++i) {
    const TickOutcome outcome = i % 50 == 0   ? TickOutcome::timeout
                                : i % 77 == 0 ? TickOutcome::decode_error
                                : i % 91 == 0 ? TickOutcome::transport_error
                                              : TickOutcome::received;
    ticks.push_back({t, outcome, std::chrono::microseconds(150 + (i * 37) % 100),
                     static_cast<std::size_t>(i % 13 == 0 ? 2 : 0)});
    t += (i % 100 == 99)
             ? 1500us
             : std::chrono::nanoseconds(1000us + std::chrono::nanoseconds((i * 7919) % 30000));
  }
  return ticks;
}

void record(LoopStats& stats, const Tick& tick) {
  stats.record_tick_start(tick.start);
  stats.record_exchange(tick.outcome, tick.round_trip, tick.stale);
}

void check_window_matches(const LoopWindow& w, const LoopStats& s) {
  CHECK(w.exchanges == s.exchanges());
  CHECK(w.received == s.received());
  CHECK(w.timeouts == s.timeouts());
  CHECK(w.decode_errors == s.decode_errors());
  CHECK(w.transport_errors == s.transport_errors());
  CHECK(w.stale_dropped == s.stale_dropped());
  CHECK(w.deadline_misses == s.deadline_misses());
  CHECK(w.loss_percent == doctest::Approx(s.loss_percent()).epsilon(1e-12));
  CHECK(w.rate == doctest::Approx(s.rate()).epsilon(1e-12));
  CHECK(w.period_mean == doctest::Approx(s.period().mean()).epsilon(1e-9));
  CHECK(w.period_error_mean == doctest::Approx(s.period_error().mean()).epsilon(1e-9));
  CHECK(w.round_trip_mean == doctest::Approx(s.round_trip().mean()).epsilon(1e-9));
}

}  // namespace

TEST_CASE("loop snapshot: small, copy-free windows with the full stats' numbers") {
  // The per-second figures come from two snapshots, not from a second LoopStats (~80 KB of
  // histograms) built and reset on the real-time thread.
  static_assert(sizeof(LoopSnapshot) <= 128);
  static_assert(sizeof(LoopWindow) <= 160);
  static_assert(std::is_trivially_copyable_v<LoopSnapshot>);
  CHECK(sizeof(LoopSnapshot) * 500 < sizeof(LoopStats));

  const auto ticks = ticks_for_windows();
  LoopStats stats(1ms);
  const LoopSnapshot start = stats.snapshot();
  CHECK(start.ticks == 0);
  LoopSnapshot middle;
  for (std::size_t i = 0; i < ticks.size(); ++i) {
    record(stats, ticks[i]);
    if (i == 1000) middle = stats.snapshot();
  }
  const LoopSnapshot end = stats.snapshot();

  SUBCASE("from the start: the whole run's figures") {
    const LoopWindow whole = end.since(start);
    CHECK(whole.ticks == 2001);
    check_window_matches(whole, stats);
    check_window_matches(end.since(LoopSnapshot{}), stats);
  }
  SUBCASE("a later window: as a LoopStats that saw only its ticks (periods from the tick before)") {
    LoopStats reference(1ms);
    reference.record_tick_start(ticks[1000].start);  // where the window's first period starts
    for (std::size_t i = 1001; i < ticks.size(); ++i) record(reference, ticks[i]);
    const LoopWindow window = end.since(middle);
    CHECK(window.ticks == 1000);
    CHECK(window.duration ==
          doctest::Approx(
              std::chrono::duration<double>(ticks.back().start - ticks[1000].start).count()));
    check_window_matches(window, reference);
    CHECK(window.deadline_misses == 10);
    CHECK(window.timeouts == 20);
  }
  SUBCASE("an empty window is all zeros") {
    const LoopWindow empty = end.since(end);
    CHECK(empty.ticks == 0);
    CHECK(empty.rate == 0.0);
    CHECK(empty.loss_percent == 0.0);
    CHECK(empty.round_trip_mean == 0.0);
  }
}

}  // namespace teleop_loop_stats_test
