//! @file
//! Umbrella header: everything endohaptics offers. Include single component headers instead
//! to keep compile times down.
#pragma once

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/dare.hpp"
#include "endohaptics/estimation/force_estimator.hpp"
#include "endohaptics/estimation/steady_state_kalman.hpp"
#include "endohaptics/io/fault_injecting_transport.hpp"
#include "endohaptics/io/in_memory_transport.hpp"
#include "endohaptics/io/transport.hpp"
#include "endohaptics/io/udp_transport.hpp"
#include "endohaptics/kinematics/cylindrical_mapper.hpp"
#include "endohaptics/kinematics/denavit_hartenberg.hpp"
#include "endohaptics/model/friction_model.hpp"
#include "endohaptics/model/hammerstein_wiener.hpp"
#include "endohaptics/model/human_arm_model.hpp"
#include "endohaptics/model/presets_2016.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/model/static_nonlinearity.hpp"
#include "endohaptics/protocol/packet_codec.hpp"
#include "endohaptics/teleop/clock.hpp"
#include "endohaptics/teleop/haptic_device.hpp"
#include "endohaptics/teleop/loop_stats.hpp"
#include "endohaptics/teleop/realtime.hpp"
#include "endohaptics/teleop/safety.hpp"
#include "endohaptics/teleop/teleop_loop.hpp"
