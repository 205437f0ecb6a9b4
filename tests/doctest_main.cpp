// doctest's main, compiled once for every test executable.
//
// CTest runs one test case per process (doctest_discover_tests: `--test-case=<name>`), and its
// count must say what ran (tests/CMakeLists.txt):
// - listing (`--list-test-cases`): test cases marked `doctest::skip` are listed too (doctest
//   leaves them out, so CTest would never see them);
// - a run in which no test case started is not a pass: if some test case matches the filters
//   and every one of them is marked skip (../shared/data absent), the line that CTest's
//   SKIP_REGULAR_EXPRESSION turns into "Skipped" is printed; if none matches (e.g. a name CTest
//   could not pass through whole), the run fails (doctest alone reports "0 test cases", exit 0).
// All in this one process: the sanitized executables used to be started three times per test.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <cstdio>
#include <initializer_list>
#include <string_view>
#include <vector>

// Every test target is compiled with the options of this one (endohaptics_test_options):
// ENDOHAPTICS_ASSERT and Eigen's assertions are active wherever a test runs.
#ifdef NDEBUG
#error "tests must be built with assertions on (tests/CMakeLists.txt: endohaptics_test_options)"
#endif

namespace {

// What the listener saw in the last run (doctest constructs a listener per run).
unsigned g_started = 0;   // test cases started
unsigned g_matching = 0;  // test cases passing the filters (count queries)

struct RunObserver : doctest::IReporter {
  explicit RunObserver(const doctest::ContextOptions& /*options*/) {}
  void report_query(const doctest::QueryData& in) override {
    if (in.run_stats != nullptr) g_matching = in.run_stats->numTestCasesPassingFilters;
  }
  void test_run_start() override {}
  void test_run_end(const doctest::TestRunStats& /*stats*/) override {}
  void test_case_start(const doctest::TestCaseData& /*data*/) override { ++g_started; }
  void test_case_reenter(const doctest::TestCaseData& /*data*/) override {}
  void test_case_end(const doctest::CurrentTestCaseStats& /*stats*/) override {}
  void test_case_exception(const doctest::TestCaseException& /*exception*/) override {}
  void subcase_start(const doctest::SubcaseSignature& /*signature*/) override {}
  void subcase_end() override {}
  void log_assert(const doctest::AssertData& /*data*/) override {}
  void log_message(const doctest::MessageData& /*data*/) override {}
  void test_case_skipped(const doctest::TestCaseData& /*data*/) override {}
};

// doctest's spelling of a flag: -x, --x, -dt-x or --dt-x. Returns x; empty for anything else
// (the query flags take no value: doctest does not read `--count=1` as --count either).
std::string_view flag_name(std::string_view arg) {
  if (!arg.starts_with('-') || arg.find('=') != std::string_view::npos) return {};
  arg.remove_prefix(arg.starts_with("--") ? 2 : 1);
  if (arg.starts_with("dt-")) arg.remove_prefix(3);
  return arg;
}

bool any_option(int argc, char** argv, std::initializer_list<std::string_view> names) {
  for (int i = 1; i < argc; ++i) {
    const std::string_view name = flag_name(argv[i]);
    for (const std::string_view wanted : names) {
      if (name == wanted) return true;
    }
  }
  return false;
}

}  // namespace

REGISTER_LISTENER("endohaptics_run_observer", 1, RunObserver);

int main(int argc, char** argv) {
  const bool listing =
      any_option(argc, argv, {"list-test-cases", "ltc", "list-test-suites", "lts"});
  const bool query = listing || any_option(argc, argv,
                                           {"list-reporters", "lr", "count", "c", "help", "h", "?",
                                            "version", "v", "no-run", "nr"});
  int result = 0;
  {
    doctest::Context context(argc, argv);
    if (listing) context.setOption("no-skip", true);  // list what skip hides, too
    result = context.run();
    if (query || result != 0 || g_started > 0) return result;
  }
  // Nothing started: count, with skip-marked test cases included, what matches the filters
  // (--count is a flag that setOption cannot set).
  std::vector<const char*> count_args(argv, argv + argc);
  count_args.insert(count_args.end(), {"--no-skip", "--count", "--out=/dev/null"});
  doctest::Context count(static_cast<int>(count_args.size()), count_args.data());
  (void)count.run();
  if (g_matching == 0) {
    std::fprintf(stderr, "endohaptics: no test case matches the filters of this run\n");
    return 1;
  }
  std::printf("endohaptics: SKIPPED: every matching test case is marked doctest::skip\n");
  return 0;
}
