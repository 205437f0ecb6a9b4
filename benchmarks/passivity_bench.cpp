// The passivity layer's cost per tick (budget <= 50 ns): the TeleopLoop tick over an
// in-memory canned sbRIO with PassivityMode off and tdpa side by side (same parts, same inputs),
// and the TimeDomainPassivity calls of one tick alone, with the combined observer and with the
// per-direction observers the sweep runs on the sensorless estimate (with and without an
// estimate tolerance); beside them, in the same run, one step of the 2016 clamp model through the
// bridge's BridgeJointModel (the yaw2016 preset), the reference docs/performance.md divides by.
#include <benchmark/benchmark.h>

#include <endohaptics/estimation/bridge_force_models.hpp>
#include <endohaptics/estimation/force_models_2016.hpp>
#include <endohaptics/kinematics/cylindrical_mapper.hpp>
#include <endohaptics/teleop/passivity.hpp>
#include <endohaptics/teleop/teleop_loop.hpp>
#include <endohaptics/transport/in_memory_transport.hpp>

#include "joint_signal_sweep.hpp"

namespace passivity_bench {

namespace {

namespace transport = endohaptics::transport;
namespace tp = endohaptics::teleop;
using Codec = endohaptics::protocol::PacketCodec<4>;

// Replies to every setpoint with a state whose clamp position and current move: the observer
// and the controllers see motion and force on every tick.
struct MovingSbrio {
  Codec::StateBytes reply{};
  int t = 0;
  template <typename Reply>
  void operator()(std::span<const std::byte>, Reply& out) noexcept {
    Codec::State s;
    const double phase = 1e-3 * (t++ % 1000);
    s.position << 0.1, -0.2, 0.3 + 0.01 * phase, -0.3;
    s.current << 0.4, 0.5, 0.6 + 0.2 * phase, -0.6;
    s.active_mask = 0x0F;
    if (Codec::encode_state(s, reply) == endohaptics::protocol::CodecStatus::ok) {
      (void)out.send(reply);
    }
  }
};

// A stylus pressing in and out along the radius (clamps close and open).
struct PressingDevice {
  int t = 0;
  tp::DeviceStatus read(tp::StylusSample& s) noexcept {
    s.position = Eigen::Vector3d(0.1 + 1e-5 * (t++ % 200), 0.12, 0.02);
    return tp::DeviceStatus::ok;
  }
  tp::DeviceStatus command_force(const Eigen::Vector3d& f) noexcept {
    benchmark::DoNotOptimize(f);
    return tp::DeviceStatus::ok;
  }
};

struct EffortEstimator {
  bool estimate(const tp::MotorState4& m, const tp::MotorVector&, tp::MotorVector& f) noexcept {
    f = -0.5 * m.current;
    return true;
  }
  void reset() noexcept {}
};

void tick(benchmark::State& st, tp::PassivityMode mode,
          tp::PassivityObserver observer = tp::PassivityObserver::combined) {
  transport::RespondingTransport<MovingSbrio> transport{MovingSbrio{}};
  PressingDevice device;
  EffortEstimator estimator;
  endohaptics::kinematics::CylindricalMapper<> mapper;
  endohaptics::SteadyClock clock;
  tp::TeleopLoopConfig config;
  config.passivity.mode = mode;
  config.passivity.round_trip_ticks = 100;
  config.passivity.observer = observer;
  tp::TeleopLoop loop(transport, device, estimator, mapper, clock, config);
  std::uint64_t active = 0;
  for (auto _ : st) {
    const auto r = loop.tick();
    active += r.passivity.operator_active || r.passivity.robot_active ? 1 : 0;
    benchmark::DoNotOptimize(r.stylus_force);
  }
  st.counters["pc_active"] =
      benchmark::Counter(static_cast<double>(active), benchmark::Counter::kAvgIterations);
}

void BM_TeleopLoop_tick_passivity_off(benchmark::State& st) { tick(st, tp::PassivityMode::off); }
BENCHMARK(BM_TeleopLoop_tick_passivity_off);
void BM_TeleopLoop_tick_passivity_tdpa(benchmark::State& st) { tick(st, tp::PassivityMode::tdpa); }
BENCHMARK(BM_TeleopLoop_tick_passivity_tdpa);
void BM_TeleopLoop_tick_passivity_tdpa_per_direction(benchmark::State& st) {
  tick(st, tp::PassivityMode::tdpa, tp::PassivityObserver::per_direction);
}
BENCHMARK(BM_TeleopLoop_tick_passivity_tdpa_per_direction);

// The layer alone: the five calls the loop makes per tick, 100 ms round trip, a delayed spring.
void run_layer(benchmark::State& st, tp::PassivityConfig config) {
  config.mode = tp::PassivityMode::tdpa;
  config.round_trip_ticks = 100;
  tp::TimeDomainPassivity tdpa(config);
  using Vector = tp::TimeDomainPassivity::Vector;
  tdpa.reset(Vector::Zero());
  Vector out, rendered, force = Vector::Zero();
  int t = 0;
  for (auto _ : st) {
    const int phase = t++ % 400;  // a triangle wave: 0.4 s period, 0..0.1 rad
    const double q = 5e-4 * (phase < 200 ? phase : 400 - phase);
    const Vector desired = Vector::Constant(q);
    tdpa.track_desired(desired);
    (void)tdpa.shape_setpoint(desired, force, out);
    tdpa.commit(out);
    force = -5.0 * out.cwiseMax(0.0);
    tdpa.observe_robot(out, force);
    benchmark::DoNotOptimize(tdpa.shape_force(force, 1e-3, rendered));
    benchmark::DoNotOptimize(rendered);
  }
}
void BM_TimeDomainPassivity_tick(benchmark::State& st) { run_layer(st, {}); }
BENCHMARK(BM_TimeDomainPassivity_tick);
// As the sweep runs it on the sensorless estimate (sim/passivity_sweep.hpp).
void BM_TimeDomainPassivity_tick_per_direction(benchmark::State& st) {
  tp::PassivityConfig config;
  config.observer = tp::PassivityObserver::per_direction;
  config.gain_recovery_rate = 0.05;
  run_layer(st, config);
}
BENCHMARK(BM_TimeDomainPassivity_tick_per_direction);
// ... with an estimate tolerance and the recovery while the hand absorbs.
void BM_TimeDomainPassivity_tick_per_direction_tolerant(benchmark::State& st) {
  tp::PassivityConfig config;
  config.observer = tp::PassivityObserver::per_direction;
  config.estimate_tolerance = tp::TimeDomainPassivity::Vector::Constant(0.05);
  config.recover_while_absorbing = true;
  run_layer(st, config);
}
BENCHMARK(BM_TimeDomainPassivity_tick_per_direction_tolerant);

// The reference: one step (advance + force) of the 2016 clamp model (appendix C yaw) through
// the bridge's BridgeJointModel, as the yaw2016 preset runs it.
void BM_Passivity_reference_BridgeJointModel_yaw2016_step(benchmark::State& st) {
  namespace est = endohaptics::estimation;
  joint_signal_sweep::run_joint_steps(st, est::BridgeJointModel(est::models_2016().clamp1));
}
BENCHMARK(BM_Passivity_reference_BridgeJointModel_yaw2016_step);

}  // namespace

}  // namespace passivity_bench
