// Hostile files (docs/safety.md): one bounded JSON reader whose limits are the parser's own (no
// second lexer to disagree with it), and file readers that read only regular files, within a stated
// size, line by line. Every case here failed before: "//\r" + 300,000 '[' took 1.67 GB
// (std::bad_alloc, or the OOM killer without a memory limit), 20,000 nested objects crashed with a
// 2 MB stack, /dev/zero as a log ended in std::bad_alloc naming no file, a FIFO blocked for ever.
#include <doctest/doctest.h>
#include <fcntl.h>
#include <pthread.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <string>
#include <system_error>
#include <vector>

#include "alloc_counter.hpp"
#include "endohaptics/core/regular_file.hpp"
#include "endohaptics/files/bridge_config.hpp"
#include "endohaptics/files/json_text.hpp"
#include "endohaptics/files/log_reader.hpp"
#include "endohaptics/files/model_file.hpp"
#include "endohaptics/files/tick_log.hpp"
#include "shared_data.hpp"
#include "test_support.hpp"

namespace files_bounded_reading_test {

using endohaptics::test::message_of;
using endohaptics::test::TempDir;
using endohaptics::test::write_text;

namespace {

namespace files = endohaptics::files;
namespace jt = endohaptics::files::detail::json_text;
using endohaptics::Error;

// The message parse_bridge_config gives for `text` (source "bridge.json").
std::string config_error(const std::string& text) {
  return message_of([&] { (void)files::parse_bridge_config(text, "bridge.json"); });
}

// Nested objects {"a": {"a": ... 1 ... }} `depth` deep.
std::string nested_objects(std::size_t depth) {
  std::string text;
  for (std::size_t i = 0; i < depth; ++i) text += "{\"a\": ";
  text += "1";
  return text + std::string(depth, '}');
}

// The message of the Error f() throws, "(no exception)", or "(blocked)" when f has not returned
// within 5 s: then a writer opens `fifo` and closes it, so that a reader blocked in open() or
// read() sees the end of the file and f returns.
std::string message_unless_blocked(const std::function<void()>& f, const std::string& fifo) {
  auto result = std::async(std::launch::async, [&f] { return message_of(f); });
  if (result.wait_for(std::chrono::seconds(5)) == std::future_status::ready) return result.get();
  const int fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd >= 0) ::close(fd);
  result.wait();
  return "(blocked)";
}

// Runs f on a thread with a stack of `bytes` (a recursion the depth limit did not stop would
// overflow it: the sanitizers report it, or the process ends).
void on_small_stack(std::size_t bytes, std::function<void()> f) {
  pthread_attr_t attr;
  REQUIRE(pthread_attr_init(&attr) == 0);
  REQUIRE(pthread_attr_setstacksize(&attr, bytes) == 0);
  pthread_t thread{};
  auto run = [](void* arg) -> void* {
    (*static_cast<std::function<void()>*>(arg))();
    return nullptr;
  };
  REQUIRE(pthread_create(&thread, &attr, run, &f) == 0);
  REQUIRE(pthread_join(thread, nullptr) == 0);
  pthread_attr_destroy(&attr);
}

}  // namespace

TEST_CASE("JSON: the depth limit holds whatever comes before the brackets") {
  const std::string deep(300000, '[');
  // The comment ends where the parser ends it: at '\r' and at '\0' as well as at '\n'.
  CHECK(config_error("//\r" + deep) ==
        "bridge.json: line 1, column 68: nested deeper than 64 levels (the limit; the bridge "
        "configuration needs 3)");
  CHECK(config_error(std::string("//\0", 3) + deep) ==
        "bridge.json: line 1, column 68: nested deeper than 64 levels (the limit; the bridge "
        "configuration needs 3)");
  for (const std::string prefix :
       {"/*\n*/", "/* [ */", "/**/", "/***/", "/* // */", "// x\r\n", "//\r//\n", "\t \r\n"}) {
    INFO("prefix: ", prefix);
    const std::string m = config_error(prefix + deep);
    CHECK(m.rfind("bridge.json: line ", 0) == 0);
    CHECK(m.find(": nested deeper than 64 levels (the limit") != std::string::npos);
  }
  // 20,000 nested objects as a value the schema would echo, hidden behind "//\r".
  const std::string objects =
      "//\r{\"loop\": {\"receive_timeout\": " + nested_objects(20000) + "}}";
  CHECK(config_error(objects).rfind("bridge.json: line 1, column 405: nested deeper than 64", 0) ==
        0);
  CHECK(config_error("//\r" + nested_objects(20000)).find("nested deeper than 64 levels") !=
        std::string::npos);
  // An unterminated block comment is invalid JSON, not a way around the limit.
  CHECK(config_error("/*" + deep).rfind("bridge.json: not valid JSON: ", 0) == 0);
  // Model files allow no comments at all, and NUL is no white space.
  const jt::Limits model{.max_depth = files::model_file_max_depth,
                         .needed = "a model file needs 4",
                         .comments = false};
  CHECK(message_of([&] {
          (void)jt::parse_strict("//\r" + deep, "m.json", model);
        }).rfind("m.json: not valid JSON: ", 0) == 0);
  CHECK(message_of([&] {
          (void)jt::parse_strict(std::string("\0", 1) + deep, "m.json", model);
        }).rfind("m.json: not valid JSON: ", 0) == 0);
  CHECK(message_of([&] { (void)jt::parse_strict(deep, "m.json", model); }) ==
        "m.json: line 1, column 33: nested deeper than 32 levels (the limit; a model file "
        "needs 4)");
  // Exactly the limit parses.
  CHECK_NOTHROW((void)jt::parse_strict(std::string(32, '[') + std::string(32, ']'), "m", model));
}

TEST_CASE("JSON: nothing beyond the limit is allocated or recursed into") {
  // The parser stops at the first level beyond the limit: twice the input, the same allocations.
  const auto allocations = [](std::size_t brackets) {
    const std::string text = "//\r" + std::string(brackets, '[');
    const long before = endohaptics::test::new_calls.load();
    (void)config_error(text);
    return endohaptics::test::new_calls.load() - before;
  };
  const long small = allocations(1000);
  CHECK(small < 2000);
  CHECK(allocations(300000) == small);
  CHECK(allocations(600000) == small);
  // No recursion either: every input above parses, or is refused, on a 256 KiB stack.
  on_small_stack(256 * 1024, [] {
    (void)config_error("//\r" + std::string(300000, '['));
    (void)config_error("//\r{\"loop\": {\"receive_timeout\": " + nested_objects(20000) + "}}");
    (void)config_error("{\"loop\": {\"receive_timeout\": " + nested_objects(60) + "}}");
  });
}

TEST_CASE("JSON: a duplicate key stops the parser where it is, naming the path") {
  const jt::Limits limits{.max_depth = 8, .needed = "x needs 2"};
  // Refused before the syntax error further on.
  CHECK(message_of([&] {
          (void)jt::parse_strict("{\"a\": {\"b\": 1,\n \"b\": 2}, garbage", "f.json", limits);
        }) == "f.json: line 2, column 4: duplicate key 'a.b' (a key may appear only once)");
  CHECK(message_of([&] {
          (void)jt::parse_strict(R"({"list": [{"x": 1}, {"x": 2, "x": 3}]})", "f.json", limits);
        }) == "f.json: line 1, column 32: duplicate key 'list[].x' (a key may appear only once)");
  // The same key in different objects, and values of every type, build the same value nlohmann
  // builds.
  const std::string text =
      R"({"a": {"x": [1, -2, 3.5, "s", true, false, null, {}, []]}, "b": {"x": 18446744073709551615}})";
  CHECK(jt::parse_strict(text, "f.json", limits) == nlohmann::json::parse(text));
}

TEST_CASE("regular files only: a FIFO, a device or a directory is refused at once, named") {
  const TempDir dir("regular_only");
  const std::string fifo = (dir.path() / "pipe").string();
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  struct Reader {
    const char* name;
    std::function<void(const std::string&)> read;
  };
  const std::vector<Reader> readers{
      {"read_csv: log file", [](const std::string& p) { (void)files::read_csv(p); }},
      {"read_endowrist_2016: log file",
       [](const std::string& p) { (void)files::read_log(p, files::LogFormat::endowrist_2016); }},
      {"read_umn_mis_2018: log file",
       [](const std::string& p) { (void)files::read_log(p, files::LogFormat::umn_mis_2018); }},
      {"tick log", [](const std::string& p) { (void)files::read_tick_log(p); }},
      {"model file", [](const std::string& p) { (void)files::load_model(p); }},
      {"configuration file", [](const std::string& p) { (void)files::load_bridge_config(p); }},
  };
  for (const auto& r : readers) {
    INFO(r.name);
    CHECK(message_unless_blocked([&] { r.read(fifo); }, fifo) ==
          std::string(r.name) + " '" + fifo + "' is a FIFO (named pipe), not a regular file");
    if (std::filesystem::exists("/dev/zero")) {
      CHECK(message_unless_blocked([&] { r.read("/dev/zero"); }, fifo) ==
            std::string(r.name) + " '/dev/zero' is a character device, not a regular file");
    }
    CHECK(message_of([&] { r.read(dir.path().string()); }) ==
          std::string(r.name) + " '" + dir.path().string() +
              "' is a directory, not a regular file");
    const std::string missing = (dir.path() / "missing").string();
    CHECK(message_of([&] { r.read(missing); }) ==
          std::string(r.name) + " '" + missing + "' cannot be opened: the file does not exist");
  }
  // A symbolic link to a FIFO is a FIFO.
  const std::string link = (dir.path() / "link").string();
  REQUIRE(::symlink(fifo.c_str(), link.c_str()) == 0);
  CHECK(message_unless_blocked([&] { (void)files::read_csv(link); }, fifo) ==
        "read_csv: log file '" + link + "' is a FIFO (named pipe), not a regular file");
}

TEST_CASE("size limits: every reader states one, the log readers' are options") {
  const TempDir dir("size_limits");
  // The default is far above the largest log of ../shared/data.
  const files::LogReadOptions defaults;
  CHECK(defaults.max_bytes == files::default_log_max_bytes);
  CHECK(files::TickLogOptions{}.max_bytes == files::default_log_max_bytes);
  if (endohaptics::test::has_shared_data("")) {
    std::uintmax_t largest = 0;
    for (const auto& e :
         std::filesystem::recursive_directory_iterator(endohaptics::test::shared_data_dir())) {
      if (e.is_regular_file()) largest = std::max(largest, e.file_size());
    }
    CHECK(largest * 100 < files::default_log_max_bytes);
  }

  std::string csv = "time,u\n";
  for (int i = 0; i < 10; ++i) csv += std::to_string(i) + ",1\n";
  const std::string path = dir.write("small.csv", csv);
  const std::string size = std::to_string(csv.size());
  files::LogReadOptions tight;
  tight.max_bytes = 20;
  files::CsvOptions csv_options;
  csv_options.read = tight;
  CHECK(message_of([&] { (void)files::read_csv(path, csv_options); }) ==
        "read_csv: log file '" + path + "' holds " + size +
            " bytes, more than the limit of 20 bytes (raise LogReadOptions::max_bytes to read it)");
  CHECK(message_of([&] {
          (void)files::read_log(path, files::LogFormat::umn_mis_2018, tight);
        }).find("holds " + size + " bytes, more than the limit of 20 bytes") != std::string::npos);
  tight.max_bytes = csv.size();  // exactly the limit reads
  csv_options.read = tight;
  CHECK(files::read_csv(path, csv_options).rows() == 10);

  files::TickLogOptions ticks;
  ticks.max_bytes = 20;
  CHECK(message_of([&] { (void)files::read_tick_log(path, ticks); }) ==
        "tick log '" + path + "' holds " + size +
            " bytes, more than the limit of 20 bytes (raise TickLogOptions::max_bytes to read it)");

  // A model file one byte over its format's limit (a sparse file: nothing is read).
  const std::string big = (dir.path() / "big.json").string();
  { std::ofstream(big).put('{'); }
  std::filesystem::resize_file(big, files::model_file_max_bytes + 1);
  CHECK(message_of([&] { (void)files::load_model(big); }) ==
        "model file '" + big + "' holds " + std::to_string(files::model_file_max_bytes + 1) +
            " bytes, more than the limit of " + std::to_string(files::model_file_max_bytes) +
            " bytes");
}

TEST_CASE("RegularFile: a file that grows beyond its limit while being read is refused") {
  const TempDir dir("grows");
  const std::string path = dir.write("grows.txt", std::string(10, 'a'));
  endohaptics::RegularFile file(path, "test file");
  file.limit(15, "raise it");
  CHECK(file.size() == 10);
  { std::ofstream(path, std::ios::app) << std::string(10, 'b'); }
  CHECK(message_of([&] { (void)file.read_all(); }) ==
        "test file '" + path + "' grew beyond the limit of 15 bytes while being read (raise it)");
  // Within the limit, read_all reads what is there, also past the size fstat gave.
  endohaptics::RegularFile again(path, "test file");
  again.limit(100, "");
  { std::ofstream(path, std::ios::app) << "cc"; }
  CHECK(again.read_all() == std::string(10, 'a') + std::string(10, 'b') + "cc");
}

TEST_CASE("log lines are streamed: longer than a read block, CR LF, blank lines, a lone BOM") {
  const TempDir dir("streamed");
  // A row 200,000 bytes long (blanks inside a field are trimmed) crosses the 64 KiB blocks.
  const std::string wide = "0.5," + std::string(200000, ' ') + "2\r\n";
  const std::string text = "\xEF\xBB\xBFtime,u\r\n0,1\r\n\r\n  \n" + wide + "1,3";
  const files::Log log = files::read_csv(dir.write("wide.csv", text));
  REQUIRE(log.rows() == 3);
  CHECK(log.data(1, 0) == 2.0);
  CHECK(log.data(2, 0) == 3.0);
  CHECK(log.report.lines == 6);
  CHECK(log.report.crlf_lines == 4);
  CHECK(log.report.blank_lines == 2);
  CHECK(log.report.byte_order_mark);
  // The mark alone is an empty file; so is nothing.
  CHECK(message_of([&] {
          (void)files::read_csv(dir.write("bom.csv", "\xEF\xBB\xBF"));
        }).find("no usable rows (file is empty)") != std::string::npos);
  CHECK(message_of([&] {
          (void)files::read_csv(dir.write("empty.csv", ""));
        }).find("no usable rows (file is empty)") != std::string::npos);
  // The line numbers in messages count every line, blank ones too.
  files::CsvOptions strict;
  strict.read = files::LogReadOptions::strict();
  CHECK(message_of([&] {
          (void)files::read_csv(dir.write("bad.csv", "time,u\n\n0,1\n\n1,x\n"), strict);
        }).find("bad.csv:5: non-numeric field") != std::string::npos);
  // The tick log reads its file line by line as parse_tick_log reads a stream.
  const std::string ticks = "time,link\r\n0.001,1\n" + std::string(100000, ' ') + "\n0.002,2";
  const files::TickLog from_file = files::read_tick_log(dir.write("ticks.csv", ticks));
  CHECK(from_file.rows() == 2);
  CHECK(from_file.column("link")[1] == 2.0);
}

}  // namespace files_bounded_reading_test
