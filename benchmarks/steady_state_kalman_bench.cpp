// SteadyStateKalman (fixed-size, constant gain from the DARE, worksheet 4.4 / 6.2) against the
// 2016 way: Eigen::MatrixXd and a time-varying Kalman filter that recomputes P and the gain with
// a matrix inverse every step. Same model, same measurement stream, one tick = update + predict.
// Model: worksheet appendix C yaw force model (C.1)-(C.3), 6 states, 2 inputs (current,
// velocity); 2 synthetic measurement rows (the worksheet does not list the augmented C).
#include <benchmark/benchmark.h>

#include <Eigen/Dense>
#include <array>
#include <cstddef>
#include <endohaptics/estimation/steady_state_kalman.hpp>
#include <endohaptics/model/state_space.hpp>
#include <random>

namespace steady_state_kalman_bench {

namespace {

using Model = endohaptics::model::StateSpace<6, 2, 1>;
using Filter = endohaptics::estimation::SteadyStateKalman<Model, 2>;

Model yaw_model() {
  Model::MatrixA A;
  A << 0.9745, -0.3699, -0.0620, 0.2917, 0.5007, -5.5391,   //
      -0.0002, 1.0135, 0.8285, -0.3743, -1.4557, -2.0967,   //
      -0.0002, -0.0123, 0.9149, -1.1440, -0.9316, -2.7853,  //
      -0.0001, -0.0002, 0.0275, 0.7842, 1.6365, 1.8560,     //
      0.0000, -0.0001, -0.0019, -0.0809, 0.8869, 2.4092,    //
      0.0000, -0.0000, 0.0001, 0.0080, -0.0583, 0.8887;
  Model::MatrixB B;
  B << 1.9790, 0.0335, -2.4107, 0.9244, 12.9892, -0.8068, 0.0178, 0.3667, 1.8671, -0.1057, -0.0295,
      -0.0104;
  Model::MatrixC C;
  C << -0.3687, -0.4929, 0.5447, 0.4463, -0.2808, 0.1893;
  return Model(A, B, C, Model::MatrixD::Zero(), 0.01);
}

Filter::MeasurementC measurement_rows() {
  Filter::MeasurementC Cm;
  Cm << 0.3, -0.2, 0.1, 0.0, 0.0, 0.0,  //
      0.0, 0.0, 0.0, 0.5, 0.2, 0.1;
  return Cm;
}

Filter::ProcessNoise process_noise() {
  return Eigen::Matrix<double, 6, 1>(1e-3, 1e-3, 1e-3, 1e-4, 1e-4, 1e-5).asDiagonal();
}

Filter::MeasurementNoise measurement_noise() {
  Filter::MeasurementNoise R;
  R << 0.05, 0.0, 0.0, 0.02;
  return R;
}

// A cyclic stream of (z, u) samples so nothing folds into constants.
struct Stream {
  static constexpr std::size_t size = 1024;
  std::array<Filter::Measurement, size> z;
  std::array<Filter::Input, size> u;
  Stream() {
    std::mt19937_64 rng(2016);
    std::normal_distribution<double> normal;
    for (std::size_t i = 0; i < size; ++i) {
      z[i] = Filter::Measurement(normal(rng), normal(rng));
      u[i] = Filter::Input(normal(rng), normal(rng));
    }
  }
};

void BM_SteadyStateKalman_update(benchmark::State& st) {
  Filter filter(yaw_model(), measurement_rows(), Filter::MeasurementD::Zero(), process_noise(),
                measurement_noise());
  const Stream stream;
  std::size_t i = 0;
  int bad = 0;
  for (auto _ : st) {
    bad += filter.update(stream.z[i], stream.u[i]) != endohaptics::estimation::NumericStatus::ok;
    bad += filter.predict(stream.u[i]) != endohaptics::estimation::NumericStatus::ok;
    benchmark::DoNotOptimize(filter.state());
    i = (i + 1) % Stream::size;
  }
  if (bad != 0) st.SkipWithError("filter refused a sample");
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_SteadyStateKalman_update);

// The 2016 way: dynamic-size matrices, P and K recomputed with an explicit inverse every tick.
void BM_Baseline2016_kalman_update(benchmark::State& st) {
  const Model model = yaw_model();
  const Eigen::MatrixXd A = model.A();
  const Eigen::MatrixXd B = model.B();
  const Eigen::MatrixXd C = measurement_rows();
  const Eigen::MatrixXd D = Eigen::MatrixXd::Zero(2, 2);
  const Eigen::MatrixXd Q = process_noise();
  const Eigen::MatrixXd R = measurement_noise();
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(6, 6);
  Eigen::MatrixXd P = Q;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(6);
  const Stream stream;
  std::size_t i = 0;
  for (auto _ : st) {
    const Eigen::VectorXd z = stream.z[i];
    const Eigen::VectorXd u = stream.u[i];
    // Measurement update.
    const Eigen::MatrixXd S = C * P * C.transpose() + R;
    const Eigen::MatrixXd K = P * C.transpose() * S.inverse();
    x = x + K * (z - C * x - D * u);
    P = (I - K * C) * P;
    // Time update.
    x = A * x + B * u;
    P = A * P * A.transpose() + Q;
    benchmark::DoNotOptimize(x.data());
    benchmark::DoNotOptimize(P.data());
    i = (i + 1) % Stream::size;
  }
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_Baseline2016_kalman_update);

// Configuration time, for scale: the DARE (SDA) and the gain, once per filter.
void BM_SteadyStateKalman_construct(benchmark::State& st) {
  const Model model = yaw_model();
  const auto Cm = measurement_rows();
  const auto Q = process_noise();
  const auto R = measurement_noise();
  for (auto _ : st) {
    Filter filter(model, Cm, Filter::MeasurementD::Zero(), Q, R);
    benchmark::DoNotOptimize(filter.gain());
  }
}
BENCHMARK(BM_SteadyStateKalman_construct);

}  // namespace

}  // namespace steady_state_kalman_bench
