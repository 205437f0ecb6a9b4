// Fixture for the layer check's own test: a real-time header that pulls in JSON.
#pragma once
#include <nlohmann/json.hpp>
