// CLI11 glue for the library's strict command-line numbers (endohaptics/workflow/command_line.hpp),
// shared by the programs in examples/: `->check(examples::number_in(1.0, 1e5))` refuses
// "100abc", "0x10", "nan", "inf" and values outside the range, naming the option, and shows the
// range in --help.
#pragma once

#include <CLI/CLI.hpp>
#include <endohaptics/workflow/command_line.hpp>
#include <string>
#include <utility>
#include <vector>

namespace examples {

//! A CLI11 check: a whole decimal number of type T in [min, max], or one of `keywords`.
template <endohaptics::workflow::OptionNumber T>
CLI::Validator number_in(T min, T max, std::vector<std::string> keywords = {}) {
  const endohaptics::workflow::NumberCheck<T> check(min, max, std::move(keywords));
  return CLI::Validator([check](std::string& text) { return check(text); }, check.description());
}

}  // namespace examples
