// What a program's command line gave, without CLI11: each program declares its options in its
// options.cpp, and every options.cpp is compiled in one translation unit (the library
// endohaptics_program_options, examples/CMakeLists.txt), so CLI11's header-only parser is compiled
// once for all the programs instead of once in each (docs/history/build-times.md, step 17). The
// values land in the program's Options struct; this says whether to run on and which options were
// on the command line.
#pragma once

#include <algorithm>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace examples {

struct Parsed {
  //! Set when the program must exit now with this status: --help printed (0), or the command
  //! line refused with the reason on stderr (CLI11's non-zero codes).
  std::optional<int> exit_code;
  //! The options given on the command line, by their long name ("--rig"). Options are declared
  //! with a long name and neither hidden nor in an option group (CLI11 names those differently).
  std::vector<std::string> given;
  //! The program's --help text, for a program that finds later that nothing was asked of it.
  std::string help;

  //! Whether option `name` ("--rig") was on the command line.
  [[nodiscard]] bool was_given(std::string_view name) const {
    return std::find(given.begin(), given.end(), name) != given.end();
  }
};

}  // namespace examples
