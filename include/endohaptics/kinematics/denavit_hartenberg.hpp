//! @file
//! Denavit-Hartenberg forward kinematics (worksheet appendix D, eq. D.1:
//! A_i = Rot_z(theta_i) Trans_z(d_i) Trans_x(a_i) Rot_x(alpha_i)), and the presets of tables D.1
//! (Geomagic Touch, literature link lengths) and D.2 (da Vinci hand). Lengths in m, angles in rad.
//! Table D.1 is written in the modified (Craig) convention; see docs/models/kinematics.md.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <string_view>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/numeric_status.hpp"

namespace endohaptics::kinematics {

//! Which DH parameter the joint variable q adds to.
enum class JointKind : std::uint8_t {
  revolute,   //!< theta_i = theta_offset + q (rad)
  prismatic,  //!< d_i = d + q (m)
};

//! Forward kinematics returns `NumericStatus` (core/numeric_status.hpp); on anything but `ok` the
//! output is left untouched.
using endohaptics::NumericStatus;

//! One row of a DH table in the convention of eq. D.1 (standard DH).
template <typename Scalar = double>
struct DhRow {
  Scalar a{};                            //!< m, along x_i
  Scalar d{};                            //!< m, along z_{i-1}; a prismatic joint adds q to it
  Scalar alpha{};                        //!< rad, about x_i
  Scalar theta_offset{};                 //!< rad, about z_{i-1}; a revolute joint adds q to it
  JointKind kind = JointKind::revolute;  //!< which of theta or d the joint variable drives
};

//! Serial chain of N DH rows: T_0^N(q) = A_1(q_1) ... A_N(q_N), eq. D.1.
template <int N, typename Scalar = double>
class DhChain {
  static_assert(N >= 1 && N <= 32, "a DH chain has 1 to 32 joints");

 public:
  static constexpr int dof = N;                              //!< number of joints
  using Row = DhRow<Scalar>;                                 //!< one DH row
  static constexpr auto size = static_cast<std::size_t>(N);  //!< number of rows (= dof)
  using Rows = std::array<Row, size>;                        //!< the DH table, base to tip
  using JointVector = Eigen::Matrix<Scalar, N, 1>;           //!< rad (revolute) or m (prismatic)
  using Transform = Eigen::Transform<Scalar, 3, Eigen::Isometry>;  //!< homogeneous transform (m)
  using Frames = std::array<Transform, size>;                      //!< frames[i] = T_0^{i+1}

  //! Throws endohaptics::Error when a parameter is not finite (naming row, field and value).
  explicit DhChain(const Rows& rows) : rows_(rows) {
    for (std::size_t i = 0; i < rows_.size(); ++i) {
      check(rows_[i].a, i, "a");
      check(rows_[i].d, i, "d");
      check(rows_[i].alpha, i, "alpha");
      check(rows_[i].theta_offset, i, "theta_offset");
      if (rows_[i].kind != JointKind::revolute && rows_[i].kind != JointKind::prismatic) {
        ENDOHAPTICS_THROW(Error("DhChain: row " + std::to_string(i + 1) + ": unknown joint kind " +
                                std::to_string(static_cast<unsigned>(rows_[i].kind))));
      }
    }
  }

  //! The DH table, base to tip.
  [[nodiscard]] const Rows& rows() const noexcept { return rows_; }

  //! Eq. D.1 in closed form for one row at joint value q.
  [[nodiscard]] static Transform link_transform(const Row& row, Scalar q) noexcept {
    const bool revolute = row.kind == JointKind::revolute;
    const Scalar theta = row.theta_offset + (revolute ? q : Scalar(0));
    const Scalar d = row.d + (revolute ? Scalar(0) : q);
    const Scalar ct = std::cos(theta);
    const Scalar st = std::sin(theta);
    const Scalar ca = std::cos(row.alpha);
    const Scalar sa = std::sin(row.alpha);
    Transform A;
    A.matrix() << ct, -st * ca, st * sa, row.a * ct,  //
        st, ct * ca, -ct * sa, row.a * st,            //
        Scalar(0), sa, ca, d,                         //
        Scalar(0), Scalar(0), Scalar(0), Scalar(1);
    return A;
  }

  //! T_0^N(q). Precondition: q finite (NaN in, NaN out); use the status overloads for device data.
  [[nodiscard]] Transform forward(const JointVector& q) const noexcept {
    Transform T = link_transform(rows_[0], q[0]);
    for (int i = 1; i < N; ++i) T = T * link_transform(rows_[static_cast<std::size_t>(i)], q[i]);
    return T;
  }

  //! T_0^N(q) into `end`; `end` is untouched unless the result is ok.
  [[nodiscard]] NumericStatus forward(const JointVector& q, Transform& end) const noexcept {
    if (!q.allFinite()) return NumericStatus::non_finite_input;
    end = forward(q);
    return NumericStatus::ok;
  }

  //! All frames T_0^1 ... T_0^N into `frames`; untouched unless the result is ok.
  [[nodiscard]] NumericStatus forward(const JointVector& q, Frames& frames) const noexcept {
    if (!q.allFinite()) return NumericStatus::non_finite_input;
    frames[0] = link_transform(rows_[0], q[0]);
    for (std::size_t i = 1; i < frames.size(); ++i) {
      frames[i] = frames[i - 1] * link_transform(rows_[i], q[static_cast<Eigen::Index>(i)]);
    }
    return NumericStatus::ok;
  }

 private:
  static void check(Scalar value, std::size_t row, const char* field) {
    if (std::isfinite(value)) return;
    ENDOHAPTICS_THROW(Error("DhChain: row " + std::to_string(row + 1) + ": " + field +
                            " must be finite, got " + endohaptics::detail::format_number(value)));
  }

  Rows rows_;
};

//! Geometry of the Touch preset. Link lengths: published Phantom Omni values (literature, not
//! measured here): a3 = d4 = 133.35 mm (Jarillo-Silva et al., CERMA 2009). d1 = 0.125 m, the
//! shoulder above the desk (public Omni URDF, WPI-AIM/ros_geomagic: 0.09 + 0.035 m), puts frame 0
//! at the origin of CylindricalMapper's mapping frame (on the waist axis at the desk, x towards
//! the operator at q1 = 0, z up), so forward() gives positions the mapper takes as they are.
//! d1 = 0 puts frame 0 at the shoulder instead (0.49 rad of 2016 pitch lower).
template <typename Scalar = double>
struct TouchGeometry {
  Scalar d1 = Scalar(0.125);    //!< m, desk (mapping-frame origin) to shoulder along z0
  Scalar a3 = Scalar(0.13335);  //!< m, upper arm (shoulder to elbow)
  Scalar d4 = Scalar(0.13335);  //!< m, forearm (elbow to gimbal centre)
  Scalar theta1 = Scalar(0);    //!< rad, offset of the shoulder joint q2 (0: q2 = 0 is horizontal)
};

//! Table D.1 (Geomagic Touch, joints q1..q6 in rad) converted to eq. D.1: the table lists
//! (a_{i-1}, alpha_{i-1}) per row, so a and alpha move up one row. Same T_0^6 as the table read
//! with the modified-DH product Rot_x(alpha_{i-1}) Trans_x(a_{i-1}) Rot_z(theta_i) Trans_z(d_i).
//! The end frame's origin is the gimbal centre, in the mapping frame with the default d1.
template <typename Scalar = double>
[[nodiscard]] DhChain<6, Scalar> geomagic_touch_chain(const TouchGeometry<Scalar>& g = {}) {
  constexpr Scalar half_pi = std::numbers::pi_v<Scalar> / 2;
  using Row = DhRow<Scalar>;
  return DhChain<6, Scalar>({
      Row{Scalar(0), g.d1, half_pi, Scalar(0)},       // q1 waist
      Row{g.a3, Scalar(0), Scalar(0), g.theta1},      // q2 + theta1 shoulder
      Row{Scalar(0), Scalar(0), half_pi, Scalar(0)},  // q3 elbow
      Row{Scalar(0), g.d4, -half_pi, Scalar(0)},      // q4 gimbal 1
      Row{Scalar(0), Scalar(0), -half_pi, -half_pi},  // -pi/2 + q5 gimbal 2
      Row{Scalar(0), Scalar(0), Scalar(0), half_pi},  // pi/2 + q6 gimbal 3 (stylus roll)
  });
}

//! Table D.2 (da Vinci hand) as written, already in the eq. D.1 convention: two revolute joints
//! about the stationary point (q1, q2 in rad) and the prismatic insertion d3 = q3 (m).
template <typename Scalar = double>
[[nodiscard]] DhChain<3, Scalar> davinci_hand_chain() {
  constexpr Scalar half_pi = std::numbers::pi_v<Scalar> / 2;
  using Row = DhRow<Scalar>;
  return DhChain<3, Scalar>({
      Row{Scalar(0), Scalar(0), -half_pi, Scalar(0)},
      Row{Scalar(0), Scalar(0), half_pi, half_pi},
      Row{Scalar(0), Scalar(0), Scalar(0), Scalar(0), JointKind::prismatic},
  });
}

}  // namespace endohaptics::kinematics
