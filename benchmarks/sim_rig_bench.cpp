// SimulatedRig (docs/models/sim.md): cost of simulating 1 ms of the 4-motor 2016 rig, i.e.
// 2 position-loop, ~5.4 speed-loop and 53.6 current-loop/plant ticks per motor. The items
// processed counter is simulated seconds, so items_per_second is the real-time factor.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <endohaptics/sim/simulated_rig.hpp>

namespace sim_rig_bench {

namespace {

namespace sim = endohaptics::sim;

template <typename Scalar>
void advance_1ms(benchmark::State& st) {
  sim::SimulatedRig<4, Scalar> rig(sim::endowrist_2016_rig<4, Scalar>(sim::Environment::tissue));
  endohaptics::protocol::MotorSetpoint<4> setpoint;
  setpoint.enable_mask = 0x0F;
  std::int64_t k = 0;
  for (auto _ : st) {
    // A 0.5 Hz sweep through the tissue contact at +0.3 rad: free motion, contact, release.
    setpoint.position.setConstant(0.6 * std::sin(0.00314159 * static_cast<double>(k++)));
    rig.command(setpoint);
    benchmark::DoNotOptimize(rig.advance(Scalar(1e-3)));
    benchmark::DoNotOptimize(rig.state());
  }
  st.SetItemsProcessed(st.iterations());  // items = simulated ms
  st.counters["realtime_factor"] =
      benchmark::Counter(static_cast<double>(st.iterations()) * 1e-3, benchmark::Counter::kIsRate);
}

void BM_SimulatedRig_advance_1ms(benchmark::State& st) { advance_1ms<double>(st); }
void BM_SimulatedRig_advance_1ms_float(benchmark::State& st) { advance_1ms<float>(st); }

}  // namespace

BENCHMARK(BM_SimulatedRig_advance_1ms);
BENCHMARK(BM_SimulatedRig_advance_1ms_float);

}  // namespace sim_rig_bench
