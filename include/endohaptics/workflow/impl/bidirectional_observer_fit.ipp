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

ENDOHAPTICS_DECL void apply_noise_rule(BidirectionalObserverFit& fit,
                                       const BidirectionalNoiseRule& rule) {
  const bool valid = std::isfinite(rule.correlation_time) && rule.correlation_time > 0.0 &&
                     std::isfinite(rule.friction_prior_scale) && rule.friction_prior_scale >= 0.0 &&
                     std::isfinite(rule.load_walk) && rule.load_walk >= 0.0;
  if (!valid) {
    ENDOHAPTICS_THROW(Error(
        "fit_bidirectional_load_observer: the noise rule needs a correlation time > 0 s and a "
        "friction prior scale and a load walk >= 0, got " +
        endohaptics::detail::format_number(rule.correlation_time) + ", " +
        endohaptics::detail::format_number(rule.friction_prior_scale) + ", " +
        endohaptics::detail::format_number(rule.load_walk)));
  }
  auto& q = fit.parameters;
  const double correlated = rule.correlation_time / q.sample_time;
  const double floor = q.min_variance;
  q.forward_variance = std::max(fit.forward_mean_square * correlated, floor);
  q.backward_variance = std::max(fit.backward_mean_square * correlated, floor);
  q.friction_variance = std::max(std::pow(rule.friction_prior_scale * fit.forward_bias_rms, 2),
                                 fit.forward_mean_square);
  q.load_process_variance = std::pow(rule.load_walk * fit.peak_load, 2) * q.sample_time;
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
  fit.rule = rule;
}

namespace detail {

// fit_bidirectional_load_observer; without `score` the training RMSE is left out (the inner
// cross-validation scores held-out experiments instead).
inline BidirectionalObserverFit fit_bidirectional(
    std::span<const LoadObserverData> measured,
    const estimation::BidirectionalLoadObserverParameters<double>& prior, double warmup,
    const BidirectionalNoiseRule& rule, bool score) {
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
  // (c) The filter's noise from the inversions on the training samples, by the rule.
  const detail::InversionError fe = detail::inversion_error(samples, skip, 1, fwd);
  const detail::InversionError be = detail::inversion_error(samples, skip, -1, bwd);
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
  q.friction_process_variance = 0.0;
  q.initial_load = initial_load;
  q.initial_variance = variance_sum / experiments;
  q.output_offset = shape[0];
  q.output_shape = shape.segment<N>(1);
  q.output_shape_per_load = shape.segment<N>(1 + N);
  fit.forward_mean_square = fe.mean_square;
  fit.backward_mean_square = be.mean_square;
  fit.forward_bias_rms = fe.bias_rms;
  fit.peak_load = peak;
  apply_noise_rule(fit, rule);
  q.validate();
  fit.reference = reference;
  fit.forward_fraction = static_cast<double>(forward) / static_cast<double>(total);
  fit.backward_fraction = static_cast<double>(backward) / static_cast<double>(total);
  if (!score) return fit;
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

}  // namespace detail

ENDOHAPTICS_DECL BidirectionalObserverFit fit_bidirectional_load_observer(
    std::span<const LoadObserverData> data,
    const estimation::BidirectionalLoadObserverParameters<double>& prior, double warmup,
    const BidirectionalNoiseRule& rule) {
  return detail::fit_bidirectional(data, prior, warmup, rule, true);
}

ENDOHAPTICS_DECL std::optional<double> encoder_step(std::span<const LoadObserverData> data) {
  double step = std::numeric_limits<double>::infinity();
  for (const auto& d : data) {
    for (Eigen::Index k = 1; k < d.position.size(); ++k) {
      const double dq = std::fabs(d.position[k] - d.position[k - 1]);
      if (dq > 1e-12) step = std::min(step, dq);
    }
  }
  if (!std::isfinite(step)) return std::nullopt;
  // Quantised: every nonzero step within 1 % of a whole number of the smallest.
  for (const auto& d : data) {
    for (Eigen::Index k = 1; k < d.position.size(); ++k) {
      const double counts = std::fabs(d.position[k] - d.position[k - 1]) / step;
      if (counts > 1e-9 && std::fabs(counts - std::round(counts)) > 0.01) return std::nullopt;
    }
  }
  return step;
}

ENDOHAPTICS_DECL estimation::BidirectionalLoadObserverParameters<double> with_settings(
    const estimation::BidirectionalLoadObserverParameters<double>& prior,
    const BidirectionalSettings& s) {
  auto p = prior;
  p.current_cutoff = s.current_cutoff;
  p.velocity_cutoff = s.velocity_cutoff;
  p.direction_scale = s.direction_scale;
  p.velocity_threshold = s.velocity_threshold;
  p.stop_thresholds = prior.stop_thresholds * s.stop_scale;
  p.start_travel = prior.start_travel * s.stop_scale;
  return p;
}

ENDOHAPTICS_DECL BidirectionalSettings
settings_of(const estimation::BidirectionalLoadObserverParameters<double>& prior) {
  BidirectionalSettings s;
  s.current_cutoff = prior.current_cutoff;
  s.velocity_cutoff = prior.velocity_cutoff;
  s.direction_scale = prior.direction_scale;
  s.velocity_threshold = prior.velocity_threshold;
  return s;
}

namespace detail {

// The mean held-out RMSE over `folds` of one front end (`front`'s rule ignored) for each rule in
// `rules`: per fold one fit on the other experiments, then each rule's variances and a causal run
// of every held-out experiment. Infinity for every rule when the front end's fit fails on a
// fold, for one rule when its variances do.
inline std::vector<double> held_out_rmse(
    std::span<const LoadObserverData> data, const std::vector<std::vector<std::size_t>>& folds,
    const estimation::BidirectionalLoadObserverParameters<double>& prior,
    const BidirectionalSettings& front, const std::vector<BidirectionalNoiseRule>& rules,
    double warmup) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> sum(rules.size(), 0.0);
  std::size_t held = 0;
  const auto p = with_settings(prior, front);
  const auto skip = static_cast<Eigen::Index>(std::ceil(warmup / p.sample_time));
  for (const auto& fold : folds) {
    std::vector<LoadObserverData> train;
    for (std::size_t e = 0; e < data.size(); ++e) {
      if (std::find(fold.begin(), fold.end(), e) == fold.end()) train.push_back(data[e]);
    }
    if (train.empty() || fold.empty()) continue;
    std::optional<BidirectionalObserverFit> fit;
#if defined(__cpp_exceptions)
    try {
#endif
      fit = fit_bidirectional(train, p, warmup, rules.front(), false);
#if defined(__cpp_exceptions)
    } catch (const Error&) {
      return std::vector<double>(rules.size(), inf);
    }
#endif
    for (std::size_t r = 0; r < rules.size(); ++r) {
      if (!std::isfinite(sum[r])) continue;
#if defined(__cpp_exceptions)
      try {
#endif
        apply_noise_rule(*fit, rules[r]);
        const estimation::BidirectionalLoadObserver<double> model(fit->parameters);
        for (const std::size_t e : fold) {
          const LoadObserverData& d = data[e];
          const Eigen::VectorXd y = simulate_bidirectional_observer(model, d, fit->reference);
          const auto n = d.load.size() - skip;
          const double rmse =
              std::sqrt((d.load.tail(n) - y.tail(n)).squaredNorm() / static_cast<double>(n));
          sum[r] += std::isfinite(rmse) ? rmse : inf;
        }
#if defined(__cpp_exceptions)
      } catch (const Error&) {
        sum[r] = inf;
      }
#endif
    }
    held += fold.size();
  }
  for (double& s : sum) s = held > 0 ? s / static_cast<double>(held) : inf;
  return sum;
}

// The correlation times and load walks of the noise-rule grid (its friction prior scales are 1,
// 2, 4, 8): the correlation time 0.05-0.8 s in steps of a factor sqrt(2) (rounded to 4 digits),
// the load walk 0.1-3 % of the range per root second in steps of about 3. Fixed before any score
// was seen; the factor-2 grid with walks 0.3-3 % it refines (research note, section 4) is a subset.
inline constexpr double noise_grid_times[] = {0.05,   0.0707, 0.1,    0.1414, 0.2,
                                              0.2828, 0.4,    0.5657, 0.8};
inline constexpr double noise_grid_walks[] = {0.001, 0.003, 0.01, 0.03};

}  // namespace detail

ENDOHAPTICS_DECL std::vector<BidirectionalNoiseRule> noise_rule_grid() {
  std::vector<BidirectionalNoiseRule> grid;
  for (const double t : detail::noise_grid_times) {
    for (const double k : {1.0, 2.0, 4.0, 8.0}) {
      for (const double w : detail::noise_grid_walks) grid.push_back({t, k, w});
    }
  }
  return grid;
}

ENDOHAPTICS_DECL BidirectionalSelection choose_bidirectional_settings(
    std::span<const LoadObserverData> data, const std::vector<std::vector<std::size_t>>& folds,
    const estimation::BidirectionalLoadObserverParameters<double>& prior, double warmup,
    bool vary_velocity_threshold) {
  BidirectionalSelection out;
  out.settings = settings_of(prior);
  prior.validate();
  if (!(std::isfinite(warmup) && warmup >= 0.0)) {
    ENDOHAPTICS_THROW(
        Error("choose_bidirectional_settings: warmup must be finite and >= 0 s, got " +
              endohaptics::detail::format_number(warmup)));
  }
  check_experiments(data, static_cast<Eigen::Index>(std::ceil(warmup / prior.sample_time)),
                    "choose_bidirectional_settings");
  for (const auto& fold : folds) {
    for (const std::size_t e : fold) {
      if (e >= data.size()) {
        ENDOHAPTICS_THROW(Error("choose_bidirectional_settings: fold index " + std::to_string(e) +
                                " beyond the " + std::to_string(data.size()) + " experiments"));
      }
    }
  }
  if (folds.size() < 2) return out;
  const double inf = std::numeric_limits<double>::infinity();
  const auto score = [&](const BidirectionalSettings& s) {
    ++out.candidates;
    return detail::held_out_rmse(data, folds, prior, s, {s.rule}, warmup).front();
  };
  BidirectionalSettings best = out.settings;
  double best_score = inf;
  // From `best`, steps of `factor` along one constant (`field`) while the score improves, at
  // most `steps`, each within `valid`; true when at least one step was taken.
  const auto walk = [&](auto field, double factor, int steps, auto valid) {
    for (int i = 0; i < steps; ++i) {
      BidirectionalSettings s = best;
      field(s) *= factor;
      if (!valid(s)) return i > 0;
      const double v = score(s);
      if (!(v < best_score)) return i > 0;
      best = s;
      best_score = v;
    }
    return true;
  };
  const auto any = [](const BidirectionalSettings&) { return true; };
  const auto t = [](BidirectionalSettings& s) -> double& { return s.rule.correlation_time; };
  const auto kf = [](BidirectionalSettings& s) -> double& { return s.rule.friction_prior_scale; };
  const auto lw = [](BidirectionalSettings& s) -> double& { return s.rule.load_walk; };
  const double ts = prior.sample_time;
  const auto above_one_sample = [ts](const BidirectionalSettings& s) {
    return s.rule.correlation_time >= ts;
  };
  // The noise rule: the grid on the current front end, then, for a constant whose best value is
  // at the grid's edge, steps beyond it while the score improves.
  const auto noise_stage = [&] {
    const std::vector<BidirectionalNoiseRule> grid = noise_rule_grid();
    std::vector<BidirectionalNoiseRule> rules = grid;
    const bool first = !std::isfinite(out.prior_rmse);
    if (first) rules.push_back(BidirectionalNoiseRule{});  // the research note's, for the report
    const std::vector<double> scores =
        detail::held_out_rmse(data, folds, prior, best, rules, warmup);
    out.candidates += rules.size();
    if (first) out.prior_rmse = scores.back();
    for (std::size_t r = 0; r < grid.size(); ++r) {
      if (scores[r] < best_score) {
        best_score = scores[r];
        best.rule = grid[r];
      }
    }
    if (!std::isfinite(best_score)) return;
    const auto edge = [&](double v, double low, double high, auto field, double factor,
                          auto valid) {
      if (v == low) (void)walk(field, 1.0 / factor, 4, valid);
      if (v == high) (void)walk(field, factor, 4, valid);
    };
    edge(best.rule.correlation_time, std::begin(detail::noise_grid_times)[0],
         std::end(detail::noise_grid_times)[-1], t, 2.0, above_one_sample);
    edge(best.rule.friction_prior_scale, 1.0, 8.0, kf, 2.0, any);
    edge(best.rule.load_walk, std::begin(detail::noise_grid_walks)[0],
         std::end(detail::noise_grid_walks)[-1], lw, 3.0, any);
  };
  noise_stage();
  if (!std::isfinite(best_score)) return out;
  // The front end, one constant at a time: a factor of 2 either way, continued while it improves
  // (the stop thresholds only narrower: the widest stays within half the stroke).
  const BidirectionalSettings start = best;
  const double nyquist = 0.5 / ts;
  const auto below_nyquist = [nyquist](const BidirectionalSettings& s) {
    return s.current_cutoff < nyquist && s.velocity_cutoff < nyquist;
  };
  const auto cut = [](BidirectionalSettings& s) -> double& { return s.current_cutoff; };
  const auto vcut = [](BidirectionalSettings& s) -> double& { return s.velocity_cutoff; };
  const auto q0 = [](BidirectionalSettings& s) -> double& { return s.direction_scale; };
  const auto vth = [](BidirectionalSettings& s) -> double& { return s.velocity_threshold; };
  const auto stops = [](BidirectionalSettings& s) -> double& { return s.stop_scale; };
  if (!walk(cut, 2.0, 3, below_nyquist)) (void)walk(cut, 0.5, 3, below_nyquist);
  if (!walk(vcut, 2.0, 3, below_nyquist)) (void)walk(vcut, 0.5, 3, below_nyquist);
  if (!walk(q0, 2.0, 3, any)) (void)walk(q0, 0.5, 3, any);
  if (vary_velocity_threshold && !walk(vth, 2.0, 3, any)) (void)walk(vth, 0.5, 3, any);
  (void)walk(stops, 0.5, 2, any);
  const bool same_front = best.current_cutoff == start.current_cutoff &&
                          best.velocity_cutoff == start.velocity_cutoff &&
                          best.direction_scale == start.direction_scale &&
                          best.velocity_threshold == start.velocity_threshold &&
                          best.stop_scale == start.stop_scale;
  // The noise rule again on a changed front end.
  if (!same_front) noise_stage();
  out.settings = best;
  out.held_out_rmse = best_score;
  out.folds = folds.size();
  return out;
}

}  // namespace endohaptics::workflow
