//! @file
//! The `HapticDevice` concept: what a TeleopLoop needs from the operator's stylus (a Geomagic
//! Touch in the 2016 rig, worksheet 2.6): read a sample (position in m, base frame, z up; buttons)
//! and command a Cartesian force (N). Both calls are noexcept and must not block for long.
#pragma once

#include <Eigen/Core>
#include <concepts>
#include <cstdint>
#include <string_view>

namespace endohaptics::teleop {

//! Outcome of a device read or force command.
enum class DeviceStatus : std::uint8_t {
  ok = 0,     //!< the sample was read / the force was commanded
  not_ready,  //!< no new sample yet / device still calibrating: try again next tick
  error,      //!< the device failed (unplugged, driver error): the loop must not trust it
};

//! Short human-readable description of `status` (for logs and error messages).
[[nodiscard]] constexpr std::string_view to_string(DeviceStatus status) noexcept {
  switch (status) {
    case DeviceStatus::ok:
      return "ok";
    case DeviceStatus::not_ready:
      return "device not ready";
    case DeviceStatus::error:
      return "device error";
  }
  return "unknown status";
}

//! One reading of the stylus.
struct StylusSample {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  //!< m, device base frame, z up
  std::uint8_t buttons = 0;                            //!< bit i: button i pressed
};

//! A stylus usable from the real-time tick: `read` fills a StylusSample, `command_force` applies
//! a Cartesian force (N); both are noexcept and return DeviceStatus.
template <typename D>
concept HapticDevice = requires(D& device, StylusSample& sample, const Eigen::Vector3d& force) {
  { device.read(sample) }
  noexcept->std::same_as<DeviceStatus>;
  { device.command_force(force) }
  noexcept->std::same_as<DeviceStatus>;
};

}  // namespace endohaptics::teleop
