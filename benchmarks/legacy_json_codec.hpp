//! @file
//! LegacyJsonCodec: the JSON state message the 2016 system replaced (worksheet listing 3.1),
//! `{"p4_primary": {"position": [...], "velocity": [...], "effort": [...]}}`, written and read
//! with nlohmann-json. Baseline for benchmarks and size comparisons only: not part of the
//! library and not real-time (it allocates and throws).
#pragma once

#include <endohaptics/protocol/packet_codec.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace endohaptics::baseline {

template <int N>
class LegacyJsonCodec {
 public:
  using State = protocol::MotorState<N>;

  //! The listing 3.1 message for `state` (the active mask had no place in it).
  [[nodiscard]] static std::string encode(const State& state) {
    nlohmann::json arm;
    arm["position"] = to_vector(state.position);
    arm["velocity"] = to_vector(state.velocity);
    arm["effort"] = to_vector(state.current);
    nlohmann::json message;
    message["p4_primary"] = std::move(arm);
    return message.dump();
  }

  //! Parses a listing 3.1 message; false (and `out` untouched) on malformed or short input.
  [[nodiscard]] static bool parse(std::string_view text, State& out) {
    const auto message = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
    if (message.is_discarded() || !message.contains("p4_primary")) return false;
    const auto& arm = message["p4_primary"];
    State parsed;
    if (!read(arm, "position", parsed.position) || !read(arm, "velocity", parsed.velocity) ||
        !read(arm, "effort", parsed.current)) {
      return false;
    }
    parsed.active_mask = out.active_mask;
    out = parsed;
    return true;
  }

 private:
  static std::vector<double> to_vector(const typename State::Vector& v) {
    return std::vector<double>(v.data(), v.data() + N);
  }
  static bool read(const nlohmann::json& arm, const char* key, typename State::Vector& v) {
    if (!arm.is_object() || !arm.contains(key)) return false;
    const auto& array = arm[key];
    if (!array.is_array() || array.size() < static_cast<std::size_t>(N)) return false;
    for (int i = 0; i < N; ++i) {
      const auto& item = array[static_cast<std::size_t>(i)];
      if (!item.is_number()) return false;
      v[i] = item.template get<double>();
    }
    return true;
  }
};

}  // namespace endohaptics::baseline
