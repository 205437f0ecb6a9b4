// The sanitized smoke pass (ENDOHAPTICS_BENCH_SMOKE=1, benchmarks/CMakeLists.txt) checks that every
// benchmark builds and runs clean, not how fast: the long ones do a fraction of their work under it
// (their names or counters show the amount actually run).
#pragma once

#include <cstdlib>
#include <string_view>

namespace bench {

//! Whether this run is the smoke pass.
[[nodiscard]] inline bool smoke_pass() {
  const char* smoke = std::getenv("ENDOHAPTICS_BENCH_SMOKE");
  return smoke != nullptr && std::string_view(smoke) == "1";
}

//! `full`, or `full / divisor` under the smoke pass.
template <typename T>
[[nodiscard]] T smoke_scaled(T full, T divisor) {
  return smoke_pass() ? full / divisor : full;
}

}  // namespace bench
