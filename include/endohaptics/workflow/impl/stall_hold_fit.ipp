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

}  // namespace endohaptics::workflow
