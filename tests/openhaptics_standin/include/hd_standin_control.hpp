//! @file
//! Test control of the HD API stand-in (<HD/hd.h> in this folder): one simulated Geomagic Touch
//! behind the HD functions. Tests set the stylus (device frame, mm), read the force the code under
//! test sent (device frame, N), make calls fail, ask for calibration, inject HD errors, and run
//! the scheduler on its own thread (~1 kHz, or back to back) or tick it by hand.
#pragma once

#include <HD/hd.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

namespace hd_standin {

//! x, y, z in the HD device frame: x right, y up, z towards the user.
using Vec3 = std::array<double, 3>;

//! Who runs the scheduler ticks once hdStartScheduler is called.
enum class Scheduler : std::uint8_t {
  thread,  //!< a std::thread started by hdStartScheduler, one tick per period (0: back to back)
  manual,  //!< no thread: step() runs ticks on the caller (hdScheduleSynchronous does too)
};

//! HD calls that fail_next can make fail once.
enum class Call : std::uint8_t {
  init_device,         //!< hdInitDevice returns HD_INVALID_HANDLE ("no device")
  enable,              //!< hdEnable leaves the capability unchanged
  schedule,            //!< hdScheduleAsynchronous schedules nothing
  start_scheduler,     //!< hdStartScheduler starts nothing
  end_frame,           //!< hdEndFrame sends no force (a fault during a servo frame)
  update_calibration,  //!< hdUpdateCalibration leaves the calibration unchanged
};

//! A snapshot of the simulated device, for assertions.
struct State {
  bool device_open = false;        //!< hdInitDevice succeeded, hdDisableDevice not yet called
  bool scheduler_running = false;  //!< between hdStartScheduler and hdStopScheduler
  int callbacks_scheduled = 0;     //!< asynchronous callbacks still in the scheduler
  bool force_output = false;       //!< HD_FORCE_OUTPUT enabled
  bool force_ramping = false;      //!< HD_FORCE_RAMPING enabled
  HDenum calibration = HD_CALIBRATION_OK;  //!< what hdCheckCalibration returns
  std::uint64_t ticks = 0;                 //!< scheduler ticks run
  std::uint64_t frames = 0;                //!< hdBeginFrame/hdEndFrame pairs completed
  std::uint64_t calibration_updates = 0;   //!< successful hdUpdateCalibration calls
  int errors_pending = 0;                  //!< errors on the stack, not yet read by hdGetError
  Vec3 force_n{};                          //!< force sent to the motors at the last hdEndFrame
  std::uint64_t misuse = 0;                //!< API contract violations seen (see first_misuse)
  std::string first_misuse;  //!< the first violation, e.g. "hdSetDoublev outside a frame"
};

//! Everything back to defaults (stops a running scheduler thread); call at the start of a test.
//! Defaults: thread scheduler at 1 ms, stylus at the origin, no buttons, calibration ok,
//! calibration style HD_CALIBRATION_INKWELL (the Touch's), no failures armed, empty error stack.
void reset();

//! Selects who runs the ticks (before hdStartScheduler); `period` is the thread's tick period.
void set_scheduler(Scheduler mode, std::chrono::nanoseconds period = std::chrono::milliseconds(1));

//! Manual mode: runs `ticks` scheduler ticks on the calling thread; returns how many ran (0 when
//! the scheduler is not started).
std::uint64_t step(std::uint64_t ticks = 1);

//! Thread mode: waits until `ticks` more ticks have run; false on timeout.
bool wait_ticks(std::uint64_t ticks, std::chrono::milliseconds timeout);

//! The stylus position that the next frames report (HD_CURRENT_POSITION, mm).
void set_position_mm(const Vec3& position);

//! The buttons the next frames report (HD_CURRENT_BUTTONS).
void set_buttons(HDint buttons);

//! Called at every hdBeginFrame on the scheduler thread with the tick number; may move the
//! stylus (mm). Replaces set_position_mm while set; an empty function removes it.
void set_position_script(std::function<void(std::uint64_t tick, Vec3& position_mm)> script);

//! Called at every hdEndFrame on the scheduler thread with the force sent to the motors (N).
void set_force_observer(std::function<void(std::uint64_t tick, const Vec3& force_n)> observer);

//! Makes the next call of `call` fail with `code` (pushed on the error stack as it would be).
void fail_next(Call call, HDerror code, int internal_code = 0);

//! What hdCheckCalibration returns from now on (hdUpdateCalibration turns NEEDS_UPDATE into OK).
void set_calibration(HDenum status);

//! The calibration styles the device supports (HD_CALIBRATION_STYLE).
void set_calibration_styles(HDint styles);

//! Pushes an error on the HD error stack now; the next hdGetError (on any thread) returns it.
void push_error(HDerror code, int internal_code = 0);

//! The simulated device's state now.
State state();

}  // namespace hd_standin
