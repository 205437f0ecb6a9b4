// The sanitized test build's own check (tests/CMakeLists.txt): with cmake/ubsan_ignorelist.txt in
// force, UndefinedBehaviorSanitizer still checks code defined in this project and AddressSanitizer
// still checks Eigen's kernels. `sanitizer_probe overflow` overflows a signed int in a function of
// ours; `sanitizer_probe overread` sums an Eigen::Map one element past the end of a heap buffer.
// Each must be reported (CTest matches the report), or the sanitized build checks less than it
// says.
#include <Eigen/Core>
#include <cstdio>
#include <cstring>
#include <memory>

namespace {

int add_offset(int a) { return a + 2147483600; }  // overflows for a > 47

double sum_of(const double* p, Eigen::Index n) {
  return Eigen::Map<const Eigen::VectorXd>(p, n).sum();  // the read happens in Eigen's redux
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[1], "overflow") == 0) {
    std::printf("%d\n", add_offset(argc * 100));
    return 0;
  }
  if (argc == 2 && std::strcmp(argv[1], "overread") == 0) {
    const auto buffer = std::make_unique<double[]>(4);
    std::printf("%g\n", sum_of(buffer.get(), 3 + argc));  // 5 elements of 4
    return 0;
  }
  std::fprintf(stderr, "usage: sanitizer_probe overflow|overread\n");
  return 2;
}
