//! @file
//! A model file replayed on prepared logs like MATLAB compare (worksheet 4.2): input maps,
//! linear block and output maps simulated segment by segment with x0 estimated, zero or stored,
//! scored over the whole file by NRMSE fit (%), correlation and RMSE (output units;
//! identification/fit_metrics.hpp). Configuration time: throws endohaptics::Error.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "endohaptics/files/model_file.hpp"
#include "endohaptics/identification/fit_metrics.hpp"
#include "endohaptics/identification/hammerstein_wiener_fit.hpp"
#include "endohaptics/identification/subspace.hpp"
#include "endohaptics/model/static_map.hpp"
#include "endohaptics/workflow/error_context.hpp"
#include "endohaptics/workflow/prepared_log.hpp"

namespace endohaptics::workflow {

using namespace endohaptics::identification;  // the workflow composes the identification area

//! How replay/compare set the initial state of every segment.
enum class InitialStateMode : std::uint8_t {
  estimate,  //!< least squares on the compared data (MATLAB compare's default)
  zero,      //!< x0 = 0
  stored,    //!< the model file's x0
};

//! A model simulated on one prepared log, segment by segment, and its fit over the whole file.
struct FileComparison {
  std::string source;                  //!< file
  std::vector<Eigen::MatrixXd> y;      //!< measured output per segment (after preprocessing)
  std::vector<Eigen::MatrixXd> y_hat;  //!< simulated output per segment
  std::vector<double> start_time;      //!< s, per segment
  double sample_time = 0.0;            //!< s
  Eigen::VectorXd fit;                 //!< NRMSE fit per output over all segments, %
  Eigen::VectorXd correlation;         //!< per output
  Eigen::VectorXd rmse;                //!< per output, output units

  //! Mean of `fit` over the outputs, %.
  [[nodiscard]] double mean_fit() const { return fit.mean(); }
};

//! Simulates the model file (input maps, linear block, output maps) on every segment of `log`
//! with x0 as `mode` says (estimate: least squares through the linear block on the mapped
//! inputs) and scores the concatenated segments. Throws Error when the log's input or output
//! count differs from the model's.
[[nodiscard]] inline FileComparison compare_log(
    const files::ModelFile& model, const PreparedLog& log,
    InitialStateMode mode = InitialStateMode::estimate) {
  namespace wf = detail;
  const auto& linear = model.state_space;  // the linear block, x0 = its state
  const auto nu = static_cast<Eigen::Index>(model.inputs.size());
  const auto ny = static_cast<Eigen::Index>(model.outputs.size());
  if (log.segments.empty()) wf::fail(log.source + ": no segments to compare");
  if (log.segments.front().u.cols() != nu || log.segments.front().y.cols() != ny) {
    wf::fail(log.source + ": the log gives " + std::to_string(log.segments.front().u.cols()) +
             " inputs and " + std::to_string(log.segments.front().y.cols()) +
             " outputs, the model has " + std::to_string(nu) + " and " + std::to_string(ny));
  }
  std::vector<StaticMap> in_maps = model.input_nonlinearity;
  std::vector<StaticMap> out_maps = model.output_nonlinearity;
  if (in_maps.empty()) in_maps.assign(static_cast<std::size_t>(nu), StaticMap{});
  if (out_maps.empty()) out_maps.assign(static_cast<std::size_t>(ny), StaticMap{});
  FileComparison c;
  c.source = log.source;
  c.sample_time = log.sample_time;
  c.start_time = log.start_time;
  const Eigen::Index total = log.samples();
  Eigen::MatrixXd y_all(total, ny);
  Eigen::MatrixXd y_hat_all(total, ny);
  Eigen::Index row = 0;
  for (const DataSet& d : log.segments) {
    const Eigen::MatrixXd u = apply_maps(in_maps, d.u);
    Eigen::VectorXd x0 = Eigen::VectorXd::Zero(linear.state_size());
    if (mode == InitialStateMode::estimate) {
      x0 = wf::with_context(log.source, [&] { return estimate_initial_state(linear, u, d.y); });
    } else if (mode == InitialStateMode::stored) {
      x0 = linear.state();
    }
    const Eigen::MatrixXd y_hat = apply_maps(out_maps, simulate(linear, u, x0));
    y_all.middleRows(row, d.y.rows()) = d.y;
    y_hat_all.middleRows(row, d.y.rows()) = y_hat;
    row += d.y.rows();
    c.y.push_back(d.y);
    c.y_hat.push_back(y_hat);
  }
  // A diverging model gives Inf/NaN: report fit -Inf rather than failing on the metric.
  if (!y_hat_all.allFinite()) {
    c.fit = Eigen::VectorXd::Constant(ny, -std::numeric_limits<double>::infinity());
    c.correlation = Eigen::VectorXd::Constant(ny, std::numeric_limits<double>::quiet_NaN());
    c.rmse = Eigen::VectorXd::Constant(ny, std::numeric_limits<double>::infinity());
    return c;
  }
  c.fit = nrmse_fit(y_all, y_hat_all);
  c.correlation = correlation(y_all, y_hat_all);
  c.rmse = rmse(y_all, y_hat_all);
  return c;
}

//! Throws Error naming the file and the output when a score of `c` is not finite, so that a
//! program never reports such a run as a success: a simulated output that diverges (an unstable
//! model: fit -Inf), a constant measured output the model does not match (fit -Inf), or a
//! constant measured or simulated output (correlation undefined). `outputs` names the outputs
//! (fewer names: numbered).
inline void require_finite_scores(const FileComparison& c,
                                  const std::vector<std::string>& outputs) {
  const auto name = [&](Eigen::Index i) {
    const auto k = static_cast<std::size_t>(i);
    return k < outputs.size() ? "'" + outputs[k] + "'" : "output " + std::to_string(i);
  };
  bool diverged = false;
  for (const Eigen::MatrixXd& y_hat : c.y_hat) diverged = diverged || !y_hat.allFinite();
  if (diverged) {
    detail::fail(c.source +
                 ": the simulated output is not finite: the model diverges on this log " +
                 "(unstable, or unstable for these inputs); no fit can be given");
  }
  for (Eigen::Index i = 0; i < c.fit.size(); ++i) {
    if (!std::isfinite(c.fit[i])) {
      detail::fail(c.source + ": fit of " + name(i) + " is " + detail::format_number(c.fit[i]) +
                   ": the measured output is constant and the model does not reproduce it");
    }
    if (i < c.correlation.size() && !std::isfinite(c.correlation[i])) {
      detail::fail(c.source + ": correlation of " + name(i) +
                   " is undefined: the measured or the simulated output is constant");
    }
    if (i < c.rmse.size() && !std::isfinite(c.rmse[i])) {
      detail::fail(c.source + ": RMSE of " + name(i) + " is not finite");
    }
  }
}

}  // namespace endohaptics::workflow
