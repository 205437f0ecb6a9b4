#!/bin/sh
# TEST_EXECUTOR of doctest_discover_tests (tests/CMakeLists.txt), so that CTest's count says what
# ran:
# - listing: doctest leaves test cases marked `doctest::skip` out of --list-test-cases, so CTest
#   would never see them; they are listed too (--no-skip, for listing only);
# - running: a filter that matches no test case is a failure (doctest alone would report
#   "0 test cases" and exit 0, a pass for CTest: a name CTest cannot pass through whole, e.g. one
#   with a ';', would never run); a test case marked skip (../shared/data absent) prints the
#   line that CTest's SKIP_REGULAR_EXPRESSION turns into "Skipped".
exe=$1
shift
for arg in "$@"; do
  [ "$arg" = "--list-test-cases" ] && exec "$exe" "$@" --no-skip
done
count() {
  "$exe" "$@" --count | sed -n 's/.*passing the current filters: \([0-9]*\).*/\1/p'
}
if [ "$(count "$@" --no-skip)" = 0 ]; then
  echo "endohaptics: no test case matches $*" >&2
  exit 1
fi
if [ "$(count "$@")" = 0 ]; then
  echo "endohaptics: SKIPPED: every matching test case is marked doctest::skip"
  exit 0
fi
exec "$exe" "$@"
