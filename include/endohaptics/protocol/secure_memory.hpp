//! @file
//! LockedBox<T>: one object of a trivially copyable type in libsodium's guarded memory
//! (sodium_malloc: its own pages between guard pages, locked into RAM with mlock so it is never
//! swapped, excluded from core dumps with MADV_DONTDUMP, and wiped by sodium_free). Protocol v2
//! keeps every key it holds (the long-term key's keyed hash state, the session keys) in one.
//! Configuration time: construction allocates and may throw; access is noexcept.
#pragma once

#include <sodium.h>

#include <new>
#include <type_traits>
#include <utility>

#include "endohaptics/core/error.hpp"

namespace endohaptics::protocol {

//! Owns one `T` in sodium_malloc'd memory, value-initialised. Move-only; the memory is wiped and
//! unmapped on destruction. `T` is trivially copyable (a key, a hash state): nothing to destroy.
template <typename T>
class LockedBox {
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);

 public:
  //! Allocates and zero-initialises. Throws Error when libsodium cannot start or the memory
  //! cannot be had (sodium_malloc returned null).
  LockedBox() {
    if (sodium_init() < 0) ENDOHAPTICS_THROW(Error("libsodium failed to initialise"));
    void* p = sodium_malloc(sizeof(T));
    if (p == nullptr) {
      ENDOHAPTICS_THROW(Error("cannot allocate locked memory for a key (sodium_malloc failed)"));
    }
    value_ = ::new (p) T{};
  }
  LockedBox(const LockedBox&) = delete;             //!< one copy of a secret, never two
  LockedBox& operator=(const LockedBox&) = delete;  //!< one copy of a secret, never two
  //! Takes `other`'s memory; `other` holds none after.
  LockedBox(LockedBox&& other) noexcept : value_(std::exchange(other.value_, nullptr)) {}
  //! Frees this box's memory (wiped) and takes `other`'s.
  LockedBox& operator=(LockedBox&& other) noexcept {
    if (this != &other) {
      release();
      value_ = std::exchange(other.value_, nullptr);
    }
    return *this;
  }
  ~LockedBox() { release(); }

  //! The object (precondition: not moved from).
  [[nodiscard]] T& operator*() noexcept { return *value_; }
  //! The object (precondition: not moved from).
  [[nodiscard]] const T& operator*() const noexcept { return *value_; }
  //! The object's address (precondition: not moved from).
  [[nodiscard]] T* operator->() noexcept { return value_; }
  //! The object's address (precondition: not moved from).
  [[nodiscard]] const T* operator->() const noexcept { return value_; }
  //! Overwrites the object with zeros (sodium_memzero).
  void wipe() noexcept {
    if (value_ != nullptr) sodium_memzero(value_, sizeof(T));
  }
  //! Swaps the two boxes' memory (no copy of the secrets).
  friend void swap(LockedBox& a, LockedBox& b) noexcept { std::swap(a.value_, b.value_); }

 private:
  void release() noexcept {
    if (value_ != nullptr) sodium_free(value_);  // wipes, then unmaps
    value_ = nullptr;
  }
  T* value_ = nullptr;
};

}  // namespace endohaptics::protocol
