//! @file
//! BidirectionalLoadObserver: a JointForceModel for a cable-driven instrument (research note K7,
//! docs/models.md): a two-state Kalman filter on the load L and the instrument's friction f from
//! the current inverted through a forward and a backward map (z = L + h f, h of opposite signs),
//! so that motion both ways cancels the friction; the output adds the hysteresis along the stroke
//! as stop operators, y = L + e0 + sum_j (a_j + b_j L) s_j. Units: A, rad, rad/s, s; load: the
//! fit's.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <utility>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/parameter.hpp"
#include "endohaptics/estimation/directional_front_end.hpp"
#include "endohaptics/estimation/joint_force_model.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/model/stop_operators.hpp"

namespace endohaptics::estimation {

// The number of stop operators of the model files (model/joint_model_bounds.hpp).
using model::bidirectional_observer_stops;

//! Parameters of BidirectionalLoadObserver. Defaults: the front end and the stop thresholds of
//! the research note (UMN grasper, 1 kHz, a stroke of about 1 rad at the spindle); the maps, the
//! noise and the output shape come from fit_bidirectional_load_observer.
template <typename Scalar = double, int N = bidirectional_observer_stops>
struct BidirectionalLoadObserverParameters {
  using Stops = model::StopOperators<Scalar, N>;  //!< the output's hysteresis basis
  using Vector = Eigen::Matrix<Scalar, N, 1>;     //!< one value per stop operator

  Scalar current_cutoff = Scalar(10);        //!< Hz, current low-pass (2nd-order Butterworth)
  Scalar velocity_cutoff = Scalar(20);       //!< Hz, velocity low-pass (of the encoder difference)
  Scalar direction_scale = Scalar(0.05);     //!< rad, q0: travel that flips the direction state
  Scalar velocity_threshold = Scalar(0.05);  //!< rad/s: slower is rest (no update)
  Scalar direction_threshold = Scalar(0.5);  //!< |h| at or above: moving that way
  //! rad, r_1 < ... < r_N; the widest at most half the stroke, so that it saturates each stroke
  Vector stop_thresholds = (Vector() << Scalar(0.005), Scalar(0.02), Scalar(0.05), Scalar(0.1),
                            Scalar(0.2), Scalar(0.3), Scalar(0.4), Scalar(0.5))
                               .finished();
  Scalar start_travel = Scalar(0.005);            //!< rad the tool moves before the operators start
  Scalar forward_gain = Scalar(1);                //!< g_f, A per load unit while moving forward
  Scalar forward_gain_stroke = Scalar(0);         //!< g'_f, A per load unit per unit of s_N
  Scalar forward_offset = Scalar(0);              //!< o_f, A
  Scalar forward_offset_stroke = Scalar(0);       //!< o'_f, A per unit of s_N
  Scalar backward_gain = Scalar(1);               //!< g_b, A per load unit while moving back
  Scalar backward_gain_stroke = Scalar(0);        //!< g'_b
  Scalar backward_offset = Scalar(0);             //!< o_b, A
  Scalar backward_offset_stroke = Scalar(0);      //!< o'_b
  Scalar forward_variance = Scalar(1);            //!< R_f, load unit^2: of one forward inversion z
  Scalar backward_variance = Scalar(1);           //!< R_b, load unit^2: of one backward inversion
  Scalar load_process_variance = Scalar(0);       //!< Q_L, load unit^2 per step
  Scalar friction_variance = Scalar(1);           //!< P_f0, load unit^2: friction prior
  Scalar friction_process_variance = Scalar(0);   //!< Q_f, load unit^2 per step
  Scalar initial_load = Scalar(0);                //!< L0, load units
  Scalar initial_variance = Scalar(1);            //!< P_L0, load unit^2
  Scalar output_offset = Scalar(0);               //!< e0, load units
  Vector output_shape = Vector::Zero();           //!< a_j, load units
  Vector output_shape_per_load = Vector::Zero();  //!< b_j, dimensionless
  Scalar sample_time = Scalar(0.001);             //!< s, one advance()

  //! Smallest variance of an inversion, load unit^2 (a smaller one could make the filter's
  //! covariance lose its sign through rounding).
  static constexpr Scalar min_variance = Scalar(1e-12);
  //! Largest |g'| / |g| of a map: its gain stays at least a tenth of g along the stroke, so that
  //! the inversion (i - offset) / gain stays bounded.
  static constexpr Scalar max_stroke_ratio = Scalar(0.9);

  //! Every parameter but the sample time, by its file name, with its bound: `v(name, field,
  //! Bound)` for each (core/parameter.hpp). The one list validate() and the model files use;
  //! validate() adds the rules that relate two fields.
  template <typename Self, typename Visitor>
  static void for_each_field(Self& p, Visitor&& v) {
    constexpr double max = max_joint_model_parameter;
    const Bound cutoff = cutoff_bound(static_cast<double>(p.sample_time));
    const Bound any = Bound::in(-max, max);
    const Bound gain = Bound::magnitude(min_current_per_load, max);
    const Bound variance = Bound::in(0, max);
    v("current_cutoff", p.current_cutoff, cutoff);
    v("velocity_cutoff", p.velocity_cutoff, cutoff);
    v("direction_scale", p.direction_scale, Bound::above(0, max, "rad"));
    v("velocity_threshold", p.velocity_threshold, Bound::in(0, max, "rad/s"));
    v("direction_threshold", p.direction_threshold, Bound::above(0, 1));
    v("stop_thresholds", p.stop_thresholds, Bound::above(0, max, "rad"));
    v("start_travel", p.start_travel, Bound::in(0, max, "rad"));
    v("forward_gain", p.forward_gain, gain);
    v("forward_gain_stroke", p.forward_gain_stroke, any);
    v("forward_offset", p.forward_offset, any);
    v("forward_offset_stroke", p.forward_offset_stroke, any);
    v("backward_gain", p.backward_gain, gain);
    v("backward_gain_stroke", p.backward_gain_stroke, any);
    v("backward_offset", p.backward_offset, any);
    v("backward_offset_stroke", p.backward_offset_stroke, any);
    v("forward_variance", p.forward_variance, Bound::in(min_variance, max));
    v("backward_variance", p.backward_variance, Bound::in(min_variance, max));
    v("load_process_variance", p.load_process_variance, variance);
    v("friction_variance", p.friction_variance, variance);
    v("friction_process_variance", p.friction_process_variance, variance);
    v("initial_load", p.initial_load, any);
    v("initial_variance", p.initial_variance, variance);
    v("output_offset", p.output_offset, any);
    v("output_shape", p.output_shape, any);
    v("output_shape_per_load", p.output_shape_per_load, any);
  }

  //! Throws ParameterError naming the field, its value and the rule.
  void validate() const {
    const ParameterChecker check{"BidirectionalLoadObserverParameters"};
    check("sample_time", sample_time, sample_time_bound);
    for_each_field(*this, check);
    for (int j = 1; j < N; ++j) {
      check.require(stop_thresholds[j] > stop_thresholds[j - 1],
                    "stop_thresholds[" + std::to_string(j) + "]", stop_thresholds[j],
                    "above the threshold before it");
    }
    const char* stroke_rule =
        "at most 0.9 times the gain's magnitude (the gain keeps its sign and a tenth of its size "
        "along the stroke)";
    check.require(std::fabs(forward_gain_stroke) <= max_stroke_ratio * std::fabs(forward_gain),
                  "forward_gain_stroke", forward_gain_stroke, stroke_rule);
    check.require(std::fabs(backward_gain_stroke) <= max_stroke_ratio * std::fabs(backward_gain),
                  "backward_gain_stroke", backward_gain_stroke, stroke_rule);
    const Scalar ratio = forward_gain / backward_gain;
    check.require(ratio > 0 && ratio <= static_cast<Scalar>(max_joint_model_parameter),
                  "backward_gain", backward_gain,
                  "of forward_gain's sign and at least 1e-6 times its magnitude (the current "
                  "grows with the load both ways)");
  }
};

//! The bidirectional load observer (see the file comment).
template <typename Scalar = double, int N = bidirectional_observer_stops>
class BidirectionalLoadObserver {
 public:
  using ScalarType = Scalar;                                          //!< floating-point type
  using Parameters = BidirectionalLoadObserverParameters<Scalar, N>;  //!< its parameters
  using Signals = JointSignals<Scalar>;                               //!< one tick's signals
  using Stops = model::StopOperators<Scalar, N>;                      //!< the hysteresis basis
  using StopValues = typename Stops::Values;                          //!< s_1 ... s_N
  //! Layout of State: the filters, the direction, the regime, the load and friction filter, then
  //! the stop operators' state (Stops::State).
  enum Index : int {
    current_z1,         //!< current filter, first delay value (direct form II transposed)
    current_z2,         //!< current filter, second delay value
    velocity_z1,        //!< velocity filter, first delay value
    velocity_z2,        //!< velocity filter, second delay value
    previous_position,  //!< rad, the last sample's
    direction,          //!< Dahl direction h in [-1, 1]
    regime_index,       //!< +1 forward, -1 backward, 0 rest
    started,            //!< 0 before the first sample, then 1
    load,               //!< L, load units
    friction,           //!< f, load units of the forward inversion
    p_ll,               //!< covariance of (L, f): var L
    p_lf,               //!< cov(L, f)
    p_ff,               //!< var f
    stops_begin         //!< Stops::State from here
  };

  //! (see Index) plus the N + 2 numbers of the stop operators.
  using State = Eigen::Matrix<Scalar, stops_begin + N + 2, 1>;

  //! Validates `p` (throws Error naming the field).
  explicit BidirectionalLoadObserver(const Parameters& p = {})
      : p_((p.validate(), p)), stops_(p.stop_thresholds, p.start_travel) {
    front_ =
        DirectionalFrontEnd<Scalar>(p_.current_cutoff, p_.velocity_cutoff, p_.direction_scale,
                                    p_.direction_threshold, p_.velocity_threshold, p_.sample_time);
    backward_weight_ = -p_.forward_gain / p_.backward_gain;
    reset();
  }

  [[nodiscard]] const Parameters& parameters() const noexcept { return p_; }    //!< as given
  [[nodiscard]] Scalar sample_time() const noexcept { return p_.sample_time; }  //!< s
  [[nodiscard]] bool memoryless() const noexcept { return false; }              //!< false: a state

  //! The load estimate with its hysteresis along the stroke: L + e0 + sum_j (a_j + b_j L) s_j.
  [[nodiscard]] Scalar force(const Signals&) const noexcept {
    const StopValues s = stop_values();
    const Scalar l = x_[load];
    return l + p_.output_offset + p_.output_shape.dot(s) + l * p_.output_shape_per_load.dot(s);
  }

  //! One sample_time. Non-finite signals: state untouched, NumericStatus::non_finite_input.
  model::NumericStatus advance(const Signals& sig) noexcept {
    if (!std::isfinite(sig.current) || !std::isfinite(sig.position)) {
      return model::NumericStatus::non_finite_input;
    }
    State x = x_;
    // The shared front end on x[current_z1 .. direction], started flag x[started].
    static_assert(current_z1 == 0 && direction == DirectionalFrontEnd<Scalar>::state_size - 1);
    const auto front = front_.step(x.data(), x[started], sig.position, sig.current);
    const Scalar i_f = front.current;
    const Scalar v = front.velocity;
    x[regime_index] = front.regime;
    typename Stops::State z = x.template segment<N + 2>(stops_begin);
    StopValues s;
    stops_.step(z, sig.position, s);
    x.template segment<N + 2>(stops_begin) = z;
    // Predict: the load a random walk, the friction (nearly) constant.
    x[p_ll] += p_.load_process_variance;
    x[p_ff] += p_.friction_process_variance;
    if (x[regime_index] != Scalar(0)) {
      const bool forward = x[regime_index] > 0;
      const Scalar stroke = s[N - 1];
      const Scalar gain = forward ? p_.forward_gain + p_.forward_gain_stroke * stroke
                                  : p_.backward_gain + p_.backward_gain_stroke * stroke;
      const Scalar offset = forward ? p_.forward_offset + p_.forward_offset_stroke * stroke
                                    : p_.backward_offset + p_.backward_offset_stroke * stroke;
      // |gain| >= |g| / 10: validate() bounds the stroke term.
      const Scalar z_load = (i_f - offset) / gain;
      // z = L + h f: a friction shift of the forward inversion f shows as -kappa f in the
      // backward one, kappa = g_f / g_b (the gains at mid-stroke; research note K7: weights that
      // follow the stroke, h = g_f / gain_f(s) and -g_f / gain_b(s), scored 4.67 / 7.31 mN m
      // across the UMN sessions against 4.95 / 4.07 for the constant ratio).
      const Scalar h = forward ? Scalar(1) : backward_weight_;
      const Scalar r = forward ? p_.forward_variance : p_.backward_variance;
      // Measurement z = L + h f + noise (variance r): the Kalman update of (L, f).
      const Scalar ph0 = x[p_ll] + h * x[p_lf];
      const Scalar ph1 = x[p_lf] + h * x[p_ff];
      const Scalar innovation_variance = ph0 + h * ph1 + r;
      const Scalar k0 = ph0 / innovation_variance;
      const Scalar k1 = ph1 / innovation_variance;
      const Scalar innovation = z_load - x[load] - h * x[friction];
      x[load] += k0 * innovation;
      x[friction] += k1 * innovation;
      x[p_ll] = std::fmax(x[p_ll] - k0 * ph0, Scalar(0));  // variances keep their sign
      x[p_lf] -= k0 * ph1;
      x[p_ff] = std::fmax(x[p_ff] - k1 * ph1, Scalar(0));
    }
    if (!x.allFinite()) return model::NumericStatus::non_finite_result;
    x_ = x;
    last_filtered_current_ = i_f;
    last_filtered_velocity_ = v;
    return model::NumericStatus::ok;
  }

  [[nodiscard]] const State& state() const noexcept { return x_; }  //!< see State
  //! Sets the state (Precondition: one that state() returned, so that the covariance is one);
  //! reset() starts over (filters wait for the next first sample).
  void reset(const State& x) noexcept { x_ = x; }
  //! Back to the start: initial load and variances, no friction, filters and operators unstarted.
  void reset() noexcept {
    x_.setZero();
    x_[load] = p_.initial_load;
    x_[p_ll] = p_.initial_variance;
    x_[p_ff] = p_.friction_variance;
    x_.template segment<N + 2>(stops_begin) = Stops::initial_state();
  }

  //! The regime of the last step: +1 forward, -1 backward, 0 at rest or reversing.
  [[nodiscard]] Scalar regime() const noexcept { return x_[regime_index]; }
  //! The load estimate L (without the output's hysteresis), load units.
  [[nodiscard]] Scalar load_estimate() const noexcept { return x_[load]; }
  //! The friction estimate f, load units of the forward inversion.
  [[nodiscard]] Scalar friction_estimate() const noexcept { return x_[friction]; }
  //! The stop operators' outputs at the last sample (0 before the first travel).
  [[nodiscard]] StopValues stop_values() const noexcept {
    return stops_.values(x_.template segment<N + 2>(stops_begin), x_[previous_position]);
  }
  //! The filtered current of the last step, A (for identification).
  [[nodiscard]] Scalar filtered_current() const noexcept { return last_filtered_current_; }
  //! The filtered velocity of the last step, rad/s (for identification).
  [[nodiscard]] Scalar filtered_velocity() const noexcept { return last_filtered_velocity_; }

 private:
  Parameters p_;
  Stops stops_;
  DirectionalFrontEnd<Scalar> front_{};
  Scalar backward_weight_{};  // -kappa = -g_f / g_b, from the parameters
  State x_ = State::Zero();
  Scalar last_filtered_current_{};
  Scalar last_filtered_velocity_{};
};

static_assert(JointForceModel<BidirectionalLoadObserver<double>>);

}  // namespace endohaptics::estimation
