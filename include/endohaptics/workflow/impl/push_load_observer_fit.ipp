//! @file
//! Function bodies of workflow/push_load_observer_fit.hpp: included at its end (header-only, the
//! default), or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION
//! (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/workflow/push_load_observer_fit.hpp"

namespace endohaptics::workflow {

ENDOHAPTICS_DECL Eigen::VectorXd referred_current(const LoadObserverData& d,
                                                  const CurrentReference& reference,
                                                  const char* where) {
  if (!reference) return d.current;
  if (d.command.size() != d.current.size()) {
    ENDOHAPTICS_THROW(
        Error(std::string(where) +
              ": the model refers the current to the command, but the experiment has " +
              std::to_string(d.command.size()) + " command samples for " +
              std::to_string(d.current.size()) + " current samples"));
  }
  estimation::CurrentOffsetReference<double> r(*reference);
  Eigen::VectorXd out(d.current.size());
  for (Eigen::Index k = 0; k < d.current.size(); ++k) {
    if (r.advance(d.current[k], d.command[k]) != model::NumericStatus::ok) {
      ENDOHAPTICS_THROW(Error(std::string(where) + ": non-finite current or command at sample " +
                              std::to_string(k)));
    }
    out[k] = r.corrected();
  }
  return out;
}

ENDOHAPTICS_DECL void check_experiments(std::span<const LoadObserverData> data, Eigen::Index skip,
                                        const char* where) {
  for (std::size_t e = 0; e < data.size(); ++e) {
    const auto& d = data[e];
    if (d.position.size() != d.current.size() || d.load.size() != d.current.size() ||
        d.current.size() <= skip + 1) {
      ENDOHAPTICS_THROW(Error(std::string(where) + ": experiment " + std::to_string(e) +
                              ": current, position and load must have the same length, longer "
                              "than the warm-up"));
    }
  }
}

ENDOHAPTICS_DECL std::vector<LoadObserverData> referred_experiments(
    std::span<const LoadObserverData> data, const CurrentReference& reference, const char* where) {
  std::vector<LoadObserverData> referred;
  if (!reference) return referred;
  for (const auto& d : data) {
    referred.push_back({referred_current(d, reference, where), d.position, d.load, {}});
  }
  return referred;
}

ENDOHAPTICS_DECL CurrentReference fit_current_reference(std::span<const LoadObserverData> data) {
  double sxy = 0.0, sxx = 0.0;
  for (const auto& d : data) {
    if (d.command.size() == 0 || d.command.size() != d.current.size()) return std::nullopt;
    const double n = static_cast<double>(d.current.size());
    const Eigen::ArrayXd u = d.command.array() - d.command.mean();
    const Eigen::ArrayXd i = d.current.array() - d.current.mean();
    sxy += (u * i).sum() / n;
    sxx += u.square().sum() / n;
  }
  if (!(sxx > 0.0)) return std::nullopt;  // the command never varies
  estimation::CurrentOffsetReferenceParameters<double> p;
  p.command_gain = sxy / sxx;
  double offset = 0.0;
  for (const auto& d : data) offset += (d.current - p.command_gain * d.command).mean();
  p.reference_offset = offset / static_cast<double>(data.size());
  const double max = model::max_joint_model_parameter;
  if (!std::isfinite(p.command_gain) || std::fabs(p.command_gain) < model::min_current_per_load ||
      std::fabs(p.command_gain) > max || !(std::fabs(p.reference_offset) <= max)) {
    return std::nullopt;
  }
  return p;
}

ENDOHAPTICS_DECL Eigen::VectorXd simulate_load_observer(
    const estimation::PushLoadObserver<double>& model, const LoadObserverData& d,
    const CurrentReference& reference) {
  return detail::simulate_observer(model, d, reference, "simulate_load_observer");
}

ENDOHAPTICS_DECL std::vector<double> load_observer_rmse(
    const estimation::PushLoadObserver<double>& model, std::span<const LoadObserverData> data,
    double warmup, const CurrentReference& reference) {
  const auto skip = static_cast<Eigen::Index>(std::ceil(warmup / model.sample_time()));
  std::vector<double> out;
  for (const auto& d : data) {
    const Eigen::VectorXd y_hat = simulate_load_observer(model, d, reference);
    const auto n = d.load.size() - skip;
    out.push_back(
        std::sqrt((d.load.tail(n) - y_hat.tail(n)).squaredNorm() / static_cast<double>(n)));
  }
  return out;
}

ENDOHAPTICS_DECL LoadObserverFit
fit_push_load_observer(std::span<const LoadObserverData> measured,
                       const estimation::PushLoadObserverParameters<double>& prior, double warmup) {
  if (measured.empty()) ENDOHAPTICS_THROW(Error("fit_push_load_observer: no data"));
  prior.validate();
  const auto skip = static_cast<Eigen::Index>(std::ceil(warmup / prior.sample_time));
  check_experiments(measured, skip, "fit_push_load_observer");
  // The current's offset reference first (when the data carry the command); everything below
  // works on the referred current, as the fitted model will see it.
  const CurrentReference reference = fit_current_reference(measured);
  const std::vector<LoadObserverData> referred =
      referred_experiments(measured, reference, "fit_push_load_observer");
  const std::span<const LoadObserverData> data =
      reference ? std::span<const LoadObserverData>(referred) : measured;
  // (a) The push regime and the filtered signals do not depend on the fitted values.
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  double load_sum = 0.0, load_sq_sum = 0.0, weight_sum = 0.0;
  std::size_t push = 0, total = 0;
  struct Sample {
    double i_f, v, y;
    double w;
  };
  std::vector<Sample> pushing, back_driven;
  Eigen::Matrix3d back_normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d back_rhs = Eigen::Vector3d::Zero();
  for (const auto& d : data) {
    estimation::PushLoadObserver<double> m(prior);
    const double w = 1.0 / static_cast<double>(d.current.size() - skip);
    for (Eigen::Index k = 0; k < d.current.size(); ++k) {
      const estimation::JointSignals<double> s{d.position[k], 0.0, d.current[k], 0.0};
      if (m.advance(s) != model::NumericStatus::ok) {
        ENDOHAPTICS_THROW(
            Error("fit_push_load_observer: non-finite signal at sample " + std::to_string(k)));
      }
      if (k < skip) continue;
      ++total;
      load_sum += w * d.load[k];
      load_sq_sum += w * d.load[k] * d.load[k];
      weight_sum += w;
      if (m.regime() > 0) {
        ++push;
        const Eigen::Vector3d row(d.load[k], 1.0, m.filtered_velocity());
        normal += w * row * row.transpose();
        rhs += w * row * m.filtered_current();
        pushing.push_back({m.filtered_current(), m.filtered_velocity(), d.load[k], w});
      } else if (m.regime() < 0) {
        const Eigen::Vector3d row(d.load[k], 1.0, m.filtered_velocity());
        back_normal += w * row * row.transpose();
        back_rhs += w * row * m.filtered_current();
        back_driven.push_back({m.filtered_current(), m.filtered_velocity(), d.load[k], w});
      }
    }
  }
  if (push < 10) {
    ENDOHAPTICS_THROW(Error("fit_push_load_observer: " + std::to_string(push) +
                            " samples in the push regime: the motor never pushes against the "
                            "load on these data (check push_sign)"));
  }
  const Eigen::Vector3d theta = (normal + 1e-9 * Eigen::Matrix3d::Identity()).ldlt().solve(rhs);
  if (!theta.allFinite() || theta[0] == 0.0) {
    ENDOHAPTICS_THROW(Error("fit_push_load_observer: the push-regime fit is singular"));
  }
  double residual = 0.0, residual_weight = 0.0;
  for (const auto& p : pushing) {
    const double r = p.i_f - theta[0] * p.y - theta[1] - theta[2] * p.v;
    residual += p.w * r * r;
    residual_weight += p.w;
  }
  LoadObserverFit fit;
  auto& q = fit.parameters = prior;
  q.current_per_load = theta[0];
  q.current_offset = theta[1];
  q.current_per_velocity = theta[2];
  q.measurement_variance = std::fmax(residual / residual_weight, 1e-12);
  q.initial_load = load_sum / weight_sum;
  q.output_offset = 0.0;
  q.output_slope = 0.0;
  // The back-driven map, for the estimate before the first push: the same least squares on the
  // back-driven samples, its error as the mean square of the inversion z_b - load (the per-run
  // bias included). Left out (c_b = 0) when there are too few samples or the slope is too small
  // to invert (|c_b| below 1e-3 of |c_p|: the current does not see the load when back-driven).
  q.back_current_per_load = 0.0;
  if (back_driven.size() >= 10) {
    const Eigen::Vector3d b =
        (back_normal + 1e-9 * Eigen::Matrix3d::Identity()).ldlt().solve(back_rhs);
    const double max = model::max_joint_model_parameter;
    if (b.allFinite() && std::fabs(b[0]) >= 1e-3 * std::fabs(theta[0]) && std::fabs(b[0]) <= max &&
        std::fabs(b[1]) <= max && std::fabs(b[2]) <= max) {
      double square = 0.0, square_weight = 0.0;
      for (const auto& p : back_driven) {
        const double z = (p.i_f - b[1] - b[2] * p.v) / b[0];
        square += p.w * (z - p.y) * (z - p.y);
        square_weight += p.w;
      }
      const double variance = square / square_weight;
      if (std::isfinite(variance) && variance > 0.0 && variance <= max) {
        q.back_current_per_load = b[0];
        q.back_current_offset = b[1];
        q.back_current_per_velocity = b[2];
        q.back_variance = variance;
      }
    }
  }
  // (b) The load-side friction map on the causal run, for a given stiffness k_q, and the causal
  // mean RMSE on the training data with it, from one run per experiment: the residual r = load -
  // estimate (e0 = e1 = 0) and the row x = [g, g estimate], g = (1 - regime) / 2, give the normal
  // equations of r on x and, per experiment, its squared error for any e = (e0, e1):
  // sum r^2 - 2 e'sum x r + e'(sum x x')e. Inf when the estimate is not finite on some sample (no
  // exception: the grid below skips such a candidate in builds without exceptions too).
  const auto fit_output_map = [&](estimation::PushLoadObserverParameters<double> r) {
    r.output_offset = 0.0;
    r.output_slope = 0.0;
    struct Sums {
      double rr = 0.0;
      Eigen::Vector2d xr = Eigen::Vector2d::Zero();
      Eigen::Matrix2d xx = Eigen::Matrix2d::Zero();
    };
    std::vector<Sums> sums(data.size());
    Eigen::Matrix2d n2 = Eigen::Matrix2d::Zero();
    Eigen::Vector2d r2 = Eigen::Vector2d::Zero();
    for (std::size_t e = 0; e < data.size(); ++e) {
      const auto& d = data[e];
      estimation::PushLoadObserver<double> m(r);
      for (Eigen::Index k = 0; k < d.current.size(); ++k) {
        const estimation::JointSignals<double> s{d.position[k], 0.0, d.current[k], 0.0};
        if (m.advance(s) != model::NumericStatus::ok) {
          return std::pair{r, std::numeric_limits<double>::infinity()};
        }
        if (k < skip) continue;
        const double tau = m.force(s);
        const double g = (1.0 - m.regime()) / 2.0;
        const Eigen::Vector2d x(g, g * tau);
        const double res = d.load[k] - tau;
        sums[e].rr += res * res;
        sums[e].xr += x * res;
        sums[e].xx += x * x.transpose();
      }
      const double w = 1.0 / static_cast<double>(d.current.size() - skip);
      n2 += w * sums[e].xx;
      r2 += w * sums[e].xr;
    }
    Eigen::Vector2d e = (n2 + 1e-12 * Eigen::Matrix2d::Identity()).ldlt().solve(r2);
    const double max = model::max_joint_model_parameter;
    if (!e.allFinite() || std::fabs(e[0]) > max || std::fabs(e[1]) > max) e.setZero();
    r.output_offset = e[0];
    r.output_slope = e[1];
    double mean = 0.0;
    for (std::size_t i = 0; i < data.size(); ++i) {
      const double square = sums[i].rr - 2.0 * e.dot(sums[i].xr) + e.dot(sums[i].xx * e);
      mean +=
          std::sqrt(std::fmax(square, 0.0) / static_cast<double>(data[i].current.size() - skip)) /
          static_cast<double>(data.size());
    }
    return std::pair{r, mean};
  };
  // k_q on a grid scaled by the load's spread (factors of its standard deviation per rad of travel
  // in the push direction; 0, the random walk alone, first), the best causal training score kept.
  // A least-squares slope of the truth on the travel since the last push is confounded with the
  // load-side friction step at each reversal (research note, K5).
  const double spread =
      std::sqrt(std::fmax(load_sq_sum / weight_sum - q.initial_load * q.initial_load, 0.0));
  auto [best, best_rmse] = fit_output_map(q);
  for (const double factor : {-0.5, -0.25, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0, 1.5}) {
    auto candidate = q;
    candidate.load_per_angle = factor * spread;
    if (!(std::fabs(candidate.load_per_angle) <= model::max_joint_model_parameter)) continue;
    auto [fitted, rmse] = fit_output_map(candidate);  // Inf: the estimate diverged, no candidate
    if (std::isfinite(rmse) && rmse < best_rmse) {
      best = fitted;
      best_rmse = rmse;
    }
  }
  q = best;
  q.validate();
  fit.reference = reference;
  fit.push_fraction = static_cast<double>(push) / static_cast<double>(total);
  fit.rmse = load_observer_rmse(estimation::PushLoadObserver<double>(q), data, warmup);
  double sum = 0.0;
  for (const double r : fit.rmse) sum += r;
  fit.mean_rmse = sum / static_cast<double>(fit.rmse.size());
  return fit;
}

}  // namespace endohaptics::workflow
