// The ROS bridge's hand-off on the loop thread, paced at 1 kHz as the loop runs it: a
// ros_bridge::TickMessage built from the tick (TickRecord::from, the system-clock stamp) and
// pushed into the boost::lockfree::spsc_queue that the publishing thread drains once a millisecond
// (examples/ros_bridge/ros1_node.hpp, RosPublisher::on_tick and run). Each hand-off is timed alone
// on the steady clock: handoff_mean_ns, handoff_p99_ns, handoff_max_ns.
//
// Baseline (`BM_Baseline_ros_handoff_same_thread`): the same hand-off with the queue drained by
// this thread after each timed push, so no other CPU ever touches the queue's or the messages'
// cache lines. `BM_RosHandoff_consumer_other_cpu`: a consumer thread on another CPU drains and
// reads every message once a millisecond, as the publisher does; the producer stays on the last
// CPU it may use (the loop's CPU in the ROS tests). The difference between the two is what the
// publisher's reading costs the loop (cache lines moving between CPUs), the one suspect of the ROS
// bridge's p99 period error docs/ros.md had not timed.
#include <benchmark/benchmark.h>

#include <sched.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <boost/lockfree/spsc_queue.hpp>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <string_view>
#include <thread>
#include <vector>

#include "../examples/ros_bridge/ros_conversion.hpp"

namespace ros_handoff_bench {

namespace {

namespace tp = endohaptics::teleop;
using Clock = std::chrono::steady_clock;
using Queue = boost::lockfree::spsc_queue<ros_bridge::TickMessage>;

// Ticks per run (a tenth under the CTest smoke pass, as loopback_bench.cpp does).
std::int64_t run_ticks(std::int64_t full) {
  const char* smoke = std::getenv("ENDOHAPTICS_BENCH_SMOKE");
  return smoke != nullptr && std::string_view(smoke) == "1" ? full / 10 : full;
}

// A tick as the loop produces it with the link up: every field the record copies set.
tp::TickResult sample_tick() {
  tp::TickResult r;
  r.status = tp::TickStatus::ok;
  r.link = tp::LinkState::up;
  r.force_scale = 1.0;
  r.setpoint << 0.1, -0.2, 0.3, -0.3;
  r.enable_mask = 0x0f;
  r.motor_force << 0.5, -0.25, 1.5, -1.0;
  r.stylus_force = Eigen::Vector3d(0.2, -0.1, 0.4);
  r.round_trip = std::chrono::microseconds(90);
  return r;
}

// The loop thread's hand-off, as RosPublisher::on_tick does it (the once-a-second figures aside).
bool hand_off(Queue& queue, const tp::TickResult& r, std::chrono::nanoseconds now) noexcept {
  ros_bridge::TickMessage m;
  m.record = tp::TickRecord::from(r, now);
  m.wall_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                  std::chrono::system_clock::now().time_since_epoch())
                  .count();
  m.input_stamp_ns = m.wall_ns - 200'000;
  m.input_fresh = true;
  m.valid_state = true;
  return queue.push(m);
}

// What a publisher reads of each message before it serializes it.
double read_message(const ros_bridge::TickMessage& m) noexcept {
  double sum = m.record.time + static_cast<double>(m.wall_ns) + m.record.force_scale;
  for (int j = 0; j < tp::loop_motors; ++j) {
    sum += m.record.setpoint[j] + m.record.motor_force[j] + m.record.position[j] +
           m.record.velocity[j] + m.record.current[j];
  }
  return sum;
}

// Pins the calling thread to one CPU of those it may use (the last or the first); restores the
// old mask at the end. Does nothing on a one-CPU machine.
class PinnedTo {
 public:
  explicit PinnedTo(bool last) {
    (void)::sched_getaffinity(0, sizeof saved_, &saved_);
    if (CPU_COUNT(&saved_) < 2) return;
    int chosen = -1;
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
      if (CPU_ISSET(static_cast<unsigned>(cpu), &saved_)) {
        chosen = cpu;
        if (!last) break;
      }
    }
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(static_cast<unsigned>(chosen), &one);
    (void)::sched_setaffinity(0, sizeof one, &one);
    pinned_ = true;
  }
  ~PinnedTo() {
    if (pinned_) (void)::sched_setaffinity(0, sizeof saved_, &saved_);
  }
  PinnedTo(const PinnedTo&) = delete;
  PinnedTo& operator=(const PinnedTo&) = delete;

 private:
  cpu_set_t saved_{};
  bool pinned_ = false;
};

// Runs `ticks` hand-offs paced at 1 kHz (absolute deadlines), each timed alone; `after` runs
// untimed after each one (the same-thread drain, or nothing).
template <typename After>
void paced_handoffs(benchmark::State& st, Queue& queue, After&& after) {
  const auto ticks = st.range(0);
  const tp::TickResult r = sample_tick();
  std::vector<std::int64_t> took(static_cast<std::size_t>(ticks));
  std::int64_t dropped = 0;
  for (auto _ : st) {
    timespec next{};
    ::clock_gettime(CLOCK_MONOTONIC, &next);
    for (std::int64_t k = 0; k < ticks; ++k) {
      next.tv_nsec += 1'000'000;
      if (next.tv_nsec >= 1'000'000'000) {
        next.tv_nsec -= 1'000'000'000;
        ++next.tv_sec;
      }
      ::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
      const auto t0 = Clock::now();
      if (!hand_off(queue, r, t0.time_since_epoch())) ++dropped;
      const auto t1 = Clock::now();
      took[static_cast<std::size_t>(k)] = (t1 - t0).count();
      after();
    }
  }
  std::sort(took.begin(), took.end());
  double sum = 0;
  for (const auto t : took) sum += static_cast<double>(t);
  st.counters["handoff_mean_ns"] = sum / static_cast<double>(took.size());
  st.counters["handoff_p99_ns"] =
      static_cast<double>(took[static_cast<std::size_t>(0.99 * static_cast<double>(ticks - 1))]);
  st.counters["handoff_max_ns"] = static_cast<double>(took.back());
  st.counters["dropped"] = static_cast<double>(dropped);
  st.SetItemsProcessed(ticks * st.iterations());
}

void BM_Baseline_ros_handoff_same_thread(benchmark::State& st) {
  const PinnedTo loop_cpu(/*last=*/true);
  Queue queue(4096);
  double sink = 0;
  paced_handoffs(st, queue,
                 [&] { queue.consume_all([&](const auto& m) { sink += read_message(m); }); });
  benchmark::DoNotOptimize(sink);
}

void BM_RosHandoff_consumer_other_cpu(benchmark::State& st) {
  const PinnedTo loop_cpu(/*last=*/true);
  Queue queue(4096);
  std::atomic<bool> done{false};
  double sink = 0;
  std::thread publisher([&] {
    const PinnedTo other(/*last=*/false);
    while (!done.load(std::memory_order_relaxed)) {
      queue.consume_all([&](const auto& m) { sink += read_message(m); });
      std::this_thread::sleep_for(std::chrono::milliseconds(1));  // a batch per wake-up
    }
  });
  paced_handoffs(st, queue, [] {});
  done.store(true);
  publisher.join();
  benchmark::DoNotOptimize(sink);
}

}  // namespace

BENCHMARK(BM_Baseline_ros_handoff_same_thread)
    ->Arg(run_ticks(3000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_RosHandoff_consumer_other_cpu)
    ->Arg(run_ticks(3000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace ros_handoff_bench
