//! @file
//! A parameter struct's JSON form, derived from its one field list (`P::for_each_field`,
//! core/parameter.hpp): every field by its name, numbers as numbers, fixed-size Eigen vectors as
//! arrays (an adl_serializer), named enumerations by name. Reading is strict: every field
//! present, of its type, no other key; the ranges are the struct's own validate(), its
//! ParameterError reworded with the place in the file. Configuration time only.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/parameter.hpp"
#include "endohaptics/files/json_text.hpp"

namespace nlohmann {
//! Fixed-size Eigen vectors as JSON arrays of numbers (write; read: an array of exactly the size).
template <typename Scalar, int N, int Options, int MaxRows, int MaxCols>
struct adl_serializer<Eigen::Matrix<Scalar, N, 1, Options, MaxRows, MaxCols>> {
  static_assert(N > 0, "a fixed-size vector");
  using Vector = Eigen::Matrix<Scalar, N, 1, Options, MaxRows, MaxCols>;  //!< the vector type
  //! [v0, v1, ...].
  static void to_json(json& j, const Vector& v) {
    j = json::array();
    for (int i = 0; i < N; ++i) j.push_back(static_cast<double>(v[i]));
  }
  //! Throws Error unless `j` is an array of N numbers.
  static void from_json(const json& j, Vector& v) {
    if (!j.is_array() || j.size() != static_cast<std::size_t>(N)) {
      endohaptics::detail::fail("expected an array of " + std::to_string(N) + " numbers, got " +
                                j.dump());
    }
    for (int i = 0; i < N; ++i) v[i] = j[static_cast<std::size_t>(i)].template get<Scalar>();
  }
};
}  // namespace nlohmann

namespace endohaptics::files {

namespace detail::parameter_json {

using nlohmann::json;

//! Writes each field into `out`.
struct Writer {
  json& out;  //!< a JSON object
  template <typename T>
  void operator()(std::string_view name, const T& value, const Bound&) const {
    if constexpr (NamedEnum<T>) {
      out[std::string(name)] = std::string(enumerator_name(value));
    } else if constexpr (std::is_arithmetic_v<T>) {
      out[std::string(name)] = static_cast<double>(value);
    } else {
      out[std::string(name)] = value;
    }
  }
};

//! Collects the field names, in list order.
struct Names {
  std::vector<std::string>& out;  //!< the names
  template <typename T>
  void operator()(std::string_view name, const T&, const Bound&) const {
    out.emplace_back(name);
  }
};

//! Reads each field from `in`; throws Error naming `where` and "<prefix>.<name>".
struct Reader {
  const json& in;            //!< a JSON object
  const std::string& where;  //!< "model file x.json"
  std::string_view prefix;   //!< "parameters"

  [[nodiscard]] std::string dotted(std::string_view name) const {
    return std::string(prefix) + "." + std::string(name);
  }
  [[nodiscard]] double number(const json& j, const std::string& name) const {
    if (!j.is_number()) {
      endohaptics::detail::fail(where + ": field \"" + name + "\" is not a number (" +
                                json_text::show(j) + ")");
    }
    return j.get<double>();
  }
  template <typename T>
  void operator()(std::string_view name, T& value, const Bound&) const {
    const auto it = in.find(std::string(name));
    if (it == in.end()) {
      endohaptics::detail::fail(where + ": " + std::string(prefix) + ": missing field \"" +
                                std::string(name) + "\"");
    }
    const json& j = *it;
    if constexpr (NamedEnum<T>) {
      const std::string text = j.is_string() ? j.get<std::string>() : json_text::show(j);
      for (const auto& [label, e] : enumerators(value)) {
        if (j.is_string() && text == label) {
          value = e;
          return;
        }
      }
      endohaptics::detail::fail(where + ": field \"" + dotted(name) + "\" is " +
                                (j.is_string() ? "\"" + text + "\"" : text) + ", expected " +
                                enumerator_list(value));
    } else if constexpr (std::is_arithmetic_v<T>) {
      value = static_cast<T>(number(j, dotted(name)));
    } else {
      const auto n = static_cast<std::size_t>(value.size());
      if (!j.is_array() || j.size() != n) {
        endohaptics::detail::fail(where + ": field \"" + dotted(name) + "\" must be an array of " +
                                  std::to_string(n) + " numbers, got " + json_text::show(j));
      }
      for (std::size_t i = 0; i < n; ++i) {
        value[static_cast<Eigen::Index>(i)] = static_cast<std::remove_cvref_t<decltype(value[0])>>(
            number(j[i], dotted(name) + "[" + std::to_string(i) + "]"));
      }
    }
  }
};

}  // namespace detail::parameter_json

//! The names of `P`'s fields, in its list's order.
template <typename P>
[[nodiscard]] std::vector<std::string> parameter_names() {
  std::vector<std::string> names;
  P defaults{};
  P::for_each_field(defaults, detail::parameter_json::Names{names});
  return names;
}

//! `p`'s fields as a JSON object (every field of its list).
template <typename P>
[[nodiscard]] nlohmann::json parameters_to_json(const P& p) {
  nlohmann::json j = nlohmann::json::object();
  P::for_each_field(p, detail::parameter_json::Writer{j});
  return j;
}

//! Reads every field of `P` from the object `j` over `p` (fields not in the list, such as the
//! sample time, keep their value): each field required and of its type, no other key. Does not
//! check ranges (validate_parameters). Throws Error "<where>: ..." naming "<prefix>.<field>",
//! or for an unknown key `what` ("for kind \"stall_hold\"") and the known names.
template <typename P>
void parameters_from_json(const nlohmann::json& j, P& p, const std::string& where,
                          std::string_view prefix, std::string_view what = {}) {
  if (!j.is_object()) {
    endohaptics::detail::fail(where + ": field \"" + std::string(prefix) + "\" is not an object");
  }
  const std::vector<std::string> known = parameter_names<P>();
  for (const auto& [key, value] : j.items()) {
    if (std::find(known.begin(), known.end(), key) == known.end()) {
      std::string all;
      for (const auto& k : known) all += (all.empty() ? "" : ", ") + k;
      endohaptics::detail::fail(where + ": unknown field \"" + std::string(prefix) + "." + key +
                                "\"" + (what.empty() ? "" : " " + std::string(what)) +
                                " (known: " + all + ")");
    }
  }
  P::for_each_field(p, detail::parameter_json::Reader{j, where, prefix});
}

//! Runs `p.validate()`; a ParameterError becomes "<where>: field \"<prefix>.<field>\" must be
//! <rule>, got <value>" (other errors get "<where>: " in front).
template <typename P>
void validate_parameters(const P& p, const std::string& where, std::string_view prefix) {
#if defined(__cpp_exceptions)
  try {
    p.validate();
  } catch (const ParameterError& e) {
    endohaptics::detail::fail(where + ": field \"" + std::string(prefix) + "." + e.field() +
                              "\" must be " + e.rule() + ", got " + e.value());
  } catch (const Error& e) {
    endohaptics::detail::fail(where + ": " + e.what());
  }
#else
  (void)where;
  (void)prefix;
  p.validate();
#endif
}

}  // namespace endohaptics::files
