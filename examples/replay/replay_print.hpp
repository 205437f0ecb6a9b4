// What endohaptics-replay prints (workflow::ReplayReport as text) and its --plot figure.
#pragma once

#include <fmt/format.h>

#include <endohaptics/workflow/gnuplot.hpp>
#include <endohaptics/workflow/option_parsing.hpp>
#include <endohaptics/workflow/replay_request.hpp>
#include <string>
#include <utility>
#include <vector>

namespace replay_print {

namespace wf = endohaptics::workflow;
namespace files = endohaptics::files;

//! The model and how it is scored.
inline void resolved(const wf::ReplayReport& r) {
  const files::ModelFile& model = r.model;
  const wf::Preprocessing& pre = r.preprocessing;
  if (model.is_joint_model()) {
    fmt::print("{}: kind {}, {} -> {}, Ts {} s, {}\n", r.name, files::to_string(model.kind()),
               fmt::join(r.model_inputs, ", "), fmt::join(r.model_outputs, ", "),
               model.state_space.sample_time(), model.provenance.method);
  } else {
    fmt::print("{}: {} states, {} -> {}, Ts {} s, {}\n", r.name, model.state_space.state_size(),
               fmt::join(r.model_inputs, ", "), fmt::join(r.model_outputs, ", "),
               model.state_space.sample_time(), model.provenance.method);
  }
  if (r.causal() && model.is_joint_model()) {
    fmt::print(
        "scoring (causal): the model's state from its reset (filters started at the first "
        "sample; --x0 does not apply), warm-up {} s per segment excluded, inputs held "
        "(lowpass_hz={}), output as logged (no offset, filter or detrend)\n",
        r.scoring.warmup, pre.cutoff);
  } else if (r.causal()) {
    fmt::print(
        "scoring (causal): x0 {}, warm-up {} s per segment excluded, inputs held and low-passed "
        "forward only (lowpass_hz={} filter_order={}, {}), output as logged (no offset, filter "
        "or detrend)\n",
        r.request.x0, r.scoring.warmup, pre.cutoff, pre.filter_order,
        r.recorded ? "as the model file records" : "flags");
    if (pre.output_offset != wf::OffsetMode::none || pre.input_offset != wf::OffsetMode::none ||
        pre.detrend) {
      fmt::print(
          "note: the model was fitted on data with offsets/detrend removed ({}); they "
          "are not removed when scoring\n",
          wf::describe(pre));
    }
  } else {
    fmt::print(
        "scoring: ORACLE, not a force-estimation result: x0 fitted to the measured output, "
        "data preprocessed as for the fit ({}: {})\n",
        r.recorded ? "model file, flags override" : "flags", wf::describe(pre));
  }
}

//! One log's scores, one line per output.
inline void scored(const wf::ReplayReport& r, const wf::FileComparison& c) {
  const std::string& path = r.request.logs[r.files.size() - 1];
  for (Eigen::Index i = 0; i < c.fit.size(); ++i) {
    const auto& o = r.model.outputs[static_cast<std::size_t>(i)];
    fmt::print("{}: {} fit {:.2f} %, correlation {:.4f}, RMSE {:.4g}{}{}, delay {:.0f} ms\n", path,
               r.selection.outputs[static_cast<std::size_t>(i)], c.fit[i], c.correlation[i],
               c.rmse[i], o.unit.empty() ? "" : " ", o.unit, 1000.0 * c.delay[i]);
  }
}

//! Measured vs simulated, one panel per file; segments break the lines. workflow/gnuplot.hpp
//! draws it: file and signal names travel to gnuplot as data, never as code.
inline void plot(const std::string& png, const std::vector<wf::FileComparison>& files,
                 const std::vector<std::string>& outputs) {
  wf::PlotFigure figure;
  for (const auto& f : files) {
    wf::PlotPanel& panel = figure.panels.emplace_back();
    panel.title = fmt::format("{} (fit {:.1f} %)", f.source, f.mean_fit());
    panel.x_label = "time (s)";
    for (std::size_t i = 0; i < outputs.size(); ++i) {
      const auto column = static_cast<Eigen::Index>(i);
      wf::PlotSeries measured, simulated;
      measured.title = outputs[i] + " measured";
      simulated.title = outputs[i] + " simulated";
      measured.line_width = simulated.line_width = 2;
      for (std::size_t s = 0; s < f.y.size(); ++s) {
        measured.gap();
        simulated.gap();
        for (Eigen::Index k = 0; k < f.y[s].rows(); ++k) {
          const double t = f.start_time[s] + static_cast<double>(k) * f.sample_time;
          measured.add(t, f.y[s](k, column));
          simulated.add(t, f.y_hat[s](k, column));
        }
      }
      panel.series.push_back(std::move(measured));
      panel.series.push_back(std::move(simulated));
    }
  }
  wf::write_png(figure, png);
}

}  // namespace replay_print
