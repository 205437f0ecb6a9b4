// Placing a benchmark's threads on CPUs: the first and the last CPU the calling thread may use, and
// a scope that pins the calling thread to one of them and gives the old mask back at its end. A
// thread inherits the mask of the thread that starts it: read the CPUs before any thread pins
// itself.
#pragma once

#include <sched.h>

namespace bench {

//! The first and the last CPU the calling thread may use (-1: unknown).
struct Cpus {
  int first = -1;
  int last = -1;
};

//! The calling thread's CPUs now.
[[nodiscard]] inline Cpus allowed_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  Cpus cpus;
  if (::sched_getaffinity(0, sizeof set, &set) != 0) return cpus;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
    if (!CPU_ISSET(static_cast<unsigned>(cpu), &set)) continue;
    if (cpus.first < 0) cpus.first = cpu;
    cpus.last = cpu;
  }
  return cpus;
}

//! Pins the calling thread to `cpu` (nothing for -1) for its lifetime.
class PinnedTo {
 public:
  explicit PinnedTo(int cpu) {
    if (cpu < 0 || ::sched_getaffinity(0, sizeof saved_, &saved_) != 0) return;
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(static_cast<unsigned>(cpu), &one);
    pinned_ = ::sched_setaffinity(0, sizeof one, &one) == 0;
  }
  ~PinnedTo() {
    if (pinned_) (void)::sched_setaffinity(0, sizeof saved_, &saved_);
  }
  PinnedTo(const PinnedTo&) = delete;
  PinnedTo& operator=(const PinnedTo&) = delete;

 private:
  cpu_set_t saved_{};
  bool pinned_ = false;
};

}  // namespace bench
