//! @file
//! Hammerstein-Wiener model (worksheet 4.1.1, figure 4.1): y = g( G( f(u) ) ) with a static
//! input nonlinearity f, a discrete linear state-space block G (eq. 4.2) and a static output
//! nonlinearity g. Units: u and y in the units of the linear block's signals.
#pragma once

#include <Eigen/Core>
#include <concepts>
#include <utility>

#include "endohaptics/model/state_space.hpp"
#include "endohaptics/model/static_nonlinearity.hpp"

namespace endohaptics::model {

//! A memoryless map of N-vectors that a tick may call (e.g. `PerChannel`):
//! `Vector apply(const Vector&) const noexcept` with Vector = Eigen::Matrix<Scalar, N, 1>.
template <typename NL, int N, typename Scalar>
concept VectorNonlinearity = requires(const NL& nl, const Eigen::Matrix<Scalar, N, 1>& u) {
  { nl.apply(u) }
  noexcept->std::convertible_to<Eigen::Matrix<Scalar, N, 1>>;
};

//! Something with the interface of `StateSpace`: sizes, aliases and a noexcept `step`.
template <typename L>
concept LinearBlock = requires(L& linear, const L& clinear, const typename L::Input& u,
                               typename L::Output& y, const typename L::State& x) {
  typename L::ScalarType;
  { L::states } -> std::convertible_to<int>;
  { L::inputs } -> std::convertible_to<int>;
  { L::outputs } -> std::convertible_to<int>;
  { linear.step(u) }
  noexcept->std::same_as<typename L::Output>;
  { linear.update(u, y) }
  noexcept->std::same_as<NumericStatus>;
  { clinear.output(u) }
  noexcept->std::same_as<typename L::Output>;
  { linear.reset(x) }
  noexcept;
  { clinear.state() }
  noexcept->std::convertible_to<const typename L::State&>;
};

//! y(k) = g( C x(k) + D f(u(k)) ), x(k+1) = A x(k) + B f(u(k)) (figure 4.1 around eq. 4.2).
//! Defaults are identity nonlinearities, so HammersteinWiener<SS> behaves like SS.
template <LinearBlock Linear,
          VectorNonlinearity<Linear::inputs, typename Linear::ScalarType> InputNL =
              PerChannel<Identity<typename Linear::ScalarType>, Linear::inputs>,
          VectorNonlinearity<Linear::outputs, typename Linear::ScalarType> OutputNL =
              PerChannel<Identity<typename Linear::ScalarType>, Linear::outputs>>
class HammersteinWiener {
 public:
  using LinearType = Linear;                       //!< the linear block (A, B, C, D)
  using InputNonlinearity = InputNL;               //!< f, applied to u
  using OutputNonlinearity = OutputNL;             //!< g, applied to the linear output
  using ScalarType = typename Linear::ScalarType;  //!< scalar type of the linear block
  static constexpr int states = Linear::states;    //!< state dimension
  static constexpr int inputs = Linear::inputs;    //!< input dimension
  static constexpr int outputs = Linear::outputs;  //!< output dimension
  using State = typename Linear::State;            //!< state vector x
  using Input = typename Linear::Input;            //!< input vector u (before f)
  using Output = typename Linear::Output;          //!< output vector y (after g)

  //! Takes copies of the three blocks; the model starts from the linear block's current state.
  HammersteinWiener(Linear linear, InputNL input_nonlinearity, OutputNL output_nonlinearity)
      : linear_(std::move(linear)),
        input_nl_(std::move(input_nonlinearity)),
        output_nl_(std::move(output_nonlinearity)) {}

  //! Identity output nonlinearity (a Hammerstein model).
  HammersteinWiener(Linear linear,
                    InputNL input_nonlinearity) requires std::default_initializable<OutputNL>
      : HammersteinWiener(std::move(linear), std::move(input_nonlinearity), OutputNL{}) {}

  //! Identity nonlinearities on both sides.
  explicit HammersteinWiener(Linear linear) requires std::default_initializable<InputNL> &&
      std::default_initializable<OutputNL>
      : HammersteinWiener(std::move(linear), InputNL{}, OutputNL{}) {}

  //! The linear block G (its state is the model's state).
  [[nodiscard]] const Linear& linear() const noexcept { return linear_; }
  //! The input nonlinearity f.
  [[nodiscard]] const InputNL& input_nonlinearity() const noexcept { return input_nl_; }
  //! The output nonlinearity g.
  [[nodiscard]] const OutputNL& output_nonlinearity() const noexcept { return output_nl_; }
  //! State x(k) of the linear block.
  [[nodiscard]] const State& state() const noexcept { return linear_.state(); }

  //! Sets the linear block's state to `x0` (zero by default).
  void reset(const State& x0 = State::Zero()) noexcept { linear_.reset(x0); }

  //! y(k) = g(C x(k) + D f(u(k))) at the current state; does not advance.
  [[nodiscard]] Output output(const Input& u) const noexcept {
    return output_nl_.apply(linear_.output(input_nl_.apply(u)));
  }

  //! One tick: returns g(G.step(f(u))). NaN/Inf inputs are not checked: they reach the state
  //! (no UB; the output is then NaN until `reset`). Use `update` to refuse them.
  Output step(const Input& u) noexcept {
    return output_nl_.apply(linear_.step(input_nl_.apply(u)));
  }

  //! Checked tick: refuses a non-finite input (before f) or a non-finite linear result; on
  //! anything but `ok` the state and `y` are untouched.
  [[nodiscard]] NumericStatus update(const Input& u, Output& y) noexcept {
    if (!detail::all_finite(u)) return NumericStatus::non_finite_input;
    Output linear_y;
    const NumericStatus status = linear_.update(input_nl_.apply(u), linear_y);
    if (status == NumericStatus::ok) y = output_nl_.apply(linear_y);
    return status;
  }

 private:
  Linear linear_;
  InputNL input_nl_;
  OutputNL output_nl_;
};

}  // namespace endohaptics::model
