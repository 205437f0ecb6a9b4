// The simulated Geomagic Touch behind the HD API stand-in (include/HD/hd.h) and its test control
// (include/hd_standin_control.hpp). One device, one scheduler and one error stack per process,
// guarded by one recursive mutex: this is test scaffolding, not real-time code (the adapter's own
// hand-off is what must be lock-free). A tick never allocates, so allocation-counting tests may run
// while the scheduler thread ticks.
//
// Where the HD reference only says "should" (frames inside scheduler callbacks, force set inside a
// frame, scheduler stopped and callbacks unscheduled before hdDisableDevice, every capability
// enabled explicitly), the stand-in is stricter: it counts a violation in State::misuse.
#include <HD/hd.h>

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdio>
#include <hd_standin_control.hpp>
#include <mutex>
#include <thread>
#include <utility>

namespace hd_standin {
namespace {

constexpr HHD kHandle = 1;  // not 0: a zero-initialised handle is caught as HD_BAD_HANDLE
constexpr std::size_t kMaxCallbacks = 32;
constexpr std::size_t kMaxErrors = 32;
constexpr std::size_t kCalls = 6;
constexpr std::size_t kCaps = HD_ONE_FRAME_LIMIT - HD_FORCE_OUTPUT + 1;

struct Entry {
  HDSchedulerCallback fn = nullptr;
  void* data = nullptr;
  HDushort priority = 0;
  HDSchedulerHandle handle = 0;
};

struct Armed {
  bool armed = false;
  HDerror code = HD_SUCCESS;
  int internal = 0;
};

struct Device {
  std::recursive_mutex mutex;
  std::condition_variable_any changed;  // a tick ended, or the scheduler stopped
  std::thread thread;
  std::atomic<bool> stop{false};

  // Configuration (test control).
  Scheduler mode = Scheduler::thread;
  std::chrono::nanoseconds period = std::chrono::milliseconds(1);
  Vec3 position{};
  HDint buttons = 0;
  HDenum calibration = HD_CALIBRATION_OK;
  HDint styles = HD_CALIBRATION_INKWELL;
  std::function<void(std::uint64_t, Vec3&)> script;
  std::function<void(std::uint64_t, const Vec3&)> observer;
  std::array<Armed, kCalls> armed{};

  // Device.
  bool open = false;
  std::array<bool, kCaps> caps{};
  bool in_frame = false;
  Vec3 frame_force{};
  Vec3 output_force{};

  // Error stack (most recent last).
  std::array<HDErrorInfo, kMaxErrors> errors{};
  std::size_t error_count = 0;

  // Scheduler: entries sorted by priority, highest first, then by scheduling order.
  std::array<Entry, kMaxCallbacks> entries{};
  std::size_t entry_count = 0;
  HDSchedulerHandle next_handle = 1;
  bool running = false;
  bool in_tick = false;
  std::thread::id tick_thread{};

  // Counters.
  std::uint64_t ticks = 0;
  std::uint64_t frames = 0;
  std::uint64_t calibration_updates = 0;
  std::uint64_t misuse = 0;
  std::array<char, 160> first_misuse{};

  Device() = default;
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;
  ~Device() {
    stop.store(true);
    if (thread.joinable()) thread.join();
  }
};

Device& dev() {
  static Device device;
  return device;
}

using Lock = std::unique_lock<std::recursive_mutex>;

void push(Device& d, HDerror code, int internal) {
  if (d.error_count == kMaxErrors) {  // drop the oldest
    for (std::size_t i = 1; i < kMaxErrors; ++i) d.errors[i - 1] = d.errors[i];
    --d.error_count;
  }
  d.errors[d.error_count++] = HDErrorInfo{code, internal, d.open ? kHandle : HD_INVALID_HANDLE};
}

void misuse(Device& d, const char* what) {
  if (d.misuse++ == 0) std::snprintf(d.first_misuse.data(), d.first_misuse.size(), "%s", what);
}

bool take_failure(Device& d, Call call) {
  Armed& a = d.armed[static_cast<std::size_t>(call)];
  if (!a.armed) return false;
  a.armed = false;
  push(d, a.code, a.internal);
  return true;
}

bool on_tick_thread(const Device& d) {
  return d.in_tick && d.tick_thread == std::this_thread::get_id();
}

bool valid_handle(Device& d, HHD handle) {
  if (d.open && handle == kHandle) return true;
  push(d, HD_BAD_HANDLE, 0);
  return false;
}

bool device_open(Device& d) {
  if (d.open) return true;
  push(d, HD_INVALID_OPERATION, 0);
  return false;
}

// Index of a capability in Device::caps, or kCaps if `cap` is not one.
std::size_t cap_index(HDenum cap) {
  if (cap < HD_FORCE_OUTPUT || cap > HD_ONE_FRAME_LIMIT) return kCaps;
  return static_cast<std::size_t>(cap - HD_FORCE_OUTPUT);
}

std::size_t find(const Device& d, HDSchedulerHandle handle) {
  for (std::size_t i = 0; i < d.entry_count; ++i) {
    if (d.entries[i].handle == handle) return i;
  }
  return kMaxCallbacks;
}

void remove(Device& d, std::size_t at) {
  for (std::size_t i = at + 1; i < d.entry_count; ++i) d.entries[i - 1] = d.entries[i];
  --d.entry_count;
}

// Inserts after every entry of higher or equal priority; returns its handle, 0 if full.
HDSchedulerHandle insert(Device& d, HDSchedulerCallback fn, void* data, HDushort priority) {
  if (d.entry_count == kMaxCallbacks) {
    push(d, HD_SCHEDULER_FULL, 0);
    return 0;
  }
  std::size_t at = 0;
  while (at < d.entry_count && d.entries[at].priority >= priority) ++at;
  for (std::size_t i = d.entry_count; i > at; --i) d.entries[i] = d.entries[i - 1];
  d.entries[at] = Entry{fn, data, priority, d.next_handle++};
  ++d.entry_count;
  return d.entries[at].handle;
}

// One scheduler tick: every callback scheduled when it starts, by priority. Mutex held.
void run_tick(Device& d) {
  d.in_tick = true;
  d.tick_thread = std::this_thread::get_id();
  ++d.ticks;
  std::array<HDSchedulerHandle, kMaxCallbacks> order{};
  const std::size_t n = d.entry_count;
  for (std::size_t i = 0; i < n; ++i) order[i] = d.entries[i].handle;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t at = find(d, order[i]);
    if (at == kMaxCallbacks) continue;  // unscheduled by an earlier callback
    const Entry entry = d.entries[at];
    const HDCallbackCode code = entry.fn(entry.data);
    if (d.in_frame) {
      misuse(d, "a callback returned inside a frame (hdBeginFrame without hdEndFrame)");
      d.in_frame = false;
    }
    if (code == HD_CALLBACK_DONE) {
      const std::size_t now_at = find(d, entry.handle);
      if (now_at != kMaxCallbacks) remove(d, now_at);
    }
  }
  d.in_tick = false;
}

void scheduler_main(Device& d, std::chrono::nanoseconds period) {
  auto next = std::chrono::steady_clock::now();
  while (!d.stop.load(std::memory_order_acquire)) {
    {
      Lock lock(d.mutex);
      if (!d.running) break;
      run_tick(d);
    }
    d.changed.notify_all();
    if (period.count() > 0) {
      next += period;
      const auto now = std::chrono::steady_clock::now();
      if (next < now) next = now;  // fell behind: no burst of catch-up ticks
      std::this_thread::sleep_until(next);
    } else {
      std::this_thread::yield();
    }
  }
}

// Stops and joins the scheduler thread, if any. Mutex not held.
void stop_thread(Device& d) {
  std::thread thread;
  {
    Lock lock(d.mutex);
    d.running = false;
    thread = std::move(d.thread);
  }
  if (thread.joinable()) {
    d.stop.store(true, std::memory_order_release);
    thread.join();
    d.stop.store(false, std::memory_order_release);
  }
  d.changed.notify_all();
}

}  // namespace

void reset() {
  Device& d = dev();
  stop_thread(d);
  Lock lock(d.mutex);
  d.mode = Scheduler::thread;
  d.period = std::chrono::milliseconds(1);
  d.position = {};
  d.buttons = 0;
  d.calibration = HD_CALIBRATION_OK;
  d.styles = HD_CALIBRATION_INKWELL;
  d.script = nullptr;
  d.observer = nullptr;
  d.armed = {};
  d.open = false;
  d.caps = {};
  d.in_frame = false;
  d.frame_force = {};
  d.output_force = {};
  d.error_count = 0;
  d.entry_count = 0;
  d.next_handle = 1;
  d.running = false;
  d.in_tick = false;
  d.ticks = 0;
  d.frames = 0;
  d.calibration_updates = 0;
  d.misuse = 0;
  d.first_misuse = {};
}

void set_scheduler(Scheduler mode, std::chrono::nanoseconds period) {
  Device& d = dev();
  Lock lock(d.mutex);
  if (d.running) misuse(d, "set_scheduler while the scheduler runs");
  d.mode = mode;
  d.period = period;
}

std::uint64_t step(std::uint64_t ticks) {
  Device& d = dev();
  Lock lock(d.mutex);
  if (!d.running || d.mode != Scheduler::manual || on_tick_thread(d)) return 0;
  for (std::uint64_t i = 0; i < ticks; ++i) run_tick(d);
  lock.unlock();
  d.changed.notify_all();
  return ticks;
}

bool wait_ticks(std::uint64_t ticks, std::chrono::milliseconds timeout) {
  Device& d = dev();
  Lock lock(d.mutex);
  const std::uint64_t target = d.ticks + ticks;
  return d.changed.wait_for(lock, timeout, [&] { return d.ticks >= target; });
}

void set_position_mm(const Vec3& position) {
  Device& d = dev();
  Lock lock(d.mutex);
  d.position = position;
}

void set_buttons(HDint buttons) {
  Device& d = dev();
  Lock lock(d.mutex);
  d.buttons = buttons;
}

void set_position_script(std::function<void(std::uint64_t, Vec3&)> script) {
  Device& d = dev();
  Lock lock(d.mutex);
  d.script = std::move(script);
}

void set_force_observer(std::function<void(std::uint64_t, const Vec3&)> observer) {
  Device& d = dev();
  Lock lock(d.mutex);
  d.observer = std::move(observer);
}

void fail_next(Call call, HDerror code, int internal_code) {
  Device& d = dev();
  Lock lock(d.mutex);
  d.armed[static_cast<std::size_t>(call)] = Armed{true, code, internal_code};
}

void set_calibration(HDenum status) {
  Device& d = dev();
  Lock lock(d.mutex);
  d.calibration = status;
}

void set_calibration_styles(HDint styles) {
  Device& d = dev();
  Lock lock(d.mutex);
  d.styles = styles;
}

void push_error(HDerror code, int internal_code) {
  Device& d = dev();
  Lock lock(d.mutex);
  push(d, code, internal_code);
}

State state() {
  Device& d = dev();
  Lock lock(d.mutex);
  State s;
  s.device_open = d.open;
  s.scheduler_running = d.running;
  s.callbacks_scheduled = static_cast<int>(d.entry_count);
  s.force_output = d.caps[cap_index(HD_FORCE_OUTPUT)];
  s.force_ramping = d.caps[cap_index(HD_FORCE_RAMPING)];
  s.calibration = d.calibration;
  s.ticks = d.ticks;
  s.frames = d.frames;
  s.calibration_updates = d.calibration_updates;
  s.errors_pending = static_cast<int>(d.error_count);
  s.force_n = d.output_force;
  s.misuse = d.misuse;
  s.first_misuse = d.first_misuse.data();
  return s;
}

}  // namespace hd_standin

// ---- The HD API ---------------------------------------------------------------------------------
using hd_standin::Call;
using hd_standin::dev;
using hd_standin::Device;
using hd_standin::Lock;
using hd_standin::Scheduler;
using hd_standin::Vec3;

extern "C" {

HHD hdInitDevice(HDstring /*pConfigName: any name opens the one simulated device*/) {
  Device& d = dev();
  Lock lock(d.mutex);
  if (hd_standin::take_failure(d, Call::init_device)) return HD_INVALID_HANDLE;
  if (d.open) {
    hd_standin::push(d, HD_DEVICE_ALREADY_INITIATED, 0);
    return HD_INVALID_HANDLE;
  }
  d.open = true;
  d.caps = {};
  d.in_frame = false;
  d.output_force = {};
  return hd_standin::kHandle;
}

void hdDisableDevice(HHD hHD) {
  Device& d = dev();
  Lock lock(d.mutex);
  if (!hd_standin::valid_handle(d, hHD)) return;
  if (d.running) hd_standin::misuse(d, "hdDisableDevice while the scheduler runs");
  if (d.entry_count > 0) hd_standin::misuse(d, "hdDisableDevice with callbacks still scheduled");
  d.open = false;
  d.caps = {};
  d.output_force = {};
}

void hdBeginFrame(HHD hHD) {
  Device& d = dev();
  Lock lock(d.mutex);
  if (!hd_standin::valid_handle(d, hHD)) return;
  if (!hd_standin::on_tick_thread(d)) hd_standin::misuse(d, "hdBeginFrame outside a callback");
  if (d.in_frame) {
    hd_standin::push(d, HD_ILLEGAL_BEGIN, 0);
    return;
  }
  d.in_frame = true;
  d.frame_force = {};  // a frame that sets no force sends zero
  if (d.script) d.script(d.ticks, d.position);
}

void hdEndFrame(HHD hHD) {
  Device& d = dev();
  Lock lock(d.mutex);
  if (!hd_standin::valid_handle(d, hHD)) return;
  if (!d.in_frame) {
    hd_standin::push(d, HD_ILLEGAL_END, 0);
    return;
  }
  d.in_frame = false;
  ++d.frames;
  const bool failed = hd_standin::take_failure(d, Call::end_frame);
  const bool output = !failed && d.caps[hd_standin::cap_index(HD_FORCE_OUTPUT)];
  d.output_force = output ? d.frame_force : Vec3{};
  if (d.observer) d.observer(d.ticks, d.output_force);
}

HDErrorInfo hdGetError(void) {
  Device& d = dev();
  Lock lock(d.mutex);
  if (d.error_count == 0) {
    return HDErrorInfo{HD_SUCCESS, 0, d.open ? hd_standin::kHandle : HD_INVALID_HANDLE};
  }
  return d.errors[--d.error_count];
}

HDstring hdGetErrorString(HDerror errorCode) {
  switch (errorCode) {
    case HD_SUCCESS:
      return "No error";
    case HD_INVALID_ENUM:
      return "Invalid enumeration value";
    case HD_INVALID_VALUE:
      return "Invalid value";
    case HD_INVALID_OPERATION:
      return "Invalid operation";
    case HD_INVALID_INPUT_TYPE:
      return "Invalid input type";
    case HD_BAD_HANDLE:
      return "Invalid device handle";
    case HD_WARM_MOTORS:
      return "Motors are warm";
    case HD_EXCEEDED_MAX_FORCE:
      return "Exceeded maximum force";
    case HD_EXCEEDED_MAX_FORCE_IMPULSE:
      return "Exceeded maximum force impulse";
    case HD_EXCEEDED_MAX_VELOCITY:
      return "Exceeded maximum velocity";
    case HD_FORCE_ERROR:
      return "Force error";
    case HD_DEVICE_FAULT:
      return "Device fault";
    case HD_DEVICE_ALREADY_INITIATED:
      return "Device already initiated";
    case HD_COMM_ERROR:
      return "Communication error";
    case HD_COMM_CONFIG_ERROR:
      return "Communication configuration error";
    case HD_TIMER_ERROR:
      return "Timer error";
    case HD_ILLEGAL_BEGIN:
      return "Illegal begin frame";
    case HD_ILLEGAL_END:
      return "Illegal end frame";
    case HD_FRAME_ERROR:
      return "Frame error";
    case HD_INVALID_PRIORITY:
      return "Invalid scheduler priority";
    case HD_SCHEDULER_FULL:
      return "Scheduler full";
    case HD_INVALID_LICENSE:
      return "Invalid license";
    default:
      return "Unknown HD error";
  }
}

void hdEnable(HDenum cap) {
  Device& d = dev();
  Lock lock(d.mutex);
  if (!hd_standin::device_open(d)) return;
  const std::size_t i = hd_standin::cap_index(cap);
  if (i == hd_standin::kCaps) {
    hd_standin::push(d, HD_INVALID_ENUM, 0);
    return;
  }
  if (hd_standin::take_failure(d, Call::enable)) return;
  d.caps[i] = true;
}

void hdDisable(HDenum cap) {
  Device& d = dev();
  Lock lock(d.mutex);
  if (!hd_standin::device_open(d)) return;
  const std::size_t i = hd_standin::cap_index(cap);
  if (i == hd_standin::kCaps) {
    hd_standin::push(d, HD_INVALID_ENUM, 0);
    return;
  }
  d.caps[i] = false;
}

void hdGetIntegerv(HDenum pname, HDint* params) {
  Device& d = dev();
  Lock lock(d.mutex);
  if (!hd_standin::device_open(d)) return;
  switch (pname) {
    case HD_CURRENT_BUTTONS:
      if (!d.in_frame) hd_standin::misuse(d, "hdGetIntegerv(HD_CURRENT_BUTTONS) outside a frame");
      params[0] = d.buttons;
      return;
    case HD_CALIBRATION_STYLE:
      params[0] = d.styles;
      return;
    default:
      hd_standin::push(d, HD_INVALID_ENUM, 0);
  }
}

void hdGetDoublev(HDenum pname, HDdouble* params) {
  Device& d = dev();
  Lock lock(d.mutex);
  if (!hd_standin::device_open(d)) return;
  switch (pname) {
    case HD_CURRENT_POSITION:
      if (!d.in_frame) hd_standin::misuse(d, "hdGetDoublev(HD_CURRENT_POSITION) outside a frame");
      for (std::size_t i = 0; i < 3; ++i) params[i] = d.position[i];
      return;
    case HD_CURRENT_FORCE:
      if (!d.in_frame) hd_standin::misuse(d, "hdGetDoublev(HD_CURRENT_FORCE) outside a frame");
      for (std::size_t i = 0; i < 3; ++i) params[i] = d.frame_force[i];
      return;
    default:
      hd_standin::push(d, HD_INVALID_ENUM, 0);
  }
}

void hdSetDoublev(HDenum pname, const HDdouble* params) {
  Device& d = dev();
  Lock lock(d.mutex);
  if (!hd_standin::device_open(d)) return;
  if (pname != HD_CURRENT_FORCE) {
    hd_standin::push(d, HD_INVALID_ENUM, 0);
    return;
  }
  if (!d.in_frame) {
    hd_standin::misuse(d, "hdSetDoublev(HD_CURRENT_FORCE) outside a frame");
    return;
  }
  for (std::size_t i = 0; i < 3; ++i) d.frame_force[i] = params[i];
}

HDenum hdCheckCalibration(void) {
  Device& d = dev();
  Lock lock(d.mutex);
  hd_standin::device_open(d);
  return d.calibration;
}

void hdUpdateCalibration(HDenum style) {
  Device& d = dev();
  Lock lock(d.mutex);
  if (!hd_standin::device_open(d)) return;
  const bool one_style = style == HD_CALIBRATION_ENCODER_RESET || style == HD_CALIBRATION_AUTO ||
                         style == HD_CALIBRATION_INKWELL;
  if (!one_style || (static_cast<HDenum>(d.styles) & style) == 0) {
    hd_standin::push(d, HD_INVALID_VALUE, 0);
    return;
  }
  if (hd_standin::take_failure(d, Call::update_calibration)) return;
  if (d.calibration == HD_CALIBRATION_NEEDS_UPDATE) {  // NEEDS_MANUAL_INPUT: the user acts first
    d.calibration = HD_CALIBRATION_OK;
    ++d.calibration_updates;
  }
}

void hdStartScheduler(void) {
  Device& d = dev();
  Lock lock(d.mutex);
  if (hd_standin::take_failure(d, Call::start_scheduler)) return;
  if (d.running) return;
  d.running = true;
  if (d.mode == Scheduler::thread) {
    d.stop.store(false);
    d.thread = std::thread(hd_standin::scheduler_main, std::ref(d), d.period);
  }
}

void hdStopScheduler(void) {
  Device& d = dev();
  {
    Lock lock(d.mutex);
    if (hd_standin::on_tick_thread(d)) {
      hd_standin::misuse(d, "hdStopScheduler from a scheduler callback");
      return;
    }
  }
  hd_standin::stop_thread(d);
}

void hdScheduleSynchronous(HDSchedulerCallback pCallback, void* pUserData, HDushort nPriority) {
  Device& d = dev();
  Lock lock(d.mutex);
  if (hd_standin::on_tick_thread(d)) {
    hd_standin::misuse(d, "hdScheduleSynchronous from a scheduler callback");
    return;
  }
  if (!d.running) {
    hd_standin::misuse(d, "hdScheduleSynchronous while the scheduler is stopped");
    return;
  }
  if (pCallback == nullptr) {
    hd_standin::push(d, HD_INVALID_VALUE, 0);
    return;
  }
  const HDSchedulerHandle handle = hd_standin::insert(d, pCallback, pUserData, nPriority);
  if (handle == 0) return;
  const auto pending = [&] { return hd_standin::find(d, handle) != hd_standin::kMaxCallbacks; };
  if (d.mode == Scheduler::manual) {
    while (pending()) hd_standin::run_tick(d);  // the caller is the scheduler thread
    return;
  }
  d.changed.wait(lock, [&] { return !pending() || !d.running; });
  if (pending()) hd_standin::remove(d, hd_standin::find(d, handle));  // stopped before it ran
}

HDSchedulerHandle hdScheduleAsynchronous(HDSchedulerCallback pCallback, void* pUserData,
                                         HDushort nPriority) {
  Device& d = dev();
  Lock lock(d.mutex);
  if (hd_standin::take_failure(d, Call::schedule)) return 0;
  if (pCallback == nullptr) {
    hd_standin::push(d, HD_INVALID_VALUE, 0);
    return 0;
  }
  return hd_standin::insert(d, pCallback, pUserData, nPriority);
}

void hdUnschedule(HDSchedulerHandle hHandle) {
  Device& d = dev();
  Lock lock(d.mutex);  // waits for a running tick: the callback does not run after this returns
  const std::size_t at = hd_standin::find(d, hHandle);
  if (at != hd_standin::kMaxCallbacks) hd_standin::remove(d, at);  // else already done: no-op
}

}  // extern "C"
