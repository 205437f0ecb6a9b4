// Subspace identification (identification/subspace.hpp) of a 6th-order, 2-input, 1-output
// system (the appendix C yaw model) from 10,000 samples with 1 % output noise: default horizon
// (15 block rows), MOESP, plus the other weightings and the automatic order. Goal: < 100 ms.
// No 2016 baseline: the worksheet identified its models with MATLAB's n4sid (section 4.2).
#include <benchmark/benchmark.h>

#include <cmath>
#include <endohaptics/identification/subspace.hpp>
#include <endohaptics/model/presets_2016.hpp>
#include <random>

#include "smoke_pass.hpp"

namespace subspace_bench {

namespace {

namespace id = endohaptics::identification;

struct Data {
  Eigen::MatrixXd u;
  Eigen::MatrixXd y;
};

const Data& yaw_data() {
  static const Data data = [] {
    // A tenth under the smoke pass (smoke_pass.hpp; the `samples` counter shows it).
    const int samples = bench::smoke_scaled(10000, 10);
    std::mt19937 rng(2016);
    std::normal_distribution<double> normal(0.0, 1.0);
    Data d;
    d.u.resize(samples, 2);
    for (int k = 0; k < samples; ++k) {
      d.u(k, 0) = 0.3 * normal(rng);  // current, A
      d.u(k, 1) = 2.0 * normal(rng);  // velocity, rad/s
    }
    d.y = id::simulate(endohaptics::model::yaw_force_2016(), d.u, Eigen::VectorXd::Zero(6));
    const double sd = std::sqrt((d.y.array() - d.y.mean()).square().mean());
    for (int k = 0; k < samples; ++k) d.y(k, 0) += 0.01 * sd * normal(rng);
    return d;
  }();
  return data;
}

void run(benchmark::State& state, id::Weighting weighting, int order) {
  const Data& d = yaw_data();
  id::SubspaceOptions options;
  options.weighting = weighting;
  options.order = order;
  options.sample_time = 0.02;
  int chosen = 0;
  for (auto _ : state) {
    const id::SubspaceModel m = id::identify(d.u, d.y, options);
    chosen = m.order;
    benchmark::DoNotOptimize(m.state_space.A().data());
  }
  state.counters["order"] = chosen;
  state.counters["samples"] = static_cast<double>(d.u.rows());
}

void BM_Subspace_identify_order6_2in_10k(benchmark::State& state) {
  run(state, id::Weighting::moesp, 6);
}
BENCHMARK(BM_Subspace_identify_order6_2in_10k)->Unit(benchmark::kMillisecond);

void BM_Subspace_identify_n4sid_order6_2in_10k(benchmark::State& state) {
  run(state, id::Weighting::n4sid, 6);
}
BENCHMARK(BM_Subspace_identify_n4sid_order6_2in_10k)->Unit(benchmark::kMillisecond);

void BM_Subspace_identify_cva_order6_2in_10k(benchmark::State& state) {
  run(state, id::Weighting::cva, 6);
}
BENCHMARK(BM_Subspace_identify_cva_order6_2in_10k)->Unit(benchmark::kMillisecond);

void BM_Subspace_identify_auto_order_2in_10k(benchmark::State& state) {
  run(state, id::Weighting::moesp, 0);
}
BENCHMARK(BM_Subspace_identify_auto_order_2in_10k)->Unit(benchmark::kMillisecond);

}  // namespace

}  // namespace subspace_bench
