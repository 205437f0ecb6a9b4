// One tick of the yaw force model (appendix C.1-C.3, 6 states, 2 inputs, table 5.2 dead zone on
// the current) as HammersteinWiener with fixed sizes, against the same model written the 2016
// way: Eigen::MatrixXd / VectorXd, a heap-allocated temporary for every intermediate vector.
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <endohaptics/model/presets_2016.hpp>
#include <utility>

namespace hammerstein_wiener_bench {

namespace {

namespace m = endohaptics::model;

// 256 samples of a slow current/velocity sweep that crosses the dead zone, reused cyclically.
constexpr std::size_t sweep_length = 256;
std::array<Eigen::Vector2d, sweep_length> input_sweep() {
  std::array<Eigen::Vector2d, sweep_length> u;
  for (std::size_t k = 0; k < sweep_length; ++k) {
    const double phase = 2.0 * 3.141592653589793 * static_cast<double>(k) / sweep_length;
    u[k] = Eigen::Vector2d{0.6 * std::sin(phase), 0.3 * std::cos(phase)};
  }
  return u;
}

// The 2016 structure: dynamic matrices, the dead zone returning a new vector, y and the next
// state built from temporaries (each VectorXd result is a heap allocation).
class Baseline2016HammersteinWiener {
 public:
  Baseline2016HammersteinWiener(Eigen::MatrixXd A, Eigen::MatrixXd B, Eigen::MatrixXd C,
                                Eigen::MatrixXd D, double deadzone)
      : A_(std::move(A)),
        B_(std::move(B)),
        C_(std::move(C)),
        D_(std::move(D)),
        x_(Eigen::VectorXd::Zero(A_.rows())),
        deadzone_(deadzone) {}

  Eigen::VectorXd step(const Eigen::VectorXd& u) {
    Eigen::VectorXd v = u;
    if (v(0) > deadzone_) {
      v(0) -= deadzone_;
    } else if (v(0) < -deadzone_) {
      v(0) += deadzone_;
    } else {
      v(0) = 0.0;
    }
    Eigen::VectorXd y = C_ * x_ + D_ * v;
    Eigen::VectorXd next = A_ * x_ + B_ * v;
    x_ = next;
    return y;
  }

 private:
  Eigen::MatrixXd A_, B_, C_, D_;
  Eigen::VectorXd x_;
  double deadzone_;
};

void BM_HammersteinWiener_step(benchmark::State& st) {
  auto model = m::yaw_force_2016_hw();
  const auto inputs = input_sweep();
  std::size_t k = 0;
  for (auto _ : st) {
    const Eigen::Matrix<double, 1, 1> y = model.step(inputs[k]);
    benchmark::DoNotOptimize(y);
    k = (k + 1) % sweep_length;
  }
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_HammersteinWiener_step);

void BM_HammersteinWiener_update(benchmark::State& st) {
  auto model = m::yaw_force_2016_hw();
  const auto inputs = input_sweep();
  Eigen::Matrix<double, 1, 1> y;
  std::size_t k = 0;
  for (auto _ : st) {
    const m::NumericStatus status = model.update(inputs[k], y);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(y);
    k = (k + 1) % sweep_length;
  }
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_HammersteinWiener_update);

void BM_Baseline2016_hammerstein_wiener_step(benchmark::State& st) {
  const auto linear = m::yaw_force_2016();
  Baseline2016HammersteinWiener model(linear.A(), linear.B(), linear.C(), linear.D(),
                                      m::yaw_static_friction_2016);
  const auto inputs = input_sweep();
  std::array<Eigen::VectorXd, sweep_length> dynamic_inputs;  // as received from ROS messages
  for (std::size_t i = 0; i < sweep_length; ++i) dynamic_inputs[i] = inputs[i];
  std::size_t k = 0;
  for (auto _ : st) {
    const Eigen::VectorXd y = model.step(dynamic_inputs[k]);
    benchmark::DoNotOptimize(y.data());
    k = (k + 1) % sweep_length;
  }
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_Baseline2016_hammerstein_wiener_step);

}  // namespace

}  // namespace hammerstein_wiener_bench
