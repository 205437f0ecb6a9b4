//! @file
//! One vocabulary for configuration-time checks: `Bound` (the allowed values of one parameter:
//! an interval, a magnitude interval, or a sign), `ParameterError` (which field broke which rule
//! with which value) and `ParameterChecker` (checks a parameter struct's field list). A parameter
//! struct declares its fields once, `for_each_field(p, visitor)` with name, member and bound;
//! its `validate()`, its file form (files/parameter_json.hpp) and the messages of every reader
//! derive from that list. Configuration time only.
#pragma once

#include <array>
#include <chrono>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

#include "endohaptics/core/error.hpp"

namespace endohaptics {

//! The allowed values of one number. Every form refuses NaN and +-Inf.
struct Bound {
  //! What the bound is about.
  enum class Form : std::uint8_t {
    interval,           //!< lo <= v <= hi (either end open)
    magnitude,          //!< lo <= |v| <= hi
    zero_or_magnitude,  //!< v == 0, or lo <= |v| <= hi
    sign,               //!< v == +1 or v == -1
  };
  double lo = -std::numeric_limits<double>::infinity();  //!< lower end
  double hi = std::numeric_limits<double>::infinity();   //!< upper end
  bool lo_open = false;                                  //!< lo itself excluded
  bool hi_open = false;                                  //!< hi itself excluded
  Form form = Form::interval;                            //!< see Form
  std::string_view unit{};                               //!< appended to the description
  std::string_view text{};                               //!< the description, when set

  //! [lo, hi] unit.
  [[nodiscard]] static constexpr Bound in(double lo, double hi, std::string_view unit = {}) {
    return {lo, hi, false, false, Form::interval, unit, {}};
  }
  //! (lo, hi] unit.
  [[nodiscard]] static constexpr Bound above(double lo, double hi, std::string_view unit = {}) {
    return {lo, hi, true, false, Form::interval, unit, {}};
  }
  //! (lo, hi) unit.
  [[nodiscard]] static constexpr Bound between(double lo, double hi, std::string_view unit = {}) {
    return {lo, hi, true, true, Form::interval, unit, {}};
  }
  //! lo <= |v| <= hi.
  [[nodiscard]] static constexpr Bound magnitude(double lo, double hi) {
    return {lo, hi, false, false, Form::magnitude, {}, {}};
  }
  //! 0, or lo <= |v| <= hi.
  [[nodiscard]] static constexpr Bound zero_or_magnitude(double lo, double hi) {
    return {lo, hi, false, false, Form::zero_or_magnitude, {}, {}};
  }
  //! +1 or -1.
  [[nodiscard]] static constexpr Bound unit_sign() { return {-1, 1, false, false, Form::sign}; }
  //! Any finite number.
  [[nodiscard]] static constexpr Bound finite(std::string_view unit = {}) {
    Bound b;
    b.unit = unit;
    return b;
  }
  //! This bound described by `description` instead (e.g. "in (0, Nyquist) Hz").
  [[nodiscard]] constexpr Bound described(std::string_view description) const {
    Bound b = *this;
    b.text = description;
    return b;
  }

  //! True when `v` is allowed.
  [[nodiscard]] constexpr bool contains(double v) const noexcept {
    if (!(v == v) || v == std::numeric_limits<double>::infinity() ||
        v == -std::numeric_limits<double>::infinity()) {
      return false;
    }
    const double a = v < 0 ? -v : v;
    const auto inside = [&](double x) {
      return (lo_open ? x > lo : x >= lo) && (hi_open ? x < hi : x <= hi);
    };
    switch (form) {
      case Form::interval:
        return inside(v);
      case Form::magnitude:
        return inside(a);
      case Form::zero_or_magnitude:
        return v == 0 || inside(a);
      case Form::sign:
        return v == 1 || v == -1;
    }
    return false;
  }

  //! `v` as a bound is written: shortest round-trip text, exponents without sign or zeros
  //! ("1e6", "1e-9", "0.5", "60").
  [[nodiscard]] static std::string format_number(double v) {
    std::string s = detail::format_number(v);
    const auto e = s.find('e');
    if (e == std::string::npos) return s;
    std::string exponent = s.substr(e + 1);
    const bool negative = exponent.front() == '-';
    if (exponent.front() == '+' || negative) exponent.erase(0, 1);
    while (exponent.size() > 1 && exponent.front() == '0') exponent.erase(0, 1);
    return s.substr(0, e + 1) + (negative ? "-" : "") + exponent;
  }

  //! "in [0, 1e6] A", "in (0, 1]", "of magnitude in [1e-9, 1e6]", "+1 or -1", "finite", ...
  [[nodiscard]] std::string describe() const {
    if (!text.empty()) return std::string(text);
    std::string d;
    const bool has_lo = std::isfinite(lo);
    const bool has_hi = std::isfinite(hi);
    const std::string range = std::string(lo_open ? "(" : "[") + format_number(lo) + ", " +
                              format_number(hi) + (hi_open ? ")" : "]");
    switch (form) {
      case Form::sign:
        return "+1 or -1";
      case Form::magnitude:
        d = "of magnitude in " + range;
        break;
      case Form::zero_or_magnitude:
        d = "0 or of magnitude in " + range;
        break;
      case Form::interval:
        if (has_lo && has_hi) {
          d = "in " + range;
        } else if (has_lo) {
          d = std::string("finite and ") + (lo_open ? "> " : ">= ") + format_number(lo);
        } else if (has_hi) {
          d = std::string("finite and ") + (hi_open ? "< " : "<= ") + format_number(hi);
        } else {
          d = "finite";
        }
        break;
    }
    return unit.empty() ? d : d + " " + std::string(unit);
  }
};

//! A configuration value that breaks its rule: the owner ("StallHoldParameters"), the field
//! ("gain", "stop_thresholds[3]"), the rule ("in [-1e6, 1e6]") and the value as text. A reader
//! that knows where the value came from (a file, a key) catches it and names its own place.
class ParameterError : public Error {
 public:
  //! "<owner>: <field> must be <rule>, got <value>".
  ParameterError(std::string_view owner, std::string field, std::string rule, std::string value)
      : Error(std::string(owner) + ": " + field + " must be " + rule + ", got " + value),
        owner_(owner),
        field_(std::move(field)),
        rule_(std::move(rule)),
        value_(std::move(value)) {}
  [[nodiscard]] const std::string& owner() const noexcept { return owner_; }  //!< the struct
  [[nodiscard]] const std::string& field() const noexcept { return field_; }  //!< e.g. "gain"
  [[nodiscard]] const std::string& rule() const noexcept { return rule_; }    //!< "in [0, 1]"
  [[nodiscard]] const std::string& value() const noexcept { return value_; }  //!< as text

 private:
  std::string owner_;
  std::string field_;
  std::string rule_;
  std::string value_;
};

//! An enumeration with a name table: `enumerators(E{})` (found by ADL) returns an array of
//! (name, value) pairs, every value once.
template <typename E>
concept NamedEnum = std::is_enum_v<E> && requires(E e) {
  enumerators(e).size();
  enumerators(e)[0].first;
};

//! The names of a NamedEnum, quoted and joined: "\"both\", \"positive\" or \"negative\"".
template <NamedEnum E>
[[nodiscard]] std::string enumerator_list(E e) {
  const auto table = enumerators(e);
  std::string out;
  for (std::size_t i = 0; i < table.size(); ++i) {
    out += (i == 0                  ? ""
            : i + 1 == table.size() ? " or "
                                    : ", ") +
           std::string("\"") + std::string(table[i].first) + "\"";
  }
  return out;
}

//! The name of `e`, or "" when it has none.
template <NamedEnum E>
[[nodiscard]] std::string_view enumerator_name(E e) {
  for (const auto& [name, value] : enumerators(e)) {
    if (value == e) return name;
  }
  return {};
}

//! A fixed-size vector of numbers in a field list (Eigen's, checked element by element).
template <typename V>
concept NumberVector = requires(const V& v) {
  { v.size() } -> std::convertible_to<long>;
  { v[0] } -> std::convertible_to<double>;
};

//! Checks every field of a field list (`for_each_field(p, checker)`) against its bound, and
//! one-off rules through `require`; throws ParameterError naming `owner` and the field.
struct ParameterChecker {
  std::string_view owner;  //!< e.g. "StallHoldParameters"

  //! Throws unless `ok`: "<owner>: <field> must be <rule>, got <value>".
  template <typename T>
  void require(bool ok, std::string_view field, T value, std::string_view rule) const {
    if (!ok) {
      ENDOHAPTICS_THROW(ParameterError(owner, std::string(field), std::string(rule),
                                       detail::format_number(value)));
    }
  }
  //! Throws unless `ok`, the value given as text (e.g. "0x10").
  void require_text(bool ok, std::string_view field, std::string value,
                    std::string_view rule) const {
    if (!ok) {
      ENDOHAPTICS_THROW(
          ParameterError(owner, std::string(field), std::string(rule), std::move(value)));
    }
  }
  //! A duration field, bounded in seconds.
  template <typename Rep, typename Period>
  void operator()(std::string_view name, const std::chrono::duration<Rep, Period>& value,
                  const Bound& bound) const {
    const double seconds = std::chrono::duration<double>(value).count();
    require(bound.contains(seconds), name, seconds, bound.describe());
  }
  //! A flag: both values are allowed.
  void operator()(std::string_view, const bool&, const Bound&) const noexcept {}
  //! A number field.
  template <typename T>
  requires std::is_arithmetic_v<T>
  void operator()(std::string_view name, const T& value, const Bound& bound) const {
    require(bound.contains(static_cast<double>(value)), name, value, bound.describe());
  }
  //! A vector field: each element, named "name[j]".
  template <NumberVector V>
  void operator()(std::string_view name, const V& value, const Bound& bound) const {
    for (long j = 0; j < static_cast<long>(value.size()); ++j) {
      require(bound.contains(static_cast<double>(value[j])),
              std::string(name) + "[" + std::to_string(j) + "]", value[j], bound.describe());
    }
  }
  //! An enumeration field: one of its named values.
  template <NamedEnum E>
  void operator()(std::string_view name, const E& value, const Bound&) const {
    if (enumerator_name(value).empty()) {
      ENDOHAPTICS_THROW(ParameterError(
          owner, std::string(name), "one of " + enumerator_list(value),
          std::to_string(static_cast<long long>(static_cast<std::underlying_type_t<E>>(value)))));
    }
  }
};

}  // namespace endohaptics
