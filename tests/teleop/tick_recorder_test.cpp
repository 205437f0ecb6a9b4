#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <sys/resource.h>

#include <cstdio>
#include <endohaptics/teleop/tick_recorder.hpp>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

namespace teleop_tick_recorder_test {

namespace tp = endohaptics::teleop;
using namespace std::chrono_literals;

TEST_CASE("records cross to a writer thread as CSV rows, in order, none lost") {
  tp::TickRecorder recorder(1024);
  std::FILE* out = std::tmpfile();
  REQUIRE(out != nullptr);
  tp::TickRecorder::write_header(out);
  std::atomic<bool> done{false};
  std::thread writer([&] {
    while (!done.load()) recorder.drain(out);
    recorder.drain(out);
  });
  for (int i = 0; i < 20000; ++i) {
    tp::TickResult r;
    r.status = tp::TickStatus::ok;
    r.setpoint.setConstant(1e-3 * i);
    r.motor_force[2] = 0.5;
    r.stylus_force = Eigen::Vector3d(0.0, -1.25, 0.0);
    while (!recorder.push(tp::TickRecord::from(r, std::chrono::milliseconds(i)))) {
      std::this_thread::yield();  // this test wants every row; the bridge would drop and count
    }
  }
  done.store(true);
  writer.join();
  CHECK(recorder.written() == 20000);
  std::rewind(out);
  std::string text;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof buf, out)) text.append(buf, n);
  std::fclose(out);
  std::istringstream lines(text);
  std::string header, line;
  std::getline(lines, header);
  CHECK(header.rfind("time,status,link,", 0) == 0);
  int rows = 0;
  std::string last;
  while (std::getline(lines, line)) {
    ++rows;
    last = line;
  }
  CHECK(rows == 20000);
  CHECK(last.rfind("19.999000000,0,", 0) == 0);
  CHECK(last.find(",0.5,") != std::string::npos);
  CHECK(last.substr(last.size() - 8) == ",-1.25,0");
}

TEST_CASE("TickRecord::values is the CSV row, column by column") {
  tp::TickResult r;
  r.status = tp::TickStatus::degraded;
  r.link = tp::LinkState::recovering;
  r.enable_mask = 0x0B;
  r.measured.active_mask = 0x03;
  r.round_trip = 250us;
  r.force_scale = 0.5;
  for (int j = 0; j < 4; ++j) {
    r.setpoint[j] = 0.1 + j;
    r.measured.position[j] = 0.2 + j;
    r.measured.velocity[j] = 0.3 + j;
    r.measured.current[j] = 0.4 + j;
    r.motor_force[j] = 0.5 + j;
  }
  r.passivity.energy = 1.5;
  r.passivity.damping = 2.5;
  r.passivity.force_gain = 0.75;
  r.passivity.drift = 0.125;
  r.stylus_force = Eigen::Vector3d(-1.0, 2.0, -3.0);
  const tp::TickRecord record = tp::TickRecord::from(r, 1500ms);
  tp::TickRecorder recorder(4);
  REQUIRE(recorder.push(record));
  std::FILE* out = std::tmpfile();
  REQUIRE(out != nullptr);
  recorder.drain(out);
  std::rewind(out);
  char line[1024] = {};
  REQUIRE(std::fgets(line, sizeof line, out) != nullptr);
  std::fclose(out);
  const auto values = record.values();
  std::istringstream row(line);
  std::string field;
  std::size_t c = 0;
  while (std::getline(row, field, ',')) {
    REQUIRE(c < values.size());
    CAPTURE(tp::tick_log_columns[c]);
    CHECK(std::stod(field) == doctest::Approx(values[c]).epsilon(1e-6));
    ++c;
  }
  CHECK(c == tp::tick_log_columns.size());
}

TEST_CASE("a full ring drops and counts instead of blocking, and push allocates nothing") {
  tp::TickRecorder recorder(8);
  tp::TickResult r;
  const long allocations = endohaptics::test::allocations_during([&] {
    for (int i = 0; i < 100; ++i) (void)recorder.push(tp::TickRecord::from(r, 1ms));
  });
  CHECK(allocations == 0);
  CHECK(recorder.dropped() == 92);
}

// Minor page faults of the calling thread so far (Linux).
long minor_faults() {
  rusage usage{};
  REQUIRE(::getrusage(RUSAGE_THREAD, &usage) == 0);
  return usage.ru_minflt;
}

TEST_CASE("the ring is mapped at construction: the loop's first pass takes no page fault") {
  // 20000 records of 256 bytes cross some 1250 pages the first time they are written (1407 minor
  // faults measured without the mapping, under ASan).
  tp::TickRecorder recorder;
  tp::TickResult r;
  r.status = tp::TickStatus::ok;
  const long before = minor_faults();
  for (int i = 0; i < 20000; ++i) REQUIRE(recorder.push(tp::TickRecord::from(r, 1ms * i)));
  const long faults = minor_faults() - before;
  INFO("minor page faults in 20000 pushes: " << faults);
  CHECK(faults < 20);
}

TEST_CASE("prefault_ring leaves a ring empty and usable from either end") {
  boost::lockfree::spsc_queue<int> ring(5);
  tp::prefault_ring(ring, 7);
  CHECK(ring.read_available() == 0);
  CHECK(ring.write_available() == 5);
  for (int i = 0; i < 5; ++i) CHECK(ring.push(i));
  CHECK_FALSE(ring.push(5));
  int sum = 0;
  CHECK(ring.consume_all([&](int v) { sum += v; }) == 5);
  CHECK(sum == 0 + 1 + 2 + 3 + 4);
}

}  // namespace teleop_tick_recorder_test
