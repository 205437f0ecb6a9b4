// Fixture for cmake/check_layers.cmake: files/model_file.hpp is held below its area (core and
// model only), so this include, allowed to any other files/ header, must be refused.
#include "endohaptics/identification/subspace.hpp"
