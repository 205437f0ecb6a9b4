//! @file
//! Umbrella header: everything endohaptics offers. Include single component headers instead
//! to keep compile times down.
#pragma once

#include "endohaptics/core/error.hpp"
#include "endohaptics/protocol/packet_codec.hpp"
