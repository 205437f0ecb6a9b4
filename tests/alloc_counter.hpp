// Allocation counting for "no heap allocation per tick" tests. Include this FIRST in a test
// translation unit (before any Eigen or endohaptics header), once per executable; the unit tests'
// CMake includes it first in every area's unity source (tests/CMakeLists.txt), so a test file
// includes it too only to say that it uses it:
//  - every global operator new (scalar, array, aligned, nothrow forms) is counted;
//  - Eigen's own heap use (malloc, not operator new) is counted through EIGEN_RUNTIME_NO_MALLOC:
//    inside allocations_during, a failed eigen_assert (Eigen's "malloc is forbidden") is counted
//    instead of aborting; everywhere else eigen_assert aborts with its message, as Eigen's does.
// allocations_during(f) returns both counts made while running f, by any thread;
// allocations_on_this_thread_during(f) the operator new calls of the calling thread only (for a
// loop thread while other threads, e.g. ROS's, allocate as they like) plus Eigen's mallocs.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <new>

namespace endohaptics::test {
inline std::atomic<long> new_calls{0};
inline std::atomic<long> eigen_mallocs{0};
inline std::atomic<bool> counting{false};
inline thread_local bool counting_this_thread = false;  // constant-initialised: safe in new
inline std::atomic<long> this_thread_new_calls{0};

[[gnu::noinline]] inline void eigen_assert_failed(const char* condition, const char* file,
                                                  int line) noexcept {
  if (counting.load()) {
    eigen_mallocs.fetch_add(1);
    return;
  }
  std::fprintf(stderr, "%s:%d: Eigen assertion failed: %s\n", file, line, condition);
  std::abort();
}
}  // namespace endohaptics::test

#ifndef EIGEN_RUNTIME_NO_MALLOC
#define EIGEN_RUNTIME_NO_MALLOC
#endif
#ifndef eigen_assert
#define eigen_assert(x)                                                         \
  do {                                                                          \
    if (!(x)) ::endohaptics::test::eigen_assert_failed(#x, __FILE__, __LINE__); \
  } while (false)
#else
#error "alloc_counter.hpp must come before any Eigen header (eigen_assert is already defined)"
#endif

#include <Eigen/Core>

// The replacements below are noinline: once GCC inlines them (-O1 and up) it sees `free` on memory
// from `operator new` and reports -Wmismatched-new-delete, though both sides are ours and match.
[[gnu::noinline]] void* operator new(std::size_t size) {
  endohaptics::test::new_calls.fetch_add(1, std::memory_order_relaxed);
  if (endohaptics::test::counting_this_thread) {
    endohaptics::test::this_thread_new_calls.fetch_add(1, std::memory_order_relaxed);
  }
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
[[gnu::noinline]] void* operator new[](std::size_t size) { return operator new(size); }
[[gnu::noinline]] void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  endohaptics::test::new_calls.fetch_add(1, std::memory_order_relaxed);
  if (endohaptics::test::counting_this_thread) {
    endohaptics::test::this_thread_new_calls.fetch_add(1, std::memory_order_relaxed);
  }
  return std::malloc(size == 0 ? 1 : size);
}
[[gnu::noinline]] void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept {
  return operator new(size, tag);
}
[[gnu::noinline]] void* operator new(std::size_t size, std::align_val_t align) {
  endohaptics::test::new_calls.fetch_add(1, std::memory_order_relaxed);
  if (endohaptics::test::counting_this_thread) {
    endohaptics::test::this_thread_new_calls.fetch_add(1, std::memory_order_relaxed);
  }
  const auto a = static_cast<std::size_t>(align);
  if (void* p = std::aligned_alloc(a, (size + a - 1) / a * a)) return p;
  throw std::bad_alloc();
}
[[gnu::noinline]] void* operator new[](std::size_t size, std::align_val_t align) {
  return operator new(size, align);
}
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}
[[gnu::noinline]] void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}

namespace endohaptics::test {

//! Heap allocations (operator new calls + Eigen mallocs) made while running `f`.
template <typename F>
long allocations_during(F&& f) {
  const long before_new = new_calls.load();
  const long before_eigen = eigen_mallocs.load();
  counting.store(true);
  Eigen::internal::set_is_malloc_allowed(false);
  f();
  Eigen::internal::set_is_malloc_allowed(true);
  counting.store(false);
  return (new_calls.load() - before_new) + (eigen_mallocs.load() - before_eigen);
}

//! Heap allocations made while running `f` by the calling thread (operator new calls; other
//! threads' are not counted) plus Eigen's mallocs (Eigen's switch is process-wide).
template <typename F>
long allocations_on_this_thread_during(F&& f) {
  const long before_new = this_thread_new_calls.load();
  const long before_eigen = eigen_mallocs.load();
  counting_this_thread = true;
  counting.store(true);
  Eigen::internal::set_is_malloc_allowed(false);
  f();
  Eigen::internal::set_is_malloc_allowed(true);
  counting.store(false);
  counting_this_thread = false;
  return (this_thread_new_calls.load() - before_new) + (eigen_mallocs.load() - before_eigen);
}

}  // namespace endohaptics::test
