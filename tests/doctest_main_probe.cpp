// The probe of tests/doctest_main.cpp's reporting (tests/CMakeLists.txt, "doctest main: ..."):
// one test case that runs and one marked skip, as a test that needs ../shared/data is when the
// data are absent.
#include <doctest/doctest.h>

TEST_CASE("probe: runs") { CHECK(1 + 1 == 2); }

TEST_CASE("probe: marked skip" * doctest::skip(true)) { FAIL("a test case marked skip ran"); }
