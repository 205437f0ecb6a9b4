//! @file
//! The bridge's configuration file (JSON) <-> the library's configuration structs: mapping
//! (kinematics::CylindricalMapperConfig), safety and receive timeout (teleop::TeleopLoopConfig),
//! force estimator settings and clamp model file, scripted operator (sim::OperatorScript).
//! Strict: every key optional, defaults are the library's; unknown or duplicate keys, wrong
//! types, non-integral or out-of-range values are errors naming the file, the key and the range.
#pragma once

#include <Eigen/Core>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/bidirectional_load_observer.hpp"
#include "endohaptics/estimation/force_estimator.hpp"
#include "endohaptics/estimation/push_load_observer.hpp"
#include "endohaptics/estimation/stall_hold.hpp"
#include "endohaptics/files/json_text.hpp"
#include "endohaptics/files/model_file.hpp"
#include "endohaptics/kinematics/cylindrical_mapper.hpp"
#include "endohaptics/model/joint_model_bounds.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/sim/scripted_operator.hpp"
#include "endohaptics/teleop/safety.hpp"
#include "endohaptics/teleop/teleop_loop.hpp"

namespace endohaptics::files {

//! Everything the bridge's --config file sets. Keys (docs/rig.md, "The configuration file"):
//! "mapping" -> mapping, "safety" -> loop.safety, "loop.receive_timeout" (s) ->
//! loop.receive_timeout, "estimator" -> estimator and clamp_model, "operator" -> operator_script.
struct BridgeConfig {
  kinematics::CylindricalMapperConfig<double> mapping{};  //!< eqs. 5.8/5.9
  //! Safety and receive timeout; `period` is not in the file (the bridge's --rate sets it).
  teleop::TeleopLoopConfig loop{};
  estimation::ForceEstimatorSettings<double> estimator{};  //!< friction levels, signs, limits
  //! "estimator.clamp_model": an identified model file (endohaptics-identify) for both clamps:
  //! Hammerstein-Wiener (6 states, 2 inputs, 1 output), "stall_hold", "push_load_observer" or
  //! "bidirectional_load_observer", resolved against the configuration file's folder; empty: the
  //! 2016 appendix C yaw model.
  std::filesystem::path clamp_model;
  sim::OperatorScript operator_script{};  //!< the scripted operator of `--device sim`
};

//! Largest configuration file `load_bridge_config` reads, bytes (a complete one is < 2 kB).
inline constexpr std::size_t bridge_config_max_bytes = std::size_t{1} << 20;
//! Deepest nesting of arrays and objects accepted (the schema itself needs 3).
inline constexpr int bridge_config_max_depth = 64;

namespace detail::bridge_config {

using nlohmann::json;

using json_text::excerpt;
using json_text::key_name;
using json_text::show;

//! The allowed values of a number: an interval (finite bounds or infinite), or exactly -1/+1.
struct Range {
  double lo = -std::numeric_limits<double>::infinity();  //!< lower bound
  double hi = std::numeric_limits<double>::infinity();   //!< upper bound
  bool lo_open = false;                                  //!< lo itself excluded
  bool hi_open = false;                                  //!< hi itself excluded
  std::string_view unit;                                 //!< appended to the description
  std::string_view text;                                 //!< description override
  bool sign = false;                                     //!< only -1 and +1

  //! Any finite number.
  [[nodiscard]] static Range any(std::string_view units = "") {
    Range r;
    r.unit = units;
    return r;
  }
  //! Finite and >= low.
  [[nodiscard]] static Range at_least(double low, std::string_view units = "") {
    Range r = any(units);
    r.lo = low;
    return r;
  }
  //! Finite and > low.
  [[nodiscard]] static Range above(double low, std::string_view units = "") {
    Range r = at_least(low, units);
    r.lo_open = true;
    return r;
  }
  //! In [low, high].
  [[nodiscard]] static Range between(double low, double high, std::string_view units = "") {
    Range r = at_least(low, units);
    r.hi = high;
    return r;
  }
  //! Exactly -1 or +1.
  [[nodiscard]] static Range plus_minus_one() {
    Range r;
    r.text = "-1 or +1";
    r.sign = true;
    return r;
  }
  //! In [low, high], described by `description` (e.g. "a number in [-pi, pi] rad").
  [[nodiscard]] static Range described(double low, double high, std::string_view description) {
    Range r = between(low, high);
    r.text = description;
    return r;
  }

  //! True when `v` is allowed.
  [[nodiscard]] bool contains(double v) const noexcept {
    if (sign) return v == 1.0 || v == -1.0;
    return std::isfinite(v) && (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  }
  //! "a finite number >= 0 s", "a number in [0, 1] s", "-1 or +1", ...
  [[nodiscard]] std::string describe() const {
    using endohaptics::detail::format_number;
    if (!text.empty()) return std::string(text);
    const bool has_lo = std::isfinite(lo);
    const bool has_hi = std::isfinite(hi);
    std::string d;
    if (has_lo && has_hi) {
      d = "a number in " + std::string(lo_open ? "(" : "[") + format_number(lo) + ", " +
          format_number(hi) + (hi_open ? ")" : "]");
    } else if (has_lo) {
      d = "a finite number " + std::string(lo_open ? "> " : ">= ") + format_number(lo);
    } else if (has_hi) {
      d = "a finite number " + std::string(hi_open ? "< " : "<= ") + format_number(hi);
    } else {
      d = "a finite number";
    }
    return unit.empty() ? d : d + " " + std::string(unit);
  }
};

//! The schema: every key of the file, its field and its range, in file order. `v` is one of the
//! visitors below (key collection, reading, writing, checking); `c` a (const) BridgeConfig.
template <typename Config, typename Visitor>
void visit_schema(Config& c, Visitor& v) {
  constexpr double pi = std::numbers::pi;
  auto& m = c.mapping;
  v.number("mapping", "a_roll", m.a_roll, Range::any("rad/rad"));
  v.number("mapping", "b_roll", m.b_roll, Range::any("rad"));
  v.number("mapping", "a_pitch", m.a_pitch, Range::any("rad/m"));
  v.number("mapping", "b_pitch", m.b_pitch, Range::any("rad"));
  v.number("mapping", "a_clamp", m.a_clamp, Range::any("rad/m"));
  v.number("mapping", "b_clamp", m.b_clamp, Range::any("rad"));
  v.vector("mapping", "lower", m.lower, Range::described(-pi, pi, "a number in [-pi, pi] rad"));
  v.vector("mapping", "upper", m.upper, Range::described(-pi, pi, "a number in [-pi, pi] rad"));
  v.number("mapping", "min_radius", m.min_radius, Range::at_least(0.0, "m"));
  v.number("mapping", "theta_neutral", m.theta_neutral,
           Range::described(-pi, pi, "a number in [-pi, pi] rad"));
  // >= 0: a negative scale would push along the operator's motion
  // (docs/models/cylindrical_mapper.md)
  v.vector("mapping", "force_scale", m.force_scale, Range::between(0.0, 100.0, "N per unit"));
  Range force_limit = Range::between(0.0, teleop::SafetyBounds::max_stylus_force, "N");
  force_limit.lo_open = true;
  v.number("mapping", "force_limit", m.force_limit, force_limit);
  // Per channel (clamp, roll, pitch) before the shared force_limit: one wrong estimate cannot
  // crowd out the others.
  v.vector("mapping", "channel_limit", m.channel_limit, force_limit);

  auto& s = c.loop.safety;
  using SB = teleop::SafetyBounds;
  v.integer("safety", "max_consecutive_misses", s.max_consecutive_misses, 0,
            SB::max_consecutive_misses);
  v.policy("safety", "policy", s.policy);
  Range hold = Range::between(0.0, SB::max_hold_time, "s");
  hold.lo_open = true;
  v.number("safety", "max_hold_time", s.max_hold_time, hold);
  v.number("safety", "force_ramp_time", s.force_ramp_time,
           Range::between(0.0, SB::max_force_ramp_time, "s"));
  Range rate = Range::between(0.0, SB::max_setpoint_rate, "rad/s");
  rate.lo_open = true;
  v.number("safety", "max_setpoint_rate", s.max_setpoint_rate, rate);
  v.number("safety", "max_stylus_force", s.max_stylus_force,
           Range::between(0.0, SB::max_stylus_force, "N"));
  v.integer("safety", "enable_mask", s.enable_mask, 0, 15);
  Range activation = Range::between(0.0, SB::max_activation_timeout, "s");
  activation.lo_open = true;
  v.number("safety", "activation_timeout", s.activation_timeout, activation);
  v.vector("safety", "joint_lower", s.joint_lower,
           Range::described(-pi, pi, "a number in [-pi, pi] rad"));
  v.vector("safety", "joint_upper", s.joint_upper,
           Range::described(-pi, pi, "a number in [-pi, pi] rad"));

  using PB = teleop::PlausibilityBounds;
  auto& p = s.plausibility;
  v.number("plausibility", "position_margin", p.position_margin,
           Range::between(0.0, PB::max_margin, "rad"));
  Range velocity = Range::between(0.0, PB::max_velocity, "rad/s");
  velocity.lo_open = true;
  v.number("plausibility", "max_velocity", p.max_velocity, velocity);
  Range current = Range::between(0.0, PB::max_current, "A");
  current.lo_open = true;
  v.number("plausibility", "max_current", p.max_current, current);
  v.number("plausibility", "jump_tolerance", p.jump_tolerance,
           Range::between(0.0, PB::max_margin, "rad"));

  auto& e = c.estimator;
  v.vector("estimator", "current_sign", e.current_sign, Range::plus_minus_one());
  v.vector("estimator", "unit_scale", e.unit_scale, Range::above(0.0));
  v.friction("estimator", "friction_level", e.friction, Range::at_least(0.0, "A"));
  v.vector("estimator", "output_deadzone", e.output_deadzone, Range::at_least(0.0));
  v.vector("estimator", "output_limit", e.output_limit, Range::above(0.0));
  v.path("estimator", "clamp_model", c.clamp_model);

  auto& o = c.operator_script;
  v.number("operator", "theta", o.theta, Range::any("rad"));
  v.number("operator", "z", o.z, Range::any("m"));
  v.number("operator", "r_open", o.r_open, Range::above(0.0, "m"));
  v.number("operator", "r_closed", o.r_closed, Range::at_least(0.0, "m"));
  v.number("operator", "open_time", o.open_time, Range::at_least(0.0, "s"));
  v.number("operator", "close_time", o.close_time, Range::above(0.0, "s"));
  v.number("operator", "hold_time", o.hold_time, Range::at_least(0.0, "s"));
  v.number("operator", "release_time", o.release_time, Range::above(0.0, "s"));

  // (0, the loop's watchdog bound]: 0 would never wait for an answer (the link never comes up).
  Range timeout = Range::between(
      0.0, std::chrono::duration<double>(teleop::TeleopLoopConfig::max_watchdog_time).count(), "s");
  timeout.lo_open = true;
  v.seconds("loop", "receive_timeout", c.loop.receive_timeout, timeout);
}

//! "section.key".
inline std::string dotted(std::string_view section, std::string_view key) {
  return std::string(section) + "." + std::string(key);
}

//! The policies by their names in the file.
inline const std::array<std::pair<std::string_view, teleop::SafeStatePolicy>, 3>& policies() {
  static const std::array<std::pair<std::string_view, teleop::SafeStatePolicy>, 3> table = {{
      {"hold_position", teleop::SafeStatePolicy::hold_position},
      {"disable_motors", teleop::SafeStatePolicy::disable_motors},
      {"zero_force", teleop::SafeStatePolicy::zero_force},
  }};
  return table;
}

//! Throws Error "<source>: <key>: <what>".
[[noreturn]] inline void fail(std::string_view source, std::string_view key,
                              const std::string& what) {
  ENDOHAPTICS_THROW(Error(std::string(source) + ": " + std::string(key) + ": " + what));
}

//! Throws unless `value` lies in `range`.
inline void check(std::string_view source, const std::string& key, double value,
                  const Range& range) {
  if (!range.contains(value)) {
    fail(source, key,
         "must be " + range.describe() + ", got " + endohaptics::detail::format_number(value));
  }
}

//! Visitor: the keys of each section, in schema order.
struct KeyCollector {
  std::map<std::string, std::vector<std::string>, std::less<>> keys;  //!< section -> keys

  void add(std::string_view section, std::string_view key) {
    keys[std::string(section)].emplace_back(key);
  }
  template <typename T>
  void number(std::string_view s, std::string_view k, T&, const Range&) {
    add(s, k);
  }
  template <typename T>
  void vector(std::string_view s, std::string_view k, T&, const Range&) {
    add(s, k);
  }
  template <typename T>
  void integer(std::string_view s, std::string_view k, T&, long long, long long) {
    add(s, k);
  }
  template <typename T>
  void policy(std::string_view s, std::string_view k, T&) {
    add(s, k);
  }
  template <typename T>
  void friction(std::string_view s, std::string_view k, T&, const Range&) {
    add(s, k);
  }
  template <typename T>
  void path(std::string_view s, std::string_view k, T&) {
    add(s, k);
  }
  template <typename T>
  void seconds(std::string_view s, std::string_view k, T&, const Range&) {
    add(s, k);
  }
};

//! Visitor: reads the keys present in `root` into a BridgeConfig.
struct Reader {
  const json& root;                //!< the whole file, an object with known sections only
  std::string_view source;         //!< for messages
  std::filesystem::path base_dir;  //!< relative clamp_model paths start here

  [[nodiscard]] const json* find(std::string_view section, std::string_view key) const {
    const auto s = root.find(std::string(section));
    if (s == root.end()) return nullptr;
    const auto k = s->find(std::string(key));
    return k == s->end() ? nullptr : &*k;
  }
  [[nodiscard]] double read(const json& j, const std::string& key, const Range& range) const {
    if (!j.is_number()) {
      fail(source, key, "must be " + range.describe() + ", got " + show(j));
    }
    const double value = j.get<double>();
    if (!std::isfinite(value)) {
      fail(source, key, "must be " + range.describe() + ", got " + show(j));
    }
    check(source, key, value, range);
    return value;
  }
  void number(std::string_view s, std::string_view k, double& out, const Range& range) const {
    if (const json* j = find(s, k)) out = read(*j, dotted(s, k), range);
  }
  template <int N>
  void read_vector(const json& j, const std::string& key, Eigen::Matrix<double, N, 1>& out,
                   const Range& range) const {
    if (!j.is_array() || j.size() != static_cast<std::size_t>(N)) {
      fail(source, key,
           "must be an array of " + std::to_string(N) + " numbers, each " + range.describe() +
               ", got " + show(j));
    }
    for (int i = 0; i < N; ++i) {
      out[i] = read(j[static_cast<std::size_t>(i)], key + "[" + std::to_string(i) + "]", range);
    }
  }
  template <int N>
  void vector(std::string_view s, std::string_view k, Eigen::Matrix<double, N, 1>& out,
              const Range& range) const {
    if (const json* j = find(s, k)) read_vector(*j, dotted(s, k), out, range);
  }
  template <typename Int>
  void integer(std::string_view s, std::string_view k, Int& out, long long lo, long long hi) const {
    const json* j = find(s, k);
    if (j == nullptr) return;
    const auto bad = [&] {
      fail(source, dotted(s, k),
           "must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
               show(*j));
    };
    // Compared in the type the parser chose, converted only once known to be in range.
    if (j->is_number_unsigned()) {
      const auto u = j->get<std::uint64_t>();
      if (u > static_cast<std::uint64_t>(hi)) bad();
      out = static_cast<Int>(u);
    } else if (j->is_number_integer()) {
      const auto i = j->get<std::int64_t>();
      if (i < lo || i > hi) bad();
      out = static_cast<Int>(i);
    } else if (j->is_number_float()) {
      const double d = j->get<double>();
      if (!(std::isfinite(d) && d == std::trunc(d) && d >= static_cast<double>(lo) &&
            d <= static_cast<double>(hi))) {
        bad();
      }
      out = static_cast<Int>(static_cast<long long>(d));
    } else {
      bad();
    }
  }
  void policy(std::string_view s, std::string_view k, teleop::SafeStatePolicy& out) const {
    const json* j = find(s, k);
    if (j == nullptr) return;
    if (j->is_string()) {
      for (const auto& [name, value] : policies()) {
        if (j->get_ref<const std::string&>() == name) {
          out = value;
          return;
        }
      }
    }
    fail(source, dotted(s, k),
         "must be \"hold_position\", \"disable_motors\" or \"zero_force\", got " + show(*j));
  }
  void friction(std::string_view s, std::string_view k,
                std::array<model::JointFriction<double>, 4>& out, const Range& range) const {
    const json* j = find(s, k);
    if (j == nullptr) return;
    Eigen::Vector4d levels;
    read_vector(*j, dotted(s, k), levels, range);
    for (int i = 0; i < 4; ++i) {
      out[static_cast<std::size_t>(i)] = model::JointFriction<double>::simplified(levels[i]);
    }
  }
  void path(std::string_view s, std::string_view k, std::filesystem::path& out) const {
    const json* j = find(s, k);
    if (j == nullptr) return;
    if (!j->is_string() || j->get_ref<const std::string&>().empty()) {
      fail(source, dotted(s, k),
           "must be the name of a model file (a non-empty string), got " + show(*j));
    }
    const std::filesystem::path p = j->get<std::string>();
    out = p.is_absolute() || base_dir.empty() ? p : base_dir / p;
  }
  void seconds(std::string_view s, std::string_view k, std::chrono::nanoseconds& out,
               const Range& range) const {
    // The range is finite (at most 1 s): the conversion to ns cannot overflow.
    if (const json* j = find(s, k)) {
      out = std::chrono::nanoseconds(std::llround(read(*j, dotted(s, k), range) * 1e9));
    }
  }
};

//! Visitor: writes every key of a BridgeConfig into `out` (clamp_model only when set).
struct Writer {
  nlohmann::ordered_json out = nlohmann::ordered_json::object();  //!< the file, in schema order

  void number(std::string_view s, std::string_view k, const double& v, const Range&) {
    out[std::string(s)][std::string(k)] = v;
  }
  template <int N>
  void vector(std::string_view s, std::string_view k, const Eigen::Matrix<double, N, 1>& v,
              const Range&) {
    auto a = nlohmann::ordered_json::array();
    for (int i = 0; i < N; ++i) a.push_back(v[i]);
    out[std::string(s)][std::string(k)] = a;
  }
  template <typename Int>
  void integer(std::string_view s, std::string_view k, const Int& v, long long, long long) {
    out[std::string(s)][std::string(k)] = static_cast<long long>(v);
  }
  void policy(std::string_view s, std::string_view k, const teleop::SafeStatePolicy& v) {
    for (const auto& [name, value] : policies()) {
      if (value == v) out[std::string(s)][std::string(k)] = std::string(name);
    }
  }
  void friction(std::string_view s, std::string_view k,
                const std::array<model::JointFriction<double>, 4>& v, const Range& r) {
    vector(
        s, k,
        Eigen::Vector4d(v[0].static_level, v[1].static_level, v[2].static_level, v[3].static_level),
        r);
  }
  void path(std::string_view s, std::string_view k, const std::filesystem::path& v) {
    if (!v.empty()) out[std::string(s)][std::string(k)] = v.string();
  }
  void seconds(std::string_view s, std::string_view k, const std::chrono::nanoseconds& v,
               const Range&) {
    out[std::string(s)][std::string(k)] = static_cast<double>(v.count()) / 1e9;
  }
};

//! Visitor: checks every field of a BridgeConfig against the schema's ranges.
struct Checker {
  std::string_view source;  //!< for messages

  void number(std::string_view s, std::string_view k, const double& v, const Range& r) const {
    check(source, dotted(s, k), v, r);
  }
  template <int N>
  void vector(std::string_view s, std::string_view k, const Eigen::Matrix<double, N, 1>& v,
              const Range& r) const {
    for (int i = 0; i < N; ++i)
      check(source, dotted(s, k) + "[" + std::to_string(i) + "]", v[i], r);
  }
  template <typename Int>
  void integer(std::string_view s, std::string_view k, const Int& v, long long lo,
               long long hi) const {
    const auto x = static_cast<long long>(v);
    if (x < lo || x > hi) {
      fail(source, dotted(s, k),
           "must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
               std::to_string(x));
    }
  }
  void policy(std::string_view s, std::string_view k, const teleop::SafeStatePolicy& v) const {
    for (const auto& [name, value] : policies()) {
      if (value == v) return;
    }
    fail(source, dotted(s, k),
         "is not a SafeStatePolicy (" + std::to_string(static_cast<int>(v)) + ")");
  }
  void friction(std::string_view s, std::string_view k,
                const std::array<model::JointFriction<double>, 4>& v, const Range& r) const {
    for (std::size_t i = 0; i < v.size(); ++i) {
      check(source, dotted(s, k) + "[" + std::to_string(i) + "]", v[i].static_level, r);
    }
  }
  void path(std::string_view, std::string_view, const std::filesystem::path&) const {}
  void seconds(std::string_view s, std::string_view k, const std::chrono::nanoseconds& v,
               const Range& r) const {
    check(source, dotted(s, k), static_cast<double>(v.count()) / 1e9, r);
  }
};

//! Parses `text` as JSON (comments allowed): nesting limited as it parses, duplicate keys
//! refused anywhere (files/json_text.hpp).
inline json parse(std::string_view text, std::string_view source) {
  return json_text::parse_strict(
      text, source,
      {.max_depth = bridge_config_max_depth, .needed = "the bridge configuration needs 3"});
}

//! Runs a library validator; its Error gets "<source>: <key>: " in front.
template <typename F>
void with_prefix(std::string_view source, std::string_view key, F&& validate) {
  try {
    validate();
  } catch (const Error& e) {
    fail(source, key, e.what());
  }
}

}  // namespace detail::bridge_config

//! The clamp model the bridge runs, whichever kind the model file holds: the appendix C yaw
//! Hammerstein-Wiener type (estimation::ClampModel2016, also identified "hammerstein_wiener" files
//! of 6 states, 2 inputs, 1 output), estimation::StallHold, estimation::PushLoadObserver or
//! estimation::BidirectionalLoadObserver. A JointForceModel (noexcept, allocation-free, fixed
//! size: a std::variant of the four). Its State is the model's own, padded with zeros to the
//! largest of the four (the bidirectional observer's 23 numbers); reset() is the
//! model's own start state (ForceEstimator::reset, through RateStepper: the yaw model at x = 0,
//! the observer with its filters waiting for the next sample and its initial load and variance).
class ClampForceModel {
 public:
  using ScalarType = double;  //!< floating-point type
  //! the bidirectional load observer (kind "bidirectional_load_observer")
  using Bidirectional = estimation::BidirectionalLoadObserver<double>;
  using Signals = estimation::JointSignals<double>;       //!< one joint's signals for one tick
  using Yaw = estimation::ClampModel2016<double>;         //!< the Hammerstein-Wiener kind
  using StallHold = estimation::StallHold<double>;        //!< kind "stall_hold"
  using Observer = estimation::PushLoadObserver<double>;  //!< kind "push_load_observer"
  //! The model's state, zero-padded to the largest.
  using State = Eigen::Matrix<double, Bidirectional::State::RowsAtCompileTime, 1>;

 private:
  template <typename F>
  decltype(auto) visit(F&& f) const noexcept {
    if (const auto* m = std::get_if<Yaw>(&model_)) return f(*m);
    if (const auto* m = std::get_if<StallHold>(&model_)) return f(*m);
    if (const auto* m = std::get_if<Observer>(&model_)) return f(*m);
    return f(*std::get_if<Bidirectional>(&model_));
  }
  template <typename F>
  decltype(auto) visit_mutable(F&& f) noexcept {
    if (auto* m = std::get_if<Yaw>(&model_)) return f(*m);
    if (auto* m = std::get_if<StallHold>(&model_)) return f(*m);
    if (auto* m = std::get_if<Observer>(&model_)) return f(*m);
    return f(*std::get_if<Bidirectional>(&model_));
  }
  template <typename M>
  static constexpr int size_of = static_cast<int>(M::State::RowsAtCompileTime);
  static_assert(size_of<Yaw> <= size_of<Bidirectional> &&
                size_of<StallHold> <= size_of<Bidirectional> &&
                size_of<Observer> <= size_of<Bidirectional>);

 public:
  //! The Hammerstein-Wiener clamp model.
  explicit ClampForceModel(const Yaw& m) : model_(m) {}
  //! The stall-hold model.
  explicit ClampForceModel(const StallHold& m) : model_(m) {}
  //! The push-load observer.
  explicit ClampForceModel(const Observer& m) : model_(m) {}
  //! The bidirectional load observer.
  explicit ClampForceModel(const Bidirectional& m) : model_(m) {}

  //! True for the kinds with their own friction handling (stall_hold, the observers).
  [[nodiscard]] bool is_joint_model() const noexcept { return model_.index() != 0; }
  //! The Hammerstein-Wiener model, or null for another kind.
  [[nodiscard]] const Yaw* yaw() const noexcept { return std::get_if<Yaw>(&model_); }
  //! The stall-hold model, or null for another kind.
  [[nodiscard]] const StallHold* stall_hold() const noexcept {
    return std::get_if<StallHold>(&model_);
  }
  //! The push-load observer, or null for another kind.
  [[nodiscard]] const Observer* observer() const noexcept { return std::get_if<Observer>(&model_); }
  //! The bidirectional load observer, or null for another kind.
  [[nodiscard]] const Bidirectional* bidirectional() const noexcept {
    return std::get_if<Bidirectional>(&model_);
  }

  //! s, the model's sample time.
  [[nodiscard]] double sample_time() const noexcept {
    return visit([](const auto& m) noexcept { return m.sample_time(); });
  }
  //! As the model's.
  [[nodiscard]] bool memoryless() const noexcept {
    return visit([](const auto& m) noexcept { return m.memoryless(); });
  }
  //! The model's force at its current state.
  [[nodiscard]] double force(const Signals& s) const noexcept {
    return visit([&s](const auto& m) noexcept { return m.force(s); });
  }
  //! One model period (the model's StepStatus; all-or-nothing).
  [[nodiscard]] model::StepStatus advance(const Signals& s) noexcept {
    return visit_mutable([&s](auto& m) noexcept { return m.advance(s); });
  }
  //! The model's state, padded with zeros.
  [[nodiscard]] State state() const noexcept {
    return visit([](const auto& m) noexcept {
      State x = State::Zero();
      x.head<size_of<std::remove_cvref_t<decltype(m)>>>() = m.state();
      return x;
    });
  }
  //! Sets the model's state to the leading entries of `x` (what state() returned restores it
  //! exactly).
  void reset(const State& x) noexcept {
    visit_mutable([&x](auto& m) noexcept {
      using M = std::remove_cvref_t<decltype(m)>;
      m.reset(typename M::State(x.head<size_of<M>>()));
      return 0;
    });
  }
  //! The model's own start state (its reset()).
  void reset() noexcept {
    visit_mutable([](auto& m) noexcept {
      m.reset();
      return 0;
    });
  }

 private:
  std::variant<Yaw, StallHold, Observer, Bidirectional> model_;
};

static_assert(estimation::JointForceModel<ClampForceModel>);

//! The models the bridge's ForceEstimator runs: the 2016 roll and pitch models, ClampForceModel
//! for both clamps.
using BridgeForceModels =
    estimation::ForceModels<estimation::RollModel2016<double>, estimation::PitchModel2016<double>,
                            ClampForceModel>;
//! The bridge's ForceEstimator: the 2016 rates (rate::Decimate) and BridgeForceModels.
using BridgeForceEstimator =
    estimation::ForceEstimator<estimation::rate::Decimate, estimation::RollModel2016<double>,
                               estimation::PitchModel2016<double>, ClampForceModel>;

//! States of the bridge's Hammerstein-Wiener clamp model (ClampModel2016: the appendix C yaw
//! model's 6); a clamp model file of lower order is embedded in them (model::embed_states).
inline constexpr int bridge_clamp_states = 6;

//! The force models the bridge runs: the 2016 models (estimation::models_2016), with the clamp
//! model file of `config.clamp_model` for both clamps when set, of any kind ClampForceModel
//! holds (a linear block of order <= bridge_clamp_states). Throws Error naming the model file
//! when it cannot be loaded, is of another size or its parameters are out of range.
[[nodiscard]] inline BridgeForceModels bridge_force_models(const BridgeConfig& config) {
  const auto m2016 = estimation::models_2016<double>();
  BridgeForceModels models{m2016.roll, m2016.pitch, ClampForceModel(m2016.clamp1),
                           ClampForceModel(m2016.clamp2)};
  if (!config.clamp_model.empty()) {
    const ModelFile file = load_model(config.clamp_model);
    const std::string where = "model file " + config.clamp_model.string();
    const auto joint_model = [&] {
      if (file.current_reference) {
        ENDOHAPTICS_THROW(Error(  // with_context below adds the file's name
            "the " + std::string(to_string(file.kind())) +
            " refers its current to the commanded current (a third input), which the sbRIO "
            "protocol does not carry: identify the bridge's model from the current and the "
            "velocity only"));
      }
      return std::visit(
          [](const auto& p) {
            using P = std::decay_t<decltype(p)>;
            if constexpr (std::is_same_v<P, estimation::StallHoldParameters<double>>) {
              return ClampForceModel(estimation::StallHold<double>(p));
            } else if constexpr (std::is_same_v<P,
                                                estimation::PushLoadObserverParameters<double>>) {
              return ClampForceModel(estimation::PushLoadObserver<double>(p));
            } else if constexpr (std::is_same_v<
                                     P, estimation::BidirectionalLoadObserverParameters<double>>) {
              return ClampForceModel(estimation::BidirectionalLoadObserver<double>(p));
            } else {
              return ClampForceModel(estimation::models_2016<double>().clamp1);  // not reached
            }
          },
          file.parameters);
    };
    // The clamp type holds 6 states (the 2016 yaw model's): a linear block of lower order runs
    // in it embedded exactly (model::embed_states: the added states are decoupled and zero).
    const auto hammerstein_wiener = [&] {
      // An unstable linear block loads as a valid model, but its estimate would grow until the
      // tick rejects it as non-finite (and renders no force): refused here, as identify does.
      const double rho = file.state_space.spectral_radius();
      if (!(rho < 1.0)) {
        ENDOHAPTICS_THROW(Error(where + ": the clamp model is not stable (spectral radius " +
                                endohaptics::detail::format_number(rho) +
                                ", must be < 1): its estimate would grow without bound"));
      }
      // A force model maps A and rad/s to N: every number of it lies within the bound of every
      // joint-model parameter (model::max_joint_model_parameter); a larger one (a corrupt or
      // hostile file, C = 1e308) would pin the estimate at its output limit on every tick.
      const model::DynamicStateSpace<>& ss = file.state_space;
      const std::pair<const char*, const Eigen::MatrixXd*> blocks[] = {
          {"A", &ss.A()}, {"B", &ss.B()}, {"C", &ss.C()}, {"D", &ss.D()}};
      const double bound = model::max_joint_model_parameter;
      for (const auto& [name, block] : blocks) {
        for (Eigen::Index r = 0; r < block->rows(); ++r) {
          for (Eigen::Index c = 0; c < block->cols(); ++c) {
            if (!(std::fabs((*block)(r, c)) <= bound)) {
              ENDOHAPTICS_THROW(
                  Error(where + ": " + name + "[" + std::to_string(r) + "][" + std::to_string(c) +
                        "] is " + endohaptics::detail::format_number((*block)(r, c)) +
                        ": a clamp force model's numbers must lie in [-1e6, 1e6] (A, rad/s -> N)"));
            }
          }
        }
      }
      if (!(ss.state().cwiseAbs().maxCoeff() <= bound)) {
        ENDOHAPTICS_THROW(Error(where + ": x0 holds a value beyond 1e6: a clamp force model's "
                                        "numbers must lie in [-1e6, 1e6]"));
      }
      ModelFile six = file;
      if (six.state_space.state_size() < bridge_clamp_states) {
        six.state_space = model::embed_states(six.state_space, bridge_clamp_states);
      }
      return ClampForceModel(estimation::ClampModel2016<double>(
          hammerstein_wiener_from<bridge_clamp_states, 2, 1>(six, where)));
    };
    const ClampForceModel clamp = file.is_joint_model()
                                      ? detail::model_file::with_context(where, joint_model)
                                      : hammerstein_wiener();
    models.clamp1 = clamp;
    models.clamp2 = clamp;
  }
  return models;
}

//! The estimator settings the bridge runs with `models`: `config.estimator`, except that the
//! 5.2.3 friction gate of both clamps is opened (level 0) when their model is a joint model
//! (stall_hold, the observers): those models hold their own friction (the dead zone, the
//! push regime), and the gate would drop the force they hold while the jaw is stalled against
//! an object and the current has relaxed below the friction level.
[[nodiscard]] inline estimation::ForceEstimatorSettings<double> bridge_estimator_settings(
    const BridgeConfig& config, const BridgeForceModels& models) {
  estimation::ForceEstimatorSettings<double> settings = config.estimator;
  if (models.clamp1.is_joint_model()) {
    for (const auto joint : {estimation::Motor::clamp1, estimation::Motor::clamp2}) {
      settings.friction[static_cast<std::size_t>(joint)] =
          model::JointFriction<double>::simplified(0.0);
    }
  }
  return settings;
}

//! Checks `config` as the bridge will use it: every field in its schema range, then the
//! library's own checks (TeleopLoopConfig, CylindricalMapper, OperatorScript, and a
//! ForceEstimator built with the clamp model file). Throws Error "<source>: <key>: ...".
inline void validate_bridge_config(const BridgeConfig& config,
                                   std::string_view source = "bridge configuration") {
  namespace bc = detail::bridge_config;
  bc::Checker checker{source};
  bc::visit_schema(config, checker);
  // Cross-field checks, named by the section they concern.
  bc::with_prefix(source, "safety", [&] { config.loop.validate(); });
  bc::with_prefix(source, "mapping",
                  [&] { (void)kinematics::CylindricalMapper<double>(config.mapping); });
  bc::with_prefix(source, "operator", [&] { config.operator_script.validate(); });
  std::optional<BridgeForceModels> models;
  bc::with_prefix(source, "estimator.clamp_model", [&] { models = bridge_force_models(config); });
  bc::with_prefix(source, "estimator", [&] {
    (void)BridgeForceEstimator(*models, bridge_estimator_settings(config, *models));
  });
}

//! Reads a bridge configuration from JSON `text` over the defaults, then validates it
//! (validate_bridge_config). `source` names the text in messages; a relative
//! estimator.clamp_model is resolved against `base_dir` (empty: left relative). Throws Error
//! naming the source, the key and the allowed range or values.
[[nodiscard]] inline BridgeConfig parse_bridge_config(std::string_view text,
                                                      std::string_view source = "<string>",
                                                      const std::filesystem::path& base_dir = {}) {
  namespace bc = detail::bridge_config;
  const bc::json root = bc::parse(text, source);
  if (!root.is_object()) {
    ENDOHAPTICS_THROW(
        Error(std::string(source) + ": must be a JSON object {...}, got " + bc::show(root)));
  }
  BridgeConfig config;
  bc::KeyCollector schema;
  bc::visit_schema(config, schema);
  auto list = [](const auto& names) {
    std::string out;
    for (const auto& n : names) out += (out.empty() ? "" : ", ") + std::string(n);
    return out;
  };
  std::vector<std::string> sections;
  for (const auto& [section, keys] : schema.keys) sections.push_back(section);
  for (const auto& [section, value] : root.items()) {
    const auto known = schema.keys.find(section);
    if (known == schema.keys.end()) {
      ENDOHAPTICS_THROW(Error(std::string(source) + ": unknown key " + bc::key_name(section) +
                              " (allowed: " + list(sections) + ")"));
    }
    if (!value.is_object()) {
      bc::fail(source, section, "must be an object {...}, got " + bc::show(value));
    }
    for (const auto& [key, ignored] : value.items()) {
      bool found = false;
      for (const auto& k : known->second) found = found || k == key;
      if (!found) {
        ENDOHAPTICS_THROW(Error(std::string(source) + ": unknown key " +
                                bc::key_name(section + "." + key) + " (allowed in '" + section +
                                "': " + list(known->second) + ")"));
      }
    }
  }
  bc::Reader reader{root, source, base_dir};
  bc::visit_schema(config, reader);
  validate_bridge_config(config, source);
  return config;
}

//! Reads the bridge configuration file `path` (a regular file of at most
//! bridge_config_max_bytes: a FIFO or device is refused without blocking, files/json_text.hpp) as
//! parse_bridge_config, with the file's name in messages and relative model files resolved
//! against its folder.
[[nodiscard]] inline BridgeConfig load_bridge_config(const std::filesystem::path& path) {
  const std::string text = detail::json_text::read_bounded(
      path, bridge_config_max_bytes, "configuration file",
      "files::bridge_config_max_bytes; a complete one is under 2 kB");
  return parse_bridge_config(text, path.string(), path.parent_path());
}

//! The configuration as JSON text in the file's format (every key; clamp_model when set):
//! parse_bridge_config reads it back to the same values.
[[nodiscard]] inline std::string bridge_config_json(const BridgeConfig& config, int indent = 2) {
  detail::bridge_config::Writer writer;
  detail::bridge_config::visit_schema(config, writer);
  return writer.out.dump(indent);
}

}  // namespace endohaptics::files
