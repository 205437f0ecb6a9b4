#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <Eigen/Geometry>  // cross

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <endohaptics/teleop/haptic_device.hpp>
#include <hd_standin_control.hpp>
#include <openhaptics_device.hpp>
#include <string>
#include <thread>

namespace openhaptics_openhaptics_device_test {

// The Geomagic Touch adapter (examples/teleop_bridge/openhaptics_device.hpp) against the HD API
// stand-in (tests/openhaptics_standin). Conventions under test:
//  - HD_CURRENT_POSITION is mm in the Touch frame (x right, y up, z towards the user); the sample
//    is m in the base frame (x right, y away from the user, z up): (x, -z, y) / 1000;
//  - forces are N in both; base (Fx, Fy, Fz) is sent to the Touch as (Fx, Fz, -Fy);
//  - the servo thread and the loop thread hand values over wait-free, the newest wins.
#ifndef ENDOHAPTICS_HD_STANDIN
#error "these tests drive the simulated Touch: compile them against tests/openhaptics_standin"
#endif

namespace {

namespace tp = endohaptics::teleop;
namespace hd = hd_standin;
using bridge::OpenHapticsDevice;
using endohaptics::test::allocations_during;
using namespace std::chrono_literals;

static_assert(tp::HapticDevice<OpenHapticsDevice>);

// A fresh simulated Touch for each test (and each subcase).
void fresh(hd::Scheduler mode = hd::Scheduler::manual, std::chrono::nanoseconds period = 1ms) {
  hd::reset();
  hd::set_scheduler(mode, period);
}

// After the adapter is gone: everything released, no error left, the HD API used as documented.
void check_released() {
  const hd::State s = hd::state();
  CHECK_FALSE(s.device_open);
  CHECK_FALSE(s.scheduler_running);
  CHECK(s.callbacks_scheduled == 0);
  CHECK(s.errors_pending == 0);
  CHECK_MESSAGE(s.misuse == 0, s.first_misuse);
}

const hd::Vec3 kZero{0.0, 0.0, 0.0};

}  // namespace

TEST_CASE("units and axes: Touch mm (x right, y up, z to the user) read as base m (y away, z up)") {
  fresh();
  {
    OpenHapticsDevice device;
    tp::StylusSample sample;
    CHECK(device.read(sample) == tp::DeviceStatus::not_ready);  // no servo frame yet

    struct Case {
      hd::Vec3 touch_mm;
      Eigen::Vector3d base_m;
    };
    const Case cases[] = {
        {{10.0, 0.0, 0.0}, {0.01, 0.0, 0.0}},   // right stays right
        {{0.0, 10.0, 0.0}, {0.0, 0.0, 0.01}},   // up is base +z
        {{0.0, 0.0, 10.0}, {0.0, -0.01, 0.0}},  // towards the user is base -y
        {{-25.5, 80.0, -120.0}, {-0.0255, 0.12, 0.08}},
    };
    for (const Case& c : cases) {
      CAPTURE(c.base_m.transpose());
      hd::set_position_mm(c.touch_mm);
      REQUIRE(hd::step() == 1);
      REQUIRE(device.read(sample) == tp::DeviceStatus::ok);
      CHECK((sample.position - c.base_m).norm() < 1e-15);
    }

    hd::set_buttons(HD_DEVICE_BUTTON_1 | HD_DEVICE_BUTTON_2);
    hd::step();
    REQUIRE(device.read(sample) == tp::DeviceStatus::ok);
    CHECK(sample.buttons == 0b11);
    CHECK(hd::state().frames >= 5);
  }
  check_released();
}

TEST_CASE("axes: one proper rotation for position and force, so force times motion is preserved") {
  const HDdouble ex[3] = {1000.0, 0.0, 0.0};  // 1 m along each Touch axis
  const HDdouble ey[3] = {0.0, 1000.0, 0.0};
  const HDdouble ez[3] = {0.0, 0.0, 1000.0};
  // Right-handed in, right-handed out (determinant +1, not a mirror).
  CHECK(bridge::touch_to_base_position(ex).cross(bridge::touch_to_base_position(ey)) ==
        bridge::touch_to_base_position(ez));

  const HDdouble motion_mm[3] = {3.0, -7.0, 11.0};
  const Eigen::Vector3d force_base(0.4, -1.5, 2.25);
  const auto force_touch = bridge::base_to_touch_force(force_base);
  const double work_touch =
      force_touch[0] * motion_mm[0] + force_touch[1] * motion_mm[1] + force_touch[2] * motion_mm[2];
  const double work_base = force_base.dot(bridge::touch_to_base_position(motion_mm)) * 1e3;
  CHECK(work_base == doctest::Approx(work_touch).epsilon(1e-12));
}

TEST_CASE("forces: N to N, rotated back into the Touch frame, non-finite sent as zero") {
  fresh();
  {
    OpenHapticsDevice device;
    hd::step();
    CHECK(hd::state().force_output);
    CHECK(hd::state().force_ramping);
    CHECK(hd::state().force_n == kZero);  // nothing commanded yet

    struct Case {
      Eigen::Vector3d base_n;
      hd::Vec3 touch_n;
    };
    const Case cases[] = {
        {{1.0, 0.0, 0.0}, {1.0, 0.0, 0.0}},   // right stays right
        {{0.0, 1.0, 0.0}, {0.0, 0.0, -1.0}},  // away from the user is Touch -z
        {{0.0, 0.0, 1.0}, {0.0, 1.0, 0.0}},   // up is Touch +y
        {{0.5, -1.25, 2.0}, {0.5, 2.0, 1.25}},
    };
    for (const Case& c : cases) {
      CAPTURE(c.base_n.transpose());
      REQUIRE(device.command_force(c.base_n) == tp::DeviceStatus::ok);
      hd::step();
      CHECK(hd::state().force_n == c.touch_n);
    }

    REQUIRE(device.command_force(Eigen::Vector3d(std::nan(""), 0.0, 1.0)) == tp::DeviceStatus::ok);
    hd::step();
    CHECK(hd::state().force_n == kZero);
  }
  check_released();
}

TEST_CASE("newest wins: the loop reads the last servo sample, the servo sends the last force") {
  fresh();
  {
    OpenHapticsDevice device;
    for (int k = 1; k <= 3; ++k) {
      hd::set_position_mm({static_cast<double>(k), 0.0, 0.0});
      hd::step();
    }
    tp::StylusSample sample;
    REQUIRE(device.read(sample) == tp::DeviceStatus::ok);
    CHECK(sample.position.x() == doctest::Approx(0.003));
    sample = tp::StylusSample{};
    REQUIRE(device.read(sample) == tp::DeviceStatus::ok);  // nothing newer: the same sample again
    CHECK(sample.position.x() == doctest::Approx(0.003));

    for (int j = 1; j <= 3; ++j) {
      REQUIRE(device.command_force(Eigen::Vector3d(static_cast<double>(j), 0.0, 0.0)) ==
              tp::DeviceStatus::ok);
    }
    hd::step();
    CHECK(hd::state().force_n == hd::Vec3{3.0, 0.0, 0.0});
    hd::step();  // no new command: the newest force is held
    CHECK(hd::state().force_n == hd::Vec3{3.0, 0.0, 0.0});
  }
  check_released();
}

TEST_CASE("loop side: read and command_force do not allocate while the servo thread runs") {
  fresh(hd::Scheduler::thread, 1ms);
  {
    OpenHapticsDevice device;
    REQUIRE(hd::wait_ticks(5, 2s));  // the servo loop runs on its own thread
    tp::StylusSample sample;
    long ok = 0;
    const long allocations = allocations_during([&] {
      for (int i = 0; i < 20000; ++i) {
        if (device.read(sample) == tp::DeviceStatus::ok) ++ok;
        if (device.command_force(Eigen::Vector3d(0.1, 0.2, 0.3)) == tp::DeviceStatus::ok) ++ok;
      }
    });
    CHECK(allocations == 0);
    CHECK(ok == 40000);
    REQUIRE(hd::wait_ticks(3, 2s));
    CHECK(hd::state().force_n == hd::Vec3{0.1, 0.3, -0.2});
  }
  check_released();
}

TEST_CASE("hand-off stress: samples and forces whole, never older, across two threads in < 1 s") {
  fresh(hd::Scheduler::thread, 0ns);  // servo ticks back to back: as many hand-offs as possible
  // Servo side: the stylus is at (k, 2k, 3k) mm in tick k; every force the servo sends must be
  // one whole command of the loop's, (j, 2j, 3j) N in base, i.e. (j, 3j, -2j) N on the Touch.
  hd::set_position_script([](std::uint64_t tick, hd::Vec3& p) {
    const double k = static_cast<double>(tick);
    p = {k, 2.0 * k, 3.0 * k};
  });
  std::atomic<bool> checking{false};
  std::atomic<long> frames{0};
  std::atomic<long> torn_forces{0};
  std::atomic<long> older_forces{0};
  double last_j = 0.0;  // scheduler thread only
  hd::set_force_observer([&](std::uint64_t, const hd::Vec3& f) {
    if (!checking.load(std::memory_order_acquire)) return;
    frames.fetch_add(1, std::memory_order_relaxed);
    const double j = f[0];
    if (f[1] != 3.0 * j || f[2] != -2.0 * j) torn_forces.fetch_add(1, std::memory_order_relaxed);
    if (j < last_j) older_forces.fetch_add(1, std::memory_order_relaxed);
    last_j = j;
  });

  const auto start = std::chrono::steady_clock::now();
  long reads = 0;
  long distinct = 0;
  long torn = 0;
  long older = 0;
  long stale = 0;
  {
    OpenHapticsDevice device;
    checking.store(true, std::memory_order_release);
    double last_k = -1.0;
    tp::StylusSample sample;
    for (long j = 1; std::chrono::steady_clock::now() - start < 250ms; ++j) {
      const double jd = static_cast<double>(j);
      (void)device.command_force(Eigen::Vector3d(jd, 2.0 * jd, 3.0 * jd));
      // Every 1024th iteration: let the servo publish samples unread, then check that read()
      // returns one at least as new as every tick finished before it was called.
      std::uint64_t finished = 0;
      if (j % 1024 == 0) {
        std::this_thread::sleep_for(100us);
        finished = hd::state().ticks;  // the stand-in's lock: no tick is half done
      }
      if (device.read(sample) != tp::DeviceStatus::ok) continue;
      ++reads;
      const double k = std::round(sample.position.x() * 1e3);
      const HDdouble p[3] = {k, 2.0 * k, 3.0 * k};
      if (sample.position != bridge::touch_to_base_position(p)) ++torn;
      if (k < last_k) ++older;
      if (k > last_k) ++distinct;
      if (k < static_cast<double>(finished)) ++stale;
      last_k = k;
    }
    checking.store(false, std::memory_order_release);
  }
  const auto elapsed = std::chrono::steady_clock::now() - start;
  INFO("reads " << reads << ", distinct samples " << distinct << ", servo frames "
                << frames.load());

  CHECK(torn == 0);
  CHECK(older == 0);
  CHECK(stale == 0);
  CHECK(torn_forces.load() == 0);
  CHECK(older_forces.load() == 0);
  CHECK(distinct > 100);  // the hand-off really happened many times
  CHECK(frames.load() > 100);
  CHECK(reads > distinct);
  CHECK(elapsed < 1s);
  check_released();
}

TEST_CASE("no device: the constructor throws the HD error and leaves nothing behind") {
  fresh();
  hd::fail_next(hd::Call::init_device, HD_COMM_CONFIG_ERROR, 42);
  std::string message;
  try {
    OpenHapticsDevice device;
  } catch (const endohaptics::Error& e) {
    message = e.what();
  }
  CHECK(message ==
        "OpenHaptics: hdInitDevice failed: Communication configuration error (HD error 0x0303, "
        "internal 42)");
  check_released();
}

TEST_CASE("a set-up step failing after hdInitDevice: throws, the earlier steps are undone") {
  fresh();
  std::string step;
  SUBCASE("hdEnable") {
    hd::fail_next(hd::Call::enable, HD_INVALID_OPERATION);
    step = "hdEnable(HD_FORCE_OUTPUT) failed: Invalid operation";
  }
  SUBCASE("hdScheduleAsynchronous") {
    hd::fail_next(hd::Call::schedule, HD_SCHEDULER_FULL);
    step = "hdScheduleAsynchronous failed: Scheduler full";
  }
  SUBCASE("hdStartScheduler") {
    hd::fail_next(hd::Call::start_scheduler, HD_TIMER_ERROR);
    step = "hdStartScheduler failed: Timer error";
  }
  std::string message;
  try {
    OpenHapticsDevice device;
  } catch (const endohaptics::Error& e) {
    message = e.what();
  }
  CAPTURE(message);
  CHECK(message.find(step) != std::string::npos);
  check_released();
}

TEST_CASE("calibration needed: not ready and no force until calibrated") {
  fresh();
  tp::StylusSample sample;
  hd::set_position_mm({10.0, 0.0, 0.0});

  SUBCASE("inkwell (the Touch): waits for the stylus in the inkwell, then the servo calibrates") {
    hd::set_calibration(HD_CALIBRATION_NEEDS_MANUAL_INPUT);
    {
      OpenHapticsDevice device;
      REQUIRE(device.command_force(Eigen::Vector3d(1.0, 0.0, 0.0)) == tp::DeviceStatus::ok);
      hd::step(3);
      CHECK(device.read(sample) == tp::DeviceStatus::not_ready);
      CHECK(device.calibration_status() == HD_CALIBRATION_NEEDS_MANUAL_INPUT);
      CHECK(hd::state().force_n == kZero);
      CHECK(hd::state().calibration_updates == 0);

      hd::set_calibration(HD_CALIBRATION_NEEDS_UPDATE);  // the stylus is now in the inkwell
      hd::step();  // the servo loop calls hdUpdateCalibration(HD_CALIBRATION_INKWELL)
      CHECK(hd::state().calibration_updates == 1);
      CHECK(hd::state().calibration == HD_CALIBRATION_OK);
      CHECK(device.read(sample) == tp::DeviceStatus::not_ready);  // that frame was uncalibrated
      CHECK(hd::state().force_n == kZero);

      hd::step();
      REQUIRE(device.read(sample) == tp::DeviceStatus::ok);
      CHECK(sample.position.x() == doctest::Approx(0.01));
      CHECK(device.calibration_status() == HD_CALIBRATION_OK);
      CHECK(hd::state().force_n == hd::Vec3{1.0, 0.0, 0.0});
    }
  }
  SUBCASE("auto calibration is preferred when the device offers it") {
    hd::set_calibration_styles(HD_CALIBRATION_AUTO);
    hd::set_calibration(HD_CALIBRATION_NEEDS_UPDATE);
    {
      OpenHapticsDevice device;
      hd::step(2);
      CHECK(hd::state().calibration_updates == 1);
      CHECK(device.read(sample) == tp::DeviceStatus::ok);
    }
  }
  SUBCASE("encoder reset only: never calibrates by itself (the arm must be held in place)") {
    hd::set_calibration_styles(HD_CALIBRATION_ENCODER_RESET);
    hd::set_calibration(HD_CALIBRATION_NEEDS_UPDATE);
    {
      OpenHapticsDevice device;
      REQUIRE(device.command_force(Eigen::Vector3d(1.0, 0.0, 0.0)) == tp::DeviceStatus::ok);
      hd::step(5);
      CHECK(device.read(sample) == tp::DeviceStatus::not_ready);
      CHECK(device.calibration_status() == HD_CALIBRATION_NEEDS_UPDATE);
      CHECK(hd::state().calibration_updates == 0);
      CHECK(hd::state().force_n == kZero);
    }
  }
  check_released();
}

TEST_CASE("an HD error in a servo frame: error from then on, force off, servo callback ended") {
  fresh(hd::Scheduler::thread, 1ms);
  {
    OpenHapticsDevice device;
    REQUIRE(hd::wait_ticks(3, 2s));
    tp::StylusSample sample;
    REQUIRE(device.read(sample) == tp::DeviceStatus::ok);
    REQUIRE(device.command_force(Eigen::Vector3d(0.0, 0.0, 1.0)) == tp::DeviceStatus::ok);
    CHECK(device.error_code() == HD_SUCCESS);

    hd::fail_next(hd::Call::end_frame, HD_EXCEEDED_MAX_FORCE);  // raised by the next hdEndFrame
    REQUIRE(hd::wait_ticks(3, 2s));
    CHECK(device.read(sample) == tp::DeviceStatus::error);
    CHECK(device.command_force(Eigen::Vector3d(0.0, 0.0, 1.0)) == tp::DeviceStatus::error);
    CHECK(device.error_code() == HD_EXCEEDED_MAX_FORCE);
    const hd::State s = hd::state();
    CHECK_FALSE(s.force_output);
    CHECK(s.force_n == kZero);
    CHECK(s.callbacks_scheduled == 0);  // the servo callback returned HD_CALLBACK_DONE
  }
  check_released();
}

TEST_CASE("an error another HD call left on the stack (hdGetError) also stops the servo loop") {
  fresh();
  {
    OpenHapticsDevice device;
    hd::step();
    tp::StylusSample sample;
    REQUIRE(device.read(sample) == tp::DeviceStatus::ok);
    hd::push_error(HD_COMM_ERROR, 7);
    hd::step();
    CHECK(device.read(sample) == tp::DeviceStatus::error);
    CHECK(device.error_code() == HD_COMM_ERROR);
    CHECK(hd::state().errors_pending == 0);
  }
  check_released();
}

TEST_CASE("destruction: zero force sent, scheduler stopped, servo unscheduled, device disabled") {
  fresh(hd::Scheduler::thread, 1ms);
  hd::Vec3 last_sent{};  // the last force a frame sent, before the device was disabled
  hd::set_force_observer([&](std::uint64_t, const hd::Vec3& f) { last_sent = f; });
  {
    OpenHapticsDevice device;
    REQUIRE(device.command_force(Eigen::Vector3d(1.0, 2.0, 3.0)) == tp::DeviceStatus::ok);
    REQUIRE(hd::wait_ticks(3, 2s));
    CHECK(hd::state().force_n == hd::Vec3{1.0, 3.0, -2.0});
  }
  CHECK(last_sent == kZero);  // the scheduler thread is joined: no race on last_sent
  check_released();
}

}  // namespace openhaptics_openhaptics_device_test
