// The ROS bridge's hand-off on the loop thread, paced at 1 kHz as the loop runs it: a
// ros_bridge::TickMessage built from the tick (TickRecord::from, the system-clock stamp) and
// pushed into the boost::lockfree::spsc_queue that the publishing thread drains once a millisecond
// (examples/ros_bridge/ros1_node.hpp, RosPublisher::on_tick and run). Each hand-off is timed alone
// on the steady clock: handoff_mean_ns, handoff_p99_ns, handoff_max_ns.
//
// `BM_RosHandoff_consumer_other_cpu`: the loop thread on the last CPU the process may use, a
// publisher thread on the first, draining once a millisecond and doing with each message what the
// publisher does in kind (six messages filled with heap-allocated vectors and a name, serialized
// into a buffer), so the queue's and the messages' cache lines move between CPUs as in the
// bridge. `BM_Baseline_ros_handoff_same_thread`: the same hand-off and the same publishing work,
// done by the loop's own thread after each timed push (untimed), so no other CPU touches those
// lines. `_unmapped_ring`: the bridge's arrangement with the ring's pages first touched by the
// timed pushes, as before RosPublisher prefaulted it (teleop::prefault_ring). The counters
// loop_cpu and publisher_cpu show where the threads ran. Run with
// --benchmark_enable_random_interleaving=true so that the repetitions of the two alternate.
#include <benchmark/benchmark.h>

#include <sched.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <boost/lockfree/spsc_queue.hpp>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include <endohaptics/teleop/realtime.hpp>

#include "../examples/ros_bridge/ros_conversion.hpp"
#include "cpu_pinning.hpp"
#include "smoke_pass.hpp"

namespace ros_handoff_bench {

namespace {

namespace tp = endohaptics::teleop;
using Clock = std::chrono::steady_clock;
using Queue = boost::lockfree::spsc_queue<ros_bridge::TickMessage>;

// Ticks per run: a tenth under the smoke pass (smoke_pass.hpp).
std::int64_t run_ticks(std::int64_t full) { return bench::smoke_scaled<std::int64_t>(full, 10); }

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

// The loop thread's hand-off, as RosPublisher::on_tick does it (the once-a-second figures aside):
// the message built by ros_bridge::tick_message, then pushed.
bool hand_off(Queue& queue, const tp::TickResult& r, std::chrono::nanoseconds now) noexcept {
  // The stylus message's stamp is the device's stored value in the bridge: a constant here.
  return queue.push(ros_bridge::tick_message(r, now, /*input_stamp_ns=*/1, /*input_fresh=*/true));
}

// What the publisher does with a message, in kind: six messages filled (heap-allocated vectors
// and a name, as roscpp's message types hold them) and serialized into `wire`. Returns the bytes.
std::size_t publish_like(const ros_bridge::TickMessage& m, std::vector<std::uint8_t>& wire) {
  std::size_t bytes = 0;
  for (int k = 0; k < 6; ++k) {
    std::vector<double> fields;
    fields.reserve(24);
    fields.push_back(m.record.time);
    fields.push_back(static_cast<double>(m.wall_ns));
    for (int j = 0; j < tp::loop_motors; ++j) {
      fields.push_back(m.record.setpoint[j]);
      fields.push_back(m.record.position[j]);
      fields.push_back(m.record.velocity[j]);
      fields.push_back(m.record.current[j]);
      fields.push_back(m.record.motor_force[j]);
    }
    const std::string name = "/EW/topic_" + std::to_string(k);
    wire.resize(fields.size() * sizeof(double) + name.size());
    std::memcpy(wire.data(), fields.data(), fields.size() * sizeof(double));
    std::memcpy(wire.data() + fields.size() * sizeof(double), name.data(), name.size());
    bytes += wire.size();
  }
  return bytes;
}

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
  st.counters["loop_cpu"] = ::sched_getcpu();
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
  const bench::Cpus cpus = bench::allowed_cpus();
  const bench::PinnedTo loop_cpu(cpus.last);
  Queue queue(4096);
  tp::prefault_ring(queue, ros_bridge::TickMessage{});  // as RosPublisher does
  std::vector<std::uint8_t> wire;
  std::size_t bytes = 0;
  paced_handoffs(st, queue, [&] {
    queue.consume_all([&](const auto& m) { bytes += publish_like(m, wire); });
  });
  st.counters["publisher_cpu"] = ::sched_getcpu();
  benchmark::DoNotOptimize(bytes);
}

// The bridge's arrangement; `mapped`: the ring prefaulted as RosPublisher does (false: as it was
// before, its pages first touched by the timed pushes).
void consumer_other_cpu(benchmark::State& st, bool mapped) {
  const bench::Cpus cpus = bench::allowed_cpus();  // before this thread pins itself
  Queue queue(4096);
  if (mapped) tp::prefault_ring(queue, ros_bridge::TickMessage{});
  std::atomic<bool> done{false};
  std::atomic<int> publisher_cpu{-1};
  std::size_t bytes = 0;
  std::thread publisher([&] {
    const bench::PinnedTo other(cpus.first);
    publisher_cpu.store(::sched_getcpu());
    std::vector<std::uint8_t> wire;
    while (!done.load(std::memory_order_relaxed)) {
      queue.consume_all([&](const auto& m) { bytes += publish_like(m, wire); });
      std::this_thread::sleep_for(std::chrono::milliseconds(1));  // a batch per wake-up
    }
  });
  {
    const bench::PinnedTo loop_cpu(cpus.last);
    paced_handoffs(st, queue, [] {});
  }
  done.store(true);
  publisher.join();
  st.counters["publisher_cpu"] = publisher_cpu.load();
  benchmark::DoNotOptimize(bytes);
}

void BM_RosHandoff_consumer_other_cpu(benchmark::State& st) { consumer_other_cpu(st, true); }
void BM_RosHandoff_consumer_other_cpu_unmapped_ring(benchmark::State& st) {
  consumer_other_cpu(st, false);
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

BENCHMARK(BM_RosHandoff_consumer_other_cpu_unmapped_ring)
    ->Arg(run_ticks(3000))
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace ros_handoff_bench
