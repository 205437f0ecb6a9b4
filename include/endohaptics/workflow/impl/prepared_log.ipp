//! @file
//! Function bodies of workflow/prepared_log.hpp: included at its end (header-only, the default), or
//! compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/workflow/prepared_log.hpp"

namespace endohaptics::workflow {

ENDOHAPTICS_DECL files::Log read_selected_format(const std::string& path, const LogSelection& sel) {
  const files::LogReadOptions read;  // bad rows dropped and reported; non-finite checked by callers
  if (sel.format == files::LogFormat::csv) {
    files::CsvOptions o;
    o.read = read;
    o.sample_time = sel.csv_row_time;
    return files::read_csv(path, o);
  }
  return files::read_log(path, sel.format, read);
}

ENDOHAPTICS_DECL std::vector<std::string> controller_signals(files::LogFormat format) {
  if (format == files::LogFormat::umn_mis_2018) {
    return {"current", "current_command", "motor_velocity"};
  }
  return {};
}
}  // namespace endohaptics::workflow

namespace endohaptics::workflow {
namespace detail {

ENDOHAPTICS_DECL Eigen::VectorXd backward_difference(const Eigen::VectorXd& time,
                                                     const Eigen::VectorXd& x, double max_gap) {
  Eigen::VectorXd v = Eigen::VectorXd::Zero(x.size());
  for (Eigen::Index k = 1; k < x.size(); ++k) {
    const double dt = time[k] - time[k - 1];
    if (dt > 0.0 && (max_gap <= 0.0 || dt <= max_gap)) v[k] = (x[k] - x[k - 1]) / dt;
  }
  return v;
}
}  // namespace detail
}  // namespace endohaptics::workflow

namespace endohaptics::workflow {

ENDOHAPTICS_DECL double default_sample_time(const std::string& path, const LogSelection& sel) {
  const double step = read_selected_format(path, sel).report.median_step;
  if (!(step > 0.0)) return step;
  // Six significant digits: 0.009999999999999787 (a sum of decimal stamps) becomes 0.01.
  const double scale = std::pow(10.0, 5.0 - std::floor(std::log10(step)));
  return std::round(step * scale) / scale;
}
}  // namespace endohaptics::workflow

namespace endohaptics::workflow {
namespace detail {

ENDOHAPTICS_DECL PreparedLog prepare_for_scoring(const std::string& path, const files::Log& log,
                                                 Eigen::MatrixXd signals, Eigen::Index nu,
                                                 const LogSelection& sel, double ts,
                                                 const Preprocessing& pre,
                                                 Eigen::Index min_samples) {
  const double source_step = median_step(log.time);
  const double max_gap = pre.max_gap > 0
                             ? pre.max_gap
                             : 5.0 * (std::isfinite(source_step) ? std::max(ts, source_step) : ts);
  // The 2016 reader's velocity is the secant over both neighbours (it looks one sample ahead):
  // a controller has the backward difference.
  if (sel.format == files::LogFormat::endowrist_2016 && log.has("position")) {
    const Eigen::VectorXd v = backward_difference(log.time, log.signal("position"), max_gap);
    for (Eigen::Index c = 0; c < nu; ++c) {
      if (sel.inputs[static_cast<std::size_t>(c)] == "velocity") signals.col(c) = v;
    }
  }
  Segments segs = resample_uniform(log.time, signals, ts, ResampleOptions{max_gap, 2});
  SosMatrix sos;
  Eigen::Matrix<double, Eigen::Dynamic, 2> zi;
  if (pre.cutoff > 0) {
    sos = butterworth_lowpass(pre.filter_order, pre.cutoff, ts);
    zi = sosfilt_zi(sos);
  }
  PreparedLog out;
  out.source = path;
  out.report = log.report;
  out.sample_time = ts;
  out.preparation = Preparation::score;
  out.gaps = segs.gaps;
  out.dropped_segments = segs.dropped_segments;
  out.input_offsets = Eigen::VectorXd::Zero(nu);
  out.output_offsets = Eigen::VectorXd::Zero(signals.cols() - nu);
  for (UniformSegment& s : segs.segments) {
    if (s.rows() < std::max<Eigen::Index>(pre.min_segment, 2)) {
      ++out.dropped_segments;
      continue;
    }
    // Inputs: zero-order hold of the last source sample at or before each grid time.
    Eigen::Index src = s.first_source;
    for (Eigen::Index g = 0; g < s.rows(); ++g) {
      const double tg = s.start_time + static_cast<double>(g) * ts;
      while (src < s.last_source && log.time[src + 1] <= tg + 1e-9 * ts) ++src;
      s.data.row(g).head(nu) = signals.row(src).head(nu);
    }
    if (sos.rows() > 0) {
      for (Eigen::Index c = 0; c < nu; ++c) {
        Eigen::Matrix<double, Eigen::Dynamic, 2> state = zi * s.data(0, c);
        s.data.col(c) = sosfilt(sos, s.data.col(c), state);
      }
    }
    out.segments.push_back(DataSet{s.data.leftCols(nu), s.data.rightCols(s.data.cols() - nu)});
    out.start_time.push_back(s.start_time);
  }
  if (out.samples() < min_samples) {
    fail(path + ": too few samples: " + std::to_string(out.samples()) + " on the grid at ts = " +
         format_number(ts) + " s in segments of >= " + std::to_string(pre.min_segment) +
         ", at least " + std::to_string(min_samples) + " needed");
  }
  return out;
}
}  // namespace detail
}  // namespace endohaptics::workflow

namespace endohaptics::workflow {

ENDOHAPTICS_DECL PreparedLog prepare_log(const std::string& path, const LogSelection& sel,
                                         double ts, const Preprocessing& pre,
                                         Eigen::Index min_samples, Preparation use) {
  namespace wf = detail;
  if (sel.inputs.empty()) wf::fail(path + ": no input signal named");
  if (sel.outputs.empty()) wf::fail(path + ": no output signal named");
  if (!std::isfinite(ts) || !(ts > 0.0))
    wf::fail(path + ": sample time must be finite and > 0 s, got " + wf::format_number(ts));
  validate(pre);
  std::vector<std::string> names = sel.inputs;
  names.insert(names.end(), sel.outputs.begin(), sel.outputs.end());
  for (std::size_t i = 0; i < names.size(); ++i) {
    for (std::size_t k = 0; k < i; ++k) {
      if (names[k] != names[i]) continue;
      const auto role = [&](std::size_t at) { return at < sel.inputs.size() ? "input" : "output"; };
      wf::fail(path + ": signal '" + names[i] + "' is named twice (as " + role(k) + " and as " +
               role(i) + "): a model needs distinct input and output signals");
    }
  }
  const std::vector<std::string> allowed = controller_signals(sel.format);
  if (!allowed.empty()) {
    for (const std::string& name : sel.inputs) {
      if (std::find(allowed.begin(), allowed.end(), name) != allowed.end()) continue;
      wf::fail(path + ": input '" + name + "' is not a signal a robot controller has (inputs of " +
               "this format: " + wf::join(allowed) +
               (name == "motor_position"
                    ? "; motor_position's zero differs between sessions: use motor_velocity"
                    : "") +
               ")");
    }
  }
  const files::Log log = read_selected_format(path, sel);
  if (!sel.drop_non_finite && log.report.non_finite > 0) {
    std::string where;
    for (const files::LogIssue& issue : log.report.issues) {
      if (issue.kind == files::LogIssueKind::non_finite) {
        where = " (first at line " + std::to_string(issue.line) + ": " + issue.detail + ")";
        break;
      }
    }
    wf::fail(path + ": " + std::to_string(log.report.non_finite) +
             " row(s) hold non-finite values" + where + "; pass --drop-non-finite to drop them");
  }
  for (const std::string& name : names) {
    if (name == "time" || !log.has(name)) {
      wf::fail(path + ": no signal named '" + name + "' (signals: " + wf::join(log.names) + ")");
    }
  }
  Eigen::MatrixXd signals = log.select(names);
  const double span = log.time[log.rows() - 1] - log.time[0];
  const double grid = std::floor(span / ts + 1e-9) + 1.0;
  if (!(grid <= static_cast<double>(limits::max_grid_samples))) {
    wf::fail(path + ": " + wf::format_number(span) + " s at ts = " + wf::format_number(ts) +
             " s would give " + wf::format_number(grid) + " grid samples, more than the limit of " +
             std::to_string(limits::max_grid_samples) + " per log: choose a larger ts");
  }
  if (std::floor(span / ts + 1e-9) + 1.0 < static_cast<double>(min_samples)) {
    wf::fail(path + ": too few samples: " + std::to_string(log.rows()) + " rows spanning " +
             wf::format_number(span) + " s give at most " +
             std::to_string(static_cast<long long>(std::floor(span / ts + 1e-9)) + 1) +
             " samples at ts = " + wf::format_number(ts) + " s, at least " +
             std::to_string(min_samples) + " needed");
  }
  const auto nu = static_cast<Eigen::Index>(sel.inputs.size());
  const auto ny = static_cast<Eigen::Index>(sel.outputs.size());

  if (use == Preparation::score) {
    return wf::with_context(path, [&] {
      return detail::prepare_for_scoring(path, log, signals, nu, sel, ts, pre, min_samples);
    });
  }

  PreprocessOptions po;
  po.sample_time = ts;
  po.max_gap = pre.max_gap;
  po.cutoff = pre.cutoff;
  po.filter_order = pre.filter_order;
  po.offset_duration = pre.offset_duration;
  po.offset_estimator = OffsetEstimator::median;
  for (Eigen::Index c = 0; c < nu + ny; ++c) {
    if ((c < nu ? pre.input_offset : pre.output_offset) == OffsetMode::start) {
      po.offset_columns.push_back(c);
    }
  }
  Segments segs = wf::with_context(path, [&] { return preprocess(log.time, signals, po); });

  PreparedLog out;
  out.source = path;
  out.report = log.report;
  out.sample_time = ts;
  out.gaps = segs.gaps;
  out.dropped_segments = segs.dropped_segments;
  Eigen::VectorXd offsets = segs.offsets;
  // Whole-file offsets (median / mean over every kept segment).
  Eigen::Index total = 0;
  for (const auto& s : segs.segments) total += s.rows();
  Eigen::MatrixXd all(total, nu + ny);
  Eigen::Index row = 0;
  for (const auto& s : segs.segments) {
    all.middleRows(row, s.rows()) = s.data;
    row += s.rows();
  }
  for (Eigen::Index c = 0; c < nu + ny; ++c) {
    const OffsetMode mode = c < nu ? pre.input_offset : pre.output_offset;
    if (mode != OffsetMode::median && mode != OffsetMode::mean) continue;
    const double offset = estimate_offset(
        all.col(c),
        OffsetWindow{0, -1,
                     mode == OffsetMode::mean ? OffsetEstimator::mean : OffsetEstimator::median});
    offsets[c] = offset;
    for (auto& s : segs.segments) s.data.col(c).array() -= offset;
  }
  out.input_offsets = offsets.head(nu);
  out.output_offsets = offsets.tail(ny);
  for (auto& s : segs.segments) {
    if (s.rows() < std::max<Eigen::Index>(pre.min_segment, 2)) {
      ++out.dropped_segments;
      continue;
    }
    DataSet d{s.data.leftCols(nu), s.data.rightCols(ny)};
    if (pre.detrend) {
      for (Eigen::Index c = 0; c < ny; ++c) d.y.col(c) = identification::detrend(d.y.col(c));
    }
    out.segments.push_back(std::move(d));
    out.start_time.push_back(s.start_time);
  }
  if (out.samples() < min_samples) {
    wf::fail(path + ": too few samples: " + std::to_string(out.samples()) +
             " on the grid at ts = " + wf::format_number(ts) + " s in segments of >= " +
             std::to_string(pre.min_segment) + " (from " + std::to_string(log.rows()) +
             " rows), at least " + std::to_string(min_samples) + " needed");
  }
  return out;
}

ENDOHAPTICS_DECL std::string summary(const PreparedLog& log) {
  const files::LogReport& r = log.report;
  std::ostringstream out;
  out.precision(4);
  out << log.source << ": " << r.rows << " rows kept of " << r.lines << " lines; dropped "
      << r.dropped() << " (empty field " << r.empty_fields << ", short line " << r.short_lines
      << ", non-numeric " << r.non_numeric << ", non-finite " << r.non_finite << ", repeated time "
      << r.repeated_time << ", backward time " << r.backward_time << "); CRLF " << r.crlf_lines
      << "; header " << (r.header ? "yes" : "no") << "; median step " << r.median_step
      << " s, largest " << r.largest_step << " s\n"
      << "  grid ts = " << log.sample_time << " s: " << log.samples() << " samples in "
      << log.segments.size() << " segment(s); " << log.gaps << " gap(s) split, "
      << log.dropped_segments << " short stretch(es) dropped";
  if (log.input_offsets.size() > 0 && log.input_offsets.cwiseAbs().maxCoeff() > 0) {
    out << "; input offsets removed [" << log.input_offsets.transpose() << "]";
  }
  if (log.output_offsets.size() > 0 && log.output_offsets.cwiseAbs().maxCoeff() > 0) {
    out << "; output offsets removed [" << log.output_offsets.transpose() << "]";
  }
  out << '\n';
  return out.str();
}

}  // namespace endohaptics::workflow
