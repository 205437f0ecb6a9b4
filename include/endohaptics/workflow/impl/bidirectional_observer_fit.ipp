//! @file
//! Function bodies of workflow/bidirectional_observer_fit.hpp: included at its end (header-only,
//! the default), or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION
//! (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/workflow/bidirectional_observer_fit.hpp"

namespace endohaptics::workflow {

ENDOHAPTICS_DECL Eigen::VectorXd simulate_bidirectional_observer(
    const estimation::BidirectionalLoadObserver<double>& model, const LoadObserverData& d,
    const CurrentReference& reference) {
  return detail::simulate_observer(model, d, reference, "simulate_bidirectional_observer");
}

namespace detail {

// One experiment as the observer's front end sees it (configuration time).
struct BidirectionalSamples {
  Eigen::VectorXd current;  // filtered, A
  Eigen::VectorXi regime;   // +1, -1, 0
  Eigen::MatrixXd stops;    // samples x N; its last column is s_N, the stroke of the maps
  double level = 0.0;       // L_e: the mean load after the warm-up
  [[nodiscard]] double stroke(Eigen::Index k) const { return stops(k, stops.cols() - 1); }
};

// Least squares of the filtered current on [L, L s_N, 1, s_N] over the samples of `regime`
// (each experiment weighs the same): (gain, gain per s_N, offset, offset per s_N).
inline Eigen::Vector4d fit_direction_map(const std::vector<BidirectionalSamples>& samples,
                                         Eigen::Index skip, int regime, const char* name) {
  Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
  Eigen::Vector4d rhs = Eigen::Vector4d::Zero();
  std::size_t total = 0;
  double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
  for (const auto& e : samples) {
    std::size_t n = 0;
    for (Eigen::Index k = skip; k < e.current.size(); ++k) n += e.regime[k] == regime ? 1U : 0U;
    if (n == 0) continue;
    total += n;
    lowest = std::min(lowest, e.level);
    highest = std::max(highest, e.level);
    const double w = 1.0 / static_cast<double>(n);
    for (Eigen::Index k = skip; k < e.current.size(); ++k) {
      if (e.regime[k] != regime) continue;
      const Eigen::Vector4d row(e.level, e.level * e.stroke(k), 1.0, e.stroke(k));
      normal += w * row * row.transpose();
      rhs += w * row * e.current[k];
    }
  }
  if (total < 10) {
    ENDOHAPTICS_THROW(Error("fit_bidirectional_load_observer: " + std::to_string(total) +
                            " samples moving " + name +
                            ": the observer needs motion both ways in the training data"));
  }
  // The gain needs experiments at two load levels at least (one level: gain and offset are one).
  if (!(highest - lowest > 1e-6 * std::max({std::fabs(highest), std::fabs(lowest), 1e-300}))) {
    ENDOHAPTICS_THROW(
        Error(std::string("fit_bidirectional_load_observer: every experiment moving ") + name +
              " is at the same load level (" + endohaptics::detail::format_number(lowest) +
              "): the map needs experiments at two levels or more"));
  }
  const Eigen::Vector4d theta = (normal + 1e-12 * Eigen::Matrix4d::Identity()).ldlt().solve(rhs);
  const double max = model::max_joint_model_parameter;
  if (!theta.allFinite() || !(std::fabs(theta[0]) >= model::min_current_per_load) ||
      theta.cwiseAbs().maxCoeff() > max) {
    ENDOHAPTICS_THROW(Error(std::string("fit_bidirectional_load_observer: the ") + name +
                            " map is singular (the current does not follow the load levels of "
                            "the experiments)"));
  }
  using Parameters = estimation::BidirectionalLoadObserverParameters<double>;
  if (!(std::fabs(theta[1]) <= Parameters::max_stroke_ratio * std::fabs(theta[0]))) {
    ENDOHAPTICS_THROW(Error(std::string("fit_bidirectional_load_observer: the ") + name +
                            " map's gain all but vanishes or changes sign along the stroke (gain " +
                            endohaptics::detail::format_number(theta[0]) + ", per s_N " +
                            endohaptics::detail::format_number(theta[1]) +
                            "; at most 0.9 times the gain)"));
  }
  return theta;
}

// Per-sample mean square and per-experiment bias of the inversion z - L_e of one direction's map.
struct InversionError {
  double mean_square = 0.0;  // mean over the experiments of their mean square
  double bias_rms = 0.0;     // RMS over the experiments of their mean
};

inline InversionError inversion_error(const std::vector<BidirectionalSamples>& samples,
                                      Eigen::Index skip, int regime, const Eigen::Vector4d& map) {
  double square_sum = 0.0, bias_square_sum = 0.0;
  std::size_t experiments = 0;
  for (const auto& e : samples) {
    double square = 0.0, sum = 0.0;
    std::size_t n = 0;
    for (Eigen::Index k = skip; k < e.current.size(); ++k) {
      if (e.regime[k] != regime) continue;
      const double z =
          (e.current[k] - map[2] - map[3] * e.stroke(k)) / (map[0] + map[1] * e.stroke(k));
      square += (z - e.level) * (z - e.level);
      sum += z - e.level;
      ++n;
    }
    if (n == 0) continue;
    square_sum += square / static_cast<double>(n);
    bias_square_sum += std::pow(sum / static_cast<double>(n), 2);
    ++experiments;
  }
  const double count = static_cast<double>(std::max<std::size_t>(experiments, 1));
  return {square_sum / count, std::sqrt(bias_square_sum / count)};
}

}  // namespace detail

ENDOHAPTICS_DECL BidirectionalObserverFit fit_bidirectional_load_observer(
    std::span<const LoadObserverData> measured,
    const estimation::BidirectionalLoadObserverParameters<double>& prior, double warmup) {
  constexpr int N = estimation::bidirectional_observer_stops;
  if (measured.empty()) ENDOHAPTICS_THROW(Error("fit_bidirectional_load_observer: no data"));
  if (!(std::isfinite(warmup) && warmup >= 0.0)) {
    ENDOHAPTICS_THROW(
        Error("fit_bidirectional_load_observer: warmup must be finite and >= 0 s, "
              "got " +
              endohaptics::detail::format_number(warmup)));
  }
  prior.validate();
  const auto skip = static_cast<Eigen::Index>(std::ceil(warmup / prior.sample_time));
  check_experiments(measured, skip, "fit_bidirectional_load_observer");
  // The current's offset reference first (when the data carry the command); everything below
  // works on the referred current, as the fitted model will see it.
  const CurrentReference reference = fit_current_reference(measured);
  const std::vector<LoadObserverData> referred =
      referred_experiments(measured, reference, "fit_bidirectional_load_observer");
  const std::span<const LoadObserverData> data =
      reference ? std::span<const LoadObserverData>(referred) : measured;
  // The front end (filters, regime, stop operators) does not depend on the fitted values.
  std::vector<detail::BidirectionalSamples> samples;
  double level_sum = 0.0, peak = 0.0;
  std::size_t forward = 0, backward = 0, total = 0;
  for (const auto& d : data) {
    estimation::BidirectionalLoadObserver<double> m(prior);
    detail::BidirectionalSamples e{Eigen::VectorXd(d.current.size()),
                                   Eigen::VectorXi(d.current.size()),
                                   Eigen::MatrixXd(d.current.size(), N), 0.0};
    for (Eigen::Index k = 0; k < d.current.size(); ++k) {
      const estimation::JointSignals<double> s{d.position[k], 0.0, d.current[k], 0.0};
      if (m.advance(s) != model::NumericStatus::ok) {
        ENDOHAPTICS_THROW(Error("fit_bidirectional_load_observer: non-finite signal at sample " +
                                std::to_string(k)));
      }
      e.current[k] = m.filtered_current();
      e.regime[k] = static_cast<int>(m.regime());
      e.stops.row(k) = m.stop_values().transpose();
      if (k < skip) continue;
      ++total;
      forward += e.regime[k] > 0 ? 1U : 0U;
      backward += e.regime[k] < 0 ? 1U : 0U;
      peak = std::max(peak, std::fabs(d.load[k]));
    }
    e.level = d.load.tail(d.load.size() - skip).mean();
    level_sum += e.level;
    samples.push_back(std::move(e));
  }
  const double experiments = static_cast<double>(data.size());
  // (a) The two maps.
  const Eigen::Vector4d fwd = detail::fit_direction_map(samples, skip, 1, "forward");
  const Eigen::Vector4d bwd = detail::fit_direction_map(samples, skip, -1, "backward");
  if (!(fwd[0] / bwd[0] > 0.0)) {
    ENDOHAPTICS_THROW(
        Error("fit_bidirectional_load_observer: the forward and the backward map's "
              "gains have opposite signs (" +
              endohaptics::detail::format_number(fwd[0]) + ", " +
              endohaptics::detail::format_number(bwd[0]) +
              " A per load unit): the current does not grow with the load both "
              "ways"));
  }
  // (b) The output's hysteresis around each experiment's level.
  constexpr int M = 1 + 2 * N;
  Eigen::Matrix<double, M, M> normal = Eigen::Matrix<double, M, M>::Zero();
  Eigen::Matrix<double, M, 1> rhs = Eigen::Matrix<double, M, 1>::Zero();
  double variance_sum = 0.0;
  const double initial_load = level_sum / experiments;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const auto& e = samples[i];
    const auto& d = data[i];
    const double w = 1.0 / static_cast<double>(d.load.size() - skip);
    for (Eigen::Index k = skip; k < d.load.size(); ++k) {
      Eigen::Matrix<double, M, 1> row;
      row[0] = 1.0;
      row.segment<N>(1) = e.stops.row(k).transpose();
      row.segment<N>(1 + N) = e.level * e.stops.row(k).transpose();
      normal += w * row * row.transpose();
      rhs += w * row * (d.load[k] - e.level);
      variance_sum += w * (d.load[k] - initial_load) * (d.load[k] - initial_load);
    }
  }
  const Eigen::Matrix<double, M, 1> shape =
      (normal + 1e-10 * Eigen::Matrix<double, M, M>::Identity()).ldlt().solve(rhs);
  if (!shape.allFinite() || shape.cwiseAbs().maxCoeff() > model::max_joint_model_parameter) {
    ENDOHAPTICS_THROW(
        Error("fit_bidirectional_load_observer: the output's hysteresis fit is "
              "singular"));
  }
  // (c) The filter's noise from the inversions on the training samples.
  const detail::InversionError fe = detail::inversion_error(samples, skip, 1, fwd);
  const detail::InversionError be = detail::inversion_error(samples, skip, -1, bwd);
  const double correlated = bidirectional_inversion_correlation_time / prior.sample_time;
  BidirectionalObserverFit fit;
  auto& q = fit.parameters = prior;
  q.forward_gain = fwd[0];
  q.forward_gain_stroke = fwd[1];
  q.forward_offset = fwd[2];
  q.forward_offset_stroke = fwd[3];
  q.backward_gain = bwd[0];
  q.backward_gain_stroke = bwd[1];
  q.backward_offset = bwd[2];
  q.backward_offset_stroke = bwd[3];
  const double floor = 1e-12;
  q.forward_variance = std::max(fe.mean_square * correlated, floor);
  q.backward_variance = std::max(be.mean_square * correlated, floor);
  q.friction_variance =
      std::max(std::pow(bidirectional_friction_prior_scale * fe.bias_rms, 2), fe.mean_square);
  q.friction_process_variance = 0.0;
  q.load_process_variance = std::pow(0.01 * peak, 2) * prior.sample_time;
  q.initial_load = initial_load;
  q.initial_variance = variance_sum / experiments;
  q.output_offset = shape[0];
  q.output_shape = shape.segment<N>(1);
  q.output_shape_per_load = shape.segment<N>(1 + N);
  // The variances scale with the square of the load's unit: a unit so small that they exceed the
  // joint-model bound is refused by name (rescale the output), not by a generic check.
  const std::pair<const char*, double> variances[] = {
      {"forward_variance", q.forward_variance},
      {"backward_variance", q.backward_variance},
      {"friction_variance", q.friction_variance},
      {"initial_variance", q.initial_variance},
      {"load_process_variance", q.load_process_variance}};
  for (const auto& [field, v] : variances) {
    if (!(v <= model::max_joint_model_parameter)) {
      ENDOHAPTICS_THROW(Error(std::string("fit_bidirectional_load_observer: ") + field + " " +
                              endohaptics::detail::format_number(v) +
                              " exceeds the model's bound 1e6 (load unit^2): give the output in "
                              "a larger unit"));
    }
  }
  q.validate();
  fit.reference = reference;
  fit.forward_fraction = static_cast<double>(forward) / static_cast<double>(total);
  fit.backward_fraction = static_cast<double>(backward) / static_cast<double>(total);
  fit.forward_bias_rms = fe.bias_rms;
  const estimation::BidirectionalLoadObserver<double> fitted(q);
  double sum = 0.0;
  for (const auto& d : data) {
    const Eigen::VectorXd y_hat = simulate_bidirectional_observer(fitted, d);
    const auto n = d.load.size() - skip;
    fit.rmse.push_back(
        std::sqrt((d.load.tail(n) - y_hat.tail(n)).squaredNorm() / static_cast<double>(n)));
    sum += fit.rmse.back();
  }
  fit.mean_rmse = sum / experiments;
  return fit;
}

}  // namespace endohaptics::workflow
