//! @file
//! Real-time set-up for the thread that runs a TeleopLoop: SCHED_FIFO priority, CPU affinity and
//! mlockall, each attempted only when asked and reported plainly when the system refuses (no
//! root / no CAP_SYS_NICE / no RLIMIT_MEMLOCK); the rings the loop hands data over by, mapped
//! before it starts. Linux. Configuration time: call before the loop.
#pragma once

#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>

#include <cerrno>
#include <cstddef>
#include <cstring>
#include <string>
#include <vector>

namespace endohaptics::teleop {

//! Which real-time settings apply_realtime() should request; the defaults request none.
struct RealtimeOptions {
  int fifo_priority = 0;     //!< 1..99 requests SCHED_FIFO at that priority; 0 leaves the scheduler
  int cpu = -1;              //!< >= 0 pins the calling thread to that CPU
  bool lock_memory = false;  //!< mlockall(MCL_CURRENT | MCL_FUTURE): no page faults in the loop
  //! >= 1 sets the thread's timer slack (ns) for sleeps of non-real-time threads; Linux's
  //! default of 50 us shows as 50 us of extra lateness on every period. -1 leaves it.
  long timer_slack_ns = -1;
};

//! What was applied and what was refused, one line each, for the user to read.
struct RealtimeReport {
  bool fifo = false;                  //!< SCHED_FIFO priority applied
  bool pinned = false;                //!< thread pinned to the requested CPU
  bool locked = false;                //!< memory locked with mlockall
  bool slack = false;                 //!< timer slack set
  std::vector<std::string> messages;  //!< one line per setting applied or refused
};

//! Applies `options` to the calling thread; never throws for a refusal, it reports it.
inline RealtimeReport apply_realtime(const RealtimeOptions& options) {
  RealtimeReport report;
  auto refused = [&](const std::string& what, int err) {
    report.messages.push_back(
        what + " refused: " + std::strerror(err) +
        (err == EPERM ? " (needs root or CAP_SYS_NICE / RLIMIT_MEMLOCK)" : ""));
  };
  if (options.fifo_priority > 0) {
    sched_param param{};
    param.sched_priority = options.fifo_priority;
    if (::sched_setscheduler(0, SCHED_FIFO, &param) == 0) {
      report.fifo = true;
      report.messages.push_back("SCHED_FIFO priority " + std::to_string(options.fifo_priority));
    } else {
      refused("SCHED_FIFO priority " + std::to_string(options.fifo_priority), errno);
    }
  }
  if (options.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(static_cast<unsigned>(options.cpu), &set);
    if (::sched_setaffinity(0, sizeof set, &set) == 0) {
      report.pinned = true;
      report.messages.push_back("pinned to CPU " + std::to_string(options.cpu));
    } else {
      refused("pinning to CPU " + std::to_string(options.cpu), errno);
    }
  }
  if (options.lock_memory) {
    if (::mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
      report.locked = true;
      report.messages.push_back("memory locked (mlockall)");
    } else {
      refused("mlockall", errno);
    }
  }
  if (options.timer_slack_ns >= 1) {
    if (::prctl(PR_SET_TIMERSLACK, static_cast<unsigned long>(options.timer_slack_ns), 0, 0, 0) ==
        0) {
      report.slack = true;
      report.messages.push_back("timer slack " + std::to_string(options.timer_slack_ns) + " ns");
    } else {
      refused("timer slack " + std::to_string(options.timer_slack_ns) + " ns", errno);
    }
  }
  return report;
}

//! For a helper thread (log writer, statistics printer) that a real-time thread created: it
//! inherits SCHED_FIFO and the CPU pin, so this puts the calling thread back to SCHED_OTHER and
//! on every CPU (the kernel keeps those the process's cpuset allows). Returns one line per
//! refusal; empty when both were applied.
[[nodiscard]] inline std::vector<std::string> leave_realtime() {
  std::vector<std::string> refused;
  sched_param param{};
  param.sched_priority = 0;
  if (::sched_setscheduler(0, SCHED_OTHER, &param) != 0) {
    refused.push_back(std::string("SCHED_OTHER refused: ") + std::strerror(errno));
  }
  cpu_set_t all;
  CPU_ZERO(&all);
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) CPU_SET(static_cast<unsigned>(cpu), &all);
  if (::sched_setaffinity(0, sizeof all, &all) != 0) {
    refused.push_back(std::string("every CPU refused: ") + std::strerror(errno));
  }
  return refused;
}

//! For a program whose loop thread will be pinned to `cpu` (apply_realtime's RealtimeOptions::cpu)
//! and whose helpers must stay off it (a middleware's threads, their network work): keeps the
//! calling thread, and every thread it creates from now on, on every CPU but `cpu`. Call it
//! before creating the helpers; apply_realtime later pins the loop thread itself. Returns one
//! line per refusal (also when `cpu` is the only CPU allowed); empty when applied.
[[nodiscard]] inline std::vector<std::string> avoid_cpu(int cpu) {
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  if (::sched_getaffinity(0, sizeof allowed, &allowed) != 0) {
    return {std::string("reading the CPU affinity refused: ") + std::strerror(errno)};
  }
  if (cpu < 0 || cpu >= CPU_SETSIZE) return {"avoid_cpu: no CPU " + std::to_string(cpu)};
  CPU_CLR(static_cast<unsigned>(cpu), &allowed);
  if (CPU_COUNT(&allowed) == 0) {
    return {"avoid_cpu: CPU " + std::to_string(cpu) + " is the only one allowed"};
  }
  if (::sched_setaffinity(0, sizeof allowed, &allowed) != 0) {
    return {std::string("every CPU but ") + std::to_string(cpu) +
            " refused: " + std::strerror(errno)};
  }
  return {};
}

//! Maps the memory behind an empty single-producer, single-consumer ring (a
//! boost::lockfree::spsc_queue with its size given at run time, or a ring with the same
//! `write_available`, `push` and `consume_all`), at configuration time and before its consumer
//! runs: every slot is written once with `value`, then the ring is emptied. Such a ring's storage
//! is allocated uninitialized, so without this the loop thread's first pass over it takes a
//! first-touch page fault every few pushes (microseconds each: one push in 16 for a 256-byte
//! TickRecord). mlockall (RealtimeOptions::lock_memory) maps the whole process instead, when the
//! system allows it.
template <typename Ring, typename T>
void prefault_ring(Ring& ring, const T& value) {
  const std::size_t slots = ring.write_available();
  for (std::size_t k = 0; k < slots; ++k) (void)ring.push(value);
  ring.consume_all([](const T&) {});
  // The ring's one slot more than its capacity (a full ring and an empty one differ by it).
  (void)ring.push(value);
  ring.consume_all([](const T&) {});
}

}  // namespace endohaptics::teleop
