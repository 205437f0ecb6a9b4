//! @file
//! A Geomagic Touch through the OpenHaptics HD API, as a teleop::HapticDevice. Built into the
//! bridge (`--device openhaptics`) only when CMake finds the SDK (docs/rig.md); always built by
//! the tests against the HD stand-in in tests/openhaptics_standin. Same HD calls either way.
#pragma once

#include <HD/hd.h>

#include <Eigen/Core>
#include <array>
#include <atomic>
#include <charconv>
#include <cstdint>
#include <endohaptics/core/error.hpp>
#include <endohaptics/kinematics/denavit_hartenberg.hpp>
#include <endohaptics/teleop/haptic_device.hpp>
#include <endohaptics/teleop/latest_value.hpp>
#include <string>

#include "touch_frame.hpp"

// Frames and units. The HD API reports HD_CURRENT_POSITION (the gimbal centre) in mm and takes
// HD_CURRENT_FORCE in N, both in the Touch's frame: x to the operator's right, y up, z towards the
// operator (right-handed). The library takes positions and forces in CylindricalMapper's mapping
// frame (include/endohaptics/kinematics/cylindrical_mapper.hpp): origin on the waist axis at the
// desk, x towards the operator (the neutral direction), y to the operator's right, z up; m, N:
//     position = (z, x, y)_Touch / 1000 + hd_origin        force_Touch = (Fy, Fz, Fx)
// a proper rotation (det +1; a cyclic permutation of the axes), the same one for position and
// force, so the force does the same work along a stylus motion in both frames. hd_origin is where
// the HD origin lies in the mapping frame. Default (assumed, not measured): the gimbal centre with
// the upper arm horizontal and the forearm vertical, which is where the published HD-frame
// kinematics of the Phantom (x = -sin q1 (l1 cos q2 + l2 sin q3), y = l1 sin q2 - l2 cos q3 + l2,
// z = -l1 + cos q1 (l1 cos q2 + l2 sin q3), q3 absolute; Ubitrack's FWKinematicPhantom with no
// origin correction) puts it: (a3, 0, d1 - d4) of kinematics::TouchGeometry = (0.133, 0, -0.008)
// m. Measure it on the rig (docs/models/cylindrical_mapper.md, "Mapping frame") and pass it in.
//
// Threads. The HD servo loop (hdScheduleAsynchronous, highest priority, ~1 kHz, the SDK's thread)
// reads the stylus and writes the force inside hdBeginFrame/hdEndFrame. It exchanges them with the
// TeleopLoop thread through two wait-free triple buffers (LatestValue): no lock, no allocation,
// the newest value wins, a sample is never torn. read() and command_force() are for one thread
// (the loop's); constructor and destructor for the owner.
//
// Errors. hdInitDevice or another set-up call failing throws endohaptics::Error with the HD text
// and code, after undoing what was done. While the Touch needs calibration read() is not_ready and
// no force is sent; calibrations the SDK can finish alone (auto, or inkwell once the stylus is in
// the inkwell) are requested with hdUpdateCalibration. Any HD error in a servo frame (hdGetError)
// is final: force output off, the servo callback ends, read() and command_force() return
// DeviceStatus::error from then on.

namespace bridge {

//! Touch frame position (mm, as the HD API reports it) to the mapping frame (m): touch_frame.hpp.
[[nodiscard]] inline Eigen::Vector3d touch_to_mapping_position(
    const HDdouble (&p_mm)[3], const Eigen::Vector3d& hd_origin = default_hd_origin()) noexcept {
  return touch_to_mapping_position(Eigen::Vector3d(p_mm[0], p_mm[1], p_mm[2]) * 1e-3, hd_origin);
}

//! Mapping-frame force (N) to the Touch frame, as hdSetDoublev takes it: touch_frame.hpp.
[[nodiscard]] inline std::array<HDdouble, 3> mapping_to_touch_force_hd(
    const Eigen::Vector3d& f) noexcept {
  const Eigen::Vector3d t = mapping_to_touch_force(f);
  return {t.x(), t.y(), t.z()};
}

using endohaptics::teleop::LatestValue;

//! A Geomagic Touch as a teleop::HapticDevice (frames, threads and errors: see the file comment).
class OpenHapticsDevice {
 public:
  //! Opens the default device, enables force output with ramping, schedules the servo callback
  //! and starts the scheduler. `hd_origin`: the HD origin in the mapping frame (m). Throws
  //! endohaptics::Error naming a non-finite `hd_origin`, or with the HD error text on failure
  //! (after undoing what was already done).
  explicit OpenHapticsDevice(const Eigen::Vector3d& hd_origin = default_hd_origin())
      : hd_origin_(hd_origin) {
    if (!hd_origin_.allFinite()) {
      throw endohaptics::Error("OpenHapticsDevice: hd_origin must be finite, got (" +
                               endohaptics::detail::format_number(hd_origin_.x()) + ", " +
                               endohaptics::detail::format_number(hd_origin_.y()) + ", " +
                               endohaptics::detail::format_number(hd_origin_.z()) + ") m");
    }
    device_ = hdInitDevice(HD_DEFAULT_DEVICE);
    check("hdInitDevice");
    try {
      HDint styles = 0;
      hdGetIntegerv(HD_CALIBRATION_STYLE, &styles);
      check("hdGetIntegerv(HD_CALIBRATION_STYLE)");
      // What the servo loop may finish alone: auto, else inkwell (once the stylus is in it). An
      // encoder reset needs the arm held at its reset position: left to the vendor's tools.
      if ((styles & HD_CALIBRATION_AUTO) != 0) {
        calibration_style_ = HD_CALIBRATION_AUTO;
      } else if ((styles & HD_CALIBRATION_INKWELL) != 0) {
        calibration_style_ = HD_CALIBRATION_INKWELL;
      }
      hdEnable(HD_FORCE_OUTPUT);
      check("hdEnable(HD_FORCE_OUTPUT)");
      hdEnable(HD_FORCE_RAMPING);  // the device ramps force in after a (re)start, not a step
      check("hdEnable(HD_FORCE_RAMPING)");
      servo_ = hdScheduleAsynchronous(&OpenHapticsDevice::servo, this, HD_MAX_SCHEDULER_PRIORITY);
      check("hdScheduleAsynchronous");
      scheduled_ = true;
      hdStartScheduler();
      stop_scheduler_ = true;  // stopped on the way out even if the start reported an error
      check("hdStartScheduler");
      running_ = true;
    } catch (...) {
      shutdown();
      throw;
    }
  }

  //! Sends zero force, stops the scheduler, unschedules the servo callback, disables the device.
  ~OpenHapticsDevice() { shutdown(); }

  OpenHapticsDevice(const OpenHapticsDevice&) = delete;
  OpenHapticsDevice& operator=(const OpenHapticsDevice&) = delete;
  OpenHapticsDevice(OpenHapticsDevice&&) = delete;
  OpenHapticsDevice& operator=(OpenHapticsDevice&&) = delete;

  //! The newest stylus sample (mapping frame, m). not_ready before the first servo frame and while
  //! the Touch needs calibration; error after an HD error. Wait-free, no allocation.
  endohaptics::teleop::DeviceStatus read(endohaptics::teleop::StylusSample& sample) noexcept {
    using endohaptics::teleop::DeviceStatus;
    if (failed_.load(std::memory_order_acquire)) return DeviceStatus::error;
    if (calibration_.load(std::memory_order_acquire) != HD_CALIBRATION_OK) {
      return DeviceStatus::not_ready;
    }
    return samples_.read(sample) ? DeviceStatus::ok : DeviceStatus::not_ready;
  }

  //! Sets the force (mapping frame, N) the servo loop sends from its next frame on; a non-finite
  //! force is sent as zero. error after an HD error. Wait-free, no allocation.
  endohaptics::teleop::DeviceStatus command_force(const Eigen::Vector3d& force) noexcept {
    using endohaptics::teleop::DeviceStatus;
    if (failed_.load(std::memory_order_acquire)) return DeviceStatus::error;
    forces_.publish(force.allFinite() ? mapping_to_touch_force_hd(force)
                                      : std::array<HDdouble, 3>{});
    return DeviceStatus::ok;
  }

  //! hdCheckCalibration in the newest servo frame (0 before the first frame).
  [[nodiscard]] HDenum calibration_status() const noexcept {
    return calibration_.load(std::memory_order_acquire);
  }

  //! The HD error that stopped the servo loop; HD_SUCCESS while it runs.
  [[nodiscard]] HDerror error_code() const noexcept {
    return error_code_.load(std::memory_order_acquire);
  }

 private:
  // The servo loop: one frame per scheduler tick, on the HD scheduler thread.
  static HDCallbackCode HDCALLBACK servo(void* self_ptr) {
    auto* self = static_cast<OpenHapticsDevice*>(self_ptr);
    hdBeginFrame(self->device_);
    HDdouble position[3] = {0.0, 0.0, 0.0};
    HDint buttons = 0;
    hdGetDoublev(HD_CURRENT_POSITION, position);
    hdGetIntegerv(HD_CURRENT_BUTTONS, &buttons);
    const HDenum calibration = hdCheckCalibration();
    std::array<HDdouble, 3> force{0.0, 0.0, 0.0};
    if (calibration == HD_CALIBRATION_OK && !self->stopping_.load(std::memory_order_acquire)) {
      (void)self->forces_.read(force);  // stays zero until the loop commands one
    }
    hdSetDoublev(HD_CURRENT_FORCE, force.data());
    hdEndFrame(self->device_);
    if (calibration == HD_CALIBRATION_NEEDS_UPDATE && self->calibration_style_ != 0) {
      hdUpdateCalibration(self->calibration_style_);
    }

    const HDErrorInfo error = hdGetError();
    if (HD_DEVICE_ERROR(error)) {
      hdDisable(HD_FORCE_OUTPUT);
      self->error_code_.store(error.errorCode, std::memory_order_release);
      self->failed_.store(true, std::memory_order_release);  // the loop sees DeviceStatus::error
      return HD_CALLBACK_DONE;
    }
    if (calibration == HD_CALIBRATION_OK) {
      endohaptics::teleop::StylusSample sample;
      sample.position = touch_to_mapping_position(position, self->hd_origin_);
      sample.buttons = static_cast<std::uint8_t>(buttons & 0xff);
      self->samples_.publish(sample);
    }
    self->calibration_.store(calibration, std::memory_order_release);
    return HD_CALLBACK_CONTINUE;
  }

  // One frame with zero force, run synchronously before the scheduler stops.
  static HDCallbackCode HDCALLBACK zero_force(void* self_ptr) {
    auto* self = static_cast<OpenHapticsDevice*>(self_ptr);
    const HDdouble zero[3] = {0.0, 0.0, 0.0};
    hdBeginFrame(self->device_);
    hdSetDoublev(HD_CURRENT_FORCE, zero);
    hdEndFrame(self->device_);
    return HD_CALLBACK_DONE;
  }

  // Undoes the constructor's steps that were done, in the SDK examples' order.
  void shutdown() noexcept {
    if (running_) {
      stopping_.store(true, std::memory_order_release);  // the servo sends zero from now on
      hdScheduleSynchronous(&OpenHapticsDevice::zero_force, this, HD_DEFAULT_SCHEDULER_PRIORITY);
    }
    if (stop_scheduler_) hdStopScheduler();
    if (scheduled_) hdUnschedule(servo_);
    hdDisableDevice(device_);
    // Leave no error of ours on the HD error stack for the next user of the API.
    for (int i = 0; i < 64 && HD_DEVICE_ERROR(hdGetError()); ++i) {
    }
  }

  // Throws if the HD API reported an error since the last check.
  static void check(const char* what) {
    const HDErrorInfo error = hdGetError();
    if (!HD_DEVICE_ERROR(error)) return;
    throw endohaptics::Error(std::string("OpenHaptics: ") + what +
                             " failed: " + hdGetErrorString(error.errorCode) + " (HD error 0x" +
                             hex(error.errorCode) + ", internal " +
                             std::to_string(error.internalErrorCode) + ")");
  }

  static std::string hex(HDerror code) {
    char text[16] = {};
    const auto end = std::to_chars(text, text + sizeof(text), code, 16).ptr;
    std::string digits(text, end);
    return std::string(digits.size() < 4 ? 4 - digits.size() : 0, '0') + digits;
  }

  Eigen::Vector3d hd_origin_;  // the HD origin in the mapping frame, m
  HHD device_ = HD_INVALID_HANDLE;
  HDSchedulerHandle servo_ = 0;
  bool scheduled_ = false;        // hdUnschedule(servo_) on the way out
  bool stop_scheduler_ = false;   // hdStopScheduler on the way out
  bool running_ = false;          // the scheduler started: synchronous calls return
  HDenum calibration_style_ = 0;  // 0: the servo loop never calibrates by itself
  LatestValue<endohaptics::teleop::StylusSample> samples_;  // servo -> loop
  LatestValue<std::array<HDdouble, 3>> forces_;             // loop -> servo, Touch frame
  std::atomic<HDenum> calibration_{0};
  std::atomic<HDerror> error_code_{HD_SUCCESS};
  std::atomic<bool> failed_{false};
  std::atomic<bool> stopping_{false};
  static_assert(std::atomic<HDenum>::is_always_lock_free && std::atomic<bool>::is_always_lock_free);
};

}  // namespace bridge
