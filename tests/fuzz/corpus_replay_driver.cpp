// Without libFuzzer (GCC builds): runs LLVMFuzzerTestOneInput once on every file named on the
// command line, or found directly inside a directory named there (a seed corpus), and prints how
// many inputs ran. It does not fuzz: that needs clang (./run fuzz). Every argument must be an
// existing file or directory; anything else (an option such as -runs=1, a typo) is refused with
// exit status 2, and so is an empty list of inputs, so that this check can fail. A target's
// LLVMFuzzerInitialize, when it has one, runs first (as under libFuzzer).
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);
// Optional in a target (weak: null when the target does not define it).
extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) __attribute__((weak));

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  if (LLVMFuzzerInitialize != nullptr) (void)LLVMFuzzerInitialize(&argc, &argv);
  std::vector<fs::path> inputs;
  for (int i = 1; i < argc; ++i) {
    const fs::path arg(argv[i]);
    std::error_code ec;
    if (fs::is_directory(arg, ec)) {
      for (const auto& entry : fs::directory_iterator(arg)) {
        if (entry.is_regular_file()) inputs.push_back(entry.path());
      }
    } else if (fs::is_regular_file(arg, ec)) {
      inputs.push_back(arg);
    } else {
      std::fprintf(stderr,
                   "corpus replay: '%s' is neither a file nor a directory (this driver takes only "
                   "corpus paths; fuzzing options need the libFuzzer build: ./run fuzz)\n",
                   argv[i]);
      return 2;
    }
  }
  if (inputs.empty()) {
    std::fprintf(stderr, "corpus replay: no inputs (usage: %s FILE|DIR...)\n", argv[0]);
    return 2;
  }
  for (const auto& path : inputs) {
    std::ifstream in(path, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                  std::istreambuf_iterator<char>());
    if (!in.eof() && in.fail()) {
      std::fprintf(stderr, "corpus replay: cannot read '%s'\n", path.c_str());
      return 2;
    }
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  }
  std::printf("corpus replay: %zu inputs ran without a crash (no fuzzing: see ./run fuzz)\n",
              inputs.size());
  return 0;
}
