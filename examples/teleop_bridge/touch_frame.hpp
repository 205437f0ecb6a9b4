//! @file
//! The Geomagic Touch's frame and the mapping frame, for every way the stylus reaches a bridge
//! (OpenHaptics, ROS): Touch frame x right, y up, z towards the operator; mapping frame
//! (kinematics/cylindrical_mapper.hpp) x towards the operator, y right, z up, origin on the waist
//! axis at the desk. position = (z, x, y)_Touch + hd_origin, force_Touch = (Fy, Fz, Fx): a proper
//! rotation (a cyclic permutation of the axes), the same for position and force. m, N.
#pragma once

#include <Eigen/Core>
#include <endohaptics/kinematics/denavit_hartenberg.hpp>

namespace bridge {

//! Where the HD origin lies in the mapping frame (m), assumed: the gimbal centre at the Touch's
//! zero pose, (a3, 0, d1 - d4) of the default kinematics::TouchGeometry (openhaptics_device.hpp
//! says why; docs/models/cylindrical_mapper.md, "Mapping frame", how to measure it).
[[nodiscard]] inline Eigen::Vector3d default_hd_origin() noexcept {
  const endohaptics::kinematics::TouchGeometry<double> g;
  return {g.a3, 0.0, g.d1 - g.d4};
}

//! Touch frame position (m) to the mapping frame (m).
[[nodiscard]] inline Eigen::Vector3d touch_to_mapping_position(
    const Eigen::Vector3d& p_touch,
    const Eigen::Vector3d& hd_origin = default_hd_origin()) noexcept {
  return Eigen::Vector3d(p_touch.z(), p_touch.x(), p_touch.y()) + hd_origin;
}

//! Mapping-frame force (N) to the Touch frame (N): the inverse rotation of
//! touch_to_mapping_position (forces are free vectors: no origin).
[[nodiscard]] inline Eigen::Vector3d mapping_to_touch_force(const Eigen::Vector3d& f) noexcept {
  return {f.y(), f.z(), f.x()};
}

//! Mapping-frame position (m) to the Touch frame (m): the inverse of touch_to_mapping_position
//! (for stand-ins and tests that play the Touch).
[[nodiscard]] inline Eigen::Vector3d mapping_to_touch_position(
    const Eigen::Vector3d& p, const Eigen::Vector3d& hd_origin = default_hd_origin()) noexcept {
  const Eigen::Vector3d d = p - hd_origin;
  return {d.y(), d.z(), d.x()};
}

//! Touch-frame force (N) to the mapping frame: the inverse of mapping_to_touch_force.
[[nodiscard]] inline Eigen::Vector3d touch_to_mapping_force(const Eigen::Vector3d& f) noexcept {
  return {f.z(), f.x(), f.y()};
}

}  // namespace bridge
