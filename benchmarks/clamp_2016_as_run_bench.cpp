// The 2016 clamp estimator as it ran (estimation/clamp_2016_as_run.hpp) beside the worksheet's
// clamp model (ClampModel2016, the appendix C yaw Hammerstein-Wiener preset) in the same run:
// one joint step (advance + force), the step through the bridge's BridgeJointModel, and the whole
// 1 kHz tick of the bridge's estimator with each clamp preset (estimation/clamp_presets.hpp);
// plus that tick with the clamp variant as it was before it could hold the as-run model (State
// 23 numbers instead of 42), to price the larger snapshot every tick takes.
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <endohaptics/estimation/bidirectional_load_observer.hpp>
#include <endohaptics/estimation/clamp_2016_as_run.hpp>
#include <endohaptics/estimation/clamp_presets.hpp>
#include <endohaptics/estimation/force_models_2016.hpp>
#include <endohaptics/estimation/push_load_observer.hpp>
#include <endohaptics/estimation/stall_hold.hpp>

#include "joint_signal_sweep.hpp"

namespace clamp_2016_as_run_bench {

namespace {

namespace est = endohaptics::estimation;

using joint_signal_sweep::sweep;
using joint_signal_sweep::sweep_length;

using joint_signal_sweep::run_estimator_ticks;
using joint_signal_sweep::run_joint_steps;

void BM_Clamp2016_worksheet_step(benchmark::State& st) {
  run_joint_steps(st, est::models_2016().clamp1);
}
BENCHMARK(BM_Clamp2016_worksheet_step);

void BM_Clamp2016_as_run_step(benchmark::State& st) {
  run_joint_steps(st, est::Clamp2016AsRun<double>());
}
BENCHMARK(BM_Clamp2016_as_run_step);

// force() alone: what the estimator evaluates on every 1 kHz tick (advance: every 20th).
template <typename Model>
void run_force(benchmark::State& st, const Model& model) {
  const auto signals = sweep();
  std::size_t k = 0;
  for (auto _ : st) {
    benchmark::DoNotOptimize(model.force(signals[k]));
    k = (k + 1) % sweep_length;
  }
  st.SetItemsProcessed(st.iterations());
}
void BM_Clamp2016_worksheet_force(benchmark::State& st) {
  run_force(st, est::models_2016().clamp1);
}
BENCHMARK(BM_Clamp2016_worksheet_force);
void BM_Clamp2016_as_run_force(benchmark::State& st) {
  run_force(st, est::Clamp2016AsRun<double>());
}
BENCHMARK(BM_Clamp2016_as_run_force);

void BM_BridgeJointModel_worksheet_step(benchmark::State& st) {
  run_joint_steps(st, est::BridgeJointModel(est::models_2016().clamp1));
}
BENCHMARK(BM_BridgeJointModel_worksheet_step);

void BM_BridgeJointModel_as_run_step(benchmark::State& st) {
  run_joint_steps(st, est::BridgeJointModel(est::Clamp2016AsRun<double>()));
}
BENCHMARK(BM_BridgeJointModel_as_run_step);

// The whole estimator tick (4 joints, decimation, gates, snapshot) at 1 kHz.

void BM_BridgeTick_yaw2016(benchmark::State& st) {
  run_estimator_ticks(st, est::preset_force_estimator(est::ClampPreset::yaw2016, 0.001));
}
BENCHMARK(BM_BridgeTick_yaw2016);

void BM_BridgeTick_clamp2016_as_run(benchmark::State& st) {
  run_estimator_ticks(st, est::preset_force_estimator(est::ClampPreset::clamp2016_as_run, 0.001));
}
BENCHMARK(BM_BridgeTick_clamp2016_as_run);

// The clamp variant before it held the as-run model: its State is the bidirectional observer's
// 23 numbers.
using ClampVariantBefore =
    est::AnyJointForceModel<est::ClampModel2016<double>, est::StallHold<double>,
                            est::PushLoadObserver<double>, est::BidirectionalLoadObserver<double>>;
void BM_BridgeTick_yaw2016_variant_before(benchmark::State& st) {
  joint_signal_sweep::run_2016_ticks_with_clamp_slot<ClampVariantBefore>(st);
}
BENCHMARK(BM_BridgeTick_yaw2016_variant_before);

}  // namespace

}  // namespace clamp_2016_as_run_bench
