#!/bin/sh
# CXX_COMPILER_LAUNCHER of the compile-only checks (tests/CMakeLists.txt): runs the compiler with
# -fsyntax-only -- every header parsed and every template instantiated, as in a full compile, but
# no code generated -- then leaves an empty object file for the build tool.
# A precompiled header (target_precompile_headers of the header checks: clang -emit-pch, GCC
# -x c++-header) is built as is.
out=""
prev=""
for arg in "$@"; do
  [ "$prev" = "-o" ] && out=$arg
  case "$arg" in -emit-pch | c++-header) exec "$@" ;; esac
  prev=$arg
done
"$@" -fsyntax-only || exit $?
[ -n "$out" ] && : >"$out"
exit 0
