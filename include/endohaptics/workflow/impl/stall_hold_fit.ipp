//! @file
//! Function bodies of workflow/stall_hold_fit.hpp: included at its end (header-only, the default),
//! or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/workflow/stall_hold_fit.hpp"

namespace endohaptics::workflow {

ENDOHAPTICS_DECL Eigen::VectorXd simulate_stall_hold(const estimation::StallHold<double>& model,
                                                     const StallHoldData& d) {
  estimation::StallHold<double> m = model;
  m.reset();
  Eigen::VectorXd y(d.current.size());
  const estimation::SimulationResult r = estimation::simulate(
      m,
      [&](Eigen::Index k) noexcept {
        return estimation::JointSignals<double>{0.0, d.velocity[k], d.current[k], 0.0};
      },
      y);
  if (!r.ok()) {
    ENDOHAPTICS_THROW(
        Error("simulate_stall_hold: non-finite signal at sample " + std::to_string(r.sample)));
  }
  return y;
}

ENDOHAPTICS_DECL StallHoldFit fit_stall_hold(std::span<const StallHoldData> data,
                                             const estimation::StallHoldParameters<double>& prior,
                                             double warmup) {
  if (data.empty()) ENDOHAPTICS_THROW(Error("fit_stall_hold: no data"));
  if (!(std::isfinite(warmup) && warmup >= 0)) {
    ENDOHAPTICS_THROW(Error("fit_stall_hold: warmup must be finite and >= 0 s, got " +
                            endohaptics::detail::format_number(warmup)));
  }
  prior.validate();
  const auto skip = static_cast<Eigen::Index>(std::ceil(warmup / prior.sample_time));
  for (std::size_t e = 0; e < data.size(); ++e) {
    const auto& d = data[e];
    if (d.velocity.size() != d.current.size() || d.force.size() != d.current.size()) {
      ENDOHAPTICS_THROW(Error("fit_stall_hold: experiment " + std::to_string(e) +
                              ": current, velocity and force differ in length"));
    }
    if (d.current.size() <= skip + 1) {
      ENDOHAPTICS_THROW(Error("fit_stall_hold: experiment " + std::to_string(e) + " has " +
                              std::to_string(d.current.size()) +
                              " samples, not more than the warm-up"));
    }
  }
  StallHoldFit best;
  best.mean_fit_percent = -std::numeric_limits<double>::infinity();
  for (const auto side : {estimation::StallHoldSide::both, estimation::StallHoldSide::positive,
                          estimation::StallHoldSide::negative}) {
    auto p = prior;
    p.side = side;
    p.gain = 1.0;
    const estimation::StallHold<double> unit(p);
    std::vector<Eigen::VectorXd> shapes;
    double num = 0.0, den = 0.0;
    for (const auto& d : data) {
      shapes.push_back(simulate_stall_hold(unit, d));
      const auto n = d.current.size() - skip;
      const auto z = shapes.back().tail(n);
      num += z.dot(d.force.tail(n)) / static_cast<double>(n);
      den += z.squaredNorm() / static_cast<double>(n);
    }
    if (!(den > 0)) continue;  // this side never leaves zero on these data
    p.gain = num / den;
    StallHoldFit candidate;
    candidate.parameters = p;
    double sum = 0.0;
    for (std::size_t e = 0; e < data.size(); ++e) {
      const auto n = data[e].current.size() - skip;
      const Eigen::VectorXd y = data[e].force.tail(n);
      const Eigen::VectorXd y_hat = p.gain * shapes[e].tail(n);
      const double fit = model::fit_percent(y, y_hat);
      candidate.fit_percent.push_back(fit);
      sum += fit;
    }
    candidate.mean_fit_percent = sum / static_cast<double>(data.size());
    if (candidate.mean_fit_percent > best.mean_fit_percent) best = std::move(candidate);
  }
  if (best.fit_percent.empty()) {
    ENDOHAPTICS_THROW(Error("fit_stall_hold: the current never exceeds the dead zone of " +
                            endohaptics::detail::format_number(prior.current_deadzone) +
                            " A while the joint moves: nothing to fit"));
  }
  return best;
}

namespace detail {

// The mean held-out causal fit of one StallHold setting over `folds`; -infinity when a fold's
// fit fails.
inline double held_out_fit(std::span<const StallHoldData> data,
                           const std::vector<std::vector<std::size_t>>& folds,
                           estimation::StallHoldParameters<double> p, const StallHoldSettings& s,
                           double warmup) {
  const double fail = -std::numeric_limits<double>::infinity();
  p.velocity_threshold = s.velocity_threshold;
  p.velocity_time_constant = s.velocity_time_constant;
  p.output_time_constant = s.output_time_constant;
  const auto skip = static_cast<Eigen::Index>(std::ceil(warmup / p.sample_time));
  double sum = 0.0;
  std::size_t held = 0;
  for (const auto& fold : folds) {
    std::vector<StallHoldData> train;
    for (std::size_t e = 0; e < data.size(); ++e) {
      if (std::find(fold.begin(), fold.end(), e) == fold.end()) train.push_back(data[e]);
    }
    if (train.empty() || fold.empty()) continue;
#if defined(__cpp_exceptions)
    try {
#endif
      const StallHoldFit fit = fit_stall_hold(train, p, warmup);
      const estimation::StallHold<double> model(fit.parameters);
      for (const std::size_t e : fold) {
        const auto n = data[e].current.size() - skip;
        const double f =
            model::fit_percent(data[e].force.tail(n), simulate_stall_hold(model, data[e]).tail(n));
        if (!std::isfinite(f)) return fail;
        sum += f;
        ++held;
      }
#if defined(__cpp_exceptions)
    } catch (const Error&) {
      return fail;
    }
#endif
  }
  return held > 0 ? sum / static_cast<double>(held) : fail;
}

}  // namespace detail

ENDOHAPTICS_DECL StallHoldSelection choose_stall_hold_settings(
    std::span<const StallHoldData> data, const std::vector<std::vector<std::size_t>>& folds,
    const estimation::StallHoldParameters<double>& prior, double warmup) {
  StallHoldSelection out;
  out.settings = {prior.velocity_threshold, prior.velocity_time_constant,
                  prior.output_time_constant};
  prior.validate();
  if (!(std::isfinite(warmup) && warmup >= 0)) {
    ENDOHAPTICS_THROW(Error("choose_stall_hold_settings: warmup must be finite and >= 0 s, got " +
                            endohaptics::detail::format_number(warmup)));
  }
  const auto skip = static_cast<Eigen::Index>(std::ceil(warmup / prior.sample_time));
  for (std::size_t e = 0; e < data.size(); ++e) {
    const auto& d = data[e];
    if (d.velocity.size() != d.current.size() || d.force.size() != d.current.size() ||
        d.current.size() <= skip + 1) {
      ENDOHAPTICS_THROW(Error("choose_stall_hold_settings: experiment " + std::to_string(e) +
                              ": current, velocity and force must have one length, longer than "
                              "the warm-up"));
    }
  }
  for (const auto& fold : folds) {
    for (const std::size_t e : fold) {
      if (e >= data.size()) {
        ENDOHAPTICS_THROW(Error("choose_stall_hold_settings: fold index " + std::to_string(e) +
                                " beyond the " + std::to_string(data.size()) + " experiments"));
      }
    }
  }
  if (folds.size() < 2) return out;
  const auto score = [&](const StallHoldSettings& s) {
    ++out.candidates;
    return detail::held_out_fit(data, folds, prior, s, warmup);
  };
  out.prior_fit = score(out.settings);
  StallHoldSettings best = out.settings;
  double best_fit = -std::numeric_limits<double>::infinity();
  const double vths[] = {0.0125, 0.025, 0.05, 0.1, 0.2};
  const double tvs[] = {0.01, 0.03, 0.1};
  const double tos[] = {0.1, 0.15, 0.2, 0.3, 0.4, 0.6, 0.8};
  for (const double v : vths) {
    for (const double tv : tvs) {
      for (const double to : tos) {
        const StallHoldSettings s{v, tv, to};
        const double f = score(s);
        if (f > best_fit) {
          best_fit = f;
          best = s;
        }
      }
    }
  }
  if (!std::isfinite(best_fit)) return out;
  // Beyond the grid's edge, a factor of 2 at a time while the fit improves.
  const auto walk = [&](double StallHoldSettings::*member, double factor) {
    for (int i = 0; i < 3; ++i) {
      StallHoldSettings s = best;
      s.*member *= factor;
      const double f = score(s);
      if (!(f > best_fit)) return;
      best = s;
      best_fit = f;
    }
  };
  const auto edge = [&](double StallHoldSettings::*member, double low, double high) {
    if (best.*member == low) walk(member, 0.5);
    if (best.*member == high) walk(member, 2.0);
  };
  edge(&StallHoldSettings::velocity_threshold, vths[0], vths[4]);
  edge(&StallHoldSettings::velocity_time_constant, tvs[0], tvs[2]);
  edge(&StallHoldSettings::output_time_constant, tos[0], tos[6]);
  out.settings = best;
  out.held_out_fit = best_fit;
  out.folds = folds.size();
  return out;
}

}  // namespace endohaptics::workflow
