// CLI11 for the programs, every function CLI11 defines compiled at -O1 under GCC.
//
// The programs are built at -O3 for their real-time loops; option parsing runs once per program
// start and gains nothing from it, while CLI11 (header-only: every program instantiates it anew)
// cost about 2 s of GCC's optimiser per program at -O3 (docs/history/build-times.md, step 16).
// `#pragma GCC optimize` gives the functions defined between push and pop their own level. Every
// program includes CLI11 through this header, before any header that includes <CLI/CLI.hpp>
// itself, or the pragma would not apply. Clang, which does not build the programs in `./run test`,
// ignores nothing here: the pragmas are GCC's only.
#pragma once

#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC push_options
#pragma GCC optimize("O1")
#endif
#include <CLI/CLI.hpp>
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC pop_options
#endif
