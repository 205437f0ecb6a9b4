// doctest's main, compiled once for every test executable.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

// Every test target is compiled with the options of this one (endohaptics_test_options):
// ENDOHAPTICS_ASSERT and Eigen's assertions are active wherever a test runs.
#ifdef NDEBUG
#error "tests must be built with assertions on (tests/CMakeLists.txt: endohaptics_test_options)"
#endif
