#!/bin/sh
# TEST_EXECUTOR of doctest_discover_tests (tests/CMakeLists.txt). doctest leaves test cases marked
# `doctest::skip` out of --list-test-cases, so CTest would never see them; this lists them too
# (--no-skip, for listing only), and each then runs as usual: doctest skips it and CTest reports
# it as skipped (SKIP_REGULAR_EXPRESSION on doctest's summary line), not as passed.
exe=$1
shift
for arg in "$@"; do
  [ "$arg" = "--list-test-cases" ] && exec "$exe" "$@" --no-skip
done
exec "$exe" "$@"
