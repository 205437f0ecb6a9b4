//! @file
//! KeyRing: the long-term keys a protocol v2 robot side accepts handshakes under: one per
//! console-robot pair, two while a key is changed over (the old one and its successor), each
//! named by its key id. Revoking a key id ends every handshake under it at once (a session
//! already open under it ends when SecureResponder::revoke is called). docs/protocol.md, "Keys".
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>

#include "endohaptics/core/error.hpp"
#include "endohaptics/protocol/handshake.hpp"
#include "endohaptics/protocol/secure_codec.hpp"

namespace endohaptics::protocol {

//! Up to `max_keys` long-term keys with distinct ids. Lookup is noexcept and allocation-free.
class KeyRing {
 public:
  static constexpr std::size_t max_keys = 2;  //!< the key in use and its successor

  //! An empty ring (add at least one key before use).
  KeyRing() = default;
  //! A ring holding `key`.
  explicit KeyRing(const SecureKey& key) { add(key); }

  //! Adds `key`. Throws Error when the ring is full or holds a key with the same id.
  void add(const SecureKey& key) {
    if (find(key.id()).has_value()) {
      ENDOHAPTICS_THROW(Error("key ring: key " + to_hex(key.id()) + " is there already"));
    }
    for (auto& slot : keys_) {
      if (!slot) {
        slot = key;
        return;
      }
    }
    ENDOHAPTICS_THROW(Error("key ring: at most " + std::to_string(max_keys) +
                            " keys (the key in use and its successor), got one more"));
  }

  //! Removes the key with id `id`; false when there is none.
  bool revoke(const KeyId& id) noexcept {
    for (auto& slot : keys_) {
      if (slot && slot->id() == id) {
        slot.reset();
        return true;
      }
    }
    return false;
  }

  //! The slot of the key with id `id`, if held.
  [[nodiscard]] std::optional<std::size_t> find(const KeyId& id) const noexcept {
    for (std::size_t i = 0; i < keys_.size(); ++i) {
      if (keys_[i] && keys_[i]->id() == id) return i;
    }
    return std::nullopt;
  }

  //! The key in slot `i` (precondition: held(i)).
  [[nodiscard]] const SecureKey& at(std::size_t i) const noexcept { return *keys_[i]; }
  //! True when slot `i` holds a key.
  [[nodiscard]] bool held(std::size_t i) const noexcept { return i < keys_.size() && keys_[i]; }
  //! Keys held.
  [[nodiscard]] std::size_t size() const noexcept {
    std::size_t n = 0;
    for (const auto& slot : keys_) n += slot ? 1u : 0u;
    return n;
  }

 private:
  std::array<std::optional<SecureKey>, max_keys> keys_{};
};

}  // namespace endohaptics::protocol
