//! @file
//! PushLoadObserver: a JointForceModel for a cable-driven grasper whose grip load shows in the
//! motor current only while the motor pushes against it (docs/research_force_models.md, structure
//! K2): a scalar Kalman filter on a random-walk load, updated only in the push regime through
//! i_f = c_p load + d_p + b_p v, held otherwise; the regime from a Dahl-type direction state on
//! the encoder increments (rate-independent, Dahl 1968) and the filtered velocity; after the
//! first push, the load also follows the encoder travel, load += k_q dq (a stiffness on the jaw
//! side: the grip torque changes along the stroke where the current cannot see it; K5); an output
//! map for the direction-dependent friction on the load side. Before the first push (a run that
//! starts back-driven), optionally an estimate from the back-driven current instead of the prior
//! alone: z_b = (i_f - d_b - b_b v) / c_b fused with the prior (initial load, P0) by inverse
//! variances, each sample afresh (z_b's error is a per-run bias, not white noise, so it is not
//! accumulated); the first push starts the filter from that estimate. Filters: second-order
//! Butterworth low-passes (bilinear transform) started at the steady state of the first sample. Per
//! step about 40 flops; noexcept, allocation-free. Units: A, rad, rad/s, s; load in the fit's unit.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <string>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/parameter.hpp"
#include "endohaptics/estimation/directional_front_end.hpp"
#include "endohaptics/estimation/joint_force_model.hpp"
#include "endohaptics/model/state_space.hpp"

namespace endohaptics::estimation {

//! Parameters of PushLoadObserver. Defaults: the research note's (UMN grasper, 1 kHz); c_p, d_p,
//! b_p, noise, e0, e1, the initial load, the back-driven map (c_b, d_b, b_b, its error) and k_q
//! come from fit_push_load_observer.
template <typename Scalar = double>
struct PushLoadObserverParameters {
  Scalar current_cutoff = Scalar(10);        //!< Hz, current low-pass (2nd-order Butterworth)
  Scalar velocity_cutoff = Scalar(20);       //!< Hz, velocity low-pass (of the encoder difference)
  Scalar direction_scale = Scalar(0.05);     //!< rad, q0: travel that flips the direction state
  Scalar velocity_threshold = Scalar(0.05);  //!< rad/s: slower is rest, not sliding
  Scalar direction_threshold = Scalar(0.5);  //!< |h| at or above: moving that way
  Scalar push_sign = Scalar(1);              //!< +1: positive motion pushes against the load
  Scalar current_per_load = Scalar(1);       //!< c_p, A per load unit in the push regime
  Scalar current_offset = Scalar(0);         //!< d_p, A
  Scalar current_per_velocity = Scalar(0);   //!< b_p, A s/rad
  Scalar measurement_variance = Scalar(1e-4);  //!< R_p, A^2
  Scalar process_variance = Scalar(1e-8);      //!< Q, load unit^2 per step
  Scalar initial_load = Scalar(0);             //!< the load estimate before any push
  Scalar initial_variance = Scalar(1e-2);      //!< P0, load unit^2
  Scalar output_offset = Scalar(0);            //!< e0: friction on the load side while not pushing
  Scalar output_slope = Scalar(0);             //!< e1: its growth with the load
  //! c_b, A per load unit while back-driven; 0: no back-driven estimate before the first push
  Scalar back_current_per_load = Scalar(0);
  Scalar back_current_offset = Scalar(0);        //!< d_b, A
  Scalar back_current_per_velocity = Scalar(0);  //!< b_b, A s/rad
  Scalar back_variance = Scalar(1);  //!< load unit^2: mean square error of z_b (its bias included)
  //! k_q, load units per rad: after the first push, load += k_q dq (dq positive in the push
  //! direction); 0: the load a pure random walk
  Scalar load_per_angle = Scalar(0);
  Scalar sample_time = Scalar(0.001);  //!< s, one advance()

  //! Every parameter but the sample time, by its file name, with its bound: `v(name, field,
  //! Bound)` for each (core/parameter.hpp). The one list validate() and the model files use.
  template <typename Self, typename Visitor>
  static void for_each_field(Self& p, Visitor&& v) {
    constexpr double max = max_joint_model_parameter;
    const Bound cutoff = cutoff_bound(static_cast<double>(p.sample_time));
    v("current_cutoff", p.current_cutoff, cutoff);
    v("velocity_cutoff", p.velocity_cutoff, cutoff);
    v("direction_scale", p.direction_scale, Bound::above(0, max, "rad"));
    v("velocity_threshold", p.velocity_threshold, Bound::in(0, max, "rad/s"));
    v("direction_threshold", p.direction_threshold, Bound::above(0, 1));
    v("push_sign", p.push_sign, Bound::unit_sign());
    v("current_per_load", p.current_per_load, Bound::magnitude(min_current_per_load, max));
    v("current_offset", p.current_offset, Bound::in(-max, max));
    v("current_per_velocity", p.current_per_velocity, Bound::in(-max, max));
    v("measurement_variance", p.measurement_variance, Bound::above(0, max));
    v("process_variance", p.process_variance, Bound::in(0, max));
    v("initial_load", p.initial_load, Bound::in(-max, max));
    v("initial_variance", p.initial_variance, Bound::in(0, max));
    v("output_offset", p.output_offset, Bound::in(-max, max));
    v("output_slope", p.output_slope, Bound::in(-max, max));
    v("back_current_per_load", p.back_current_per_load,
      Bound::zero_or_magnitude(min_current_per_load, max));
    v("back_current_offset", p.back_current_offset, Bound::in(-max, max));
    v("back_current_per_velocity", p.back_current_per_velocity, Bound::in(-max, max));
    v("back_variance", p.back_variance, Bound::above(0, max));
    v("load_per_angle", p.load_per_angle, Bound::in(-max, max));
  }

  //! Throws ParameterError naming the field, its value and the rule.
  void validate() const {
    const ParameterChecker check{"PushLoadObserverParameters"};
    check("sample_time", sample_time, sample_time_bound);
    for_each_field(*this, check);
  }
};

//! The push-regime load observer (see the file comment).
template <typename Scalar = double>
class PushLoadObserver {
 public:
  using ScalarType = Scalar;                              //!< floating-point type
  using Parameters = PushLoadObserverParameters<Scalar>;  //!< the model's parameters
  using Signals = JointSignals<Scalar>;                   //!< one joint's signals for one tick
  //! (current filter z1, z2, velocity filter z1, z2, previous position, direction h, load, its
  //! variance, regime -1/0/+1, started 0/1, pushed yet 0/1)
  using State = Eigen::Matrix<Scalar, 11, 1>;

  //! Validates `p` (throws Error naming the field).
  explicit PushLoadObserver(const Parameters& p = {}) : p_((p.validate(), p)) {
    front_ =
        DirectionalFrontEnd<Scalar>(p_.current_cutoff, p_.velocity_cutoff, p_.direction_scale,
                                    p_.direction_threshold, p_.velocity_threshold, p_.sample_time);
    reset();
  }

  [[nodiscard]] const Parameters& parameters() const noexcept { return p_; }    //!< as given
  [[nodiscard]] Scalar sample_time() const noexcept { return p_.sample_time; }  //!< s
  [[nodiscard]] bool memoryless() const noexcept { return false; }              //!< false: a state
  //! The load estimate plus the load-side friction while not pushing: tau + g (e0 + e1 tau),
  //! g = (1 - regime) / 2 (1 when back-driven, 1/2 at rest, 0 while pushing).
  [[nodiscard]] Scalar force(const Signals&) const noexcept {
    const Scalar g = (Scalar(1) - x_[8]) / 2;
    return x_[6] + g * (p_.output_offset + p_.output_slope * x_[6]);
  }

  //! One sample_time. Non-finite signals: state untouched, NumericStatus::non_finite_input.
  model::NumericStatus advance(const Signals& s) noexcept {
    if (!std::isfinite(s.current) || !std::isfinite(s.position)) {
      return model::NumericStatus::non_finite_input;
    }
    State x = x_;
    // The shared front end on x[0..5] (filters, previous position, direction), started flag x[9];
    // the regime judged in the push direction.
    const auto front = front_.step(x.data(), x[9], s.position, s.current, p_.push_sign);
    const Scalar delta = front.delta;
    const Scalar i_f = front.current;
    const Scalar v = front.velocity;
    x[8] = front.regime;
    if (x[8] < 0 && x[10] == Scalar(0) && p_.back_current_per_load != Scalar(0) &&
        p_.initial_variance > Scalar(0)) {
      // Back-driven before any push: the prior and this sample's back-driven inversion, weighed by
      // their inverse variances (not accumulated over samples: z_b's error is mostly a bias).
      const Scalar z = (i_f - p_.back_current_offset - p_.back_current_per_velocity * v) /
                       p_.back_current_per_load;
      const Scalar w = p_.back_variance / (p_.back_variance + p_.initial_variance);
      x[6] = w * p_.initial_load + (Scalar(1) - w) * z;
      x[7] = w * p_.initial_variance;
    }
    if (x[10] != Scalar(0)) x[6] += p_.load_per_angle * p_.push_sign * delta;  // stiffness
    x[7] += p_.process_variance;
    if (x[8] > 0) {  // pushing: the current sees the load
      x[10] = Scalar(1);
      const Scalar c = p_.current_per_load;
      const Scalar k = x[7] * c / (c * c * x[7] + p_.measurement_variance);
      x[6] += k * (i_f - c * x[6] - p_.current_offset - p_.current_per_velocity * v);
      x[7] *= Scalar(1) - k * c;
    }
    if (!x.allFinite()) return model::NumericStatus::non_finite_result;
    x_ = x;
    last_filtered_current_ = i_f;
    last_filtered_velocity_ = v;
    return model::NumericStatus::ok;
  }

  [[nodiscard]] const State& state() const noexcept { return x_; }  //!< see State
  //! Sets the state; reset() starts over (filters wait for the next first sample).
  void reset(const State& x) noexcept { x_ = x; }
  //! Back to the start: initial load and variance, filters unstarted, direction 0, at rest.
  void reset() noexcept {
    x_.setZero();
    x_[6] = p_.initial_load;
    x_[7] = p_.initial_variance;
  }
  //! The regime of the last step: +1 pushing, -1 back-driven, 0 at rest or reversing.
  [[nodiscard]] Scalar regime() const noexcept { return x_[8]; }
  //! The filtered current and velocity of the last step (for identification).
  [[nodiscard]] Scalar filtered_current() const noexcept { return last_filtered_current_; }
  [[nodiscard]] Scalar filtered_velocity() const noexcept {
    return last_filtered_velocity_;
  }  //!< rad/s

 private:
  Parameters p_;
  DirectionalFrontEnd<Scalar> front_{};
  State x_ = State::Zero();
  Scalar last_filtered_current_{};
  Scalar last_filtered_velocity_{};
};

static_assert(JointForceModel<PushLoadObserver<double>>);

}  // namespace endohaptics::estimation
