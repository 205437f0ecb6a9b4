// Fuzz target for the model-file loader (files/model_file.hpp), one seed corpus per kind
// (corpus/model_file_<kind>/: state_space, hammerstein_wiener, stall_hold, push_load_observer,
// bidirectional_load_observer): the input is a file's content, written to an in-memory file
// (memfd) that load_model reads by path exactly as it reads any model file (the bounded read of a
// regular file, the strict JSON parse with the model-file limits, model_from_json). It may refuse
// an input only with endohaptics::Error; whatever it accepts must convert back to JSON and load
// again equal.
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <endohaptics/files/model_file.hpp>
#include <string>

namespace {

int g_fd = -1;
std::string g_path;

void write_input(const std::uint8_t* data, std::size_t size) {
  if (::ftruncate(g_fd, 0) != 0) std::abort();
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::pwrite(g_fd, data + done, size - done, static_cast<off_t>(done));
    if (n <= 0) std::abort();
    done += static_cast<std::size_t>(n);
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
  g_fd = ::memfd_create("endohaptics-fuzz-model", 0);  // one for the whole run
  if (g_fd < 0) {
    std::perror("fuzz_model_file: memfd_create");
    std::exit(2);
  }
  g_path = "/proc/self/fd/" + std::to_string(g_fd);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace files = endohaptics::files;
  write_input(data, size);
  try {
    const files::ModelFile m = files::load_model(g_path);
    const files::ModelFile again = files::model_from_json(files::to_json(m), "fuzz round trip");
    if (again.kind() != m.kind() || again.state_space.A() != m.state_space.A() ||
        again.state_space.B() != m.state_space.B() || again.state_space.C() != m.state_space.C() ||
        again.state_space.D() != m.state_space.D()) {
      std::abort();
    }
  } catch (const endohaptics::Error&) {
  }
  return 0;
}
