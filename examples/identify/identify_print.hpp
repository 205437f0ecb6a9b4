// What endohaptics-identify prints (workflow::IdentifyReport as text), at the three points it
// prints: once the logs are prepared, once the subspace family is fitted, once the family is
// chosen. The lines are those docs/identification.md explains and tests/e2e/identify_cli.sh reads.
#pragma once

#include <fmt/format.h>

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <endohaptics/model/stop_operators.hpp>
#include <endohaptics/workflow/identify_request.hpp>
#include <functional>
#include <string>
#include <string_view>

namespace identify_print {

namespace wf = endohaptics::workflow;

//! The search's progress, one line per model and fold on standard error, when that is a
//! terminal (a long search, e.g. the 70 UMN runs, shows it is moving; logs and pipes stay as
//! they were).
inline std::function<void(std::string_view)> progress_on_terminal() {
  if (::isatty(STDERR_FILENO) == 0) return {};
  return [](std::string_view line) { fmt::print(stderr, "identify: {}\n", line); };
}

//! The preprocessing and the causal score's settings.
inline void prepared(const wf::IdentifyProgress& r) {
  fmt::print("preprocessing for the fit: {}\n", wf::describe(r.preprocessing));
  const wf::TimeConstantLimit& tc = r.time_constant_limit;
  fmt::print(
      "scoring (causal): x0 {}, warm-up {} s per segment excluded, inputs held and low-passed "
      "forward only ({} Hz), output as logged (no offset, filter or detrend); refused: "
      "spectral radius >= 1 or slowest time constant > {}\n",
      r.request.x0, r.request.warmup, r.preprocessing.cutoff,
      std::isfinite(tc.seconds)
          ? fmt::format("{} s{}", tc.seconds, tc.source.empty() ? "" : " (" + tc.source + ")")
          : std::string("(no limit)"));
}

//! Every subspace candidate, the order search and the subspace family's choice.
inline void subspace_fitted(const wf::IdentifyProgress& r) {
  if (!r.subspace_left_out.empty()) {
    fmt::print("subspace family left out: {}\n", r.subspace_left_out);
  }
  const wf::WorkflowResult& result = r.subspace_result();
  for (const wf::CandidateModel& c : result.candidates) {
    if (c.kind != wf::Method::static_gain) {
      const auto& sv = c.linear.order_singular_values;
      std::string line;
      for (Eigen::Index i = 0; i < std::min<Eigen::Index>(sv.size(), r.options.max_order + 5);
           ++i) {
        line += fmt::format(" {:.4g}", sv[i]);
      }
      fmt::print("{}: Hankel singular values (MOESP, {} block rows):{}\n", c.method,
                 c.linear.block_rows, line);
      fmt::print("{}: order {} ({}), spectral radius {:.5f}, slowest time constant {:.3g} s{}\n",
                 c.method, c.linear.order,
                 c.order_searched       ? "order search"
                 : r.options.order == 0 ? "automatic"
                                        : "given",
                 c.spectral_radius, c.time_constant,
                 c.refused.empty() ? std::string() : " REFUSED: " + c.refused);
    }
    for (std::size_t j = 0; j < c.model.input_nonlinearity.size(); ++j) {
      const auto& m = c.model.input_nonlinearity[j];
      if (m.kind == endohaptics::model::StaticMapKind::none) continue;
      fmt::print("{}: input {} dead zone [{:.4g}, {:.4g}]\n", c.method, r.selection.inputs[j],
                 m.lower, m.upper);
    }
    fmt::print("{}: mean causal fit {:.2f} %\n", c.method, c.mean_fit);
  }
  for (const wf::OrderTrial& t : result.order_search) {
    fmt::print("order search: order {} mean causal fit {:.2f} %, spectral radius {:.5f}{}\n",
               t.order, t.mean_fit, t.spectral_radius,
               t.refused.empty() ? std::string() : " REFUSED: " + t.refused);
  }
  fmt::print("models fitted and scored: {}\n", result.evaluations);
  for (const std::string& f : result.failures) fmt::print("failed: {}\n", f);
  if (!r.subspace) return;
  const wf::CandidateModel& best = result.chosen();
  if (best.kind != wf::Method::static_gain && (best.linear.input_scale.array() != 1.0).any()) {
    fmt::print(
        "scaling: each column divided by its RMS for the fit (inputs {:.4g}, outputs "
        "{:.4g}); the model is in the logs' units\n",
        fmt::join(best.linear.input_scale.begin(), best.linear.input_scale.end(), " "),
        fmt::join(best.linear.output_scale.begin(), best.linear.output_scale.end(), " "));
  }
  fmt::print("subspace family: {} (order {}, spectral radius {:.5f}), mean causal fit {:.2f} %\n",
             best.method, best.model.state_space.state_size(), best.spectral_radius, best.mean_fit);
}

//! The family choice, the chosen model and its scores on each file.
inline void chosen(const wf::IdentifyReport& r) {
  const wf::ModelChoice& choice = r.choice;
  const auto& sel = r.selection;
  if (choice.families.size() > 1) {
    fmt::print(
        "family choice ({}): causal score of each family fitted on the other training files"
        "{}\n",
        choice.folds.empty() ? "one training file: the training score"
                             : fmt::format("inner cross-validation, {} folds", choice.folds.size()),
        r.subspace ? " (the subspace family refitted with its structure chosen on all of them)"
                   : "");
    for (const wf::FamilyScore& f : choice.families) {
      fmt::print("family {}: mean causal fit {:.2f} %, mean RMSE {:.4g} {} (per fold: {:.1f}){}\n",
                 f.family, f.mean_fit, f.mean_rmse, r.output_info.front().unit,
                 fmt::join(f.fold_fit, " "),
                 f.failure.empty() ? std::string() : " FAILED on a fold: " + f.failure);
    }
  }
  const bool joint = r.joint_chosen();
  fmt::print("chosen: {}{}\n", choice.family,
             choice.families.size() > 1 ? " (the highest mean causal fit of the families above)"
             : joint                    ? " (the only family asked for)"
                                        : "");
  if (joint) {
    fmt::print(
        "{}\nits grid: Ts {} s, inputs {} (current) and {} (velocity){}, no low-pass "
        "beyond its own filters; the state starts from the model's reset (filters at the "
        "first sample)\n",
        choice.joint_summary, choice.model.state_space.sample_time(), sel.inputs[0], sel.inputs[1],
        sel.inputs.size() > 2 ? " and " + sel.inputs[2] + " (the current command)" : std::string());
  } else {
    fmt::print("chosen model: order {}, spectral radius {:.5f}\n",
               choice.model.state_space.state_size(), r.subspace_result().chosen().spectral_radius);
    if (choice.model.free_motion_threshold > 0.0) {
      fmt::print(
          "free-motion threshold: {:.4g} (the estimate reads 0 up to it; scores include it)\n",
          choice.model.free_motion_threshold);
    }
    if (r.request.current_play > 0.0) {
      fmt::print("current play: half width {:.4g} on {} (fitted and scored on the played input)\n",
                 r.request.current_play, sel.inputs[0]);
      if (r.request.current_play_slide || r.request.current_play_viscous != 0.0) {
        fmt::print("  sliding half width {:.4g}, viscous current {:.4g} x {}\n",
                   endohaptics::model::friction_play_slide(r.request.current_play,
                                                           r.request.current_play_slide),
                   r.request.current_play_viscous, sel.inputs.size() > 1 ? sel.inputs[1] : "-");
      }
    }
  }
  for (std::size_t k = 0; k < choice.files.size(); ++k) {
    const wf::FileComparison& f = choice.files[k];
    for (Eigen::Index i = 0; i < f.fit.size(); ++i) {
      const std::string oracle =
          joint ? "no oracle score: a joint model has no linear state"
                : fmt::format("oracle x0, zero-phase data: {:.2f} %", r.oracle[k].fit[i]);
      const auto o = static_cast<std::size_t>(i);
      fmt::print(
          "fit {}: {} causal {:.2f} %, correlation {:.4f}, RMSE {:.4g} {}, delay {:.0f} ms ({})\n",
          f.source, sel.outputs[o], f.fit[i], f.correlation[i], f.rmse[i], r.output_info[o].unit,
          1000.0 * f.delay[i], oracle);
    }
  }
}

//! The last two lines: the means over the files.
inline void means(const wf::IdentifyReport& r) {
  const std::string& unit = r.output_info.front().unit;
  fmt::print("mean RMSE: {:.4g}{}{}\n", r.mean_rmse, unit.empty() ? "" : " ", unit);
  fmt::print("mean fit: {:.2f}%\n", r.mean_fit);
}

}  // namespace identify_print
