// Fuzz target for the log readers: ONE executable (the reader is compiled once), the format named
// by the environment variable ENDOHAPTICS_FUZZ_FORMAT, read in LLVMFuzzerInitialize:
//   endowrist-2016  the 2016 rig logs (files::read_log, LogFormat::endowrist_2016)
//   csv             generic CSV (LogFormat::csv)
//   umn-mis-2018    the UMN 2018 logs (LogFormat::umn_mis_2018)
//   tick-log        the bridge's tick log (files::parse_tick_log)
// A missing or unknown value is refused with a message and exit status 2. The input is the file's
// content, written to an in-memory file (memfd) that the reader opens by path. A reader may
// refuse an input only with endohaptics::Error (a message naming file, line and field); any
// other exception, a crash or a sanitizer report is a finding. Whatever it reads must be a
// consistent log: as many time stamps as rows, every time stamp finite and increasing.
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <endohaptics/files/log_reader.hpp>
#include <endohaptics/files/tick_log.hpp>
#include <sstream>
#include <string>
#include <string_view>

namespace {

namespace files = endohaptics::files;

enum class Target : std::uint8_t { endowrist_2016, csv, umn_mis_2018, tick_log };

Target g_target = Target::endowrist_2016;
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

void check(const files::Log& log) {
  const auto rows = log.time.size();
  if (log.data.rows() != rows) std::abort();
  for (Eigen::Index i = 0; i < rows; ++i) {
    if (!std::isfinite(log.time[i])) std::abort();
    if (i > 0 && !(log.time[i] > log.time[i - 1])) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
  const char* env = std::getenv("ENDOHAPTICS_FUZZ_FORMAT");
  const std::string_view name = env != nullptr ? env : "";
  if (name == "endowrist-2016") {
    g_target = Target::endowrist_2016;
  } else if (name == "csv") {
    g_target = Target::csv;
  } else if (name == "umn-mis-2018") {
    g_target = Target::umn_mis_2018;
  } else if (name == "tick-log") {
    g_target = Target::tick_log;
  } else {
    std::fprintf(stderr,
                 "fuzz_log_reader: set ENDOHAPTICS_FUZZ_FORMAT to endowrist-2016, csv, "
                 "umn-mis-2018 or tick-log (got %s%s%s)\n",
                 env != nullptr ? "'" : "", env != nullptr ? env : "nothing",
                 env != nullptr ? "'" : "");
    std::exit(2);
  }
  if (g_target != Target::tick_log) {
    // One memfd for the whole run; each input replaces its content.
    g_fd = ::memfd_create("endohaptics-fuzz-log", 0);
    if (g_fd < 0) {
      std::perror("fuzz_log_reader: memfd_create");
      std::exit(2);
    }
    g_path = "/proc/self/fd/" + std::to_string(g_fd);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    switch (g_target) {
      case Target::tick_log: {
        std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
        (void)files::parse_tick_log(in, "fuzz");
        break;
      }
      case Target::endowrist_2016:
        write_input(data, size);
        check(files::read_log(g_path, files::LogFormat::endowrist_2016));
        break;
      case Target::csv:
        write_input(data, size);
        check(files::read_log(g_path, files::LogFormat::csv));
        break;
      case Target::umn_mis_2018:
        write_input(data, size);
        check(files::read_log(g_path, files::LogFormat::umn_mis_2018));
        break;
    }
  } catch (const endohaptics::Error&) {
    // A refusal with a message: expected for most inputs.
  }
  return 0;
}
