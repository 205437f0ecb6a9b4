#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <endohaptics/kinematics/cylindrical_mapper.hpp>
#include <endohaptics/sim/scripted_operator.hpp>
#include <numbers>

namespace sim_scripted_operator_test {

namespace sim = endohaptics::sim;
namespace tp = endohaptics::teleop;
using namespace std::chrono_literals;

TEST_CASE("the default script opens and closes clamp 1 through the default mapping") {
  endohaptics::ManualClock clock(5s);
  sim::ScriptedOperator op(clock);
  endohaptics::kinematics::CylindricalMapper<> mapper;
  Eigen::Vector4d setpoint;
  tp::StylusSample s;
  REQUIRE(op.read(s) == tp::DeviceStatus::ok);
  REQUIRE(mapper.map_position(s.position, setpoint).ok());
  CHECK(setpoint[0] == doctest::Approx(0.0).epsilon(0.01));           // roll ~ 0
  CHECK(setpoint[1] == doctest::Approx(0.0).scale(1).epsilon(0.01));  // pitch ~ 0
  CHECK(setpoint[2] == doctest::Approx(0.0).epsilon(0.01));           // clamp 1 open
  CHECK(setpoint[3] == doctest::Approx(0.0).epsilon(0.01));           // clamp 2 mirrors it
  clock.advance(1800ms);  // open 0.7 s + close 0.8 s + 0.3 s into the hold
  REQUIRE(op.read(s) == tp::DeviceStatus::ok);
  REQUIRE(mapper.map_position(s.position, setpoint).ok());
  CHECK(setpoint[2] == doctest::Approx(0.6).epsilon(0.01));  // closed
  CHECK(setpoint[3] == doctest::Approx(-0.6).epsilon(0.01));
  clock.advance(1300ms);  // the hold is over and the release too (0.8 s): open again
  REQUIRE(op.read(s) == tp::DeviceStatus::ok);
  REQUIRE(mapper.map_position(s.position, setpoint).ok());
  CHECK(setpoint[2] == doctest::Approx(0.0).scale(1).epsilon(0.01));
}

TEST_CASE("the grasp turns and lifts the wrist, and its depth varies from cycle to cycle") {
  sim::OperatorScript script;
  script.theta_swing = 0.8;
  script.z_swing = 0.14;
  endohaptics::kinematics::CylindricalMapper<> mapper;
  const auto setpoint_at = [&](double t) {
    Eigen::Vector4d sp;
    REQUIRE(mapper.map_position(script.intent(t), sp).ok());
    return sp;
  };
  // Open: roll and pitch at rest. Closed (0.3 s into the hold): roll +0.71 x 0.8 rad, pitch
  // +3.93 x 0.14 rad (eq. 5.9), clamp 1 at 0.6 rad as without the swings.
  CHECK(setpoint_at(0.1)[0] == doctest::Approx(0.0066).epsilon(0.05));
  const Eigen::Vector4d closed = setpoint_at(1.8);
  CHECK(closed[0] == doctest::Approx(0.0066 + 0.7096 * 0.8).epsilon(0.01));
  CHECK(closed[1] == doctest::Approx(3.93 * 0.14).epsilon(0.01));
  CHECK(closed[2] == doctest::Approx(0.6).epsilon(0.01));
  // Depth variation: every cycle a different depth in [1 - v, 1] of the full grasp, the first
  // full; without it every cycle the same.
  const double cycle = script.cycle();
  script.depth_variation = 0.6;
  double lowest = 1.0;
  double previous = -1.0;
  for (int k = 0; k < 8; ++k) {
    const double depth = setpoint_at(1.8 + k * cycle)[2] / 0.6;
    if (k == 0) CHECK(depth == doctest::Approx(1.0).epsilon(0.01));
    CHECK(depth >= 0.4 - 1e-9);
    CHECK(depth <= 1.0 + 1e-9);
    CHECK(std::fabs(depth - previous) > 0.01);  // not repeated
    lowest = std::min(lowest, depth);
    previous = depth;
  }
  CHECK(lowest < 0.55);  // the depths spread over the range
  script.depth_variation = 0.0;
  CHECK(setpoint_at(1.8 + 5 * cycle)[2] == doctest::Approx(0.6).epsilon(0.01));
  script.depth_variation = 1.0;  // out of range: refused
  CHECK_THROWS(script.validate());
}

TEST_CASE("the scripted rest pose is the mapper's rest pose: straight ahead, mid-range setpoints") {
  // One definition of the rest pose (kinematics::rest_position, the mapping frame: +x towards the
  // operator, z up, origin on the waist axis at the desk), shared with the Touch adapters.
  endohaptics::ManualClock clock(0s);
  sim::ScriptedOperator op(clock);
  tp::StylusSample s;
  REQUIRE(op.read(s) == tp::DeviceStatus::ok);  // t = 0: resting open, no force yet
  const Eigen::Vector3d rest = endohaptics::kinematics::rest_position<double>();
  CHECK((s.position - rest).norm() < 1e-15);  // before: 5 um off (z = 0.1374, r = 0.1300)
  CHECK(std::abs(s.position.y()) < 1e-15);    // straight ahead: +x
  endohaptics::kinematics::CylindricalMapper<> mapper;
  Eigen::Vector4d setpoint;
  const auto result = mapper.map_position(s.position, setpoint);
  REQUIRE(result.ok());
  CHECK(result.coordinates.theta == doctest::Approx(std::numbers::pi / 2).epsilon(1e-15));
  CHECK(std::abs(setpoint[0]) < 0.01);   // roll 0.0066 rad
  CHECK(std::abs(setpoint[1]) < 1e-12);  // pitch
  CHECK(std::abs(setpoint[2]) < 1e-12);  // clamps open at mid-range
  CHECK(std::abs(setpoint[3]) < 1e-12);
}

TEST_CASE("the rendered force moves the stylus by the arm's static compliance (eq. 5.3 at DC)") {
  endohaptics::ManualClock clock(0s);
  sim::OperatorScript script;
  script.close_time = 1e3;  // keep the intent still for the test
  script.open_time = 1e3;
  sim::ScriptedOperator op(clock, script);
  tp::StylusSample s;
  REQUIRE(op.read(s) == tp::DeviceStatus::ok);
  const Eigen::Vector3d rest = s.position;
  REQUIRE(op.command_force(Eigen::Vector3d(0.0, 1.0, 0.0)) == tp::DeviceStatus::ok);
  for (int i = 0; i < 5000; ++i) {  // 5 s, read at 1 kHz
    clock.advance(1ms);
    REQUIRE(op.read(s) == tp::DeviceStatus::ok);
  }
  const double compliance = endohaptics::model::HumanArmParameters<double>{}.static_compliance();
  CHECK(compliance == doctest::Approx((48.8 + 375.0) / (48.8 * 375.0)));
  CHECK(s.position.y() - rest.y() == doctest::Approx(compliance).epsilon(0.01));
  CHECK(s.position.x() == doctest::Approx(rest.x()));
  CHECK(s.position.z() == doctest::Approx(rest.z()));
}

TEST_CASE("a non-finite force is refused, a bad script is refused with the field's name") {
  endohaptics::ManualClock clock;
  sim::ScriptedOperator op(clock);
  CHECK(op.command_force(Eigen::Vector3d(std::nan(""), 0, 0)) == tp::DeviceStatus::error);
  CHECK(op.force().isZero());
  sim::OperatorScript bad;
  bad.close_time = 0.0;
  CHECK_THROWS_WITH_AS(sim::ScriptedOperator(clock, bad), doctest::Contains("close_time"),
                       endohaptics::Error);
}

}  // namespace sim_scripted_operator_test
