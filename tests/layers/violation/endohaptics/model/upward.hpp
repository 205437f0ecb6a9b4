// Fixture for the layer check's own test: a model header that reaches up into teleop/.
#pragma once
#include "endohaptics/teleop/teleop_loop.hpp"
