//! @file
//! The identification methods endohaptics-identify fits (worksheet 4.2.2 and the joint force
//! models): a subspace weighting (N4SID, MOESP, CVA), the static least-squares baseline, or a
//! joint force model kind, as one enum with one table of names. --method lists parse into it;
//! code asks the enum (never the display string) which fit a candidate came from.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/files/model_file.hpp"
#include "endohaptics/identification/subspace.hpp"

namespace endohaptics::workflow {

//! One identification method: what is fitted.
enum class Method : std::uint8_t {
  n4sid,                        //!< subspace, N4SID weighting
  moesp,                        //!< subspace, MOESP weighting
  cva,                          //!< subspace, CVA weighting
  static_gain,                  //!< y = D u + c, no dynamics (workflow/static_gain_fit.hpp)
  stall_hold,                   //!< estimation::StallHold (workflow/stall_hold_fit.hpp)
  push_load_observer,           //!< estimation::PushLoadObserver
  bidirectional_load_observer,  //!< estimation::BidirectionalLoadObserver
};

//! A method and its name on the command line and in reports.
struct MethodName {
  std::string_view name;  //!< e.g. "moesp", "static"
  Method method;          //!< the method it names
};

//! The one table of method names ("best" is a list, not a method: parse_methods).
inline constexpr std::array<MethodName, 7> method_names{{
    {"n4sid", Method::n4sid},
    {"moesp", Method::moesp},
    {"cva", Method::cva},
    {"static", Method::static_gain},
    {"stall_hold", Method::stall_hold},
    {"push_load_observer", Method::push_load_observer},
    {"bidirectional_load_observer", Method::bidirectional_load_observer},
}};

//! The name of `method` in method_names.
[[nodiscard]] constexpr std::string_view to_string(Method method) noexcept {
  for (const MethodName& m : method_names) {
    if (m.method == method) return m.name;
  }
  return {};
}

//! The subspace weighting of a subspace method; none for the others.
[[nodiscard]] constexpr std::optional<identification::Weighting> weighting_of(
    Method method) noexcept {
  switch (method) {
    case Method::n4sid:
      return identification::Weighting::n4sid;
    case Method::moesp:
      return identification::Weighting::moesp;
    case Method::cva:
      return identification::Weighting::cva;
    default:
      return std::nullopt;
  }
}

//! The subspace method of `weighting`.
[[nodiscard]] constexpr Method method_of(identification::Weighting weighting) noexcept {
  switch (weighting) {
    case identification::Weighting::n4sid:
      return Method::n4sid;
    case identification::Weighting::cva:
      return Method::cva;
    case identification::Weighting::moesp:
      break;
  }
  return Method::moesp;
}

//! The model-file kind of a joint force model method; none for the linear ones.
[[nodiscard]] constexpr std::optional<files::ModelKind> joint_kind_of(Method method) noexcept {
  switch (method) {
    case Method::stall_hold:
      return files::ModelKind::stall_hold;
    case Method::push_load_observer:
      return files::ModelKind::push_load_observer;
    case Method::bidirectional_load_observer:
      return files::ModelKind::bidirectional_load_observer;
    default:
      return std::nullopt;
  }
}

//! Parses a --method value: a comma list of the names of method_names and "best" (= n4sid,
//! moesp, cva), in the order given. Throws Error naming the value and the names otherwise.
[[nodiscard]] ENDOHAPTICS_DECL std::vector<Method> parse_methods(std::string_view list);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/method.ipp"
#endif
