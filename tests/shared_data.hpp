// Locating ../shared/data for tests that use the real 2016 logs. Such tests are declared with
// `* doctest::skip(!endohaptics::test::has_shared_data("endowrist-2016"))` so they skip cleanly
// when the folder is absent. ENDOHAPTICS_SHARED_DATA overrides the location.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <string>

namespace endohaptics::test {

inline std::filesystem::path shared_data_dir() {
  if (const char* env = std::getenv("ENDOHAPTICS_SHARED_DATA")) return env;
#ifdef ENDOHAPTICS_SHARED_DATA_DIR
  return ENDOHAPTICS_SHARED_DATA_DIR;
#else
  return "../shared/data";
#endif
}

//! Path of a file or folder under shared/data (may not exist).
inline std::filesystem::path shared_data(const std::string& relative) {
  return shared_data_dir() / relative;
}

inline bool has_shared_data(const std::string& relative) {
  std::error_code ec;
  return std::filesystem::exists(shared_data(relative), ec);
}

}  // namespace endohaptics::test
