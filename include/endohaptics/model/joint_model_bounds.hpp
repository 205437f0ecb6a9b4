//! @file
//! Bounds and sizes of the joint force models (estimation::StallHold,
//! estimation::PushLoadObserver, estimation::BidirectionalLoadObserver), defined once for their
//! own validation and for the model-file loader (files/model_file.hpp), which sits below
//! estimation/ and checks a file before any estimation type exists. Configuration time only.
#pragma once

namespace endohaptics::model {

//! Largest magnitude of a joint model's parameter in its own unit (A, rad/s, s, N, N m, mN m, ...
//! per unit): far beyond any surgical instrument, and small enough that no product of two
//! parameters and a plausible signal overflows. A larger value is a corrupt or hostile model
//! file, refused at configuration time rather than turning every tick's estimate into Inf (which
//! the tick would reject, rendering no force at all).
inline constexpr double max_joint_model_parameter = 1e6;
//! Smallest |current_per_load| of a PushLoadObserver, A per load unit (it divides the current).
inline constexpr double min_current_per_load = 1e-9;
//! Stop operators of a BidirectionalLoadObserver (its model files hold this many thresholds).
inline constexpr int bidirectional_observer_stops = 8;

}  // namespace endohaptics::model
