// A Geomagic Touch through the OpenHaptics HD API, as a teleop::HapticDevice. Compiled only when
// the OpenHaptics SDK is found (CMake: ENDOHAPTICS_OPENHAPTICS_ROOT or the default /usr paths;
// see docs/rig.md). The HD servo loop (1 kHz, its own thread, hdScheduleAsynchronous) reads
// HD_CURRENT_POSITION and writes HD_CURRENT_FORCE; it exchanges them with the TeleopLoop thread
// through lock-free atomics only. Frames: the Touch's (x right, y up, z towards the user, mm) is
// turned into the library's base frame (x right, y away from the user, z up, m).
#pragma once

#include <HD/hd.h>

#include <Eigen/Core>
#include <atomic>
#include <endohaptics/core/error.hpp>
#include <endohaptics/teleop/haptic_device.hpp>
#include <string>

namespace bridge {

class OpenHapticsDevice {
 public:
  //! Opens the default device, enables force output with ramping, starts the servo loop.
  //! Throws endohaptics::Error with the HD error text on failure.
  OpenHapticsDevice() {
    device_ = hdInitDevice(HD_DEFAULT_DEVICE);
    check("hdInitDevice");
    hdEnable(HD_FORCE_OUTPUT);
    hdEnable(HD_FORCE_RAMPING);  // the device ramps force in after a (re)start, not a step
    check("hdEnable");
    callback_ =
        hdScheduleAsynchronous(&OpenHapticsDevice::servo, this, HD_DEFAULT_SCHEDULER_PRIORITY);
    hdStartScheduler();
    check("hdStartScheduler");
  }

  ~OpenHapticsDevice() {
    for (auto& f : force_) f.store(0.0);
    hdStopScheduler();
    hdUnschedule(callback_);
    hdDisableDevice(device_);
  }

  OpenHapticsDevice(const OpenHapticsDevice&) = delete;
  OpenHapticsDevice& operator=(const OpenHapticsDevice&) = delete;

  endohaptics::teleop::DeviceStatus read(endohaptics::teleop::StylusSample& sample) noexcept {
    if (failed_.load(std::memory_order_acquire)) return endohaptics::teleop::DeviceStatus::error;
    if (!fresh_.load(std::memory_order_acquire))
      return endohaptics::teleop::DeviceStatus::not_ready;
    sample.position = Eigen::Vector3d(position_[0].load(std::memory_order_relaxed),
                                      position_[1].load(std::memory_order_relaxed),
                                      position_[2].load(std::memory_order_relaxed));
    sample.buttons = static_cast<std::uint8_t>(buttons_.load(std::memory_order_relaxed));
    return endohaptics::teleop::DeviceStatus::ok;
  }

  endohaptics::teleop::DeviceStatus command_force(const Eigen::Vector3d& f) noexcept {
    if (failed_.load(std::memory_order_acquire)) return endohaptics::teleop::DeviceStatus::error;
    for (int i = 0; i < 3; ++i) force_[i].store(f[i], std::memory_order_relaxed);
    return endohaptics::teleop::DeviceStatus::ok;
  }

 private:
  static HDCallbackCode HDCALLBACK servo(void* self_ptr) {
    auto* self = static_cast<OpenHapticsDevice*>(self_ptr);
    hdBeginFrame(self->device_);
    HDdouble p[3];
    HDint buttons = 0;
    hdGetDoublev(HD_CURRENT_POSITION, p);
    hdGetIntegerv(HD_CURRENT_BUTTONS, &buttons);
    // Touch (x right, y up, z towards the user, mm) -> base (x right, y away, z up, m).
    self->position_[0].store(p[0] * 1e-3, std::memory_order_relaxed);
    self->position_[1].store(-p[2] * 1e-3, std::memory_order_relaxed);
    self->position_[2].store(p[1] * 1e-3, std::memory_order_relaxed);
    self->buttons_.store(buttons, std::memory_order_relaxed);
    const HDdouble f[3] = {self->force_[0].load(std::memory_order_relaxed),
                           self->force_[2].load(std::memory_order_relaxed),
                           -self->force_[1].load(std::memory_order_relaxed)};
    hdSetDoublev(HD_CURRENT_FORCE, f);
    hdEndFrame(self->device_);
    self->fresh_.store(true, std::memory_order_release);
    const HDErrorInfo error = hdGetError();
    if (HD_DEVICE_ERROR(error)) {
      self->failed_.store(true, std::memory_order_release);  // the loop sees DeviceStatus::error
      return HD_CALLBACK_DONE;
    }
    return HD_CALLBACK_CONTINUE;
  }

  static void check(const char* what) {
    const HDErrorInfo error = hdGetError();
    if (HD_DEVICE_ERROR(error)) {
      throw endohaptics::Error(std::string("OpenHaptics: ") + what +
                               " failed: " + hdGetErrorString(error.errorCode));
    }
  }

  HHD device_ = HD_INVALID_HANDLE;
  HDSchedulerHandle callback_ = 0;
  std::atomic<double> position_[3] = {0.0, 0.0, 0.0};
  std::atomic<double> force_[3] = {0.0, 0.0, 0.0};
  std::atomic<int> buttons_{0};
  std::atomic<bool> fresh_{false};
  std::atomic<bool> failed_{false};
};

}  // namespace bridge
