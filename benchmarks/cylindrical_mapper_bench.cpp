// Per-tick cost of the teleoperation mapping (eq. 5.9 position -> setpoints, eq. 5.8 forces ->
// stylus force) and of DH forward kinematics of the Touch (eq. D.1, table D.1). No 2016 baseline:
// the 2016 mapping code is not in the public repository, so there is nothing faithful to compare.
#include <benchmark/benchmark.h>

#include <cmath>
#include <endohaptics/kinematics/cylindrical_mapper.hpp>
#include <endohaptics/kinematics/denavit_hartenberg.hpp>

namespace cylindrical_mapper_bench {

namespace {

using Mapper = endohaptics::kinematics::CylindricalMapper<double>;

void BM_CylindricalMapper_map_position(benchmark::State& st) {
  Mapper mapper;
  Mapper::MotorVector setpoint = Mapper::MotorVector::Zero();
  double t = 0;
  for (auto _ : st) {
    t += 1e-3;
    const Mapper::Vector3 p(0.12 * std::cos(t), 0.12 * std::sin(t), 0.1);
    const auto result = mapper.map_position(p, setpoint);
    benchmark::DoNotOptimize(result);
    benchmark::DoNotOptimize(setpoint);
  }
}
BENCHMARK(BM_CylindricalMapper_map_position);

void BM_CylindricalMapper_map_force(benchmark::State& st) {
  const Mapper mapper;
  const Mapper::MotorVector motor_force(0.3, -0.2, 0.5, -0.5);
  Mapper::Vector3 force = Mapper::Vector3::Zero();
  double theta = 0;
  for (auto _ : st) {
    theta += 1e-3;
    const auto result = mapper.map_force(motor_force, theta, force);
    benchmark::DoNotOptimize(result);
    benchmark::DoNotOptimize(force);
  }
}
BENCHMARK(BM_CylindricalMapper_map_force);

void BM_DhChain_forward_touch_frames(benchmark::State& st) {
  const auto touch = endohaptics::kinematics::geomagic_touch_chain();
  using Touch = decltype(touch);
  Touch::JointVector q = Touch::JointVector::Constant(0.1);
  Touch::Frames frames;
  for (auto _ : st) {
    q[0] += 1e-6;
    const auto status = touch.forward(q, frames);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(frames);
  }
}
BENCHMARK(BM_DhChain_forward_touch_frames);

}  // namespace

}  // namespace cylindrical_mapper_bench
