#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "ros_conversion.hpp"  // examples/ros_bridge: no ROS in it, so tested without ROS

namespace ros_conversion_test {

namespace rb = ros_bridge;
namespace tp = endohaptics::teleop;

namespace {

// Message types with the ROS field names (what ROS 1's and ROS 2's generated types share).
struct Stamp {
  std::int64_t ns = 0;
};
struct Header {
  Stamp stamp;
  std::string frame_id;
};
struct Point {
  double x = 0, y = 0, z = 0;
};
struct Quaternion {
  double x = 0, y = 0, z = 0, w = 1;
};
struct Pose {
  Point position;
  Quaternion orientation;
};
struct PoseStamped {
  Header header;
  Pose pose;
};
struct JointState {
  Header header;
  std::vector<std::string> name;
  std::vector<double> position, velocity, effort;
};
struct Dimension {
  std::string label;
  std::uint32_t size = 0, stride = 0;
};
struct Layout {
  std::vector<Dimension> dim;
};
struct Float64MultiArray {
  Layout layout;
  std::vector<double> data;
};

PoseStamped pose(double x, double y, double z, const std::string& frame = "touch") {
  PoseStamped m;
  m.header.frame_id = frame;
  m.pose.position = {x, y, z};
  return m;
}

}  // namespace

TEST_CASE("a stylus pose is checked before use: NaN, wrong frame, stamp 0, out of order") {
  Eigen::Vector3d p(7, 7, 7);
  CHECK(rb::stylus_position(pose(0.1, 0.2, 0.3), "touch", 100, 50, p) == rb::InputError::none);
  CHECK(p.isApprox(Eigen::Vector3d(0.1, 0.2, 0.3)));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  p.setConstant(7);
  CHECK(rb::stylus_position(pose(nan, 0, 0), "touch", 100, 50, p) == rb::InputError::non_finite);
  CHECK(rb::stylus_position(pose(0, inf, 0), "", 100, 50, p) == rb::InputError::non_finite);
  auto q = pose(0, 0, 0);
  q.pose.orientation.w = nan;
  CHECK(rb::stylus_position(q, "", 100, 50, p) == rb::InputError::non_finite);
  CHECK(rb::stylus_position(pose(0, 0, 0, "world"), "touch", 100, 50, p) ==
        rb::InputError::wrong_frame);
  CHECK(rb::stylus_position(pose(0, 0, 0, "/touch"), "touch", 100, 50, p) ==
        rb::InputError::none);  // ROS 1's leading slash is the same frame
  CHECK(rb::stylus_position(pose(0, 0, 0, "anything"), "", 100, 50, p) == rb::InputError::none);
  CHECK(rb::stylus_position(pose(0, 0, 0), "touch", 0, 0, p) == rb::InputError::invalid);
  CHECK(rb::stylus_position(pose(0, 0, 0), "touch", 40, 50, p) == rb::InputError::out_of_order);
  p.setConstant(7);
  (void)rb::stylus_position(pose(nan, 0, 0), "touch", 100, 50, p);
  CHECK(p == Eigen::Vector3d(7, 7, 7));  // a refused message leaves the output alone
}

TEST_CASE("the TF chain composes base -> ... -> tip as tf did, and refuses what it cannot") {
  rb::TfChain chain;
  Eigen::Vector3d p;
  CHECK_FALSE(chain.lookup("base", "tip", p));  // nothing heard yet
  const Eigen::Quaterniond quarter(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  REQUIRE(chain.update("/base", "arm", Eigen::Vector3d(0, 0, 0.1), quarter) ==
          rb::InputError::none);
  CHECK_FALSE(chain.lookup("base", "tip", p));  // arm -> tip missing
  REQUIRE(chain.update("arm", "tip", Eigen::Vector3d(0.2, 0, 0), Eigen::Quaterniond::Identity()) ==
          rb::InputError::none);
  REQUIRE(chain.lookup("/base", "/tip", p));
  CHECK(p.isApprox(Eigen::Vector3d(0, 0.2, 0.1)));  // arm turned 90 deg about z, lifted 0.1
  // A newer transform of the same child replaces the old one.
  REQUIRE(chain.update("arm", "tip", Eigen::Vector3d(0.3, 0, 0), Eigen::Quaterniond::Identity()) ==
          rb::InputError::none);
  REQUIRE(chain.lookup("base", "tip", p));
  CHECK(p.isApprox(Eigen::Vector3d(0, 0.3, 0.1)));
  // Non-finite transforms are refused and the previous one kept.
  CHECK(chain.update("arm", "tip", Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0, 0),
                     Eigen::Quaterniond::Identity()) == rb::InputError::non_finite);
  CHECK(chain.update("arm", "tip", Eigen::Vector3d(0, 0, 0), Eigen::Quaterniond(0, 0, 0, 0)) ==
        rb::InputError::non_finite);
  REQUIRE(chain.lookup("base", "tip", p));
  CHECK(p.isApprox(Eigen::Vector3d(0, 0.3, 0.1)));
  // A cycle never reaches the base: refused, no endless walk.
  rb::TfChain cycle;
  REQUIRE(cycle.update("a", "b", Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity()) ==
          rb::InputError::none);
  REQUIRE(cycle.update("b", "a", Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity()) ==
          rb::InputError::none);
  CHECK_FALSE(cycle.lookup("base", "a", p));
}

TEST_CASE("the joint states carry the motors in protocol order, by name") {
  JointState js;
  tp::MotorVector position(0.1, 0.2, 0.3, 0.4), current(1, 2, 3, 4);
  rb::fill_joint_state(js, Stamp{42}, &position, nullptr, &current);
  CHECK(js.header.stamp.ns == 42);
  CHECK(js.name == std::vector<std::string>{"roll", "pitch", "clamp1", "clamp2"});
  CHECK(js.position == std::vector<double>{0.1, 0.2, 0.3, 0.4});
  CHECK(js.velocity.empty());
  CHECK(js.effort == std::vector<double>{1, 2, 3, 4});
}

TEST_CASE("the tick-log message is the CSV row, named once a second") {
  tp::TickResult r;
  r.status = tp::TickStatus::ok;
  r.link = tp::LinkState::up;
  r.setpoint = tp::MotorVector(0.5, 0.6, 0.7, 0.8);
  const auto record = tp::TickRecord::from(r, std::chrono::milliseconds(1500));
  Float64MultiArray m;
  rb::fill_tick_log<Float64MultiArray, Dimension>(m, record, true);
  REQUIRE(m.layout.dim.size() == 1);
  CHECK(m.layout.dim[0].label.rfind("time,status,link,", 0) == 0);
  CHECK(m.layout.dim[0].size == tp::tick_log_columns.size());
  const auto values = record.values();
  CHECK(std::equal(m.data.begin(), m.data.end(), values.begin(), values.end()));
  rb::fill_tick_log<Float64MultiArray, Dimension>(m, record, false);
  CHECK(m.layout.dim[0].label.empty());
  CHECK(m.data.size() == tp::tick_log_columns.size());
}

TEST_CASE("the operating state says waiting, link up, link lost or safe") {
  tp::TickRecord r;
  r.link = tp::LinkState::waiting;
  CHECK(rb::operating_state(r) == "waiting");
  r.link = tp::LinkState::up;
  r.enable_mask = 0x0F;
  CHECK(rb::operating_state(r) == "link up");
  r.link = tp::LinkState::degraded;
  CHECK(rb::operating_state(r) == "link up");
  r.link = tp::LinkState::lost;
  CHECK(rb::operating_state(r) == "link lost");  // a hold policy keeps the motors enabled
  r.enable_mask = 0;
  CHECK(rb::operating_state(r) == "safe");
  r.link = tp::LinkState::up;  // a lost operator: released with the link up
  CHECK(rb::operating_state(r) == "safe");
}

TEST_CASE("the tick's message: its record, the stylus message it used, a valid state or not") {
  tp::TickResult r;
  r.status = tp::TickStatus::ok;
  r.setpoint << 0.1, -0.2, 0.3, -0.3;
  rb::TickMessage m;
  const long allocations = endohaptics::test::allocations_during(
      [&] { m = rb::tick_message(r, std::chrono::milliseconds(2500), 1234, true); });
  CHECK(allocations == 0);
  CHECK(m.record.time == doctest::Approx(2.5));
  CHECK(m.record.setpoint[2] == 0.3);
  CHECK(m.input_stamp_ns == 1234);
  CHECK(m.input_fresh);
  CHECK(m.wall_ns > 0);  // the system time, for the published stamps
  // Valid while the link is up, degraded or recovering; not before the first state or when lost.
  const std::pair<tp::LinkState, bool> cases[] = {{tp::LinkState::waiting, false},
                                                  {tp::LinkState::up, true},
                                                  {tp::LinkState::degraded, true},
                                                  {tp::LinkState::lost, false},
                                                  {tp::LinkState::recovering, true}};
  for (const auto& c : cases) {
    r.link = c.first;
    CAPTURE(tp::to_string(c.first));
    CHECK(rb::tick_message(r, std::chrono::milliseconds(1), 0, false).valid_state() == c.second);
  }
}

}  // namespace ros_conversion_test
