//! @file
//! TickRecorder: per-tick CSV logging without I/O on the real-time thread. The loop thread
//! `push`es a fixed-size record into a lock-free single-producer/single-consumer ring
//! (Boost.Lockfree, preallocated); another thread `drain`s it to a file. A full ring drops the
//! record and counts it (never blocks the loop). Times in s, angles in rad, forces in N.
//! `tick_log_columns` names the CSV's columns: readers find them by these names
//! (files/tick_log.hpp), never by position.
#pragma once

#include <Eigen/Core>
#include <array>
#include <atomic>
#include <boost/lockfree/spsc_queue.hpp>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

#include "endohaptics/core/error.hpp"
#include "endohaptics/teleop/realtime.hpp"
#include "endohaptics/teleop/teleop_loop.hpp"

namespace endohaptics::teleop {

//! The tick log's columns in the order `TickRecorder::drain` writes them: the one definition of
//! the header line (`TickRecorder::write_header`) and of the names readers look columns up by.
//! status, link and state_fault are the numeric values of TickStatus, LinkState and StateFault.
//! The passivity_* columns are TickResult::passivity (PassivityFigures; zero with it off).
// clang-format off
inline constexpr std::array<std::string_view, 8 + 5 * loop_motors + 4 + 3> tick_log_columns = {
    "time", "status", "link", "state_fault", "enable_mask", "active_mask", "round_trip",
    "force_scale",
    "setpoint0", "setpoint1", "setpoint2", "setpoint3",
    "position0", "position1", "position2", "position3",
    "velocity0", "velocity1", "velocity2", "velocity3",
    "current0", "current1", "current2", "current3",
    "motor_force0", "motor_force1", "motor_force2", "motor_force3",
    "passivity_energy", "passivity_damping", "passivity_force_gain", "passivity_drift",
    "stylus_fx", "stylus_fy", "stylus_fz"};
// clang-format on

//! One CSV row: what a tick sent, received, estimated and rendered.
struct TickRecord {
  double time = 0.0;                              //!< s, the clock's time when the tick ended
  TickStatus status = TickStatus::waiting;        //!< the tick's overall status
  LinkState link = LinkState::waiting;            //!< the watchdog's link state
  StateFault state_fault = StateFault::none;      //!< why a received state was refused
  std::uint8_t enable_mask = 0;                   //!< motors enabled in the packet sent
  std::uint8_t active_mask = 0;                   //!< motors the sbRIO reported active
  double round_trip = 0.0;                        //!< s
  double force_scale = 0.0;                       //!< force ramp factor, 0..1
  MotorVector setpoint = MotorVector::Zero();     //!< rad
  MotorVector position = MotorVector::Zero();     //!< rad (newest valid)
  MotorVector velocity = MotorVector::Zero();     //!< rad/s
  MotorVector current = MotorVector::Zero();      //!< A
  MotorVector motor_force = MotorVector::Zero();  //!< estimate, motor order (N; roll N m)
  double passivity_energy = 0.0;      //!< J, the passivity observer (PassivityFigures::energy)
  double passivity_damping = 0.0;     //!< N s/m, the operator-side controller's damping
  double passivity_force_gain = 1.0;  //!< the operator-side controller's force scale, 0..1
  double passivity_drift = 0.0;       //!< rad, setpoint held back by the robot-side controller
  Eigen::Vector3d stylus_force = Eigen::Vector3d::Zero();  //!< N

  //! The record of tick result `r`, stamped `now` (the loop clock's time).
  [[nodiscard]] static TickRecord from(const TickResult& r, std::chrono::nanoseconds now) noexcept {
    TickRecord rec;
    rec.time = std::chrono::duration<double>(now).count();
    rec.status = r.status;
    rec.link = r.link;
    rec.state_fault = r.state_fault;
    rec.enable_mask = r.enable_mask;
    rec.active_mask = r.measured.active_mask;
    rec.round_trip = std::chrono::duration<double>(r.round_trip).count();
    rec.force_scale = r.force_scale;
    rec.setpoint = r.setpoint;
    rec.position = r.measured.position;
    rec.velocity = r.measured.velocity;
    rec.current = r.measured.current;
    rec.motor_force = r.motor_force;
    rec.passivity_energy = r.passivity.energy;
    rec.passivity_damping = r.passivity.damping;
    rec.passivity_force_gain = r.passivity.force_gain;
    rec.passivity_drift = r.passivity.drift;
    rec.stylus_force = r.stylus_force;
    return rec;
  }

  //! The row as numbers, in the order of `tick_log_columns` (what `TickRecorder::drain` prints;
  //! status, link and state_fault as their numeric values): for other outputs of the same log,
  //! such as the ROS bridge's tick-log topic.
  [[nodiscard]] std::array<double, tick_log_columns.size()> values() const noexcept {
    std::array<double, tick_log_columns.size()> v{};
    std::size_t i = 0;
    for (const double x : {time, static_cast<double>(status), static_cast<double>(link),
                           static_cast<double>(state_fault), static_cast<double>(enable_mask),
                           static_cast<double>(active_mask), round_trip, force_scale}) {
      v[i++] = x;
    }
    for (const MotorVector* m : {&setpoint, &position, &velocity, &current, &motor_force}) {
      for (int j = 0; j < loop_motors; ++j) v[i++] = (*m)[j];
    }
    for (const double x : {passivity_energy, passivity_damping, passivity_force_gain,
                           passivity_drift, stylus_force.x(), stylus_force.y(), stylus_force.z()}) {
      v[i++] = x;
    }
    return v;
  }
};

//! The ring between the loop thread (push) and a writer thread (drain). `capacity` records are
//! allocated once, at construction.
class TickRecorder {
 public:
  //! A ring of `capacity` records, its memory mapped here (prefault_ring): the loop's pushes take
  //! no page fault.
  explicit TickRecorder(std::size_t capacity = std::size_t{1} << 16) : queue_(capacity) {
    prefault_ring(queue_, TickRecord{});
  }

  //! Loop thread: wait-free, allocation-free. False (and counted) when the ring is full.
  bool push(const TickRecord& record) noexcept {
    if (queue_.push(record)) return true;
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }

  //! CSV header matching `drain`'s rows: `tick_log_columns`, comma-separated. Throws Error when
  //! the file cannot be written.
  static void write_header(std::FILE* out) {
    int written = 0;
    for (std::size_t c = 0; c < tick_log_columns.size() && written >= 0; ++c) {
      if (c > 0) written = std::fputc(',', out);
      if (written >= 0) {
        written = std::fprintf(out, "%.*s", static_cast<int>(tick_log_columns[c].size()),
                               tick_log_columns[c].data());
      }
    }
    if (written >= 0) written = std::fputc('\n', out);
    if (written < 0) ENDOHAPTICS_THROW(Error("TickRecorder: cannot write the tick log header"));
  }

  //! Writer thread: writes every queued record as a CSV row, its fields in the order of
  //! `tick_log_columns`; returns how many. Throws Error when the file cannot be written.
  std::size_t drain(std::FILE* out) {
    std::size_t n = 0;
    TickRecord r;
    while (queue_.pop(r)) {
      int written = std::fprintf(out, "%.9f,%d,%d,%d,%u,%u,%.9g,%.4g", r.time,
                                 static_cast<int>(r.status), static_cast<int>(r.link),
                                 static_cast<int>(r.state_fault), unsigned{r.enable_mask},
                                 unsigned{r.active_mask}, r.round_trip, r.force_scale);
      for (const MotorVector* v :
           {&r.setpoint, &r.position, &r.velocity, &r.current, &r.motor_force}) {
        for (int i = 0; i < loop_motors; ++i) written = std::fprintf(out, ",%.7g", (*v)[i]);
      }
      written = std::fprintf(out, ",%.7g,%.5g,%.5g,%.5g", r.passivity_energy, r.passivity_damping,
                             r.passivity_force_gain, r.passivity_drift);
      written = std::fprintf(out, ",%.6g,%.6g,%.6g\n", r.stylus_force.x(), r.stylus_force.y(),
                             r.stylus_force.z());
      if (written < 0) ENDOHAPTICS_THROW(Error("TickRecorder: cannot write the tick log"));
      ++n;
    }
    written_ += n;
    return n;
  }

  //! Records dropped because the ring was full.
  [[nodiscard]] std::uint64_t dropped() const noexcept {
    return dropped_.load(std::memory_order_relaxed);
  }
  //! Rows written by `drain` (writer thread).
  [[nodiscard]] std::uint64_t written() const noexcept { return written_; }

 private:
  boost::lockfree::spsc_queue<TickRecord> queue_;
  std::atomic<std::uint64_t> dropped_{0};
  std::uint64_t written_ = 0;
};

}  // namespace endohaptics::teleop
