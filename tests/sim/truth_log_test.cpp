#include "endohaptics/sim/truth_log.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <string>

namespace sim_truth_log_test {

namespace {

namespace sim = endohaptics::sim;
namespace protocol = endohaptics::protocol;

}  // namespace

TEST_CASE("truth log: one row per column of the header, time in ns, values in 7 digits") {
  protocol::MotorSetpoint<4> setpoint;
  setpoint.position << 0.1, -0.2, 1.0 / 3.0, 0.0;
  setpoint.enable_mask = 0x0f;
  sim::RigTruth<4> truth;
  truth.joint_position << 0.1, -0.2, 0.3333333333, 0.0;
  truth.external_force << 0.0, 0.0, -1.25e-7, 12345678.0;
  protocol::MotorState<4> reported;
  reported.active_mask = 0x0b;
  reported.current << 0.5, 0.0, 0.0, -0.0;
  const std::string row = sim::truth_log_row(12.5, setpoint, truth, reported);
  const auto commas = [](std::string_view s) { return std::count(s.begin(), s.end(), ','); };
  CHECK(commas(row) == commas(sim::truth_log_header));
  CHECK(row.back() == '\n');
  CHECK(sim::truth_log_header.back() == '\n');
  CHECK(row.starts_with("12.500000000,15,11,0.1,-0.2,0.3333333,0,0.1,-0.2,0.3333333,0,"));
  // force0..3 are columns 19..22 of the header.
  CHECK(row.find(",0,0,-1.25e-07,1.234568e+07,") != std::string::npos);
  CHECK(row.ends_with(",0.5,0,0,-0\n"));
}

}  // namespace sim_truth_log_test
