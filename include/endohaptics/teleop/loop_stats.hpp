//! @file
//! LoopStats: the figures of worksheet table 3.1 (achieved rate, period jitter, round-trip delay,
//! packet loss), online, O(1) memory and allocation-free: Welford mean/variance plus fixed-width
//! histograms (1 us bins) for percentiles. Times in seconds unless a name says otherwise.
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>

#include "endohaptics/teleop/passivity.hpp"
#include "endohaptics/teleop/state_plausibility.hpp"

namespace endohaptics::teleop {

//! Online summary of one duration signal (a period or a round trip), in seconds.
//! `Bins` histogram bins of `bin_width_ns` each; larger values fall into an overflow bin and
//! still count in mean, std and max (the p99 then reports the histogram's upper edge as a bound).
template <int Bins = 5000, std::int64_t BinWidthNs = 1000>
class DurationStats {
  static_assert(Bins >= 10, "a histogram needs a few bins");
  static_assert(BinWidthNs > 0);

 public:
  //! Adds one duration (any sign; negative ones land in the first bin).
  void add(std::chrono::nanoseconds d) noexcept {
    const auto ns = d.count();
    const double s = static_cast<double>(ns) * 1e-9;
    ++count_;
    const double delta = s - mean_;
    mean_ += delta / static_cast<double>(count_);
    m2_ += delta * (s - mean_);
    min_ = std::min(min_, s);
    max_ = std::max(max_, s);
    const std::int64_t bin = ns < 0 ? 0 : ns / BinWidthNs;
    if (bin >= Bins) {
      ++overflow_;
    } else {
      ++histogram_[static_cast<std::size_t>(bin)];
    }
  }

  //! Durations added so far.
  [[nodiscard]] std::uint64_t count() const noexcept { return count_; }
  //! Mean, s (0 when empty).
  [[nodiscard]] double mean() const noexcept { return count_ ? mean_ : 0.0; }
  //! Sample standard deviation (n - 1).
  [[nodiscard]] double stddev() const noexcept {
    return count_ > 1 ? std::sqrt(m2_ / static_cast<double>(count_ - 1)) : 0.0;
  }
  //! Smallest duration, s (0 when empty).
  [[nodiscard]] double min() const noexcept { return count_ ? min_ : 0.0; }
  //! Largest duration, s (0 when empty).
  [[nodiscard]] double max() const noexcept { return count_ ? max_ : 0.0; }
  //! Upper edge of the histogram bin holding quantile q in [0, 1] (resolution BinWidthNs),
  //! capped by the largest value seen.
  [[nodiscard]] double quantile(double q) const noexcept {
    if (count_ == 0) return 0.0;
    q = std::clamp(q, 0.0, 1.0);
    const auto target = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_)));
    std::uint64_t seen = 0;
    for (int i = 0; i < Bins; ++i) {
      seen += histogram_[static_cast<std::size_t>(i)];
      if (seen >= target && seen > 0) {
        return std::min(static_cast<double>((i + 1) * BinWidthNs) * 1e-9, max_);
      }
    }
    return max_;  // in the overflow bin: the largest value seen bounds it
  }
  //! Durations beyond the histogram's last bin (Bins x BinWidthNs).
  [[nodiscard]] std::uint64_t overflow() const noexcept { return overflow_; }
  //! Counts per bin; bin i holds [i, i + 1) x BinWidthNs.
  [[nodiscard]] const std::array<std::uint32_t, static_cast<std::size_t>(Bins)>& histogram()
      const noexcept {
    return histogram_;
  }
  //! Width of one histogram bin, s.
  static constexpr double bin_width() noexcept { return static_cast<double>(BinWidthNs) * 1e-9; }
  //! Forgets everything added.
  void reset() noexcept { *this = DurationStats{}; }

 private:
  std::uint64_t count_ = 0;
  double mean_ = 0.0;
  double m2_ = 0.0;
  double min_ = std::numeric_limits<double>::infinity();
  double max_ = 0.0;
  std::uint64_t overflow_ = 0;
  std::array<std::uint32_t, static_cast<std::size_t>(Bins)> histogram_{};
};

//! What happened in one tick, as reported by the loop.
enum class TickOutcome : std::uint8_t {
  received,         //!< a valid state packet arrived before the deadline
  timeout,          //!< nothing arrived before the deadline (a miss)
  decode_error,     //!< a datagram arrived but the codec rejected it (also a miss)
  transport_error,  //!< send or receive failed at the OS level (also a miss)
  state_fault,      //!< a state decoded but is implausible (StateFault): never used (a miss)
  //! a plausible state that reports inactive a motor the loop has enabled for longer than
  //! SafetyConfig::activation_timeout: the robot does not obey (a miss)
  not_obeyed,
};

//! Figures of the ticks between two LoopSnapshots (a window, e.g. one second), as a LoopStats
//! that recorded only those ticks would give them; periods are measured from the tick before
//! the window, so consecutive windows cover every period once. Times in seconds.
struct LoopWindow {
  std::uint64_t ticks = 0;             //!< ticks started in the window
  double duration = 0.0;               //!< s, covered by the window's periods
  double rate = 0.0;                   //!< Hz, achieved
  double period_mean = 0.0;            //!< s
  double period_error_mean = 0.0;      //!< s, mean |period - nominal| (0 with nominal 0)
  std::uint64_t deadline_misses = 0;   //!< periods more than 10 % over nominal
  double round_trip_mean = 0.0;        //!< s, over the received exchanges
  std::uint64_t exchanges = 0;         //!< received + every kind of miss
  std::uint64_t received = 0;          //!< valid state packets
  std::uint64_t timeouts = 0;          //!< nothing before the deadline
  std::uint64_t decode_errors = 0;     //!< a datagram the codec refused
  std::uint64_t transport_errors = 0;  //!< send or receive failed
  std::uint64_t stale_dropped = 0;     //!< older datagrams drained
  std::uint64_t state_faults = 0;      //!< implausible states refused
  std::uint64_t not_obeyed = 0;        //!< states showing enabled motors inactive
  std::uint64_t rejected = 0;          //!< datagrams the drain refused (any cause)
  double loss_percent = 0.0;           //!< exchanges without a valid state packet, %
};

//! Datagrams a receive's drain refused, by cause (the loop's decoder decides).
struct RejectedDatagrams {
  std::uint64_t wrong_size = 0;  //!< empty, short, long or oversized
  std::uint64_t non_finite = 0;  //!< NaN or Inf in a value
  std::uint64_t bad_mask = 0;    //!< active bit at or above the motor count
  //! All causes.
  [[nodiscard]] std::uint64_t total() const noexcept { return wrong_size + non_finite + bad_mask; }
};

//! A LoopStats' cumulative counters at one instant: fixed size, about 100 bytes (no histograms),
//! trivially copyable. Take one per window on the loop thread (`LoopStats::snapshot()`), hand
//! it to another thread, and get the window's figures there with `later.since(earlier)`.
struct LoopSnapshot {
  std::chrono::nanoseconds first_start{0};       //!< start of the first tick
  std::chrono::nanoseconds last_start{0};        //!< start of the newest tick
  std::uint64_t ticks = 0;                       //!< ticks started
  std::uint64_t received = 0;                    //!< valid state packets
  std::uint64_t timeouts = 0;                    //!< receive deadlines missed
  std::uint64_t decode_errors = 0;               //!< datagrams the codec refused
  std::uint64_t transport_errors = 0;            //!< sends or receives that failed
  std::uint64_t stale_dropped = 0;               //!< older datagrams drained
  std::uint64_t state_faults = 0;                //!< implausible states refused
  std::uint64_t not_obeyed = 0;                  //!< states showing enabled motors inactive
  std::uint64_t rejected = 0;                    //!< datagrams the drain refused
  std::uint64_t deadline_misses = 0;             //!< periods more than 10 % over nominal
  std::uint64_t period_errors = 0;               //!< periods summed in period_error_sum
  std::chrono::nanoseconds period_error_sum{0};  //!< sum of |period - nominal|
  std::chrono::nanoseconds round_trip_sum{0};    //!< sum over the received exchanges

  //! The window from `earlier` (a snapshot of the same LoopStats, or a default one for "from
  //! the start") to this one.
  [[nodiscard]] LoopWindow since(const LoopSnapshot& earlier) const noexcept {
    const auto seconds = [](std::chrono::nanoseconds d) {
      return std::chrono::duration<double>(d).count();
    };
    const auto ratio = [](double num, std::uint64_t den) {
      return den ? num / static_cast<double>(den) : 0.0;
    };
    LoopWindow w;
    w.ticks = ticks - earlier.ticks;
    // From the start the first tick opens the first period; otherwise the window's first period
    // starts at the earlier snapshot's newest tick.
    const bool from_start = earlier.ticks == 0;
    const std::uint64_t periods = from_start ? (ticks ? ticks - 1 : 0) : w.ticks;
    if (periods) w.duration = seconds(last_start - (from_start ? first_start : earlier.last_start));
    w.rate = w.duration > 0 ? static_cast<double>(periods) / w.duration : 0.0;
    w.period_mean = ratio(w.duration, periods);
    w.period_error_mean = ratio(seconds(period_error_sum - earlier.period_error_sum),
                                period_errors - earlier.period_errors);
    w.deadline_misses = deadline_misses - earlier.deadline_misses;
    w.received = received - earlier.received;
    w.round_trip_mean = ratio(seconds(round_trip_sum - earlier.round_trip_sum), w.received);
    w.timeouts = timeouts - earlier.timeouts;
    w.decode_errors = decode_errors - earlier.decode_errors;
    w.transport_errors = transport_errors - earlier.transport_errors;
    w.stale_dropped = stale_dropped - earlier.stale_dropped;
    w.state_faults = state_faults - earlier.state_faults;
    w.not_obeyed = not_obeyed - earlier.not_obeyed;
    w.rejected = rejected - earlier.rejected;
    w.exchanges = w.received + w.timeouts + w.decode_errors + w.transport_errors + w.state_faults +
                  w.not_obeyed;
    w.loss_percent = ratio(100.0 * static_cast<double>(w.exchanges - w.received), w.exchanges);
    return w;
  }
};

//! The passivity layer over a run (PassivityMode::tdpa; all zero with it off). Energies in J.
struct PassivityStats {
  std::uint64_t ticks = 0;            //!< ticks recorded with the layer on
  std::uint64_t operator_active = 0;  //!< ticks the operator-side controller changed the force
  std::uint64_t robot_active = 0;     //!< ticks the robot-side controller changed the setpoint
  double min_energy = 0.0;            //!< J, lowest value of the observer (< 0: generated)
  double dissipated_operator = 0.0;   //!< J, removed by the operator-side controller
  double dissipated_robot = 0.0;      //!< J, removed by the robot-side controller
  double max_damping = 0.0;           //!< N s/m at the tool, largest operator-side damping
  double max_drift = 0.0;             //!< rad, largest |desired - sent| setpoint difference

  //! Adds one tick's figures.
  void add(const PassivityFigures& f) noexcept {
    ++ticks;
    if (f.operator_active) ++operator_active;
    if (f.robot_active) ++robot_active;
    min_energy = std::min(min_energy, f.energy);
    dissipated_operator = f.dissipated_operator;
    dissipated_robot = f.dissipated_robot;
    max_damping = std::max(max_damping, f.damping);
    max_drift = std::max(max_drift, f.drift);
  }
};

//! Loop statistics: the worksheet's table 3.1 and more. One `record_*` per tick, all noexcept.
class LoopStats {
 public:
  using Clock = std::chrono::steady_clock;  //!< the clock of the recorded time points

  //! Nominal period, for deadline-miss counting and the period-error figures.
  explicit LoopStats(
      std::chrono::nanoseconds nominal_period = std::chrono::milliseconds(1)) noexcept
      : nominal_(nominal_period) {}

  //! Start of a tick at time `t` (the loop's clock). Periods are measured start to start.
  void record_tick_start(std::chrono::nanoseconds t) noexcept {
    if (ticks_ > 0) {
      const auto period = t - last_start_;
      period_.add(period);
      if (nominal_.count() > 0) {  // a nominal period of 0 means "as fast as possible"
        const auto error = period > nominal_ ? period - nominal_ : nominal_ - period;
        period_error_.add(error);
        period_error_sum_ += error;
        if (period > nominal_ + nominal_ / 10) ++deadline_misses_;
      }
    }
    if (ticks_ == 0) first_start_ = t;
    last_start_ = t;
    ++ticks_;
  }

  //! Outcome of the tick's exchange; `round_trip` is send -> receive (only for `received`).
  void record_exchange(TickOutcome outcome, std::chrono::nanoseconds round_trip,
                       std::size_t stale_dropped) noexcept {
    stale_dropped_ += stale_dropped;
    switch (outcome) {
      case TickOutcome::received:
        ++received_;
        round_trip_.add(round_trip);
        round_trip_sum_ += round_trip;
        break;
      case TickOutcome::timeout:
        ++timeouts_;
        break;
      case TickOutcome::decode_error:
        ++decode_errors_;
        break;
      case TickOutcome::transport_error:
        ++transport_errors_;
        break;
      case TickOutcome::state_fault:
        ++state_faults_total_;
        break;
      case TickOutcome::not_obeyed:
        ++not_obeyed_;
        break;
    }
  }

  //! An implausible state refused this tick (its cause; TickOutcome::state_fault is recorded
  //! by record_exchange).
  void record_state_fault(StateFault fault) noexcept {
    const auto i = static_cast<std::size_t>(fault);
    if (i < state_faults_.size()) ++state_faults_[i];
  }

  //! Datagrams the tick's drain refused, by cause.
  void record_rejected(const RejectedDatagrams& r) noexcept {
    rejected_.wrong_size += r.wrong_size;
    rejected_.non_finite += r.non_finite;
    rejected_.bad_mask += r.bad_mask;
  }

  //! Time spent computing in the tick (everything except waiting), for the compute budget.
  void record_compute(std::chrono::nanoseconds compute) noexcept { compute_.add(compute); }

  //! The passivity layer's figures of a tick (call only with the layer on).
  void record_passivity(const PassivityFigures& figures) noexcept { passivity_.add(figures); }
  //! The passivity layer over the run (ticks 0: the layer was off).
  [[nodiscard]] const PassivityStats& passivity() const noexcept { return passivity_; }

  //! Ticks recorded.
  [[nodiscard]] std::uint64_t ticks() const noexcept { return ticks_; }
  //! Exchanges that brought a valid state packet.
  [[nodiscard]] std::uint64_t received() const noexcept { return received_; }
  //! Exchanges where nothing arrived before the receive deadline.
  [[nodiscard]] std::uint64_t timeouts() const noexcept { return timeouts_; }
  //! Exchanges whose datagram did not decode (size, NaN/Inf, mask).
  [[nodiscard]] std::uint64_t decode_errors() const noexcept { return decode_errors_; }
  //! Exchanges the operating system refused (send or receive error).
  [[nodiscard]] std::uint64_t transport_errors() const noexcept { return transport_errors_; }
  //! Exchanges whose state decoded but was implausible (never used).
  [[nodiscard]] std::uint64_t state_faults() const noexcept { return state_faults_total_; }
  //! Exchanges whose state showed a motor inactive that the loop had enabled for longer than
  //! the activation timeout: the robot answered but did not obey (never counted as received).
  [[nodiscard]] std::uint64_t not_obeyed() const noexcept { return not_obeyed_; }
  //! Implausible states of one cause (StateFault::none: always 0).
  [[nodiscard]] std::uint64_t state_faults(StateFault fault) const noexcept {
    const auto i = static_cast<std::size_t>(fault);
    return i < state_faults_.size() ? state_faults_[i] : 0;
  }
  //! Datagrams the drains refused, by cause (a refused datagram need not cost an exchange: a
  //! valid one in the same drain still counts as received).
  [[nodiscard]] const RejectedDatagrams& rejected() const noexcept { return rejected_; }
  //! Older datagrams discarded by the transports' drains.
  [[nodiscard]] std::uint64_t stale_dropped() const noexcept { return stale_dropped_; }
  //! Ticks that started later than one nominal period after the previous one.
  [[nodiscard]] std::uint64_t deadline_misses() const noexcept { return deadline_misses_; }
  //! All exchanges: received + timeouts + decode errors + transport errors + state faults +
  //! states not obeyed.
  [[nodiscard]] std::uint64_t exchanges() const noexcept {
    return received_ + timeouts_ + decode_errors_ + transport_errors_ + state_faults_total_ +
           not_obeyed_;
  }
  //! Percentage of exchanges without a valid state packet (table 3.1's "packet loss").
  [[nodiscard]] double loss_percent() const noexcept {
    const auto n = exchanges();
    return n ? 100.0 * static_cast<double>(n - received_) / static_cast<double>(n) : 0.0;
  }
  //! Achieved rate (Hz) from the first to the last tick start.
  [[nodiscard]] double rate() const noexcept {
    if (ticks_ < 2) return 0.0;
    const double span = std::chrono::duration<double>(last_start_ - first_start_).count();
    return span > 0 ? static_cast<double>(ticks_ - 1) / span : 0.0;
  }
  //! Tick start to tick start.
  [[nodiscard]] const DurationStats<>& period() const noexcept { return period_; }
  //! |period - nominal|: the period error the user feels as jitter.
  [[nodiscard]] const DurationStats<>& period_error() const noexcept { return period_error_; }
  //! Send to receive of each exchange that brought a valid state (misses are not included).
  [[nodiscard]] const DurationStats<>& round_trip() const noexcept { return round_trip_; }
  //! Time each tick spent computing (everything but waiting).
  [[nodiscard]] const DurationStats<>& compute() const noexcept { return compute_; }
  //! The nominal period given at construction.
  [[nodiscard]] std::chrono::nanoseconds nominal_period() const noexcept { return nominal_; }

  //! Forgets everything recorded (keeps the nominal period).
  void reset() noexcept { *this = LoopStats{nominal_}; }

  //! The cumulative counters now, about 100 bytes: for per-second figures on another thread
  //! (LoopSnapshot::since) without copying or resetting this object's histograms.
  [[nodiscard]] LoopSnapshot snapshot() const noexcept {
    LoopSnapshot s;
    s.first_start = first_start_;
    s.last_start = last_start_;
    s.ticks = ticks_;
    s.received = received_;
    s.timeouts = timeouts_;
    s.decode_errors = decode_errors_;
    s.transport_errors = transport_errors_;
    s.stale_dropped = stale_dropped_;
    s.state_faults = state_faults_total_;
    s.not_obeyed = not_obeyed_;
    s.rejected = rejected_.total();
    s.deadline_misses = deadline_misses_;
    s.period_errors = period_error_.count();
    s.period_error_sum = period_error_sum_;
    s.round_trip_sum = round_trip_sum_;
    return s;
  }

  //! Table 3.1 layout plus percentiles. Not for the tick (allocates the string).
  [[nodiscard]] std::string to_table() const {
    char buf[1024];
    const auto us = [](double s) { return s * 1e6; };
    char nominal_buf[32];
    std::snprintf(nominal_buf, sizeof nominal_buf, "%.1f Hz",
                  nominal_.count() > 0 ? 1e9 / static_cast<double>(nominal_.count()) : 0.0);
    const std::string nominal = nominal_.count() > 0 ? nominal_buf : "as fast as possible";
    const int n = std::snprintf(
        buf, sizeof buf,
        "rate        %10.1f Hz   (nominal %s)\n"
        "period      mean %8.1f us  std %7.2f us  p99 %7.1f us  max %8.1f us\n"
        "period err  mean %8.2f us  p99 %7.1f us  max %8.1f us  deadline misses %llu\n"
        "round trip  mean %8.1f us  std %7.2f us  p99 %7.1f us  max %8.1f us\n"
        "compute     mean %8.2f us  p99 %7.1f us  max %8.1f us\n"
        "packets     %llu ticks, %llu received, loss %.3f %% (timeouts %llu, decode errors "
        "%llu, transport errors %llu, state faults %llu, not obeyed %llu), stale dropped %llu\n"
        "rejected    %llu datagrams (wrong size %llu, non-finite %llu, bad mask %llu)\n",
        rate(), nominal.c_str(), us(period_.mean()), us(period_.stddev()),
        us(period_.quantile(0.99)), us(period_.max()), us(period_error_.mean()),
        us(period_error_.quantile(0.99)), us(period_error_.max()),
        static_cast<unsigned long long>(deadline_misses_), us(round_trip_.mean()),
        us(round_trip_.stddev()), us(round_trip_.quantile(0.99)), us(round_trip_.max()),
        us(compute_.mean()), us(compute_.quantile(0.99)), us(compute_.max()),
        static_cast<unsigned long long>(ticks_), static_cast<unsigned long long>(received_),
        loss_percent(), static_cast<unsigned long long>(timeouts_),
        static_cast<unsigned long long>(decode_errors_),
        static_cast<unsigned long long>(transport_errors_),
        static_cast<unsigned long long>(state_faults_total_),
        static_cast<unsigned long long>(not_obeyed_),
        static_cast<unsigned long long>(stale_dropped_),
        static_cast<unsigned long long>(rejected_.total()),
        static_cast<unsigned long long>(rejected_.wrong_size),
        static_cast<unsigned long long>(rejected_.non_finite),
        static_cast<unsigned long long>(rejected_.bad_mask));
    std::string table(buf, n > 0 ? static_cast<std::size_t>(std::min<int>(n, sizeof buf - 1)) : 0);
    if (passivity_.ticks > 0) {
      const int m = std::snprintf(
          buf, sizeof buf,
          "passivity   min energy %.3g J; dissipated operator %.3g J, robot %.3g J; controller "
          "active on %llu (operator) and %llu (robot) of %llu ticks; max damping %.3g N s/m, "
          "drift %.3g rad\n",
          passivity_.min_energy, passivity_.dissipated_operator, passivity_.dissipated_robot,
          static_cast<unsigned long long>(passivity_.operator_active),
          static_cast<unsigned long long>(passivity_.robot_active),
          static_cast<unsigned long long>(passivity_.ticks), passivity_.max_damping,
          passivity_.max_drift);
      table.append(buf, m > 0 ? static_cast<std::size_t>(std::min<int>(m, sizeof buf - 1)) : 0);
    }
    return table;
  }

 private:
  std::chrono::nanoseconds nominal_;
  std::chrono::nanoseconds first_start_{0};
  std::chrono::nanoseconds last_start_{0};
  std::uint64_t ticks_ = 0;
  std::uint64_t received_ = 0;
  std::uint64_t timeouts_ = 0;
  std::uint64_t decode_errors_ = 0;
  std::uint64_t transport_errors_ = 0;
  std::uint64_t stale_dropped_ = 0;
  std::uint64_t state_faults_total_ = 0;
  std::uint64_t not_obeyed_ = 0;
  std::array<std::uint64_t, state_fault_count> state_faults_{};
  RejectedDatagrams rejected_{};
  std::uint64_t deadline_misses_ = 0;
  std::chrono::nanoseconds period_error_sum_{0};
  std::chrono::nanoseconds round_trip_sum_{0};
  DurationStats<> period_;
  DurationStats<> period_error_;
  DurationStats<> round_trip_;
  DurationStats<> compute_;
  PassivityStats passivity_{};
};

}  // namespace endohaptics::teleop
