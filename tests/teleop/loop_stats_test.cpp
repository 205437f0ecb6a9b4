#include <doctest/doctest.h>

#include <endohaptics/teleop/loop_stats.hpp>

using endohaptics::teleop::DurationStats;
using endohaptics::teleop::LoopStats;
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
