// ForceEstimator (fixed-size models, rate policy, friction gate) against the force estimation
// written the way the 2016 code did it (dynamic Eigen matrices, a time-varying Kalman filter that
// recomputes its gain with a matrix inverse every step, temporaries allocated every step), on the
// same 1 kHz joint-state sequence, in the same run.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstddef>
#include <endohaptics/estimation/force_estimator.hpp>
#include <vector>

namespace force_estimator_bench {

namespace {

namespace est = endohaptics::estimation;
namespace m = endohaptics::model;
using State = est::JointState<double>;

// 1000 ticks of a grip-and-move sequence: every gate opens and closes now and then.
std::vector<State> inputs() {
  std::vector<State> out(1000);
  for (std::size_t k = 0; k < out.size(); ++k) {
    const double t = 0.001 * static_cast<double>(k);
    State& s = out[k];
    s.current << 0.8 * std::sin(6 * t), 0.3 * std::sin(9 * t), -0.4 * std::sin(5 * t),
        0.4 * std::sin(5 * t);
    s.velocity << 0.2 * std::cos(6 * t), 0.1 * std::cos(9 * t), -0.1 * std::cos(5 * t),
        0.1 * std::cos(5 * t);
    s.position = 0.05 * s.velocity;
    s.setpoint = s.position.array() - 0.02 * s.current.array();
  }
  return out;
}

template <typename Estimator>
void run(benchmark::State& st, Estimator& estimator) {
  const std::vector<State> in = inputs();
  typename Estimator::Forces forces = Estimator::Forces::Zero();
  std::size_t k = 0;
  for (auto _ : st) {
    const est::NumericStatus status = estimator.step(in[k], forces);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(forces);
    k = k + 1 == in.size() ? 0 : k + 1;
  }
}

// The default estimator at 1 kHz: appendix C models decimated 20:1, table 5.2 gates.
void BM_ForceEstimator_step(benchmark::State& st) {
  est::ForceEstimator<est::rate::Decimate> estimator;
  run(st, estimator);
}
BENCHMARK(BM_ForceEstimator_step);

// Every model stepped on every call (rate::SameRate at the models' 0.02 s): the cost of the one
// tick in 20 on which the decimating estimator steps its models.
void BM_ForceEstimator_step_model_update(benchmark::State& st) {
  est::ForceEstimatorSettings<double> settings;
  settings.loop_period = 0.02;
  est::ForceEstimator<est::rate::SameRate> estimator(settings);
  run(st, estimator);
}
BENCHMARK(BM_ForceEstimator_step_model_update);

// rate::Resample at 1 kHz (every model stepped every tick). The pitch preset cannot be resampled
// (pole -0.0952), so the pitch slot runs the linear yaw model, same size.
void BM_ForceEstimator_step_resample(benchmark::State& st) {
  auto models = est::models_2016();
  models.pitch = est::PitchModel2016<>(m::yaw_force_2016());
  est::ForceEstimator<est::rate::Resample> estimator(models, {});
  run(st, estimator);
}
BENCHMARK(BM_ForceEstimator_step_resample);

// ---------------------------------------------------------------------------------------------
// The 2016 way. Per joint a dynamic-size model and a time-varying Kalman filter (worksheet 4.4,
// 6.2: "position error and velocity measurements"). The appendix C models have no such outputs,
// so the measurement matrix is [C; e1'] (2 x n): the same arithmetic as a real one. Everything
// is stepped at the loop rate; the gate is the 2016 one (no hysteresis).
class LegacyForceEstimator2016 {
 public:
  LegacyForceEstimator2016() {
    add(m::roll_torque_2016(), 0.7, 0.0);
    add(m::pitch_force_2016(), 0.17, 0.0);
    add(m::yaw_force_2016(), 0.21, 0.21);
    add(m::yaw_force_2016(), 0.20, 0.20);
  }

  Eigen::VectorXd step(const Eigen::VectorXd& position, const Eigen::VectorXd& velocity,
                       const Eigen::VectorXd& current, const Eigen::VectorXd& setpoint) {
    Eigen::VectorXd forces(4);
    for (std::size_t j = 0; j < joints_.size(); ++j) {
      Joint& J = joints_[j];
      const auto i = static_cast<Eigen::Index>(j);
      const Eigen::Index n = J.A.rows();
      Eigen::VectorXd u(J.B.cols());
      const double c = current(i);
      u(0) = std::abs(c) <= J.deadzone ? 0.0 : c - std::copysign(J.deadzone, c);
      if (u.size() > 1) u(1) = velocity(i);
      Eigen::VectorXd z(J.Cm.rows());
      z(0) = setpoint(i) - position(i);
      z(1) = velocity(i);
      const Eigen::VectorXd x_pred = J.A * J.x + J.B * u;
      const Eigen::MatrixXd P_pred = J.A * J.P * J.A.transpose() + J.Q;
      const Eigen::MatrixXd S = J.Cm * P_pred * J.Cm.transpose() + J.R;
      const Eigen::MatrixXd K = P_pred * J.Cm.transpose() * S.inverse();
      J.x = x_pred + K * (z - J.Cm * x_pred);
      J.P = (Eigen::MatrixXd::Identity(n, n) - K * J.Cm) * P_pred;
      const Eigen::VectorXd y = J.C * J.x + J.D * u;
      forces(i) = std::abs(c) > J.friction ? y(0) : 0.0;
    }
    return forces;
  }

 private:
  struct Joint {
    Eigen::MatrixXd A, B, C, D, Cm, Q, R, P;
    Eigen::VectorXd x;
    double friction;
    double deadzone;
  };

  template <typename Model>
  void add(const Model& model, double friction, double deadzone) {
    Joint J;
    J.A = model.A();
    J.B = model.B();
    J.C = model.C();
    J.D = model.D();
    const Eigen::Index n = J.A.rows();
    J.Cm = Eigen::MatrixXd::Zero(2, n);
    J.Cm.row(0) = J.C.row(0);
    J.Cm(1, 0) = 1.0;
    J.Q = 1e-3 * Eigen::MatrixXd::Identity(n, n);
    J.R = 1e-2 * Eigen::MatrixXd::Identity(2, 2);
    J.P = Eigen::MatrixXd::Identity(n, n);
    J.x = Eigen::VectorXd::Zero(n);
    J.friction = friction;
    J.deadzone = deadzone;
    joints_.push_back(J);
  }

  std::vector<Joint> joints_;
};

void BM_Baseline2016_force_estimator_step(benchmark::State& st) {
  const std::vector<State> in = inputs();
  LegacyForceEstimator2016 estimator;
  std::size_t k = 0;
  for (auto _ : st) {
    const State& s = in[k];
    // The 2016 code copied the received arrays into dynamic vectors every tick.
    const Eigen::VectorXd forces = estimator.step(s.position, s.velocity, s.current, s.setpoint);
    benchmark::DoNotOptimize(forces.data());
    k = k + 1 == in.size() ? 0 : k + 1;
  }
}
BENCHMARK(BM_Baseline2016_force_estimator_step);

}  // namespace

}  // namespace force_estimator_bench
