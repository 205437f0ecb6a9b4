#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <Eigen/Geometry>  // cross

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <endohaptics/kinematics/cylindrical_mapper.hpp>
#include <endohaptics/teleop/haptic_device.hpp>
#include <hd_standin_control.hpp>
#include <numbers>
#include <openhaptics_device.hpp>
#include <string>
#include <thread>

namespace openhaptics_openhaptics_device_test {

// The Geomagic Touch adapter (examples/teleop_bridge/openhaptics_device.hpp) against the HD API
// stand-in (tests/openhaptics_standin). Conventions under test:
//  - HD_CURRENT_POSITION is mm in the Touch frame (x right, y up, z towards the operator); the
//    sample is m in CylindricalMapper's mapping frame (x towards the operator, y right, z up,
//    origin on the waist axis at the desk): (z, x, y) / 1000 + hd_origin;
//  - forces are N in both; mapping-frame (Fx, Fy, Fz) is sent to the Touch as (Fy, Fz, Fx);
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

TEST_CASE("units and axes: Touch mm (x right, y up, z to the operator) read in the mapping frame") {
  // Default HD origin in the mapping frame: (a3, 0, d1 - d4) = (0.13335, 0, 0.125 - 0.13335) m.
  const Eigen::Vector3d o(0.13335, 0.0, 0.125 - 0.13335);
  CHECK((bridge::default_hd_origin() - o).norm() < 1e-15);
  fresh();
  {
    OpenHapticsDevice device;
    tp::StylusSample sample;
    CHECK(device.read(sample) == tp::DeviceStatus::not_ready);  // no servo frame yet

    struct Case {
      hd::Vec3 touch_mm;
      Eigen::Vector3d mapping_m;
    };
    const Case cases[] = {
        {{0.0, 0.0, 0.0}, o},                                     // the HD origin
        {{10.0, 0.0, 0.0}, o + Eigen::Vector3d(0.0, 0.01, 0.0)},  // right is mapping +y
        {{0.0, 10.0, 0.0}, o + Eigen::Vector3d(0.0, 0.0, 0.01)},  // up is mapping +z
        {{0.0, 0.0, 10.0}, o + Eigen::Vector3d(0.01, 0.0, 0.0)},  // to the operator is +x
        {{-25.5, 80.0, -120.0}, o + Eigen::Vector3d(-0.12, -0.0255, 0.08)},
    };
    for (const Case& c : cases) {
      CAPTURE(c.mapping_m.transpose());
      hd::set_position_mm(c.touch_mm);
      REQUIRE(hd::step() == 1);
      REQUIRE(device.read(sample) == tp::DeviceStatus::ok);
      CHECK((sample.position - c.mapping_m).norm() < 1e-12);
    }

    hd::set_buttons(HD_DEVICE_BUTTON_1 | HD_DEVICE_BUTTON_2);
    hd::step();
    REQUIRE(device.read(sample) == tp::DeviceStatus::ok);
    CHECK(sample.buttons == 0b11);
    CHECK(hd::state().frames >= 6);
  }
  check_released();

  // Another origin (measured on a rig) is taken as given; a non-finite one is refused.
  fresh();
  {
    OpenHapticsDevice device(Eigen::Vector3d(0.2, -0.01, 0.09));
    hd::set_position_mm({1.0, 2.0, 3.0});
    REQUIRE(hd::step() == 1);
    tp::StylusSample sample;
    REQUIRE(device.read(sample) == tp::DeviceStatus::ok);
    CHECK((sample.position - Eigen::Vector3d(0.203, -0.009, 0.092)).norm() < 1e-12);
  }
  check_released();
  fresh();
  CHECK_THROWS_WITH_AS(OpenHapticsDevice(Eigen::Vector3d(0.1, std::nan(""), 0.0)),
                       "OpenHapticsDevice: hd_origin must be finite, got (0.1, nan, 0) m",
                       endohaptics::Error);
  CHECK_FALSE(hd::state().device_open);
}

TEST_CASE("the rest pose read through the adapter maps to mid-range setpoints") {
  // The 2016 rig's mistake: with the 2016 frame passed through ((x, -z, y) / 1000, no origin shift)
  // the stylus straight ahead gave theta = 0: roll pinned at its -1.028 rad limit (and clamp 1 at
  // 0.682). The rest pose (kinematics::rest_position: straight ahead, r = 0.130015 m, z = 0.137405
  // m) has the joint angles q2 = 1.154162 rad, absolute forearm angle q2 + q3 = 0.606876 rad (see
  // tests/kinematics/denavit_hartenberg_test.cpp). The published HD-frame kinematics of the
  // Phantom (x = -sin q1 (l1 cos q2 + l2 sin q3), y = l1 sin q2 - l2 cos q3 + l2,
  // z = -l1 + cos q1 (l1 cos q2 + l2 sin q3), l1 = l2 = 133.35 mm, q3 absolute) put the stylus
  // there at HD (0, 145.7546, -3.3351) mm (python3, same formulas), independently of the adapter.
  const double l = 133.35;
  const double q2 = 1.1541618871391688;
  const double q3 = 0.6068764694012174;
  const hd::Vec3 rest_mm{0.0, l * std::sin(q2) - l * std::cos(q3) + l,
                         -l + (l * std::cos(q2) + l * std::sin(q3))};
  CHECK(rest_mm[1] == doctest::Approx(145.7546).epsilon(1e-6));
  CHECK(rest_mm[2] == doctest::Approx(-3.3351).epsilon(1e-4));
  fresh();
  {
    OpenHapticsDevice device;
    hd::set_position_mm(rest_mm);
    REQUIRE(hd::step() == 1);
    tp::StylusSample sample;
    REQUIRE(device.read(sample) == tp::DeviceStatus::ok);
    CHECK((sample.position - endohaptics::kinematics::rest_position<double>()).norm() < 1e-9);
    endohaptics::kinematics::CylindricalMapper<> mapper;
    Eigen::Vector4d setpoint = Eigen::Vector4d::Zero();
    const auto result = mapper.map_position(sample.position, setpoint);
    REQUIRE(result.ok());
    CHECK(result.coordinates.theta == doctest::Approx(std::numbers::pi / 2));
    CHECK(std::abs(setpoint[0]) < 0.01);  // roll (before: -1.028, pinned at its limit)
    CHECK(std::abs(setpoint[1]) < 0.01);  // pitch
    CHECK(std::abs(setpoint[2]) < 0.01);  // clamps
    CHECK(result.clamped_mask == 0);

    // Turning the waist so that the stylus goes to the operator's right (HD +x) lowers theta.
    hd::set_position_mm({30.0, rest_mm[1], rest_mm[2]});
    REQUIRE(hd::step() == 1);
    REQUIRE(device.read(sample) == tp::DeviceStatus::ok);
    REQUIRE(mapper.map_position(sample.position, setpoint).ok());
    CHECK(mapper.theta() < std::numbers::pi / 2 - 0.2);
  }
  check_released();
}

TEST_CASE("axes: one proper rotation for position and force, so force times motion is preserved") {
  const HDdouble zero[3] = {0.0, 0.0, 0.0};
  const HDdouble ex[3] = {1000.0, 0.0, 0.0};  // 1 m along each Touch axis
  const HDdouble ey[3] = {0.0, 1000.0, 0.0};
  const HDdouble ez[3] = {0.0, 0.0, 1000.0};
  const Eigen::Vector3d o = bridge::touch_to_mapping_position(zero);
  const Eigen::Vector3d mx = bridge::touch_to_mapping_position(ex) - o;
  const Eigen::Vector3d my = bridge::touch_to_mapping_position(ey) - o;
  const Eigen::Vector3d mz = bridge::touch_to_mapping_position(ez) - o;
  // Right-handed in, right-handed out (determinant +1, not a mirror).
  CHECK((mx.cross(my) - mz).norm() < 1e-12);

  const HDdouble motion_mm[3] = {3.0, -7.0, 11.0};
  const Eigen::Vector3d force_mapping(0.4, -1.5, 2.25);
  const auto force_touch = bridge::mapping_to_touch_force_hd(force_mapping);
  const double work_touch =
      force_touch[0] * motion_mm[0] + force_touch[1] * motion_mm[1] + force_touch[2] * motion_mm[2];
  const double work_mapping =
      force_mapping.dot(bridge::touch_to_mapping_position(motion_mm) - o) * 1e3;
  CHECK(work_mapping == doctest::Approx(work_touch).epsilon(1e-12));
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
      Eigen::Vector3d mapping_n;
      hd::Vec3 touch_n;
    };
    const Case cases[] = {
        {{1.0, 0.0, 0.0}, {0.0, 0.0, 1.0}},  // towards the operator is Touch +z
        {{0.0, 1.0, 0.0}, {1.0, 0.0, 0.0}},  // the operator's right is Touch +x
        {{0.0, 0.0, 1.0}, {0.0, 1.0, 0.0}},  // up is Touch +y
        {{0.5, -1.25, 2.0}, {-1.25, 2.0, 0.5}},
    };
    for (const Case& c : cases) {
      CAPTURE(c.mapping_n.transpose());
      REQUIRE(device.command_force(c.mapping_n) == tp::DeviceStatus::ok);
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
    CHECK(sample.position.y() == doctest::Approx(0.003));  // Touch x is mapping y
    sample = tp::StylusSample{};
    REQUIRE(device.read(sample) == tp::DeviceStatus::ok);  // nothing newer: the same sample again
    CHECK(sample.position.y() == doctest::Approx(0.003));  // Touch x is mapping y

    for (int j = 1; j <= 3; ++j) {
      REQUIRE(device.command_force(Eigen::Vector3d(static_cast<double>(j), 0.0, 0.0)) ==
              tp::DeviceStatus::ok);
    }
    hd::step();
    CHECK(hd::state().force_n == hd::Vec3{0.0, 0.0, 3.0});
    hd::step();  // no new command: the newest force is held
    CHECK(hd::state().force_n == hd::Vec3{0.0, 0.0, 3.0});
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
    CHECK(hd::state().force_n == hd::Vec3{0.2, 0.3, 0.1});
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
    const double j = f[2];  // (j, 2j, 3j) in the mapping frame is (2j, 3j, j) on the Touch
    if (f[0] != 2.0 * j || f[1] != 3.0 * j) torn_forces.fetch_add(1, std::memory_order_relaxed);
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
      const double k = std::round(sample.position.y() * 1e3);  // Touch x
      const HDdouble p[3] = {k, 2.0 * k, 3.0 * k};
      if (sample.position != bridge::touch_to_mapping_position(p)) ++torn;
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
      CHECK(sample.position.y() == doctest::Approx(0.01));
      CHECK(device.calibration_status() == HD_CALIBRATION_OK);
      CHECK(hd::state().force_n == hd::Vec3{0.0, 0.0, 1.0});
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
    CHECK(hd::state().force_n == hd::Vec3{2.0, 3.0, 1.0});
  }
  CHECK(last_sent == kZero);  // the scheduler thread is joined: no race on last_sent
  check_released();
}

}  // namespace openhaptics_openhaptics_device_test
