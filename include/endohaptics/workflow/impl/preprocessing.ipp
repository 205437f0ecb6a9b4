//! @file
//! Function bodies of workflow/preprocessing.hpp: included at its end (header-only, the default),
//! or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/workflow/preprocessing.hpp"

namespace endohaptics::workflow {

ENDOHAPTICS_DECL void validate(const Preprocessing& p) {
  using endohaptics::detail::fail;
  using endohaptics::detail::format_number;
  const auto check = [](bool ok, const char* name, const std::string& value,
                        const std::string& range) {
    if (!ok) fail("preprocessing: " + std::string(name) + " is " + value + ", expected " + range);
  };
  check(std::isfinite(p.cutoff) && p.cutoff >= 0.0 && p.cutoff <= limits::max_cutoff, "lowpass_hz",
        format_number(p.cutoff), "0 (none) or a cutoff in (0, 1e9] Hz");
  check(p.filter_order >= limits::min_filter_order && p.filter_order <= limits::max_filter_order,
        "filter_order", std::to_string(p.filter_order), "[1, 32]");
  check(std::isfinite(p.offset_duration) && p.offset_duration >= limits::min_offset_duration &&
            p.offset_duration <= limits::max_duration,
        "offset_duration_s", format_number(p.offset_duration), "[1e-09, 1e+09] s");
  check(std::isfinite(p.max_gap) && p.max_gap >= 0.0 && p.max_gap <= limits::max_duration,
        "max_gap_s", format_number(p.max_gap), "[0, 1e+09] s (0: automatic)");
  check(p.min_segment >= limits::min_segment && p.min_segment <= limits::max_grid_samples,
        "min_segment", std::to_string(p.min_segment), "[2, 10000000] samples");
}

}  // namespace endohaptics::workflow
