//! @file
//! The median of a sample, for the offline tools (robust offsets, step sizes, scale estimates):
//! one definition for the whole library. Configuration time: takes its input by value.
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>
#include <vector>

namespace endohaptics::detail {

//! Median of `values` (NaN when empty); an even count averages the two middle values.
[[nodiscard]] inline double median(std::vector<double> values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  double m = *mid;
  if (values.size() % 2 == 0) m = 0.5 * (m + *std::max_element(values.begin(), mid));
  return m;
}

}  // namespace endohaptics::detail
