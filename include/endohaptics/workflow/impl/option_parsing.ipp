//! @file
//! Function bodies of workflow/option_parsing.hpp: included at its end (header-only, the default),
//! or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/workflow/option_parsing.hpp"

namespace endohaptics::workflow {
namespace detail {

ENDOHAPTICS_DECL double parse_double(std::string_view text, const std::string& what) {
  double value = 0.0;
  if (files::detail::log_text::parse_number(text, value) != files::detail::log_text::Number::ok) {
    fail(what + ": '" + std::string(text) + "' is not a finite number");
  }
  return value;
}

ENDOHAPTICS_DECL std::vector<std::string_view> split(std::string_view text, char separator) {
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
}  // namespace detail
}  // namespace endohaptics::workflow

namespace endohaptics::workflow {

ENDOHAPTICS_DECL OffsetMode offset_mode_from_string(std::string_view name) {
  for (const OffsetMode m :
       {OffsetMode::none, OffsetMode::start, OffsetMode::median, OffsetMode::mean}) {
    if (name == to_string(m)) return m;
  }
  ENDOHAPTICS_THROW(
      Error("unknown offset mode '" + std::string(name) + "' (valid: none, start, median, mean)"));
}

ENDOHAPTICS_DECL std::string describe(const Preprocessing& p) {
  std::ostringstream out;
  out.precision(17);
  out << "lowpass_hz=" << p.cutoff << " filter_order=" << p.filter_order
      << " output_offset=" << to_string(p.output_offset)
      << " input_offset=" << to_string(p.input_offset) << " offset_duration_s=" << p.offset_duration
      << " detrend=" << (p.detrend ? "linear" : "none") << " max_gap_s=" << p.max_gap
      << " min_segment=" << p.min_segment;
  return out.str();
}

ENDOHAPTICS_DECL Preprocessing parse_preprocessing(std::string_view text) {
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
      p.filter_order =
          parse_number<int>(value, what, limits::min_filter_order, limits::max_filter_order);
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
      p.min_segment =
          parse_number<Eigen::Index>(value, what, limits::min_segment, limits::max_grid_samples);
    } else {
      wf::fail("preprocessing: unknown key '" + key + "'");
    }
  }
  validate(p);
  return p;
}

ENDOHAPTICS_DECL std::optional<Preprocessing> recorded_preprocessing(const files::ModelFile& m) {
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

ENDOHAPTICS_DECL InitialStateMode initial_state_from_string(std::string_view name) {
  for (const InitialStateMode m : {InitialStateMode::steady, InitialStateMode::zero,
                                   InitialStateMode::stored, InitialStateMode::oracle}) {
    if (name == to_string(m)) return m;
  }
  if (name == "estimate") {
    ENDOHAPTICS_THROW(Error(
        "x0 mode 'estimate' was renamed 'oracle': it fits the initial state to the measured "
        "output, which a sensorless estimator never has; use --x0 steady (the default: steady "
        "state of the first input sample) or zero, or --x0 oracle to reproduce the old, "
        "output-fitted score"));
  }
  ENDOHAPTICS_THROW(
      Error("unknown x0 mode '" + std::string(name) + "' (valid: steady, zero, stored, oracle)"));
}

ENDOHAPTICS_DECL std::vector<DeadzoneSetting> parse_deadzone(std::string_view text,
                                                             std::size_t inputs) {
  namespace wf = detail;
  const auto parts = wf::split(text, ',');
  if (parts.size() != 1 && parts.size() != inputs) {
    wf::fail("--deadzone '" + std::string(text) + "' has " + std::to_string(parts.size()) +
             " entries for " + std::to_string(inputs) + " inputs (give one, or one per input)");
  }
  std::vector<DeadzoneSetting> out;
  for (std::size_t i = 0; i < inputs; ++i) {
    const std::string_view p = files::detail::log_text::trim(parts[parts.size() == 1 ? 0 : i]);
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

}  // namespace endohaptics::workflow
