#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include "endohaptics/kinematics/denavit_hartenberg.hpp"

#include "endohaptics/kinematics/cylindrical_mapper.hpp"

#include <doctest/doctest.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <random>
#include <string>

namespace kinematics_denavit_hartenberg_test {

namespace {

using endohaptics::kinematics::davinci_hand_chain;
using endohaptics::kinematics::DhChain;
using endohaptics::kinematics::DhRow;
using endohaptics::kinematics::geomagic_touch_chain;
using endohaptics::kinematics::JointKind;
using endohaptics::kinematics::NumericStatus;
using endohaptics::kinematics::TouchGeometry;
using endohaptics::test::allocations_during;

constexpr double pi = std::numbers::pi;
constexpr double half_pi = pi / 2;
constexpr double L = 0.13335;  // Phantom Omni upper arm and forearm, m (literature value)

using Touch = DhChain<6>;
using Hand = DhChain<3>;

// Frame 0 at the shoulder (d1 = 0): the frame the hand computations below are written in.
Touch shoulder_chain(double theta1 = 0.0) {
  return geomagic_touch_chain<double>({.d1 = 0.0, .theta1 = theta1});
}

// The four factors of eq. D.1 multiplied one by one with Eigen (independent of the closed form).
template <typename Scalar>
Eigen::Transform<Scalar, 3, Eigen::Isometry> four_factor_link(const DhRow<Scalar>& row, Scalar q) {
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
  const bool revolute = row.kind == JointKind::revolute;
  const Scalar theta = row.theta_offset + (revolute ? q : Scalar(0));
  const Scalar d = row.d + (revolute ? Scalar(0) : q);
  Eigen::Transform<Scalar, 3, Eigen::Isometry> A =
      Eigen::Transform<Scalar, 3, Eigen::Isometry>::Identity();
  A.rotate(Eigen::AngleAxis<Scalar>(theta, Vector3::UnitZ()));
  A.translate(Vector3(0, 0, d));
  A.translate(Vector3(row.a, 0, 0));
  A.rotate(Eigen::AngleAxis<Scalar>(row.alpha, Vector3::UnitX()));
  return A;
}

// Table D.1 exactly as printed, read with the modified (Craig) product
// Rot_x(alpha_{i-1}) Trans_x(a_{i-1}) Rot_z(theta_i) Trans_z(d_i), the columns being
// (a_{i-1}, d_i, alpha_{i-1}, theta_i).
Eigen::Isometry3d table_d1_modified(const Touch::JointVector& q, double d1, double a3, double d4,
                                    double theta1) {
  struct Printed {
    double a, d, alpha, theta;
  };
  const std::array<Printed, 6> table = {{{0, d1, 0, q[0]},
                                         {0, 0, half_pi, q[1] + theta1},
                                         {a3, 0, 0, q[2]},
                                         {0, d4, half_pi, q[3]},
                                         {0, 0, -half_pi, -half_pi + q[4]},
                                         {0, 0, -half_pi, half_pi + q[5]}}};
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (const auto& row : table) {
    T.rotate(Eigen::AngleAxisd(row.alpha, Eigen::Vector3d::UnitX()));
    T.translate(Eigen::Vector3d(row.a, 0, 0));
    T.rotate(Eigen::AngleAxisd(row.theta, Eigen::Vector3d::UnitZ()));
    T.translate(Eigen::Vector3d(0, 0, row.d));
  }
  return T;
}

bool near(const Eigen::Matrix4d& a, const Eigen::Matrix4d& b, double tol = 1e-12) {
  return (a - b).cwiseAbs().maxCoeff() <= tol;
}

}  // namespace

TEST_CASE("link transform: closed form of eq. D.1 equals the product of its four factors") {
  std::mt19937_64 rng(20161220);
  std::uniform_real_distribution<double> angle(-pi, pi);
  std::uniform_real_distribution<double> length(-0.5, 0.5);
  for (int trial = 0; trial < 500; ++trial) {
    const DhRow<double> row{length(rng), length(rng), angle(rng), angle(rng),
                            trial % 2 == 0 ? JointKind::revolute : JointKind::prismatic};
    const double q = trial % 2 == 0 ? angle(rng) : length(rng);
    const auto closed = DhChain<1>::link_transform(row, q);
    const auto product = four_factor_link(row, q);
    CAPTURE(trial);
    REQUIRE(near(closed.matrix(), product.matrix()));
  }
}

TEST_CASE("link transform: hand-computed single rows") {
  // Revolute, theta = pi/2, a = 0.2, d = 0.1, alpha = 0: Rot_z(pi/2) maps x to y, so the
  // translation (a cos theta, a sin theta, d) = (0, 0.2, 0.1); rotation = Rot_z(pi/2).
  const auto A = DhChain<1>::link_transform({0.2, 0.1, 0.0, 0.0}, half_pi);
  Eigen::Matrix4d expected;
  expected << 0, -1, 0, 0,  //
      1, 0, 0, 0.2,         //
      0, 0, 1, 0.1,         //
      0, 0, 0, 1;
  CHECK(near(A.matrix(), expected, 1e-15));

  // Prismatic, d = 0.05 + q with q = 0.1, alpha = pi/2: translation (0, 0, 0.15), rotation
  // Rot_x(pi/2) = [1 0 0; 0 0 -1; 0 1 0].
  const auto P = DhChain<1>::link_transform({0.0, 0.05, half_pi, 0.0, JointKind::prismatic}, 0.1);
  expected << 1, 0, 0, 0,  //
      0, 0, -1, 0,         //
      0, 1, 0, 0.15,       //
      0, 0, 0, 1;
  CHECK(near(P.matrix(), expected, 1e-15));
}

TEST_CASE("Geomagic Touch preset: zero configuration worked out by hand") {
  // Rows (eq. D.1): A1 = Rot_x(pi/2) (d1 = 0), A2 = Trans_x(L), A3 = Rot_x(pi/2),
  // A4 = Trans_z(L) Rot_x(-pi/2), A5 = Rot_z(-pi/2) Rot_x(-pi/2), A6 = Rot_z(pi/2).
  // Position: A1 A2 puts the elbow at Rot_x(pi/2) (L,0,0) = (L,0,0); R_03 = Rot_x(pi) so the
  // forearm Trans_z(L) points along Rot_x(pi) z = -z: wrist centre (L, 0, -L) (upper arm
  // horizontal, forearm down). Rotation: Rot_x(pi) Rot_x(-pi/2) = Rot_x(pi/2), then
  // Rot_x(pi/2) Rot_z(-pi/2) = [0 1 0; 0 0 -1; -1 0 0], times Rot_x(-pi/2) = [0 0 1; 0 1 0;
  // -1 0 0], times Rot_z(pi/2) = [0 0 1; 1 0 0; 0 1 0].
  const Touch touch = shoulder_chain();
  Eigen::Matrix4d expected;
  expected << 0, 0, 1, L,  //
      1, 0, 0, 0,          //
      0, 1, 0, -L,         //
      0, 0, 0, 1;
  CHECK(near(touch.forward(Touch::JointVector::Zero()).matrix(), expected));

  // d1 only lifts everything: wrist centre (L, 0, d1 - L). The default d1 is 0.125 m.
  const Touch lifted = geomagic_touch_chain<double>({.d1 = 0.125});
  expected(2, 3) = 0.125 - L;
  CHECK(near(lifted.forward(Touch::JointVector::Zero()).matrix(), expected));
  CHECK(near(geomagic_touch_chain().forward(Touch::JointVector::Zero()).matrix(), expected));
}

TEST_CASE("Geomagic Touch preset: single joints at 90 degrees worked out by hand") {
  const Touch touch = shoulder_chain();
  Touch::JointVector q = Touch::JointVector::Zero();

  SUBCASE("waist q1 = pi/2 turns the whole arm about z0") {
    // Rot_z(pi/2) (L, 0, -L) = (0, L, -L).
    q[0] = half_pi;
    CHECK(touch.forward(q).translation().isApprox(Eigen::Vector3d(0, L, -L), 1e-12));
  }
  SUBCASE("shoulder q2 = pi/2 lifts the upper arm") {
    // Elbow: Rot_x(pi/2) Rot_z(pi/2) (L,0,0) = Rot_x(pi/2) (0,L,0) = (0,0,L).
    // Forearm: Rot_x(pi/2) Rot_z(pi/2) Rot_x(pi/2) (0,0,L) = Rot_x(pi/2) Rot_z(pi/2) (0,-L,0)
    //        = Rot_x(pi/2) (L,0,0) = (L,0,0). Wrist centre (L, 0, L).
    q[1] = half_pi;
    CHECK(touch.forward(q).translation().isApprox(Eigen::Vector3d(L, 0, L), 1e-12));
  }
  SUBCASE("theta1 is the same as an offset on q2") {
    const Touch shifted = shoulder_chain(half_pi);
    CHECK(shifted.forward(q).translation().isApprox(Eigen::Vector3d(L, 0, L), 1e-12));
  }
  SUBCASE("elbow q3 = pi/2 stretches the arm forward") {
    // Elbow (L,0,0); forearm R_03 (0,0,L) with R_03 = Rot_x(pi/2) Rot_z(pi/2) Rot_x(pi/2):
    // as above (L,0,0). Wrist centre (2L, 0, 0).
    q[2] = half_pi;
    CHECK(touch.forward(q).translation().isApprox(Eigen::Vector3d(2 * L, 0, 0), 1e-12));
  }
  SUBCASE("gimbal joints q4..q6 only turn the stylus about the wrist centre") {
    for (int j = 3; j < 6; ++j) {
      q.setZero();
      q[j] = half_pi;
      CAPTURE(j);
      CHECK((touch.forward(q).translation() - Eigen::Vector3d(L, 0, -L)).norm() < 1e-12);
    }
    // q6 = pi/2 (stylus roll about z5): R_06 = R_06(0) Rot_z(pi/2): first column becomes the old
    // second, second column minus the old first: [0 -0 1; 0 -1 0; 1 0 0].
    q.setZero();
    q[5] = half_pi;
    Eigen::Matrix3d expected;
    expected << 0, 0, 1,  //
        0, -1, 0,         //
        1, 0, 0;
    CHECK(touch.forward(q).rotation().isApprox(expected, 1e-12));
  }
}

TEST_CASE("Touch preset: the rest pose maps to mid-range setpoints through the default chain") {
  // Frame 0 must be the mapper's frame (origin on the waist axis at the desk, x towards
  // the operator, z up). Rest pose = stylus straight ahead where the 2016 eq. 5.9 puts pitch and
  // clamps mid-range: r = 0.7 / 5.384 = 0.130015 m, z = 0.54 / 3.93 = 0.137405 m; the gimbal
  // centre is then z - d1 = 0.012405 m above the shoulder (d1 = 0.125 m, URDF). Joint angles by
  // the law of cosines, elbow up (python3, same formulas): D = hypot(0.130015, 0.012405) =
  // 0.130605 m, interior elbow angle gamma = acos(1 - D^2 / (2 L^2)) = 1.023511 rad,
  // q2 = atan2(0.012405, 0.130015) + (pi - gamma) / 2 = 1.154162 rad (upper arm 66.1 deg up),
  // q3 = pi/2 - (pi - gamma) = -0.547285 rad (forearm 55.2 deg below horizontal).
  const Eigen::Vector3d rest = endohaptics::kinematics::rest_position<double>();
  const double h = rest.z() - TouchGeometry<double>{}.d1;
  const double D = std::hypot(rest.x(), h);
  const double gamma = std::acos(1 - D * D / (2 * L * L));
  Touch::JointVector q = Touch::JointVector::Zero();
  q[1] = std::atan2(h, rest.x()) + (pi - gamma) / 2;
  q[2] = half_pi - (pi - gamma);
  CHECK(q[1] == doctest::Approx(1.154162).epsilon(1e-6));
  CHECK(q[2] == doctest::Approx(-0.547285).epsilon(1e-6));

  const Touch touch = geomagic_touch_chain();  // the default geometry: frame 0 on the desk
  const Eigen::Vector3d p = touch.forward(q).translation();
  CHECK((p - rest).norm() < 1e-12);
  endohaptics::kinematics::CylindricalMapper<> mapper;
  Eigen::Vector4d setpoint = Eigen::Vector4d::Zero();
  const auto result = mapper.map_position(p, setpoint);
  REQUIRE(result.ok());
  CHECK(std::abs(setpoint[0]) < 0.01);  // roll (0.0066 rad)
  CHECK(std::abs(setpoint[1]) < 0.01);  // pitch (before the fix, from the shoulder: -0.491 rad)
  CHECK(std::abs(setpoint[2]) < 0.01);  // clamps
  CHECK(result.clamped_mask == 0);

  // The gimbal joints do not move the point that is mapped.
  q[3] = 0.4;
  q[4] = -0.7;
  q[5] = 1.1;
  CHECK((touch.forward(q).translation() - rest).norm() < 1e-12);
  // The waist turns the stylus about z: q1 > 0 moves it from +x towards +y (the operator's
  // right), theta = atan2(x, y) falls by q1 and roll with it.
  q[0] = 0.3;
  REQUIRE(mapper.map_position(touch.forward(q).translation(), setpoint).ok());
  CHECK(mapper.theta() == doctest::Approx(half_pi - 0.3).epsilon(1e-12));
}

TEST_CASE("Geomagic Touch preset equals table D.1 as printed read as modified DH") {
  // The conversion moves (a, alpha) up one row; the end frame must be the same for any q.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> angle(-pi, pi);
  const TouchGeometry<double> g{.d1 = 0.11, .a3 = 0.13335, .d4 = 0.13335, .theta1 = 0.3};
  const Touch touch = geomagic_touch_chain(g);
  for (int trial = 0; trial < 200; ++trial) {
    Touch::JointVector q;
    for (int j = 0; j < 6; ++j) q[j] = angle(rng);
    CAPTURE(trial);
    REQUIRE(
        near(touch.forward(q).matrix(), table_d1_modified(q, g.d1, g.a3, g.d4, g.theta1).matrix()));
  }
}

TEST_CASE("table D.1 as printed is degenerate under eq. D.1 (why the preset converts it)") {
  // With alpha_1 = 0 the axes of joints 1 and 2 coincide: only q1 + q2 matters.
  const Touch literal({{{0, 0, 0, 0},
                        {0, 0, half_pi, 0},
                        {L, 0, 0, 0},
                        {0, L, half_pi, 0},
                        {0, 0, -half_pi, -half_pi},
                        {0, 0, -half_pi, half_pi}}});
  Touch::JointVector q;
  q << 0.3, 0.4, -0.2, 0.1, 0.5, -0.6;
  Touch::JointVector merged = q;
  merged[0] = 0.7;
  merged[1] = 0.0;
  CHECK(near(literal.forward(q).matrix(), literal.forward(merged).matrix()));
  // The preset has no such degeneracy.
  const Touch touch = geomagic_touch_chain();
  CHECK_FALSE(near(touch.forward(q).matrix(), touch.forward(merged).matrix(), 1e-3));
}

TEST_CASE("da Vinci hand preset (table D.2): hand-computed poses") {
  const Hand hand = davinci_hand_chain();
  Hand::JointVector q;

  // q = (0, 0, 0.1): R_01 = Rot_x(-pi/2) maps (x,y,z) to (x, z, -y); R_02 = R_01 Rot_z(pi/2)
  // Rot_x(pi/2). Insertion axis z2 = R_01 Rot_z(pi/2) (0,-1,0) = R_01 (1,0,0) = (1,0,0):
  // end-effector at (0.1, 0, 0).
  q << 0, 0, 0.1;
  Eigen::Matrix4d expected;
  expected << 0, 0, 1, 0.1,  //
      0, 1, 0, 0,            //
      -1, 0, 0, 0,           //
      0, 0, 0, 1;
  CHECK(near(hand.forward(q).matrix(), expected));

  // q1 = pi/2 turns the insertion axis about z0: Rot_z(pi/2) (1,0,0) = (0,1,0).
  q << half_pi, 0, 0.1;
  CHECK(hand.forward(q).translation().isApprox(Eigen::Vector3d(0, 0.1, 0), 1e-12));

  // q2 = pi/2: z2 = R_01 Rot_z(pi) (0,-1,0) = R_01 (0,1,0) = (0, 0, -1).
  q << 0, half_pi, 0.1;
  CHECK(hand.forward(q).translation().isApprox(Eigen::Vector3d(0, 0, -0.1), 1e-12));

  // The stationary point: both rotations leave the origin of frame 2 at the origin.
  Hand::Frames frames;
  q << 0.4, -0.7, 0.08;
  REQUIRE(hand.forward(q, frames) == NumericStatus::ok);
  CHECK(frames[0].translation().norm() < 1e-15);
  CHECK(frames[1].translation().norm() < 1e-15);
  CHECK(frames[2].translation().norm() == doctest::Approx(0.08).epsilon(1e-12));
}

TEST_CASE_TEMPLATE("composition equals the product of single links and rotations are orthonormal",
                   Chain, DhChain<1>, DhChain<3>, DhChain<6>, DhChain<7>, DhChain<4, float>) {
  using Scalar = typename Chain::JointVector::Scalar;
  constexpr int N = Chain::dof;
  const Scalar tol = std::is_same_v<Scalar, float> ? Scalar(2e-5) : Scalar(1e-12);
  std::mt19937_64 rng(42 + N);
  std::uniform_real_distribution<double> angle(-pi, pi);
  std::uniform_real_distribution<double> length(-0.3, 0.3);
  typename Chain::Rows rows;
  for (int i = 0; i < N; ++i) {
    rows[static_cast<std::size_t>(i)] = {
        static_cast<Scalar>(length(rng)), static_cast<Scalar>(length(rng)),
        static_cast<Scalar>(angle(rng)), static_cast<Scalar>(angle(rng)),
        i % 3 == 2 ? JointKind::prismatic : JointKind::revolute};
  }
  const Chain chain(rows);
  for (int trial = 0; trial < 100; ++trial) {
    typename Chain::JointVector q;
    for (int i = 0; i < N; ++i) q[i] = static_cast<Scalar>(angle(rng));
    typename Chain::Transform product = Chain::Transform::Identity();
    for (int i = 0; i < N; ++i) {
      product = product * four_factor_link(rows[static_cast<std::size_t>(i)], q[i]);
    }
    const typename Chain::Transform T = chain.forward(q);
    CAPTURE(trial);
    REQUIRE((T.matrix() - product.matrix()).cwiseAbs().maxCoeff() <= tol);

    typename Chain::Frames frames;
    REQUIRE(chain.forward(q, frames) == NumericStatus::ok);
    REQUIRE((frames[N - 1].matrix() - T.matrix()).cwiseAbs().maxCoeff() <= tol);
    for (int i = 0; i < N; ++i) {
      const auto R = frames[static_cast<std::size_t>(i)].rotation();
      const auto identity = Eigen::Matrix<Scalar, 3, 3>::Identity();
      REQUIRE(((R.transpose() * R) - identity).cwiseAbs().maxCoeff() <= tol);
      REQUIRE(std::abs(R.determinant() - Scalar(1)) <= tol);
    }
    for (int i = 1; i < N; ++i) {
      const auto step = frames[static_cast<std::size_t>(i - 1)] *
                        Chain::link_transform(rows[static_cast<std::size_t>(i)], q[i]);
      REQUIRE(
          (frames[static_cast<std::size_t>(i)].matrix() - step.matrix()).cwiseAbs().maxCoeff() <=
          tol);
    }
  }
}

TEST_CASE("non-finite joint values are refused and leave the outputs untouched") {
  const Touch touch = geomagic_touch_chain();
  const Eigen::Isometry3d sentinel(Eigen::Translation3d(1, 2, 3));
  for (const double bad :
       {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
        -std::numeric_limits<double>::infinity()}) {
    for (int j = 0; j < 6; ++j) {
      Touch::JointVector q = Touch::JointVector::Zero();
      q[j] = bad;
      Eigen::Isometry3d end = sentinel;
      Touch::Frames frames;
      frames.fill(sentinel);
      CAPTURE(j);
      CHECK(touch.forward(q, end) == NumericStatus::non_finite_input);
      CHECK(end.matrix() == sentinel.matrix());
      CHECK(touch.forward(q, frames) == NumericStatus::non_finite_input);
      for (const auto& f : frames) CHECK(f.matrix() == sentinel.matrix());
    }
  }
}

TEST_CASE("non-finite DH parameters are a configuration error naming row and field") {
  DhChain<2>::Rows rows{};
  rows[1].alpha = std::numeric_limits<double>::infinity();
  try {
    const DhChain<2> chain(rows);
    FAIL("expected endohaptics::Error");
  } catch (const endohaptics::Error& e) {
    CHECK(std::string(e.what()) == "DhChain: row 2: alpha must be finite, got inf");
  }
  rows[1].alpha = 0;
  rows[0].d = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(DhChain<2>{rows}, endohaptics::Error);
  rows[0].d = 0;
  rows[0].kind = static_cast<JointKind>(9);
  CHECK_THROWS_WITH_AS(DhChain<2>{rows}, "DhChain: row 1: unknown joint kind 9",
                       endohaptics::Error);
}

TEST_CASE("forward kinematics allocates nothing over 10000 ticks") {
  const Touch touch = geomagic_touch_chain();
  const Hand hand = davinci_hand_chain();
  Touch::Frames frames;
  Eigen::Isometry3d end = Eigen::Isometry3d::Identity();
  Touch::JointVector q = Touch::JointVector::Constant(0.1);
  Hand::JointVector qh(0.1, -0.2, 0.05);
  double sink = 0;
  const long allocations = allocations_during([&] {
    for (int tick = 0; tick < 10000; ++tick) {
      q[tick % 6] += 1e-4;
      if (touch.forward(q, frames) != NumericStatus::ok) sink += 1;
      if (hand.forward(qh, end) != NumericStatus::ok) sink += 1;
      sink += frames[5].translation().x() + end.translation().z();
    }
  });
  CHECK(allocations == 0);
  CHECK(std::isfinite(sink));
}

}  // namespace kinematics_denavit_hartenberg_test
