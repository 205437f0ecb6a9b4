//! @file
//! AnyJointForceModel<Models...>: one of several JointForceModel types chosen at configuration
//! time (e.g. by a model file's kind) and itself a JointForceModel: a std::variant visited without
//! virtual calls, noexcept and allocation-free; its State is the held model's, padded with zeros
//! to the largest of the Models. Units: the models'.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <tuple>
#include <type_traits>
#include <utility>
#include <variant>

#include "endohaptics/estimation/joint_force_model.hpp"
#include "endohaptics/model/state_space.hpp"

namespace endohaptics::estimation {

//! One of `Models` (JointForceModel types of one ScalarType, each with reset() to its own start
//! state), behaving as the one it holds. reset() is the held model's own start state;
//! reset(x) sets it from the leading entries of `x` (what state() returned restores it exactly).
template <JointForceModel... Models>
class AnyJointForceModel {
  static_assert(sizeof...(Models) >= 1, "AnyJointForceModel needs at least one model type");
  using First = std::tuple_element_t<0, std::tuple<Models...>>;

 public:
  using ScalarType = typename First::ScalarType;  //!< floating-point type of every model
  static_assert((std::is_same_v<typename Models::ScalarType, ScalarType> && ...),
                "AnyJointForceModel: every model has the same ScalarType");
  using Signals = JointSignals<ScalarType>;  //!< one joint's signals for one tick
  //! Rows of the largest model State.
  static constexpr int state_size =
      std::max({static_cast<int>(Models::State::RowsAtCompileTime)...});
  using State = Eigen::Matrix<ScalarType, state_size, 1>;  //!< the held model's, zero-padded

  //! Holds `m` (one of Models).
  template <typename M>
  requires(std::is_same_v<std::remove_cvref_t<M>, Models> || ...) explicit AnyJointForceModel(M&& m)
      : model_(std::forward<M>(m)) {}

  //! Which of Models is held (0 for the first).
  [[nodiscard]] std::size_t index() const noexcept { return model_.index(); }
  //! The held model as `M`, or null when it is another.
  template <typename M>
  [[nodiscard]] const M* get() const noexcept {
    return std::get_if<M>(&model_);
  }

  //! s, the held model's sample time.
  [[nodiscard]] ScalarType sample_time() const noexcept {
    return visit([](const auto& m) noexcept { return m.sample_time(); });
  }
  //! As the held model's.
  [[nodiscard]] bool memoryless() const noexcept {
    return visit([](const auto& m) noexcept { return m.memoryless(); });
  }
  //! The held model's force at its current state.
  [[nodiscard]] ScalarType force(const Signals& s) const noexcept {
    return visit([&s](const auto& m) noexcept { return m.force(s); });
  }
  //! One model period (the held model's NumericStatus; all-or-nothing).
  [[nodiscard]] model::NumericStatus advance(const Signals& s) noexcept {
    return visit([&s](auto& m) noexcept { return m.advance(s); });
  }
  //! The held model's state, padded with zeros.
  [[nodiscard]] State state() const noexcept {
    return visit([](const auto& m) noexcept {
      using M = std::remove_cvref_t<decltype(m)>;
      State x = State::Zero();
      x.template head<rows<M>>() = m.state();
      return x;
    });
  }
  //! Sets the held model's state to the leading entries of `x`.
  void reset(const State& x) noexcept {
    visit([&x](auto& m) noexcept {
      using M = std::remove_cvref_t<decltype(m)>;
      m.reset(typename M::State(x.template head<rows<M>>()));
      return 0;
    });
  }
  //! The held model's own start state (its reset()).
  void reset() noexcept {
    visit([](auto& m) noexcept {
      m.reset();
      return 0;
    });
  }

 private:
  template <typename M>
  static constexpr int rows = static_cast<int>(M::State::RowsAtCompileTime);

  // std::visit may throw (a valueless variant); this cannot: the variant is never valueless
  // (every alternative is copied whole, Eigen fixed-size members do not throw).
  template <std::size_t I = 0, typename Self, typename F>
  static decltype(auto) visit_at(Self& self, F& f) noexcept {
    if constexpr (I + 1 == sizeof...(Models)) {
      return f(*std::get_if<I>(&self.model_));
    } else {
      if (auto* m = std::get_if<I>(&self.model_)) return f(*m);
      return visit_at<I + 1>(self, f);
    }
  }
  template <typename F>
  decltype(auto) visit(F&& f) const noexcept {
    return visit_at(*this, f);
  }
  template <typename F>
  decltype(auto) visit(F&& f) noexcept {
    return visit_at(*this, f);
  }

  std::variant<Models...> model_;
};

}  // namespace endohaptics::estimation
