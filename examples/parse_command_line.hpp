// CLI11's parse for the programs' options.cpp files (never included by a main.cpp): what
// CLI11_PARSE does -- --help and errors printed, their status returned -- as a Parsed value, with
// the options given listed.
#pragma once

#include <CLI/CLI.hpp>

#include "program_options.hpp"

namespace examples {

//! Parses argv into the options `app` declares.
[[nodiscard]] inline Parsed parse_command_line(CLI::App& app, int argc, const char* const* argv) {
  Parsed parsed;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    parsed.exit_code = app.exit(e);
    return parsed;
  }
  parsed.help = app.help();  // after the parse: it names the program as argv[0] does
  for (const CLI::Option* option : app.get_options()) {
    if (option->count() > 0) parsed.given.push_back(option->get_name());
  }
  return parsed;
}

}  // namespace examples
