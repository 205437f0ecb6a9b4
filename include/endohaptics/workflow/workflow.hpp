//! @file
//! The identification workflow of worksheet 4.2 as endohaptics-identify/-replay run it: read
//! logs, select named inputs/outputs, resample to Ts (s) split at gaps, low-pass and remove
//! offsets (4.2.1), identify (subspace 4.2.2, input dead zones 4.2.3, or a static gain baseline)
//! and compare per file like MATLAB compare (NRMSE fit %, fit_metrics.hpp). Signals keep their
//! log units. Configuration time: allocates, throws endohaptics::Error. See
//! docs/identification_results.md.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/files/identified_model_file.hpp"
#include "endohaptics/files/log_reader.hpp"
#include "endohaptics/files/model_file.hpp"
#include "endohaptics/identification/fit_metrics.hpp"
#include "endohaptics/identification/hammerstein_wiener_fit.hpp"
#include "endohaptics/identification/signal.hpp"
#include "endohaptics/identification/subspace.hpp"
#include "endohaptics/model/presets_2016.hpp"

namespace endohaptics::workflow {

using namespace endohaptics::identification;  // the workflow composes the identification area

// ---------------------------------------------------------------------------------------------
// Preprocessing (worksheet 4.2.1)

//! How an offset is removed from a signal, one offset per file and signal.
enum class OffsetMode : std::uint8_t {
  none,    //!< kept as logged
  start,   //!< median of the first Preprocessing::offset_duration s (after filtering)
  median,  //!< median over the whole file (the load-cell zero when contact is the exception)
  mean,    //!< mean over the whole file
};

//! Lower-case name ("none", "start", "median", "mean").
[[nodiscard]] constexpr std::string_view to_string(OffsetMode mode) noexcept {
  switch (mode) {
    case OffsetMode::none:
      return "none";
    case OffsetMode::start:
      return "start";
    case OffsetMode::median:
      return "median";
    case OffsetMode::mean:
      return "mean";
  }
  return "unknown";
}

//! Mode named `name` (as `to_string` writes it). Throws Error naming the value otherwise.
[[nodiscard]] inline OffsetMode offset_mode_from_string(std::string_view name) {
  for (const OffsetMode m :
       {OffsetMode::none, OffsetMode::start, OffsetMode::median, OffsetMode::mean}) {
    if (name == to_string(m)) return m;
  }
  ENDOHAPTICS_THROW(
      Error("unknown offset mode '" + std::string(name) + "' (valid: none, start, median, mean)"));
}

//! What is done to a log between reading and identification (worksheet 4.2.1).
struct Preprocessing {
  double cutoff = 0.0;                          //!< Hz, zero-phase Butterworth low-pass; 0: none
  int filter_order = 4;                         //!< Butterworth order, 1..32
  OffsetMode output_offset = OffsetMode::none;  //!< offset removed from every output
  OffsetMode input_offset = OffsetMode::none;   //!< offset removed from every input
  double offset_duration = 0.5;                 //!< s, window of OffsetMode::start
  bool detrend = false;           //!< least-squares line removed from the outputs of each segment
  double max_gap = 0.0;           //!< s, longer time steps split a log; 0: 5 x max(Ts, median step)
  Eigen::Index min_segment = 20;  //!< samples; shorter gap-free stretches are dropped
};

//! One line, `key=value` pairs separated by blanks; `parse_preprocessing` reads it back.
[[nodiscard]] inline std::string describe(const Preprocessing& p) {
  std::ostringstream out;
  out.precision(17);
  out << "lowpass_hz=" << p.cutoff << " filter_order=" << p.filter_order
      << " output_offset=" << to_string(p.output_offset)
      << " input_offset=" << to_string(p.input_offset) << " offset_duration_s=" << p.offset_duration
      << " detrend=" << (p.detrend ? "linear" : "none") << " max_gap_s=" << p.max_gap
      << " min_segment=" << p.min_segment;
  return out.str();
}

namespace detail {

[[noreturn]] inline void fail(const std::string& message) { ENDOHAPTICS_THROW(Error(message)); }

using endohaptics::detail::format_number;

//! Whole-string number; throws naming `what` and the text otherwise.
inline double parse_double(std::string_view text, const std::string& what) {
  double value = 0.0;
  if (files::detail::log_reader::parse_number(text, value) !=
      files::detail::log_reader::Number::ok) {
    fail(what + ": '" + std::string(text) + "' is not a finite number");
  }
  return value;
}

inline std::vector<std::string_view> split(std::string_view text, char separator) {
  std::vector<std::string_view> parts;
  std::size_t pos = 0;
  while (true) {
    const std::size_t end = text.find(separator, pos);
    parts.push_back(text.substr(pos, end == std::string_view::npos ? end : end - pos));
    if (end == std::string_view::npos) break;
    pos = end + 1;
  }
  return parts;
}

inline std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

//! Rethrows an Error with `prefix` in front of its message.
template <typename F>
auto with_context(const std::string& prefix, F&& f) -> decltype(f()) {
#if defined(__cpp_exceptions)
  try {
    return f();
  } catch (const Error& e) {
    fail(prefix + ": " + e.what());
  }
#else
  (void)prefix;
  return f();
#endif
}

}  // namespace detail

//! Reads what `describe` wrote. Unknown keys or bad values throw Error naming them.
[[nodiscard]] inline Preprocessing parse_preprocessing(std::string_view text) {
  namespace wf = detail;
  Preprocessing p;
  for (std::string_view item : wf::split(text, ' ')) {
    if (item.empty()) continue;
    const auto eq = item.find('=');
    if (eq == std::string_view::npos)
      wf::fail("preprocessing: '" + std::string(item) + "' is not key=value");
    const std::string key(item.substr(0, eq));
    const std::string_view value = item.substr(eq + 1);
    const std::string what = "preprocessing: " + key;
    if (key == "lowpass_hz") {
      p.cutoff = wf::parse_double(value, what);
    } else if (key == "filter_order") {
      p.filter_order = static_cast<int>(wf::parse_double(value, what));
    } else if (key == "output_offset") {
      p.output_offset = offset_mode_from_string(value);
    } else if (key == "input_offset") {
      p.input_offset = offset_mode_from_string(value);
    } else if (key == "offset_duration_s") {
      p.offset_duration = wf::parse_double(value, what);
    } else if (key == "detrend") {
      if (value != "linear" && value != "none")
        wf::fail(what + ": expected linear or none, got '" + std::string(value) + "'");
      p.detrend = value == "linear";
    } else if (key == "max_gap_s") {
      p.max_gap = wf::parse_double(value, what);
    } else if (key == "min_segment") {
      p.min_segment = static_cast<Eigen::Index>(wf::parse_double(value, what));
    } else {
      wf::fail("preprocessing: unknown key '" + key + "'");
    }
  }
  return p;
}

//! The preprocessing a model file records in its provenance notes (a line starting with
//! "preprocessing: "), if any. Throws Error when the line is there but malformed.
[[nodiscard]] inline std::optional<Preprocessing> recorded_preprocessing(
    const files::ModelFile& m) {
  constexpr std::string_view tag = "preprocessing: ";
  const std::string& notes = m.provenance.notes;
  std::size_t pos = 0;
  while (pos < notes.size()) {
    const std::size_t end = std::min(notes.find('\n', pos), notes.size());
    const std::string_view line = std::string_view(notes).substr(pos, end - pos);
    if (line.starts_with(tag)) return parse_preprocessing(line.substr(tag.size()));
    pos = end + 1;
  }
  return std::nullopt;
}

// ---------------------------------------------------------------------------------------------
// Logs on the uniform grid

//! Which file format and which named signals to read.
struct LogSelection {
  files::LogFormat format = files::LogFormat::endowrist_2016;  //!< reader
  std::vector<std::string> inputs;                             //!< signal names, >= 1
  std::vector<std::string> outputs;                            //!< signal names, >= 1
  double csv_row_time = 1.0;     //!< s per row of a CSV without a "time" column
  bool drop_non_finite = false;  //!< false: a NaN/Inf field fails; true: its row is dropped
};

//! One log on the grid k Ts: gap-free segments of inputs and outputs, and what was done.
struct PreparedLog {
  std::string source;                //!< file
  files::LogReport report;           //!< what the reader dropped or repaired
  std::vector<DataSet> segments;     //!< u: N x nu, y: N x ny per gap-free stretch
  std::vector<double> start_time;    //!< s, time of row 0 of each segment (rebased log time)
  double sample_time = 0.0;          //!< s
  std::size_t gaps = 0;              //!< time steps > max_gap that split the log
  std::size_t dropped_segments = 0;  //!< stretches shorter than min_segment
  Eigen::VectorXd input_offsets;     //!< removed from each input, input units
  Eigen::VectorXd output_offsets;    //!< removed from each output, output units

  //! Grid samples over all segments.
  [[nodiscard]] Eigen::Index samples() const noexcept {
    Eigen::Index n = 0;
    for (const auto& s : segments) n += s.u.rows();
    return n;
  }
};

//! Reads `path` as `sel` says (no checks beyond the reader's).
[[nodiscard]] inline files::Log read_selected_format(const std::string& path,
                                                     const LogSelection& sel) {
  const files::LogReadOptions read;  // bad rows dropped and reported; non-finite checked by callers
  if (sel.format == files::LogFormat::csv) {
    files::CsvOptions o;
    o.read = read;
    o.sample_time = sel.csv_row_time;
    return files::read_csv(path, o);
  }
  files::Endowrist2016Options o;
  o.read = read;
  return files::read_endowrist_2016(path, o);
}

//! The default resampling period: the median time step of the log at `path` (s), rounded to six
//! significant digits; for a CSV without time column sel.csv_row_time. Throws Error as the reader.
[[nodiscard]] inline double default_sample_time(const std::string& path, const LogSelection& sel) {
  const double step = read_selected_format(path, sel).report.median_step;
  if (!(step > 0.0)) return step;
  // Six significant digits: 0.009999999999999787 (a sum of decimal stamps) becomes 0.01.
  const double scale = std::pow(10.0, 5.0 - std::floor(std::log10(step)));
  return std::round(step * scale) / scale;
}

//! Reads `path`, selects the named signals, resamples to `ts` (split at gaps), filters and
//! removes offsets as `pre` says. Throws Error naming the file: unreadable, unknown signal
//! (listing the known ones), non-finite values (unless drop_non_finite), fewer than
//! `min_samples` grid samples, bad options.
[[nodiscard]] inline PreparedLog prepare_log(const std::string& path, const LogSelection& sel,
                                             double ts, const Preprocessing& pre,
                                             Eigen::Index min_samples = 20) {
  namespace wf = detail;
  if (sel.inputs.empty()) wf::fail(path + ": no input signal named");
  if (sel.outputs.empty()) wf::fail(path + ": no output signal named");
  if (!std::isfinite(ts) || !(ts > 0.0))
    wf::fail(path + ": sample time must be finite and > 0 s, got " + wf::format_number(ts));
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
  std::vector<std::string> names = sel.inputs;
  names.insert(names.end(), sel.outputs.begin(), sel.outputs.end());
  for (const std::string& name : names) {
    if (name == "time" || !log.has(name)) {
      wf::fail(path + ": no signal named '" + name + "' (signals: " + wf::join(log.names) + ")");
    }
  }
  const Eigen::MatrixXd signals = log.select(names);
  const double span = log.time[log.rows() - 1] - log.time[0];
  if (std::floor(span / ts + 1e-9) + 1.0 < static_cast<double>(min_samples)) {
    wf::fail(path + ": too few samples: " + std::to_string(log.rows()) + " rows spanning " +
             wf::format_number(span) + " s give at most " +
             std::to_string(static_cast<long long>(std::floor(span / ts + 1e-9)) + 1) +
             " samples at ts = " + wf::format_number(ts) + " s, at least " +
             std::to_string(min_samples) + " needed");
  }
  const auto nu = static_cast<Eigen::Index>(sel.inputs.size());
  const auto ny = static_cast<Eigen::Index>(sel.outputs.size());

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

//! One-paragraph summary: reader report counts, grid, segments, offsets.
[[nodiscard]] inline std::string summary(const PreparedLog& log) {
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

// ---------------------------------------------------------------------------------------------
// Models and comparison

//! Presets by name: "yaw2016" (appendix C yaw, inputs current A, velocity rad/s, output force N)
//! and "pitch2016" (appendix C pitch, output in gram-force, see docs/models/presets_2016.md).
//! Throws Error for another name.
[[nodiscard]] inline files::ModelFile preset_model(std::string_view name) {
  const std::vector<files::SignalInfo> inputs{{"current", "A"}, {"velocity", "rad/s"}};
  files::ModelProvenance p;
  p.date = "2016";
  if (name == "yaw2016") {
    p.method = "worksheet appendix C (yaw, eqs. C.1-C.3)";
    return files::make_model_file(model::yaw_force_2016(), inputs, {{"force", "N"}}, p);
  }
  if (name == "pitch2016") {
    p.method = "worksheet appendix C (pitch, eqs. C.4-C.6)";
    return files::make_model_file(model::pitch_force_2016(), inputs, {{"force", "gf"}}, p);
  }
  ENDOHAPTICS_THROW(
      Error("unknown preset '" + std::string(name) + "' (valid: yaw2016, pitch2016)"));
}

//! How replay/compare set the initial state of every segment.
enum class InitialStateMode : std::uint8_t {
  estimate,  //!< least squares on the compared data (MATLAB compare's default)
  zero,      //!< x0 = 0
  stored,    //!< the model file's x0
};

//! Parses "estimate", "zero" or "stored". Throws Error otherwise.
[[nodiscard]] inline InitialStateMode initial_state_from_string(std::string_view name) {
  if (name == "estimate") return InitialStateMode::estimate;
  if (name == "zero") return InitialStateMode::zero;
  if (name == "stored") return InitialStateMode::stored;
  ENDOHAPTICS_THROW(
      Error("unknown x0 mode '" + std::string(name) + "' (valid: estimate, zero, stored)"));
}

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

// ---------------------------------------------------------------------------------------------
// Identification

//! Dead zone on one input: none, fitted jointly with the linear block, or of a given half width.
struct DeadzoneSetting {
  //! No dead zone, fitted jointly with the linear block, or fixed at half width `width`.
  enum class Mode : std::uint8_t { none, fit, fixed };
  Mode mode = Mode::none;  //!< what to do on this input
  double width = 0.0;      //!< half width for `fixed`, input units (symmetric: [-w, w])
};

//! Parses --deadzone: "auto", "none" or a half width for every input, or a comma-separated list
//! with one of those per input. Throws Error naming the value or the count.
[[nodiscard]] inline std::vector<DeadzoneSetting> parse_deadzone(std::string_view text,
                                                                 std::size_t inputs) {
  namespace wf = detail;
  const auto parts = wf::split(text, ',');
  if (parts.size() != 1 && parts.size() != inputs) {
    wf::fail("--deadzone '" + std::string(text) + "' has " + std::to_string(parts.size()) +
             " entries for " + std::to_string(inputs) + " inputs (give one, or one per input)");
  }
  std::vector<DeadzoneSetting> out;
  for (std::size_t i = 0; i < inputs; ++i) {
    const std::string_view p = files::detail::log_reader::trim(parts[parts.size() == 1 ? 0 : i]);
    DeadzoneSetting s;
    if (p == "auto") {
      s.mode = DeadzoneSetting::Mode::fit;
    } else if (p == "none") {
      s.mode = DeadzoneSetting::Mode::none;
    } else {
      s.mode = DeadzoneSetting::Mode::fixed;
      s.width = wf::parse_double(p, "--deadzone");
      if (s.width < 0) wf::fail("--deadzone: half width must be >= 0, got " + std::string(p));
    }
    out.push_back(s);
  }
  return out;
}

//! Settings of `identify_logs`.
struct WorkflowOptions {
  //! Subspace weightings to try; the one with the highest mean fit over the logs is kept
  //! (worksheet 4.2.2: "the best one is chosen depending on the average fit").
  std::vector<Weighting> candidates{Weighting::moesp};
  bool static_gain = false;  //!< instead: least-squares y = D u + c, no dynamics (baseline)
  int order = 0;             //!< model order; 0: automatic (select_order)
  int max_order = 10;        //!< largest automatic order
  int block_rows = 0;        //!< subspace horizon; 0: automatic
  std::vector<DeadzoneSetting> deadzone;  //!< per input; empty: none
  int deadzone_grid = 21;                 //!< grid points of the dead-zone search
  int deadzone_refine = 15;               //!< golden-section steps of the dead-zone search
  InitialStateMode initial_state = InitialStateMode::estimate;  //!< for the per-file fits
  //! Choose among stable candidates (spectral radius < 1) when there is one: an unstable force
  //! model cannot run open loop in the teleoperation loop.
  bool prefer_stable = true;
};

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

//! y = D u + c by least squares over every segment, as a model file with one constant state per
//! output (A = I, B = 0, C = I, x0 = c). Throws Error when the regression is singular.
[[nodiscard]] inline SubspaceModel fit_static_gain(std::span<const DataSet> data,
                                                   double sample_time) {
  const Eigen::Index nu = data.front().u.cols();
  const Eigen::Index ny = data.front().y.cols();
  Eigen::Index rows = 0;
  for (const DataSet& d : data) rows += d.u.rows();
  Eigen::MatrixXd X(rows, nu + 1);
  Eigen::MatrixXd Y(rows, ny);
  Eigen::Index r = 0;
  for (const DataSet& d : data) {
    X.block(r, 0, d.u.rows(), nu) = d.u;
    X.block(r, nu, d.u.rows(), 1).setOnes();
    Y.middleRows(r, d.y.rows()) = d.y;
    r += d.u.rows();
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X);
  if (qr.rank() < X.cols()) {
    detail::fail("static gain: the inputs are constant or collinear (rank " +
                 std::to_string(qr.rank()) + " of " + std::to_string(X.cols()) + ")");
  }
  const Eigen::MatrixXd theta = qr.solve(Y);  // (nu + 1) x ny
  model::DynamicStateSpace<> gain(Eigen::MatrixXd::Identity(ny, ny), Eigen::MatrixXd::Zero(ny, nu),
                                  Eigen::MatrixXd::Identity(ny, ny), theta.topRows(nu).transpose(),
                                  sample_time);
  const Eigen::VectorXd offset = theta.row(nu).transpose();
  gain.reset(offset);
  return SubspaceModel{
      .state_space = std::move(gain), .initial_states = {offset}, .order = static_cast<int>(ny)};
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
