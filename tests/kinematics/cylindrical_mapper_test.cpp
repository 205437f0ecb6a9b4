#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include "endohaptics/kinematics/cylindrical_mapper.hpp"

#include <doctest/doctest.h>

#include <Eigen/Geometry>  // cross()

#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <random>
#include <string>

namespace kinematics_cylindrical_mapper_test {

namespace {

using endohaptics::kinematics::CylindricalMapper;
using endohaptics::kinematics::CylindricalMapperConfig;
using endohaptics::kinematics::NumericStatus;
using endohaptics::protocol::Motor;
using endohaptics::test::allocations_during;
using Mapper = CylindricalMapper<double>;
using Config = Mapper::Config;
using Vector3 = Mapper::Vector3;
using Motors = Mapper::MotorVector;

constexpr double pi = std::numbers::pi;
constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();
constexpr double inf = std::numeric_limits<double>::infinity();
constexpr std::uint8_t bit(Motor j) {
  return static_cast<std::uint8_t>(1u << static_cast<unsigned>(j));
}

doctest::Approx exact(double x) { return doctest::Approx(x).epsilon(1e-12).scale(1.0); }

// Default motor order is [roll, pitch, clamp1, clamp2].
Motors joint_forces(double roll, double pitch, double clamp1, double clamp2) {
  return Motors(roll, pitch, clamp1, clamp2);
}

Motors map(Mapper& mapper, const Vector3& p) {
  Motors out = Motors::Constant(99.0);
  const auto result = mapper.map_position(p, out);
  REQUIRE(result.ok());
  return out;
}

}  // namespace

TEST_CASE("eq. 5.9 with the 2016 defaults at hand-computed points") {
  // theta = atan2(x, y) (from +y towards +x), r = hypot(x, y); setpoints
  //   roll = 0.7096 theta - 1.108, pitch = 3.93 z - 0.54,
  //   clamp1 = -(5.384 r - 0.7), clamp2 = 5.384 r - 0.7,  each limited to +-1.028 rad.
  // Values re-checked with /usr/bin/python3 (math.atan2, math.hypot, the same formulas).
  Mapper mapper;

  SUBCASE("theta = pi/2 (stylus along +x), r = 0.1 m, z = 0.2 m") {
    // roll = 0.7096 * 1.5707963267948966 - 1.108 = 1.1146370734936585 - 1.108 = 0.0066370734936585
    // pitch = 0.786 - 0.54 = 0.246; clamp1 = -(0.5384 - 0.7) = 0.1616; clamp2 = -0.1616.
    Motors out = Motors::Zero();
    const auto result = mapper.map_position(Vector3(0.1, 0.0, 0.2), out);
    REQUIRE(result.ok());
    CHECK(result.coordinates.theta == exact(pi / 2));
    CHECK(result.coordinates.r == exact(0.1));
    CHECK(result.coordinates.z == 0.2);
    CHECK(out[0] == exact(0.0066370734936584963));
    CHECK(out[1] == exact(0.246));
    CHECK(out[2] == exact(0.1616));
    CHECK(out[3] == exact(-0.1616));
    CHECK(result.clamped_mask == 0);
    CHECK_FALSE(result.theta_held);
  }
  SUBCASE("theta = pi/4, r = 0.1 sqrt(2), z = 0") {
    // roll = 0.7096 * 0.7853981633974483 - 1.108 = -0.5506814632531708;
    // pitch = -0.54; clamp2 = 5.384 * 0.1414213562373095 - 0.7 = 0.06141258198167443.
    const Motors out = map(mapper, Vector3(0.1, 0.1, 0.0));
    CHECK(out[0] == exact(-0.5506814632531708));
    CHECK(out[1] == exact(-0.54));
    CHECK(out[2] == exact(-0.06141258198167443));
    CHECK(out[3] == exact(0.06141258198167443));
  }
  SUBCASE("theta = 3 pi/4, z = 0.3") {
    // roll = 0.7096 * 2.356194490192345 - 1.108 = 0.5639556102404879; pitch = 1.179 - 0.54.
    const Motors out = map(mapper, Vector3(0.1, -0.1, 0.3));
    CHECK(out[0] == exact(0.5639556102404879));
    CHECK(out[1] == exact(0.639));
    CHECK(out[3] == exact(0.06141258198167443));
  }
  SUBCASE("theta = 0 (stylus along +y): roll -1.108 is below the range and is clamped") {
    // pitch = 0.393 - 0.54 = -0.147; clamp1 = -(0.8076 - 0.7) = -0.1076.
    Motors out = Motors::Zero();
    const auto result = mapper.map_position(Vector3(0.0, 0.15, 0.1), out);
    REQUIRE(result.ok());
    CHECK(result.coordinates.theta == 0.0);
    CHECK(out[0] == -1.028);
    CHECK(out[1] == exact(-0.147));
    CHECK(out[2] == exact(-0.1076));
    CHECK(out[3] == exact(0.1076));
    CHECK(result.clamped_mask == bit(Motor::roll));
    CHECK(result.clamped(Motor::roll));
    CHECK_FALSE(result.clamped(Motor::clamp1));
  }
  SUBCASE("theta = pi (stylus along -y): roll 1.1213 is above the range and is clamped") {
    Motors out = Motors::Zero();
    const auto result = mapper.map_position(Vector3(0.0, -0.12, 0.15), out);
    REQUIRE(result.ok());
    CHECK(result.coordinates.theta == exact(pi));
    CHECK(out[0] == 1.028);
    CHECK(result.clamped_mask == bit(Motor::roll));
  }
}

TEST_CASE(
    "theta is wrapped around theta_neutral: the branch cut is opposite the neutral direction") {
  Mapper mapper;  // neutral pi/2: theta in (-pi/2, 3pi/2]
  Motors out = Motors::Zero();
  auto result = mapper.map_position(Vector3(-0.1, 0.0, 0.0), out);  // along -x
  REQUIRE(result.ok());
  CHECK(result.coordinates.theta == exact(3 * pi / 2));
  CHECK(out[0] == 1.028);  // 0.7096 * 4.712 - 1.108 = 2.236 -> upper limit, not lower

  result = mapper.map_position(Vector3(-0.1, -1e-9, 0.0), out);  // just past -x towards -y
  CHECK(result.coordinates.theta < 3 * pi / 2);
  result = mapper.map_position(Vector3(-0.1, 1e-9, 0.0), out);  // just past -x towards +y
  CHECK(result.coordinates.theta == doctest::Approx(-pi / 2));

  Config config;
  config.theta_neutral = 0.0;  // theta in (-pi, pi]
  Mapper centred(config);
  result = centred.map_position(Vector3(-0.1, 0.0, 0.0), out);
  CHECK(result.coordinates.theta == exact(-pi / 2));
  result = centred.map_position(Vector3(0.0, -0.1, 0.0), out);
  CHECK(result.coordinates.theta == exact(pi));
}

TEST_CASE("per-joint range limits: each joint is limited and reported") {
  Config config;
  // Index = Motor: roll, pitch, clamp1, clamp2.
  config.lower << -2.0, -0.1, -0.5, -0.05;
  config.upper << 2.0, 0.1, 0.5, 0.05;
  Mapper mapper(config);
  Motors out = Motors::Zero();
  // r = 0.2: clamp2 = 1.0768 - 0.7 = 0.3768 -> 0.05, clamp1 = -0.3768 (inside -0.5).
  // z = 0.2: pitch 0.246 -> 0.1. theta = pi/2: roll 0.0066 inside.
  const auto result = mapper.map_position(Vector3(0.2, 0.0, 0.2), out);
  REQUIRE(result.ok());
  CHECK(out[0] == exact(0.0066370734936584963));
  CHECK(out[1] == 0.1);
  CHECK(out[2] == exact(-0.3768));
  CHECK(out[3] == 0.05);
  CHECK(result.clamped_mask == (bit(Motor::pitch) | bit(Motor::clamp2)));

  // Opening the jaws too far (worksheet 6.2): r = 0.4 m gives clamp2 = 1.4536, clamp1 = -1.4536;
  // with the default +-1.028 rad both stop at the range.
  Mapper defaults;
  const auto wide = defaults.map_position(Vector3(0.4, 0.0, 0.137), out);
  CHECK(out[2] == -1.028);
  CHECK(out[3] == 1.028);
  CHECK(wide.clamped_mask == (bit(Motor::clamp1) | bit(Motor::clamp2)));
}

TEST_CASE("unclipped joint force: the largest joint force each channel renders unclipped") {
  Config c;
  c.motor_order = {Motor::clamp2, Motor::roll, Motor::clamp1, Motor::pitch};
  c.force_scale = Vector3(4.0, 2.0, 0.0);  // radial, tangential, z (pitch not rendered)
  c.channel_limit = Vector3(3.0, 1.0, 1.5);
  c.force_limit = 1e9;  // only the channel limits here
  const Mapper mapper(c);
  const Motors limit = mapper.unclipped_joint_force();
  CHECK(limit[0] == doctest::Approx(1.5));  // clamp: 2 x 3 N / 4 (half its force is radial)
  CHECK(limit[1] == doctest::Approx(0.5));  // roll: 1 N / 2
  CHECK(limit[2] == doctest::Approx(1.5));
  CHECK(std::isinf(limit[3]));  // a channel scaled to 0 never clips
  // At the limit a lone joint force is rendered unclipped, just beyond it the channel clips.
  for (int m = 0; m < 3; ++m) {
    Motors f = Motors::Zero();
    Vector3 stylus;
    f[m] = 0.999 * limit[m];
    CHECK(mapper.map_force(f, stylus).channel_limited_mask == 0);
    f[m] = 1.01 * limit[m];
    CHECK(mapper.map_force(f, stylus).channel_limited_mask != 0);
  }
}

TEST_CASE("motor order is a configurable permutation") {
  Config config;
  config.motor_order = {Motor::clamp2, Motor::roll, Motor::clamp1, Motor::pitch};
  Mapper mapper(config);
  const Motors out = map(mapper, Vector3(0.1, 0.0, 0.2));
  CHECK(out[0] == exact(-0.1616));                // clamp2
  CHECK(out[1] == exact(0.0066370734936584963));  // roll
  CHECK(out[2] == exact(0.1616));                 // clamp1
  CHECK(out[3] == exact(0.246));                  // pitch

  // Joint forces follow the same order: a pure clamp2 force of +2 N is F_clamp = +1 N radial.
  Vector3 force = Vector3::Zero();
  REQUIRE(mapper.map_force(Motors(2.0, 0.0, 0.0, 0.0), pi / 2, force).ok());
  CHECK(force.isApprox(Vector3(1.0, 0.0, 0.0), 1e-15));
  // A pure roll force sits in motor slot 1 now.
  REQUIRE(mapper.map_force(Motors(0.0, 1.0, 0.0, 0.0), pi / 2, force).ok());
  CHECK(force.isApprox(Vector3(0.0, -1.0, 0.0), 1e-15));
}

TEST_CASE("r -> 0: theta is undefined and the last valid theta is held") {
  Mapper mapper;
  Motors out = Motors::Zero();

  // Before any valid theta: theta_neutral = pi/2 (roll 0.0066), clamp setpoints from r = 0.
  auto result = mapper.map_position(Vector3(0.0, 0.0, 0.2), out);
  REQUIRE(result.ok());
  CHECK(result.theta_held);
  CHECK(result.coordinates.theta == exact(pi / 2));
  CHECK(out[0] == exact(0.0066370734936584963));
  CHECK(out[2] == exact(0.7));
  CHECK(out[3] == exact(-0.7));

  result = mapper.map_position(Vector3(0.1, 0.1, 0.2), out);  // theta = pi/4
  CHECK_FALSE(result.theta_held);
  CHECK(mapper.theta() == exact(pi / 4));

  for (const Vector3& p : {Vector3(0.0, 0.0, 0.2), Vector3(-0.0, -0.0, 0.2),
                           Vector3(5e-4, -5e-4, 0.1),   // r = 0.71 mm < 1 mm
                           Vector3(1e-3, 0.0, 0.1)}) {  // r = min_radius exactly: still held
    result = mapper.map_position(p, out);
    CAPTURE(p.transpose());
    CHECK(result.theta_held);
    CHECK(result.coordinates.theta == exact(pi / 4));
    CHECK(out[0] == exact(-0.5506814632531708));
  }

  // The force map without an explicit theta uses the held one: a clamp force at pi/4 points
  // along (sin, cos)(pi/4).
  Vector3 force = Vector3::Zero();
  REQUIRE(mapper.map_force(joint_forces(0, 0, -1, 1), force).ok());
  CHECK(force.isApprox(Vector3(std::sqrt(0.5), std::sqrt(0.5), 0.0), 1e-15));

  mapper.reset();
  CHECK(mapper.theta() == exact(pi / 2));
}

TEST_CASE("eq. 5.8: clamp force is radial and roll force tangential and pitch force vertical") {
  Mapper mapper;
  Vector3 force = Vector3::Zero();
  // F_clamp = (f_clamp2 - f_clamp1) / 2; e_r = (sin, cos, 0), e_theta = (cos, -sin, 0).
  SUBCASE("theta = 0: e_r = +y, e_theta = +x") {
    REQUIRE(mapper.map_force(joint_forces(0, 0, -1, 1), 0.0, force).ok());
    CHECK(force == Vector3(0, 1, 0));
    REQUIRE(mapper.map_force(joint_forces(1, 0, 0, 0), 0.0, force).ok());
    CHECK(force == Vector3(1, 0, 0));
  }
  SUBCASE("theta = pi/2: e_r = +x, e_theta = -y") {
    REQUIRE(mapper.map_force(joint_forces(0, 0, -0.5, 0.5), pi / 2, force).ok());
    CHECK(force.isApprox(Vector3(0.5, 0, 0), 1e-15));
    REQUIRE(mapper.map_force(joint_forces(1, 0, 0, 0), pi / 2, force).ok());
    CHECK(force.isApprox(Vector3(0, -1, 0), 1e-15));
  }
  SUBCASE("pitch maps to z at any theta") {
    REQUIRE(mapper.map_force(joint_forces(0, -1.25, 0, 0), 1.234, force).ok());
    CHECK(force == Vector3(0, 0, -1.25));
  }
  SUBCASE("one jaw alone gives half its force (the mean of the two jaws)") {
    REQUIRE(mapper.map_force(joint_forces(0, 0, 0, 1.2), 0.0, force).ok());
    CHECK(force.isApprox(Vector3(0, 0.6, 0), 1e-15));
  }
  SUBCASE("parallel and perpendicular to the stylus position, at random theta") {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> value(-1.0, 1.0);
    for (int trial = 0; trial < 1000; ++trial) {
      const Vector3 p(0.1 * std::cos(trial * 0.37), 0.1 * std::sin(trial * 0.37), 0.15);
      Motors out = Motors::Zero();
      const auto result = mapper.map_position(p, out);
      REQUIRE(result.ok());
      const double theta = result.coordinates.theta;
      const Vector3 radial(p.x(), p.y(), 0.0);
      const double clamp = value(rng);
      REQUIRE(mapper.map_force(joint_forces(0, 0, -clamp, clamp), force).ok());
      CAPTURE(trial);
      CHECK(force.cross(radial).norm() < 1e-15);                                // parallel
      CHECK(force.dot(radial) == doctest::Approx(clamp * 0.1).epsilon(1e-12));  // same sense
      REQUIRE(mapper.map_force(joint_forces(value(rng), 0, 0, 0), theta, force).ok());
      CHECK(std::abs(force.dot(radial)) < 1e-15);  // perpendicular
      CHECK(force.z() == 0.0);
    }
  }
}

TEST_CASE("the force mapping does the same work as the joint forces axis by axis") {
  // For a small stylus move along e_r, e_theta or z alone, F . dx must have the sign of
  // sum_j f_j dP_j (eq. 5.9): the feedback pushes where the tool is pushed. Holds also when a
  // scale a is negative, because F carries sign(a).
  for (const double sign : {1.0, -1.0}) {
    Config config;
    config.a_roll *= sign;
    config.a_clamp *= sign;
    config.a_pitch *= sign;
    config.b_roll = config.b_pitch = config.b_clamp = 0.0;
    config.lower.setConstant(-100.0);
    config.upper.setConstant(100.0);
    config.force_limit = 1e6;
    Mapper mapper(config);
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> value(-1.0, 1.0);
    for (int trial = 0; trial < 300; ++trial) {
      const double theta = 1.4 * value(rng);  // away from the cut at -pi/2
      const Vector3 p(0.12 * std::sin(theta), 0.12 * std::cos(theta), 0.1);
      const Vector3 e_r(std::sin(theta), std::cos(theta), 0);
      const Vector3 e_t(std::cos(theta), -std::sin(theta), 0);
      const Motors f(value(rng), value(rng), value(rng), value(rng));
      Motors p0 = Motors::Zero();
      REQUIRE(mapper.map_position(p, p0).ok());
      Vector3 force = Vector3::Zero();
      REQUIRE(mapper.map_force(f, force).ok());
      for (const Vector3& dir : {e_r, e_t, Vector3(Vector3::UnitZ())}) {
        const Vector3 dx = 1e-6 * dir;
        Motors p1 = Motors::Zero();
        REQUIRE(mapper.map_position(p + dx, p1).ok());
        const double joint_work = f.dot(p1 - p0);
        const double stylus_work = force.dot(dx);
        CAPTURE(trial);
        CAPTURE(sign);
        if (std::abs(joint_work) > 1e-9) CHECK((joint_work > 0) == (stylus_work > 0));
      }
    }
  }
}

TEST_CASE("magnitude limit scales the force and keeps its direction") {
  Config shared_only;  // the shared 2.5 N limit alone: channel limits out of the way
  shared_only.channel_limit.setConstant(1e9);
  Mapper mapper(shared_only);
  Vector3 force = Vector3::Zero();
  // theta = 0: clamp 3 N along +y, roll 4 N along +x: (4, 3, 0), |F| = 5 -> (2, 1.5, 0).
  auto result = mapper.map_force(joint_forces(4, 0, -3, 3), 0.0, force);
  REQUIRE(result.ok());
  CHECK(result.limited);
  CHECK(force.isApprox(Vector3(2.0, 1.5, 0.0), 1e-15));
  CHECK(force.norm() == exact(2.5));

  // Below the limit nothing changes: (1.2, 0.9, 0.8), |F| = 1.7.
  result = mapper.map_force(joint_forces(1.2, 0.8, -0.9, 0.9), 0.0, force);
  CHECK_FALSE(result.limited);
  CHECK(force.isApprox(Vector3(1.2, 0.9, 0.8), 1e-15));

  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> value(-50.0, 50.0);
  for (int trial = 0; trial < 1000; ++trial) {
    const Motors f(value(rng), value(rng), value(rng), value(rng));
    const double theta = value(rng) / 10;
    Config unlimited = shared_only;
    unlimited.force_limit = 1e9;
    Vector3 raw = Vector3::Zero();
    REQUIRE(Mapper(unlimited).map_force(f, theta, raw).ok());
    REQUIRE(mapper.map_force(f, theta, force).ok());
    CAPTURE(trial);
    CHECK(force.norm() <= 2.5 * (1 + 1e-15));
    if (raw.norm() > 2.5) CHECK(force.isApprox(raw.normalized() * 2.5, 1e-12));
  }

  // Huge but finite forces do not overflow the norm.
  REQUIRE(mapper.map_force(joint_forces(1e300, 0, 0, 0), 0.0, force).ok());
  CHECK(force.isApprox(Vector3(2.5, 0, 0), 1e-15));
  // (f2 - f1) / 2 overflowing to inf is limited like any large channel, never NaN.
  result = Mapper().map_force(joint_forces(0, 0, -1.7e308, 1.7e308), 0.0, force);
  REQUIRE(result.ok());
  CHECK(result.channel_limited_mask == 0b001);
  CHECK(force.isApprox(Vector3(0, 1.4, 0), 1e-15));
}

TEST_CASE("per-channel limits: one wrong joint estimate cannot crowd out the others") {
  // The worksheet saw a spurious ~10 N pitch estimate. With only the shared 2.5 N cap,
  // (clamp 1, pitch 10) N scales to 2.5 / sqrt(101) = 0.249 of itself: the clamp feedback the
  // operator needs drops to 0.25 N. Limited per channel first (1.4 N), nothing is shared-scaled.
  Mapper mapper;
  CHECK(mapper.config().channel_limit == Vector3::Constant(1.4));
  Vector3 force = Vector3::Zero();
  // theta = pi/2: e_r = +x, e_theta = -y. Clamp 1 N: f_clamp2 - f_clamp1 = 2.
  auto result = mapper.map_force(joint_forces(0, 10, -1, 1), pi / 2, force);
  REQUIRE(result.ok());
  const Vector3 cyl = Mapper::cylindrical_force(force, pi / 2);
  CHECK(cyl.x() >= 0.9);  // clamp component (before the fix: 0.2488 N)
  CHECK(cyl.x() == exact(1.0));
  CHECK(cyl.z() == exact(1.4));  // pitch limited to its channel limit, sign kept
  CHECK(result.channel_limited_mask == 0b100);
  CHECK_FALSE(result.limited);

  // Signs survive the channel limit: -8 N pitch -> -1.4 N, -5 N roll -> -1.4 N along e_theta.
  result = mapper.map_force(joint_forces(-5, -8, 0.25, -0.25), 0.0, force);
  REQUIRE(result.ok());
  CHECK(result.channel_limited_mask == 0b110);
  CHECK(force.isApprox(Vector3(-1.4, -0.25, -1.4), 1e-15));

  // All three channels saturated: 1.4 sqrt(3) = 2.425 N < 2.5 N, the shared cap stays idle.
  result = mapper.map_force(joint_forces(30, 30, -30, 30), 0.3, force);
  REQUIRE(result.ok());
  CHECK(result.channel_limited_mask == 0b111);
  CHECK_FALSE(result.limited);
  CHECK(force.norm() == exact(1.4 * std::sqrt(3.0)));

  // The shared cap still acts after the channel limits when configured tighter.
  Config tight;
  tight.force_limit = 1.0;
  result = Mapper(tight).map_force(joint_forces(0, 10, -1, 1), pi / 2, force);
  REQUIRE(result.ok());
  CHECK(result.limited);
  CHECK(force.norm() == exact(1.0));
  CHECK(Mapper::cylindrical_force(force, pi / 2).x() == exact(1.0 / std::hypot(1.0, 1.4)));
}

TEST_CASE("the rendered force opposes every stylus motion its joint force resists") {
  // A joint force f_j resists the joint motion dP_j when f_j dP_j < 0. The stylus motion dx that
  // causes dP (eq. 5.9) must then feel F . dx < 0, and F . dx > 0 when the tool is pushed along:
  // sign(F . dx) = sign(sum_j f_j dP_j), per cylindrical axis, for either sign of each a_i, any
  // scale >= 0 and with the channel and shared limits active.
  std::mt19937_64 rng(14);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::uniform_real_distribution<double> scale(0.0, 3.0);
  int resisted = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Config config;
    config.a_roll *= value(rng) < 0 ? -1.0 : 1.0;
    config.a_clamp *= value(rng) < 0 ? -1.0 : 1.0;
    config.a_pitch *= value(rng) < 0 ? -1.0 : 1.0;
    config.b_roll = config.b_pitch = config.b_clamp = 0.0;
    config.lower.setConstant(-100.0);
    config.upper.setConstant(100.0);
    config.force_scale << scale(rng), scale(rng), scale(rng);
    Mapper mapper(config);
    const double theta = pi / 2 + 1.4 * value(rng);  // away from the cut at -pi/2
    const Vector3 p(0.12 * std::sin(theta), 0.12 * std::cos(theta), 0.1);
    const Vector3 e_r(std::sin(theta), std::cos(theta), 0);
    const Vector3 e_t(std::cos(theta), -std::sin(theta), 0);
    const Motors f = 3.0 * Motors(value(rng), value(rng), value(rng), value(rng));
    Motors p0 = Motors::Zero();
    REQUIRE(mapper.map_position(p, p0).ok());
    Vector3 force = Vector3::Zero();
    REQUIRE(mapper.map_force(f, force).ok());
    int axis = 0;
    for (const Vector3& dir : {e_r, e_t, Vector3(Vector3::UnitZ())}) {
      const double channel_scale = config.force_scale[axis++];
      for (const double step : {1e-6, -1e-6}) {
        Motors p1 = Motors::Zero();
        REQUIRE(mapper.map_position(p + step * dir, p1).ok());
        const double joint_work = f.dot(p1 - p0);
        const double stylus_work = force.dot(step * dir);
        CAPTURE(trial);
        if (std::abs(joint_work) < 1e-9 || channel_scale < 1e-3) continue;
        CHECK((joint_work > 0) == (stylus_work > 0));
        if (joint_work < 0) ++resisted;
      }
    }
  }
  CHECK(resisted > 2000);  // both signs were exercised many times
}

TEST_CASE("force scale per cylindrical axis and the sign of the position scales") {
  Config config;
  config.force_scale << 0.5, 2.0, 0.0;  // clamp, roll, pitch (0: no pitch feedback)
  Mapper mapper(config);
  Vector3 force = Vector3::Zero();
  // theta = 0: clamp (1 - -1)/2 * 0.5 = 0.5 along +y, roll 0.5 * 2 = 1 along +x, pitch 0.
  REQUIRE(mapper.map_force(joint_forces(0.5, 1.0, -1.0, 1.0), 0.0, force).ok());
  CHECK(force.isApprox(Vector3(1.0, 0.5, 0.0), 1e-15));

  Config mirrored;
  mirrored.a_roll = -0.7096;      // roll runs the other way round: so does its feedback
  mirrored.force_scale[0] = 0.0;  // no clamp feedback: a force scale of 0 says so (a gain of
                                  // 0 is refused: it silently removed the feedback)
  Mapper other(mirrored);
  REQUIRE(other.map_force(joint_forces(1.0, 0.0, -1.0, 1.0), 0.0, force).ok());
  CHECK(force == Vector3(-1.0, 0.0, 0.0));
}

TEST_CASE("round trip: the projection inverts eq. 5.8 and a radial force is clamp only") {
  std::mt19937_64 rng(2016);
  std::uniform_real_distribution<double> value(-0.7, 0.7);
  std::uniform_real_distribution<double> angle(-pi / 2, 3 * pi / 2);
  Mapper mapper;
  for (int trial = 0; trial < 1000; ++trial) {
    const double theta = angle(rng);
    const Motors f(value(rng), value(rng), value(rng), value(rng));  // |F| < 2.5 N
    Vector3 force = Vector3::Zero();
    const auto result = mapper.map_force(f, theta, force);
    REQUIRE(result.ok());
    REQUIRE_FALSE(result.limited);
    const Vector3 back = Mapper::cylindrical_force(force, theta);
    CAPTURE(trial);
    CHECK(back.x() == doctest::Approx((f[3] - f[2]) / 2).epsilon(1e-12).scale(1));
    CHECK(back.y() == doctest::Approx(f[0]).epsilon(1e-12).scale(1));
    CHECK(back.z() == f[1]);

    const Vector3 radial = 1.7 * Vector3(std::sin(theta), std::cos(theta), 0);
    const Vector3 cyl = Mapper::cylindrical_force(radial, theta);
    CHECK(cyl.x() == exact(1.7));
    CHECK(std::abs(cyl.y()) < 1e-15);
    CHECK(cyl.z() == 0.0);
  }
}

TEST_CASE("the rest pose straight ahead maps to mid-range setpoints") {
  // Mapping frame: neutral direction +x (theta = pi/2), z up, origin on the waist axis at the
  // desk. rest_position: r = b_clamp / a_clamp = 0.7 / 5.384 = 0.130015 m,
  // z = -b_pitch / a_pitch = 0.54 / 3.93 = 0.137405 m (python3: 0.7/5.384, 0.54/3.93).
  const Vector3 rest = endohaptics::kinematics::rest_position<double>();
  CHECK(rest.x() == exact(0.7 / 5.384));
  CHECK(rest.y() == 0.0);
  CHECK(rest.z() == exact(0.54 / 3.93));
  Mapper mapper;
  Motors out = Motors::Zero();
  const auto result = mapper.map_position(rest, out);
  REQUIRE(result.ok());
  CHECK(result.coordinates.theta == exact(pi / 2));
  CHECK(std::abs(out[0]) < 0.01);   // roll 0.0066 rad of +-1.028
  CHECK(std::abs(out[1]) < 1e-12);  // pitch
  CHECK(std::abs(out[2]) < 1e-12);  // clamps
  CHECK(std::abs(out[3]) < 1e-12);
  CHECK(result.clamped_mask == 0);

  // Straight ahead at any radius or height keeps roll mid-range; sideways does not (roll is the
  // azimuth): 0.1 m to the operator's right (+y) at the rest radius turns theta down.
  REQUIRE(mapper.map_position(Vector3(0.2, 0.0, 0.1), out).ok());
  CHECK(std::abs(out[0]) < 0.01);
  REQUIRE(mapper.map_position(Vector3(rest.x(), 0.1, rest.z()), out).ok());
  CHECK(out[0] == exact(0.7096 * std::atan2(rest.x(), 0.1) - 1.108));

  // Other ranges and coefficients: the middle of each range.
  Config config;
  config.lower << -0.5, -0.2, -1.0, -1.0;
  config.upper << 0.5, 0.6, 0.4, 0.4;  // pitch mid 0.2, clamp1 mid -0.3
  config.a_pitch = -2.0;
  const Vector3 other = endohaptics::kinematics::rest_position(config);
  Mapper custom(config);
  REQUIRE(custom.map_position(other, out).ok());
  CHECK(out[1] == exact(0.2));
  CHECK(out[2] == exact(-0.3));
  config.a_clamp = 0.0;
  CHECK_THROWS_WITH_AS((void)endohaptics::kinematics::rest_position(config),
                       "rest_position: a_clamp and a_pitch must be non-zero, got a_clamp 0, "
                       "a_pitch -2",
                       endohaptics::Error);
}

TEST_CASE("non-finite input is refused and leaves outputs and theta untouched") {
  Mapper mapper;
  Motors out = Motors::Zero();
  REQUIRE(mapper.map_position(Vector3(0.1, 0.1, 0.1), out).ok());  // theta = pi/4
  const Motors before = out;
  for (const double bad : {not_a_number, inf, -inf}) {
    for (int axis = 0; axis < 3; ++axis) {
      Vector3 p(0.05, -0.1, 0.2);
      p[axis] = bad;
      const auto result = mapper.map_position(p, out);
      CAPTURE(axis);
      CHECK(result.status == NumericStatus::non_finite_input);
      CHECK_FALSE(result.ok());
      CHECK(out == before);
      CHECK(mapper.theta() == exact(pi / 4));
    }
    const Vector3 sentinel(7, 8, 9);
    Vector3 force = sentinel;
    for (int j = 0; j < 4; ++j) {
      Motors f = Motors::Constant(0.1);
      f[j] = bad;
      CHECK(mapper.map_force(f, 0.3, force).status == NumericStatus::non_finite_input);
      CHECK(force == sentinel);
    }
    CHECK(mapper.map_force(Motors::Zero(), bad, force).status == NumericStatus::non_finite_input);
    CHECK(force == sentinel);
  }
  CHECK(to_string(Motor::clamp2) == "clamp2");
}

TEST_CASE("huge finite positions are clamped and never NaN") {
  Mapper mapper;
  Motors out = Motors::Zero();
  // hypot(1.5e308, 1.5e308) overflows to +inf: clamp setpoints go to their limits.
  auto result = mapper.map_position(Vector3(1.5e308, 1.5e308, 1e308), out);
  REQUIRE(result.ok());
  CHECK(out[1] == 1.028);
  CHECK(out[2] == -1.028);
  CHECK(out[3] == 1.028);
  CHECK(result.clamped_mask == (bit(Motor::pitch) | bit(Motor::clamp1) | bit(Motor::clamp2)));

  // A zero clamp gain (which would make 0 * inf = NaN) is refused at configuration.
  Config config;
  config.a_clamp = 0.0;
  CHECK_THROWS_WITH_AS((void)Mapper{config},
                       "CylindricalMapper: a_clamp must be of magnitude in [1e-6, 1e6] (a gain of "
                       "0 freezes the joint and removes its force feedback), got 0",
                       endohaptics::Error);
}

TEST_CASE("invalid configurations throw endohaptics::Error naming field and value") {
  const auto message = [](const Config& config) -> std::string {
    try {
      const Mapper mapper(config);
    } catch (const endohaptics::Error& e) {
      return e.what();
    }
    return "no error";
  };
  Config c;
  CHECK(message(c) == "no error");

  c = Config{};
  c.motor_order = {Motor::roll, Motor::roll, Motor::clamp1, Motor::clamp2};
  CHECK(message(c) ==
        "CylindricalMapper: motor_order is not a permutation: roll appears twice (again at motor "
        "1)");
  c = Config{};
  c.motor_order[2] = static_cast<Motor>(4);
  CHECK(message(c) == "CylindricalMapper: motor_order[2] is not a tool joint: 4");
  c = Config{};
  c.lower[1] = 0.5;
  c.upper[1] = -0.5;
  CHECK(message(c) == "CylindricalMapper: range of pitch is empty: lower 0.5 > upper -0.5");
  c = Config{};
  c.a_roll = not_a_number;
  CHECK(message(c) ==
        "CylindricalMapper: a_roll must be of magnitude in [1e-6, 1e6] (a gain of 0 freezes the "
        "joint and removes its force feedback), got nan");
  c = Config{};
  c.upper[3] = inf;
  CHECK(message(c) == "CylindricalMapper: upper[3] must be finite rad, got inf");
  c = Config{};
  c.force_limit = 0.0;
  CHECK(message(c) == "CylindricalMapper: force_limit must be finite and > 0 N, got 0");
  c = Config{};
  c.min_radius = -1.0;
  CHECK(message(c) == "CylindricalMapper: min_radius must be finite and >= 0 m, got -1");
  c = Config{};
  c.theta_neutral = 4.0;
  CHECK(message(c) == "CylindricalMapper: theta_neutral must be in [-pi, pi] rad, got 4");
  c = Config{};
  c.force_scale[1] = -inf;
  CHECK(message(c) == "CylindricalMapper: force_scale[1] must be in [0, 100] N per unit, got -inf");
  c = Config{};
  c.force_scale[0] = -1.0;  // would render the clamp force along the operator's motion
  CHECK(message(c) == "CylindricalMapper: force_scale[0] must be in [0, 100] N per unit, got -1");
  c = Config{};
  c.force_scale[2] = -1e-9;
  CHECK(message(c) ==
        "CylindricalMapper: force_scale[2] must be in [0, 100] N per unit, got -1e-09");
  c = Config{};
  c.channel_limit[2] = 0.0;
  CHECK(message(c) == "CylindricalMapper: channel_limit[2] must be finite and > 0 N, got 0");
  c = Config{};
  c.channel_limit[1] = not_a_number;
  CHECK(message(c) == "CylindricalMapper: channel_limit[1] must be finite and > 0 N, got nan");
  c = Config{};
  c.force_scale[1] = 0.0;  // zero is allowed: that channel renders nothing
  CHECK(message(c) == "no error");
  c = Config{};
  c.roll_lever_radius = -0.01;
  CHECK(message(c) == "CylindricalMapper: roll_lever_radius must be finite and >= 0 m, got -0.01");
  c = Config{};
  c.roll_lever_radius = inf;
  CHECK(message(c) == "CylindricalMapper: roll_lever_radius must be finite and >= 0 m, got inf");
  c = Config{};
  c.roll_lever_radius = 0.0;  // zero is allowed: eq. 5.8 verbatim at every radius
  CHECK(message(c) == "no error");
}

TEST_CASE("the roll channel near the waist axis: scaled by r / roll_lever_radius inside it") {
  // Off by default (eq. 5.8 verbatim); the geometric choice is the rest radius, b_clamp / a_clamp
  // (where eq. 5.9 puts the clamps mid-range).
  CHECK(Config{}.roll_lever_radius == 0.0);
  Config config;
  config.roll_lever_radius = endohaptics::kinematics::rest_position(config).x();
  CHECK(config.roll_lever_radius == exact(0.7 / 5.384));
  Mapper mapper(config);
  const double lever = config.roll_lever_radius;
  const Motors f = joint_forces(0.8, 0.5, -0.6, 0.6);  // roll, pitch, clamp1, clamp2
  Vector3 force = Vector3::Zero();

  SUBCASE("at and beyond the lever radius: eq. 5.8 verbatim") {
    for (const double r : {lever, 0.2, 0.3, inf}) {
      REQUIRE(mapper.map_force(f, pi / 2, r, force).ok());
      CAPTURE(r);
      // theta = pi/2: e_r = +x, e_theta = -y (module docs).
      CHECK(force.x() == exact(0.6));
      CHECK(force.y() == exact(-0.8));
      CHECK(force.z() == exact(0.5));
    }
  }
  SUBCASE("inside it the roll channel alone scales with r; clamp and pitch untouched") {
    for (const double r : {0.1, 0.04, 0.0186, 1e-4, 0.0}) {
      REQUIRE(mapper.map_force(f, pi / 2, r, force).ok());
      CAPTURE(r);
      CHECK(mapper.roll_lever(r) == exact(r / lever));
      CHECK(force.x() == exact(0.6));
      CHECK(force.y() == exact(-0.8 * r / lever));
      CHECK(force.z() == exact(0.5));
    }
  }
  SUBCASE("the held radius is the last map_position's r; before it and after reset, unscaled") {
    CHECK(mapper.radius() == inf);  // no position yet: theta_neutral, radius not known
    REQUIRE(mapper.map_force(f, force).ok());
    CHECK(force.y() == exact(-0.8));
    const double r = 0.04;
    Motors setpoint = Motors::Zero();
    REQUIRE(mapper.map_position(Vector3(r, 0.0, 0.137), setpoint).ok());
    CHECK(mapper.radius() == exact(r));
    REQUIRE(mapper.map_force(f, force).ok());
    CHECK(force.y() == exact(-0.8 * r / lever));
    // The explicit-theta overload does not know r: unscaled, as before this lever existed.
    REQUIRE(mapper.map_force(f, pi / 2, force).ok());
    CHECK(force.y() == exact(-0.8));
    mapper.reset();
    CHECK(mapper.radius() == inf);
    REQUIRE(mapper.map_force(f, force).ok());
    CHECK(force.y() == exact(-0.8));
  }
  SUBCASE("lever radius 0 (the default): eq. 5.8 verbatim at every radius") {
    const Mapper plain;
    for (const double r : {0.0, 1e-4, 0.04, 0.2}) {
      REQUIRE(plain.map_force(f, pi / 2, r, force).ok());
      CHECK(force.y() == exact(-0.8));
    }
  }
  SUBCASE("a NaN or negative radius is refused, the output untouched") {
    force = Vector3::Constant(7.0);
    CHECK(mapper.map_force(f, pi / 2, not_a_number, force).status ==
          NumericStatus::non_finite_input);
    CHECK(mapper.map_force(f, pi / 2, -0.01, force).status == NumericStatus::non_finite_input);
    CHECK(force == Vector3::Constant(7.0));
  }
}

TEST_CASE("the roll a compliant hand gives back under the roll force is bounded at every radius") {
  // The loop the lever radius bounds: a joint force f on roll is rendered as a tangential stylus
  // force F; a hand of compliance c (table 5.1's arm in series: 1/k1 + 1/k2 = 23.2 mm/N) yields
  // c F along e_theta, and eq. 5.9 turns that into a_roll c F / r of roll setpoint. Eq. 5.8
  // verbatim makes that grow as 1/r towards the waist axis (the checks below fail with
  // roll_lever_radius 0); with the lever it never exceeds its value at the lever radius,
  // a_roll c s f / roll_lever_radius, and equals it at every r up to there.
  const double compliance = 1.0 / 48.8 + 1.0 / 375.0;  // m/N
  const double rest_radius = endohaptics::kinematics::rest_position<double>().x();
  for (const double lever_radius : {0.0, rest_radius}) {
    Config config;
    config.roll_lever_radius = lever_radius;
    config.lower.setConstant(-100.0);
    config.upper.setConstant(100.0);
    Mapper mapper(config);
    const double bound = config.a_roll * compliance * 0.5 / rest_radius;
    bool exceeded = false;
    for (double r = 0.005; r <= 0.3; r += 0.005) {
      const double theta = pi / 2 + 0.3;
      const Vector3 p(r * std::sin(theta), r * std::cos(theta), 0.137);
      Motors before = Motors::Zero();
      REQUIRE(mapper.map_position(p, before).ok());
      Vector3 force = Vector3::Zero();
      REQUIRE(mapper.map_force(joint_forces(0.5, 0, 0, 0), force).ok());
      // Move the hand by c F, a small step along the arc (the rotation keeps r exact).
      const double tangential =
          compliance * force.dot(Vector3(std::cos(theta), -std::sin(theta), 0));
      const double moved = theta + tangential / r;
      Motors after = Motors::Zero();
      REQUIRE(mapper.map_position(Vector3(r * std::sin(moved), r * std::cos(moved), 0.137), after)
                  .ok());
      const double taken_back = std::abs(after[0] - before[0]);
      CAPTURE(r);
      CAPTURE(lever_radius);
      if (lever_radius > 0) {
        CHECK(taken_back <= bound * (1 + 1e-12));
        if (r <= lever_radius) CHECK(taken_back == doctest::Approx(bound).epsilon(1e-9));
      }
      exceeded = exceeded || taken_back > bound * (1 + 1e-6);
    }
    CHECK(exceeded == (lever_radius == 0));  // eq. 5.8 verbatim exceeds it near the axis
  }
}

TEST_CASE_TEMPLATE("float and double give the hand-computed values", Scalar, double, float) {
  using M = CylindricalMapper<Scalar>;
  using V3 = typename M::Vector3;
  const double tol = std::is_same_v<Scalar, float> ? 1e-6 : 1e-12;
  typename M::Config config;
  config.channel_limit.setConstant(Scalar(100));  // the shared limit alone, as in the test above
  M mapper(config);
  typename M::MotorVector out = M::MotorVector::Zero();
  const auto result = mapper.map_position(V3(Scalar(0.1), Scalar(0), Scalar(0.2)), out);
  REQUIRE(result.ok());
  CHECK(static_cast<double>(out[0]) ==
        doctest::Approx(0.0066370734936584963).epsilon(tol).scale(1));
  CHECK(static_cast<double>(out[1]) == doctest::Approx(0.246).epsilon(tol).scale(1));
  CHECK(static_cast<double>(out[2]) == doctest::Approx(0.1616).epsilon(tol).scale(1));
  CHECK(static_cast<double>(out[3]) == doctest::Approx(-0.1616).epsilon(tol).scale(1));

  V3 force = V3::Zero();
  const auto fr = mapper.map_force(
      typename M::MotorVector(Scalar(4), Scalar(0), Scalar(-3), Scalar(3)), Scalar(0), force);
  REQUIRE(fr.ok());
  CHECK(fr.limited);
  CHECK(static_cast<double>(force.x()) == doctest::Approx(2.0).epsilon(tol));
  CHECK(static_cast<double>(force.y()) == doctest::Approx(1.5).epsilon(tol));
}

TEST_CASE("10000 ticks of position and force mapping allocate nothing") {
  Mapper mapper;
  Motors setpoint = Motors::Zero();
  Vector3 force = Vector3::Zero();
  double sink = 0;
  const long allocations = allocations_during([&] {
    for (int tick = 0; tick < 10000; ++tick) {
      const double t = tick * 1e-3;
      const Vector3 p(0.12 * std::cos(t), 0.12 * std::sin(t), 0.1 + 0.01 * std::sin(3 * t));
      const auto position = mapper.map_position(p, setpoint);
      const auto feedback = mapper.map_force(Motors(0.3, -0.2, 0.5, -0.5), force);
      if (!position.ok() || !feedback.ok()) sink += 1000;
      sink += setpoint.sum() + force.sum();
    }
  });
  CHECK(allocations == 0);
  CHECK(std::isfinite(sink));
}

}  // namespace kinematics_cylindrical_mapper_test
