#include <doctest/doctest.h>
#include <sched.h>
#include <unistd.h>

#include <endohaptics/teleop/realtime.hpp>
#include <string>
#include <thread>
#include <vector>

namespace teleop_realtime_test {

namespace tp = endohaptics::teleop;

TEST_CASE("leave_realtime: a helper thread started by a pinned thread gets every CPU back") {
  cpu_set_t process{};
  REQUIRE(::sched_getaffinity(0, sizeof process, &process) == 0);
  std::size_t first = 0;
  while (!CPU_ISSET(first, &process)) ++first;

  int inherited_cpus = 0;
  int policy_after = -1;
  bool same_cpus_after = false;
  std::vector<std::string> problems;
  std::thread realtime([&] {
    cpu_set_t one{};
    CPU_SET(first, &one);
    if (::sched_setaffinity(0, sizeof one, &one) != 0) return;
    std::thread helper([&] {  // created by the pinned thread: inherits its pin
      cpu_set_t set{};
      (void)::sched_getaffinity(0, sizeof set, &set);
      inherited_cpus = CPU_COUNT(&set);
      problems = tp::leave_realtime();
      (void)::sched_getaffinity(0, sizeof set, &set);
      same_cpus_after = CPU_EQUAL(&set, &process);
      policy_after = ::sched_getscheduler(0);
    });
    helper.join();
  });
  realtime.join();
  CHECK(inherited_cpus == 1);
  CHECK(problems.empty());
  CHECK(same_cpus_after);
  CHECK(policy_after == SCHED_OTHER);
}

TEST_CASE("leave_realtime: SCHED_FIFO inherited from the creating thread is dropped" *
          doctest::skip(::geteuid() != 0)) {
  int inherited = -1;
  int after = -1;
  std::thread realtime([&] {
    sched_param param{};
    param.sched_priority = 1;
    if (::sched_setscheduler(0, SCHED_FIFO, &param) != 0) return;  // not permitted here
    std::thread helper([&] {
      inherited = ::sched_getscheduler(0);
      (void)tp::leave_realtime();
      after = ::sched_getscheduler(0);
    });
    helper.join();
  });
  realtime.join();
  if (inherited == -1) return;  // SCHED_FIFO refused (no CAP_SYS_NICE): nothing to undo
  CHECK(inherited == SCHED_FIFO);
  CHECK(after == SCHED_OTHER);
}

TEST_CASE("avoid_cpu keeps the calling thread and the threads it creates off one CPU") {
  std::thread owner([] {
    cpu_set_t before;
    CPU_ZERO(&before);
    REQUIRE(::sched_getaffinity(0, sizeof before, &before) == 0);
    int first = -1;
    for (int c = 0; c < CPU_SETSIZE && first < 0; ++c) {
      if (CPU_ISSET(static_cast<unsigned>(c), &before)) first = c;
    }
    REQUIRE(first >= 0);
    const auto messages = tp::avoid_cpu(first);
    if (CPU_COUNT(&before) == 1) {  // one CPU: refused, with the reason
      REQUIRE(messages.size() == 1);
      CHECK(messages[0].find("only one allowed") != std::string::npos);
      return;
    }
    CHECK(messages.empty());
    bool helper_on_it = true;
    std::thread helper([&] {
      cpu_set_t now;
      CPU_ZERO(&now);
      if (::sched_getaffinity(0, sizeof now, &now) == 0) {
        helper_on_it = CPU_ISSET(static_cast<unsigned>(first), &now);
      }
    });
    helper.join();
    CHECK_FALSE(helper_on_it);
  });
  owner.join();
  CHECK(tp::avoid_cpu(-1).size() == 1);
}

}  // namespace teleop_realtime_test
