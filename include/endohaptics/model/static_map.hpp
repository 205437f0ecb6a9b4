//! @file
//! The description of a static map on one channel (worksheet 4.1.1, figure 4.1: a dead zone, a
//! saturation or none, by its breakpoints in signal units), as identification fits it and model
//! files store it, and its conversion to and from the fixed-size real-time nonlinearities
//! (Deadzone, Saturation, Identity) and HammersteinWiener. Configuration time: throws Error.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

#include "endohaptics/core/error.hpp"
#include "endohaptics/model/hammerstein_wiener.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/model/static_nonlinearity.hpp"

namespace endohaptics::model {

//! A static map on one channel, by breakpoints (Deadzone / Saturation / Identity).
enum class StaticMapKind : std::uint8_t {
  none = 0,    //!< y = u
  deadzone,    //!< 0 on [lower, upper], u - upper above, u - lower below
  saturation,  //!< clamp(u, lower, upper)
};

//! Lower-case name ("none", "deadzone", "saturation").
[[nodiscard]] constexpr std::string_view to_string(StaticMapKind kind) noexcept {
  switch (kind) {
    case StaticMapKind::none:
      return "none";
    case StaticMapKind::deadzone:
      return "deadzone";
    case StaticMapKind::saturation:
      return "saturation";
  }
  return "unknown";
}

//! The kind named `name` as `to_string` writes it (case-sensitive), or std::nullopt.
[[nodiscard]] constexpr std::optional<StaticMapKind> static_map_kind_from_string(
    std::string_view name) noexcept {
  for (const StaticMapKind kind :
       {StaticMapKind::none, StaticMapKind::deadzone, StaticMapKind::saturation}) {
    if (name == to_string(kind)) return kind;
  }
  return std::nullopt;
}

//! One channel's static map; lower <= upper (ignored for `none`).
struct StaticMap {
  StaticMapKind kind = StaticMapKind::none;  //!< which map
  double lower = 0.0;                        //!< lower breakpoint / limit, signal units
  double upper = 0.0;                        //!< upper breakpoint / limit, signal units

  //! The map applied to one value (NaN stays NaN).
  [[nodiscard]] double apply(double u) const noexcept {
    switch (kind) {
      case StaticMapKind::deadzone:
        if (u > upper) return u - upper;
        if (u < lower) return u - lower;
        return std::isnan(u) ? u : 0.0;
      case StaticMapKind::saturation:
        if (u > upper) return upper;
        if (u < lower) return lower;
        return u;
      case StaticMapKind::none:
        return u;
    }
    return u;
  }
};

//! One fixed-size channel (Deadzone, Saturation or Identity of any Scalar) as a StaticMap.
template <typename NL>
[[nodiscard]] StaticMap to_static_map(const NL& channel) {
  using Scalar = typename NL::ScalarType;
  if constexpr (std::is_same_v<NL, Deadzone<Scalar>>) {
    return {StaticMapKind::deadzone, static_cast<double>(channel.lower()),
            static_cast<double>(channel.upper())};
  } else if constexpr (std::is_same_v<NL, Saturation<Scalar>>) {
    return {StaticMapKind::saturation, static_cast<double>(channel.lower()),
            static_cast<double>(channel.upper())};
  } else {
    static_assert(std::is_same_v<NL, Identity<Scalar>>,
                  "a StaticMap describes a Deadzone, Saturation or Identity channel");
    return {};
  }
}

namespace detail::static_map {

//! One channel as the fixed-size nonlinearity NL (Deadzone, Saturation or Identity); throws
//! Error naming `where` when the map cannot be expressed by NL (a `none` map is a zero-width
//! Deadzone), or as NL's constructor (breakpoints not finite or not ordered).
template <typename NL>
NL to_channel(const StaticMap& map, const std::string& where) {
  using Scalar = typename NL::ScalarType;
  const auto lower = static_cast<Scalar>(map.lower);
  const auto upper = static_cast<Scalar>(map.upper);
  if constexpr (std::is_same_v<NL, Deadzone<Scalar>>) {
    if (map.kind == StaticMapKind::none) return NL(Scalar(0));
    if (map.kind == StaticMapKind::deadzone) return NL(lower, upper);
  } else if constexpr (std::is_same_v<NL, Saturation<Scalar>>) {
    if (map.kind == StaticMapKind::saturation) return NL(lower, upper);
  } else if constexpr (std::is_same_v<NL, Identity<Scalar>>) {
    if (map.kind == StaticMapKind::none) return NL{};
  }
  ENDOHAPTICS_THROW(Error("to_hammerstein_wiener: " + where + " is a " +
                          std::string(to_string(map.kind)) +
                          ", which the requested nonlinearity type cannot represent"));
}

//! N maps as PerChannel<NL, N>. Precondition: maps.size() == N.
template <typename NL, int N>
PerChannel<NL, N> to_channels(std::span<const StaticMap> maps, const char* what) {
  ENDOHAPTICS_ASSERT(maps.size() == static_cast<std::size_t>(N));
  std::array<NL, static_cast<std::size_t>(N)> channels = [&]<std::size_t... I>(
      std::index_sequence<I...>) {
    return std::array<NL, sizeof...(I)>{
        to_channel<NL>(maps[I], std::string(what) + " " + std::to_string(I))...};
  }
  (std::make_index_sequence<static_cast<std::size_t>(N)>{});
  return PerChannel<NL, N>(channels);
}

}  // namespace detail::static_map

//! The fixed-size real-time HammersteinWiener<StateSpace<Nx, Nu, Ny, Scalar>, PerChannel<InputNL,
//! Nu>, PerChannel<OutputNL, Ny>> from a linear block of any sizes (e.g. DynamicStateSpace, its
//! state kept) and one map per input and output. InputNL defaults to Deadzone (a `none` input is
//! a zero-width dead zone), OutputNL to Identity. Throws Error when the map counts are not Nu
//! and Ny, the linear block's sizes differ (StateSpace's converting constructor), or a map does
//! not fit the nonlinearity type.
template <int Nx, int Nu, int Ny, typename Scalar = double, typename InputNL = Deadzone<Scalar>,
          typename OutputNL = Identity<Scalar>, int Mx, int Mu, int My, typename LinearScalar>
[[nodiscard]] HammersteinWiener<StateSpace<Nx, Nu, Ny, Scalar>, PerChannel<InputNL, Nu>,
                                PerChannel<OutputNL, Ny>>
to_hammerstein_wiener(const StateSpace<Mx, Mu, My, LinearScalar>& linear,
                      std::span<const StaticMap> input, std::span<const StaticMap> output) {
  if (input.size() != static_cast<std::size_t>(Nu) ||
      output.size() != static_cast<std::size_t>(Ny)) {
    ENDOHAPTICS_THROW(Error("to_hammerstein_wiener: " + std::to_string(input.size()) +
                            " input and " + std::to_string(output.size()) +
                            " output maps; the target type has " + std::to_string(Nu) +
                            " inputs and " + std::to_string(Ny) + " outputs"));
  }
  return {StateSpace<Nx, Nu, Ny, Scalar>(linear),
          detail::static_map::to_channels<InputNL, Nu>(input, "input"),
          detail::static_map::to_channels<OutputNL, Ny>(output, "output")};
}

}  // namespace endohaptics::model
