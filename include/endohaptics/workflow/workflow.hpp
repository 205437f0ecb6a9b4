//! @file
//! The identification workflow of worksheet 4.2 as endohaptics-identify runs it: from prepared
//! logs (workflow/prepared_log.hpp, 4.2.1), identify one model per candidate (subspace 4.2.2,
//! input dead zones 4.2.3, or the static gain baseline), score each per file like MATLAB compare
//! (workflow/model_comparison.hpp) and keep the best. Includes the whole workflow area.
//! Configuration time: allocates, throws endohaptics::Error. See docs/identification_results.md.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/files/identified_model_file.hpp"
#include "endohaptics/files/model_file.hpp"
#include "endohaptics/identification/hammerstein_wiener_fit.hpp"
#include "endohaptics/identification/subspace.hpp"
#include "endohaptics/model/static_map.hpp"
#include "endohaptics/workflow/error_context.hpp"
#include "endohaptics/workflow/model_comparison.hpp"
#include "endohaptics/workflow/prepared_log.hpp"
#include "endohaptics/workflow/static_gain_fit.hpp"
#include "endohaptics/workflow/workflow_options.hpp"
// Not used here: the rest of the workflow area, so that this header still gives all of it.
#include "endohaptics/workflow/option_parsing.hpp"
#include "endohaptics/workflow/preprocessing.hpp"
#include "endohaptics/workflow/preset_models.hpp"

namespace endohaptics::workflow {

using namespace endohaptics::identification;  // the workflow composes the identification area

//! One candidate model and its per-file fits on the identification logs.
struct CandidateModel {
  std::string method;                   //!< "moesp", "n4sid", "cva" or "static"
  files::ModelFile model;               //!< with names, units, provenance (notes empty)
  SubspaceModel linear;                 //!< the identified linear block (singular values, ...)
  std::vector<FileComparison> files{};  //!< per identification log
  double mean_fit = 0.0;                //!< mean over files and outputs, %
  double spectral_radius = 0.0;         //!< max |eig(A)|
};

//! All candidates tried and the index of the best.
struct WorkflowResult {
  std::vector<CandidateModel> candidates;  //!< in the order tried
  std::size_t best = 0;                    //!< index of the chosen one (best_candidate)
  std::vector<std::string> failures;       //!< "method: message" of candidates that failed

  //! The candidate at index `best`; throws std::out_of_range if `best` is out of range.
  [[nodiscard]] const CandidateModel& chosen() const { return candidates.at(best); }
};

//! Index of the candidate with the highest mean fit; with `prefer_stable`, among those with
//! spectral radius < 1 when there is any. Throws Error when `candidates` is empty.
[[nodiscard]] inline std::size_t best_candidate(const std::vector<CandidateModel>& candidates,
                                                bool prefer_stable) {
  if (candidates.empty()) detail::fail("best_candidate: no candidates");
  const bool any_stable =
      prefer_stable && std::any_of(candidates.begin(), candidates.end(),
                                   [](const CandidateModel& c) { return c.spectral_radius < 1.0; });
  std::size_t best = candidates.size();
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (any_stable && !(candidates[i].spectral_radius < 1.0)) continue;
    if (best == candidates.size() || candidates[i].mean_fit > candidates[best].mean_fit) best = i;
  }
  return best;
}

//! Identifies one model per candidate from all segments of all logs (one x0 per segment),
//! with dead zones as `options.deadzone` says, scores each on every log (compare_log) and keeps
//! the best (best_candidate). With several candidates a failing one is recorded in `failures`
//! and skipped. Throws Error on bad options or data (as identify / fit_hammerstein_wiener), or
//! when every candidate failed.
[[nodiscard]] inline WorkflowResult identify_logs(const std::vector<PreparedLog>& logs,
                                                  const std::vector<files::SignalInfo>& inputs,
                                                  const std::vector<files::SignalInfo>& outputs,
                                                  const WorkflowOptions& options) {
  namespace wf = detail;
  if (logs.empty()) wf::fail("identify: no logs");
  const auto nu = inputs.size();
  std::vector<DataSet> data;
  std::vector<std::string> files;
  for (const PreparedLog& log : logs) {
    files.push_back(log.source);
    for (const DataSet& d : log.segments) data.push_back(d);
  }
  if (data.empty()) wf::fail("identify: the logs have no usable segments");
  const double ts = logs.front().sample_time;
  std::vector<DeadzoneSetting> dz = options.deadzone;
  if (dz.empty()) dz.assign(nu, DeadzoneSetting{});
  if (dz.size() != nu) {
    wf::fail("identify: " + std::to_string(dz.size()) + " dead-zone settings for " +
             std::to_string(nu) + " inputs");
  }
  const bool any_fit = std::any_of(dz.begin(), dz.end(), [](const DeadzoneSetting& s) {
    return s.mode == DeadzoneSetting::Mode::fit;
  });
  const bool any_map = std::any_of(dz.begin(), dz.end(), [](const DeadzoneSetting& s) {
    return s.mode != DeadzoneSetting::Mode::none;
  });
  // Fixed dead zones are applied to the data before anything is fitted.
  std::vector<StaticMap> fixed(nu);
  for (std::size_t j = 0; j < nu; ++j) {
    if (dz[j].mode == DeadzoneSetting::Mode::fixed) {
      fixed[j] = {StaticMapKind::deadzone, -dz[j].width, dz[j].width};
    }
  }
  std::vector<DataSet> mapped;
  for (const DataSet& d : data) mapped.push_back({apply_maps(fixed, d.u), d.y});

  SubspaceOptions so;
  so.order = options.order;
  so.max_order = options.max_order;
  so.block_rows = options.block_rows;
  so.sample_time = ts;

  WorkflowResult result;
  auto finish = [&](std::string method, SubspaceModel linear, const std::vector<StaticMap>& maps) {
    files::ModelProvenance p;
    p.method = method;
    p.files = files;
    CandidateModel c{.method = std::move(method),
                     .model = files::make_model_file(linear, inputs, outputs, p),
                     .linear = std::move(linear)};
    if (any_map) {
      c.model.input_nonlinearity = maps;
      c.model.output_nonlinearity.assign(outputs.size(), StaticMap{});
    }
    double sum = 0.0;
    for (const PreparedLog& log : logs) {
      c.files.push_back(compare_log(c.model, log, options.initial_state));
      sum += c.files.back().mean_fit();
    }
    c.mean_fit = sum / static_cast<double>(logs.size());
    std::vector<double> per_output(outputs.size(), 0.0);
    for (const FileComparison& f : c.files) {
      for (std::size_t i = 0; i < outputs.size(); ++i) {
        per_output[i] += f.fit[static_cast<Eigen::Index>(i)] / static_cast<double>(logs.size());
      }
    }
    c.model.provenance.fit_percent = per_output;
    c.spectral_radius = c.linear.state_space.spectral_radius();
    result.candidates.push_back(std::move(c));
  };

  if (options.static_gain) {
    if (any_fit) wf::fail("identify: --deadzone auto needs a subspace method, not static");
    finish("static", fit_static_gain(std::span<const DataSet>(mapped), ts), fixed);
  } else {
    if (options.candidates.empty()) wf::fail("identify: no subspace method to try");
    for (const Weighting w : options.candidates) {
      so.weighting = w;
      std::string method(to_string(w));
      std::vector<StaticMap> maps = fixed;
      // One of several weightings may fail (e.g. a model so unstable that the B, D, x0
      // regression overflows): record it and go on with the others.
      const auto attempt = [&] {
        if (any_fit) {
          HammersteinWienerFitOptions ho;
          ho.linear = so;
          ho.grid_points = options.deadzone_grid;
          ho.refine_iterations = options.deadzone_refine;
          for (std::size_t j = 0; j < nu; ++j) {
            ho.input_kind.push_back(dz[j].mode == DeadzoneSetting::Mode::fit
                                        ? StaticMapKind::deadzone
                                        : StaticMapKind::none);
          }
          HammersteinWienerFit hw = fit_hammerstein_wiener(std::span<const DataSet>(mapped), ho);
          for (std::size_t j = 0; j < nu; ++j) {
            if (dz[j].mode == DeadzoneSetting::Mode::fit) maps[j] = hw.input[j];
          }
          finish(method + " + dead zone", std::move(hw.linear), maps);
        } else {
          finish(method, identify(std::span<const DataSet>(mapped), so), maps);
        }
      };
#if defined(__cpp_exceptions)
      if (options.candidates.size() > 1) {
        try {
          attempt();
        } catch (const Error& e) {
          result.failures.push_back(std::string(to_string(w)) + ": " + e.what());
        }
        continue;
      }
#endif
      wf::with_context(std::string(to_string(w)), attempt);
    }
  }
  if (result.candidates.empty()) {
    std::string all;
    for (const auto& f : result.failures) all += (all.empty() ? "" : "; ") + f;
    wf::fail("identify: every method failed: " + all);
  }
  result.best = best_candidate(result.candidates, options.prefer_stable);
  return result;
}

}  // namespace endohaptics::workflow
