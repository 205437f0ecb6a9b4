// One joint step of the per-joint force models as ForceEstimator drives them (advance + force):
// the stall-hold model (estimation/stall_hold.hpp), the push-load observer
// (estimation/push_load_observer.hpp) and the bidirectional load observer
// (estimation/bidirectional_load_observer.hpp) side by side with today's clamp model, the
// 2016 yaw Hammerstein-Wiener preset run open loop (ClampModel2016). The budget: <= 200 ns
// per joint step.
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <endohaptics/estimation/bidirectional_load_observer.hpp>
#include <endohaptics/estimation/force_models_2016.hpp>
#include <endohaptics/estimation/push_load_observer.hpp>
#include <endohaptics/estimation/stall_hold.hpp>

#include "joint_signal_sweep.hpp"

namespace joint_force_model_bench {

namespace {

namespace est = endohaptics::estimation;

using joint_signal_sweep::sweep;
using joint_signal_sweep::sweep_length;

using joint_signal_sweep::run_joint_steps;

void BM_JointModel_stall_hold(benchmark::State& st) {
  run_joint_steps(st, est::StallHold<double>(est::StallHoldParameters<double>{}));
}
BENCHMARK(BM_JointModel_stall_hold);

void BM_JointModel_push_load_observer(benchmark::State& st) {
  run_joint_steps(st, est::PushLoadObserver<double>(est::PushLoadObserverParameters<double>{}));
}
BENCHMARK(BM_JointModel_push_load_observer);

// The observer's path before the first push, every step: the spindle turns back at 0.5 rad/s
// forever (never pushing), the back-driven map fused with the prior on each sample.
void BM_JointModel_push_load_observer_before_push(benchmark::State& st) {
  est::PushLoadObserverParameters<double> p;
  p.back_current_per_load = 0.8;
  p.back_current_offset = -0.1;
  p.back_variance = 4e-4;
  est::PushLoadObserver<double> model(p);
  const auto signals = sweep();
  std::size_t k = 0;
  double position = 0.0;
  for (auto _ : st) {
    position -= 5e-4;  // 0.5 rad/s at 1 kHz
    const est::JointSignals<double> s{position, -0.5, signals[k].current, 0.0};
    const auto status = model.advance(s);
    const double f = model.force(s);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(f);
    k = (k + 1) % sweep_length;
  }
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_JointModel_push_load_observer_before_push);

// The bidirectional observer with the maps fitted on the UMN grasper (L_4, research note K7): the
// sweep moves it forward and back, so every step runs the stop operators and a Kalman update.
void BM_JointModel_bidirectional_load_observer(benchmark::State& st) {
  est::BidirectionalLoadObserverParameters<double> p;
  p.forward_gain = -1.41e-3;
  p.forward_gain_stroke = -2.3e-4;
  p.forward_offset = 0.066;
  p.backward_gain = -6.1e-4;
  p.backward_offset = -0.09;
  p.backward_offset_stroke = 0.035;
  p.forward_variance = 9000.0;
  p.backward_variance = 30000.0;
  p.friction_variance = 62.0;
  p.load_process_variance = 0.002;
  p.initial_load = -65.8;
  p.initial_variance = 1180.0;
  p.output_shape.setConstant(0.5);
  p.output_shape_per_load.setConstant(0.01);
  run_joint_steps(st, est::BidirectionalLoadObserver<double>(p));
}
BENCHMARK(BM_JointModel_bidirectional_load_observer);

void BM_JointModel_clamp_2016_preset(benchmark::State& st) {
  run_joint_steps(st, est::models_2016<double>().clamp1);
}
BENCHMARK(BM_JointModel_clamp_2016_preset);

}  // namespace

}  // namespace joint_force_model_bench
