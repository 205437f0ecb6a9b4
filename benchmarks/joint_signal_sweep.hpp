// The input every joint-model benchmark steps through (joint_force_model_bench.cpp,
// clamp_2016_as_run_bench.cpp, identified_joint_models_bench.cpp), so their figures compare: 256
// samples of a slow squeeze whose position, velocity and current cross zero, the dead zones and
// the stall threshold; the benchmark loop of one joint step as ForceEstimator drives a model
// (advance, then force); and the loop of the whole estimator tick (every joint on the sweep).
#pragma once

#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <endohaptics/estimation/force_estimator.hpp>
#include <endohaptics/estimation/force_models_2016.hpp>
#include <endohaptics/estimation/joint_force_model.hpp>

namespace joint_signal_sweep {

inline constexpr std::size_t sweep_length = 256;

inline std::array<endohaptics::estimation::JointSignals<double>, sweep_length> sweep() {
  std::array<endohaptics::estimation::JointSignals<double>, sweep_length> s{};
  for (std::size_t k = 0; k < sweep_length; ++k) {
    const double phase = 2.0 * 3.141592653589793 * static_cast<double>(k) / sweep_length;
    s[k] = {0.5 * std::sin(phase), 0.3 * std::cos(phase), 0.6 * std::sin(phase), 0.0};
  }
  return s;
}

//! One joint step per iteration: model.advance then model.force on the sweep's next sample.
template <typename Model>
void run_joint_steps(benchmark::State& st, Model model) {
  const auto signals = sweep();
  std::size_t k = 0;
  for (auto _ : st) {
    const auto status = model.advance(signals[k]);
    const double f = model.force(signals[k]);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(f);
    k = (k + 1) % sweep_length;
  }
  st.SetItemsProcessed(st.iterations());
}

//! One ForceEstimator tick per iteration (4 joints, decimation, gates, snapshot), every joint on
//! the sweep's next sample.
template <typename Estimator>
void run_estimator_ticks(benchmark::State& st, Estimator estimator) {
  const auto signals = sweep();
  typename Estimator::Input in;
  typename Estimator::Forces f;
  std::size_t k = 0;
  for (auto _ : st) {
    const auto& s = signals[k];
    in.position.setConstant(s.position);
    in.velocity.setConstant(s.velocity);
    in.current.setConstant(s.current);
    benchmark::DoNotOptimize(estimator.step(in, f));
    benchmark::DoNotOptimize(f);
    k = (k + 1) % sweep_length;
  }
  st.SetItemsProcessed(st.iterations());
}

//! run_estimator_ticks with the 2016 presets, roll and pitch as their own 2016 types and both
//! clamps in `ClampSlot` (an AnyJointForceModel holding ClampModel2016): the bridge's tick as it
//! was before a change of its slot types, for a benchmark to price the change against.
template <typename ClampSlot>
void run_2016_ticks_with_clamp_slot(benchmark::State& st) {
  namespace est = endohaptics::estimation;
  using Estimator = est::ForceEstimator<est::rate::Decimate, est::RollModel2016<double>,
                                        est::PitchModel2016<double>, ClampSlot>;
  const auto m = est::models_2016();
  est::ForceEstimatorSettings<double> settings;
  settings.loop_period = 0.001;
  run_estimator_ticks(
      st, Estimator({m.roll, m.pitch, ClampSlot(m.clamp1), ClampSlot(m.clamp2)}, settings));
}

}  // namespace joint_signal_sweep
