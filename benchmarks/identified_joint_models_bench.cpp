// The identified models the bridge runs on every motor (estimation::IdentifiedHammersteinWiener:
// the appendix C yaw type at 1 kHz with its free-motion threshold) beside the worksheet's clamp
// model (ClampModel2016, the 2016 yaw preset) in the same run: one joint step, and the whole
// 1 kHz tick of the bridge's estimator with an identified model on every joint against the 2016
// presets (and with the estimator's stiction memory on every joint); plus the tick with roll and
// pitch held as their own 2016 types (the bridge before every slot became one BridgeJointModel),
// to price the common slot type.
#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <array>
#include <endohaptics/estimation/bridge_force_models.hpp>
#include <endohaptics/estimation/clamp_presets.hpp>
#include <endohaptics/estimation/force_models_2016.hpp>
#include <endohaptics/model/presets_2016.hpp>
#include <endohaptics/model/static_nonlinearity.hpp>
#include <optional>

#include "joint_signal_sweep.hpp"

namespace identified_joint_models_bench {

namespace {

namespace est = endohaptics::estimation;
namespace model = endohaptics::model;

using joint_signal_sweep::run_estimator_ticks;
using joint_signal_sweep::run_joint_steps;

// An order-2 model embedded in the 6 states at 1 ms (what endohaptics-identify --order 2 writes
// and the bridge runs), a dead zone on the current, a free-motion threshold of 0.18 N (the demo's
// clamp models: 0.166-0.204 N); with `current_play` > 0 the current passes a play of that half
// width instead of the dead zone (the demo's pitch and clamps: --current-play K_s), with
// `slide` the friction play (model::friction_play: sliding at `slide` plus `viscous` x velocity;
// the demo's roll: --current-play-slide 0.065 --current-play-viscous -0.025).
est::IdentifiedHammersteinWiener<double> identified(double current_play = 0.0,
                                                    std::optional<double> slide = std::nullopt,
                                                    double viscous = 0.0) {
  using SS = model::StateSpace<6, 2, 1>;
  SS::MatrixA A = SS::MatrixA::Zero();
  A.topLeftCorner<2, 2>() << 0.995, 0.01, -0.004, 0.97;
  SS::MatrixB B = SS::MatrixB::Zero();
  B.topRows<2>() << 0.02, -0.001, 0.01, 0.002;
  SS::MatrixC C = SS::MatrixC::Zero();
  C.leftCols<2>() << -2.5, 0.77;
  const SS::MatrixD D{{-0.23, -0.096}};
  using Channels = model::PerChannel<model::Deadzone<double>, 2>;
  const std::array<model::Deadzone<double>, 2> maps{
      model::Deadzone<double>(current_play > 0.0 ? 0.0 : 0.099), model::Deadzone<double>(0.0)};
  return est::IdentifiedHammersteinWiener<double>(
      model::YawForceHW2016<double>(SS(A, B, C, D, 0.001), Channels(maps)),
      model::FreeMotionThreshold<double>(0.18), current_play, slide, viscous);
}

void BM_IdentifiedHW_step(benchmark::State& st) { run_joint_steps(st, identified()); }
BENCHMARK(BM_IdentifiedHW_step);

// The same model with a play of 0.17 A on the current (clamp 1's K_s in the emulator's table).
void BM_IdentifiedHW_step_current_play(benchmark::State& st) {
  run_joint_steps(st, identified(0.17));
}
BENCHMARK(BM_IdentifiedHW_step_current_play);

// The same model with the friction play of the demo's roll (sticks at 0.13 A, slides at 0.065 A
// plus -0.025 A s/rad x velocity).
void BM_IdentifiedHW_step_friction_play(benchmark::State& st) {
  run_joint_steps(st, identified(0.13, 0.065, -0.025));
}
BENCHMARK(BM_IdentifiedHW_step_friction_play);

void BM_IdentifiedHW_reference_Clamp2016_worksheet_step(benchmark::State& st) {
  run_joint_steps(st, est::models_2016().clamp1);
}
BENCHMARK(BM_IdentifiedHW_reference_Clamp2016_worksheet_step);

// Every joint an identified model, advanced on every tick (1 ms models: no decimation), the
// bridge's estimator settings over `settings`, each model's current through a play of
// `current_play` A (0: none).
void run_identified_every_joint(benchmark::State& st, est::ForceEstimatorSettings<double> settings,
                                double current_play = 0.0,
                                std::optional<double> slide = std::nullopt, double viscous = 0.0) {
  const est::BridgeJointModel m(identified(current_play, slide, viscous));
  const est::BridgeForceModels models{m, m, m, m};
  settings.loop_period = 0.001;
  run_estimator_ticks(
      st, est::BridgeForceEstimator(models, est::bridge_estimator_settings(settings, models)));
}

void BM_BridgeTick_identified_every_joint(benchmark::State& st) {
  run_identified_every_joint(st, {});
}
BENCHMARK(BM_BridgeTick_identified_every_joint);

// The same with the stiction memory on every joint (ForceEstimatorSettings::stick_*: the demo's
// constants, examples/demo.sh).
void BM_BridgeTick_identified_every_joint_stiction_memory(benchmark::State& st) {
  est::ForceEstimatorSettings<double> settings;
  settings.stick_travel << 0.0330, 0.0432, 0.0314, 0.0299;
  settings.stick_play.setConstant(0.01745);
  settings.stick_force << 0.458, 0.599, 0.416, 0.397;
  run_identified_every_joint(st, settings);
}
BENCHMARK(BM_BridgeTick_identified_every_joint_stiction_memory);

// The same with a play of 0.17 A on every joint's current (the demo's pitch and clamps).
void BM_BridgeTick_identified_every_joint_current_play(benchmark::State& st) {
  run_identified_every_joint(st, {}, 0.17);
}
BENCHMARK(BM_BridgeTick_identified_every_joint_current_play);

// The same with the friction play of the demo's roll on every joint.
void BM_BridgeTick_identified_every_joint_friction_play(benchmark::State& st) {
  run_identified_every_joint(st, {}, 0.13, 0.065, -0.025);
}
BENCHMARK(BM_BridgeTick_identified_every_joint_friction_play);

void BM_BridgeTick_identified_reference_yaw2016(benchmark::State& st) {
  run_estimator_ticks(st, est::preset_force_estimator(est::ClampPreset::yaw2016, 0.001));
}
BENCHMARK(BM_BridgeTick_identified_reference_yaw2016);

// Before: roll and pitch as their own 2016 types, the clamps in the 5-kind variant of then.
using ClampVariantBefore =
    est::AnyJointForceModel<est::ClampModel2016<double>, est::StallHold<double>,
                            est::PushLoadObserver<double>, est::BidirectionalLoadObserver<double>,
                            est::Clamp2016AsRun<double>>;
void BM_BridgeTick_yaw2016_slots_before(benchmark::State& st) {
  joint_signal_sweep::run_2016_ticks_with_clamp_slot<ClampVariantBefore>(st);
}
BENCHMARK(BM_BridgeTick_yaw2016_slots_before);

}  // namespace

}  // namespace identified_joint_models_bench
