//! @file
//! TeleopLoop: the 2016 single-thread cycle (worksheet 3.3.1, figures 3.5/3.6 and 5.1) as a
//! policy-based composition: read stylus -> map (eq. 5.9) -> encode -> send -> receive with
//! deadline -> decode -> estimate force -> map force (eq. 5.8) -> command stylus, guarded by the
//! watchdog and safe state. One `tick()` is noexcept and allocation-free.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <chrono>
#include <concepts>
#include <cstdint>
#include <span>

#include "endohaptics/core/clock.hpp"
#include "endohaptics/estimation/joint_force_estimator.hpp"
#include "endohaptics/protocol/packet_codec.hpp"
#include "endohaptics/teleop/haptic_device.hpp"
#include "endohaptics/teleop/loop_stats.hpp"
#include "endohaptics/teleop/passivity.hpp"
#include "endohaptics/teleop/safety.hpp"
#include "endohaptics/teleop/state_plausibility.hpp"
#include "endohaptics/transport/transport.hpp"

namespace endohaptics::teleop {

inline constexpr int loop_motors = protocol::endowrist_motors;  //!< roll, pitch, clamp1, clamp2
using estimation::JointForceEstimator;
using estimation::MotorState4;
using estimation::MotorVector;
using estimation::NoForceEstimator;

//! Stylus position -> setpoints and joint forces -> stylus force (CylindricalMapper's shape).
//! Both calls run in the tick, so both must be noexcept (as every other policy's).
template <typename M>
concept TeleopMapper = requires(M& mapper, const Eigen::Vector3d& position, MotorVector& setpoint,
                                const MotorVector& motor_force, Eigen::Vector3d& stylus_force) {
  { mapper.map_position(position, setpoint) }
  noexcept;
  { mapper.map_force(motor_force, stylus_force) }
  noexcept;
  { mapper.map_position(position, setpoint).ok() } -> std::convertible_to<bool>;
  { mapper.map_position(position, setpoint).clamped_mask } -> std::convertible_to<std::uint8_t>;
  { mapper.map_force(motor_force, stylus_force).ok() } -> std::convertible_to<bool>;
  { mapper.map_force(motor_force, stylus_force).limited } -> std::convertible_to<bool>;
};

//! Overall outcome of a tick.
enum class TickStatus : std::uint8_t {
  ok = 0,        //!< fresh state, fresh estimate, force rendered
  degraded,      //!< this exchange missed (timeout, bad packet, transport error): last force held
  link_lost,     //!< safe state: zero force, robot per SafeStatePolicy
  waiting,       //!< no valid state yet: motors disabled, zero force
  device_error,  //!< the haptic device failed: zero force commanded, robot held
  state_fault,   //!< an implausible state arrived (TickResult::state_fault): refused, safe state
};

//! The status's name for logs ("ok", "degraded", "link lost", ...).
[[nodiscard]] constexpr std::string_view to_string(TickStatus s) noexcept {
  switch (s) {
    case TickStatus::ok:
      return "ok";
    case TickStatus::degraded:
      return "degraded";
    case TickStatus::link_lost:
      return "link lost";
    case TickStatus::waiting:
      return "waiting";
    case TickStatus::device_error:
      return "device error";
    case TickStatus::state_fault:
      return "state fault";
  }
  return "unknown";
}

//! Everything a tick did, for logging and tests. Look at `status`.
struct [[nodiscard]] TickResult {
  TickStatus status = TickStatus::waiting;                   //!< overall outcome
  LinkState link = LinkState::waiting;                       //!< watchdog state after this tick
  TickOutcome exchange = TickOutcome::timeout;               //!< how the send/receive ended
  protocol::CodecStatus decode = protocol::CodecStatus::ok;  //!< decoding of the state packet
  StateFault state_fault = StateFault::none;  //!< why the decoded state was refused, if it was
  //! Motors enabled for longer than SafetyConfig::activation_timeout that the state reported
  //! inactive (TickOutcome::not_obeyed; 0 otherwise).
  std::uint8_t not_obeyed_mask = 0;
  //! Status of the send, or of the receive when the send succeeded.
  transport::TransportStatus transport = transport::TransportStatus::ok;
  //! Stylus read status; error also when commanding the force failed.
  DeviceStatus device = DeviceStatus::ok;
  bool mapper_rejected = false;     //!< stylus sample non-finite: previous setpoint kept
  bool estimator_rejected = false;  //!< estimator gave no finite force: force held/zeroed
  std::uint8_t clamped_mask = 0;    //!< joints limited to their range by the mapper
  bool rate_limited = false;        //!< setpoint change limited by max_setpoint_rate
  bool force_limited = false;       //!< stylus force scaled down to a limit
  //! The watchdog's count of misses in a row after this tick.
  int consecutive_misses = 0;
  double force_scale = 0.0;                    //!< ramp factor applied to the force, 0..1
  MotorVector setpoint = MotorVector::Zero();  //!< rad, what was sent (motor order)
  std::uint8_t enable_mask = 0;                //!< what was sent
  MotorState4 measured{};  //!< newest valid, plausible state (held on a miss or a fault)
  MotorVector motor_force = MotorVector::Zero();           //!< estimate, motor order
  Eigen::Vector3d stylus_force = Eigen::Vector3d::Zero();  //!< N, what the device was told
  std::chrono::nanoseconds round_trip{0};  //!< ns from send to receive return; 0 if not sent
  RejectedDatagrams rejected{};            //!< datagrams this tick's drain refused, by cause
  PassivityFigures passivity{};            //!< the passivity layer's energies (zero with it off)

  //! True when `status` is TickStatus::ok.
  [[nodiscard]] bool ok() const noexcept { return status == TickStatus::ok; }
};

//! Timing and safety settings of a TeleopLoop.
struct TeleopLoopConfig {
  //! Nominal period; 0 runs ticks back to back (as fast as the link allows).
  std::chrono::nanoseconds period = std::chrono::milliseconds(1);
  std::chrono::nanoseconds receive_timeout = std::chrono::milliseconds(1);  //!< 2016: 1 ms
  SafetyConfig safety{};        //!< watchdog, safe state, ramp and limits
  PassivityConfig passivity{};  //!< stability under delay and loss (off by default; passivity.hpp)

  //! Longest silence before the safe state: (misses + 1) x the longest tick (validate()).
  static constexpr std::chrono::nanoseconds max_watchdog_time = std::chrono::milliseconds(500);

  //! Largest dt a tick gives the setpoint rate limit and the force ramp: the period, or with
  //! period 0 the receive timeout (a tick's longest wait) but at least 1 ms.
  [[nodiscard]] std::chrono::nanoseconds max_tick_dt() const noexcept {
    if (period.count() > 0) return period;
    return std::max(receive_timeout, std::chrono::nanoseconds(std::chrono::milliseconds(1)));
  }

  //! The fields a configuration file sets, by name, with their bounds (core/parameter.hpp):
  //! receive_timeout in (0, max_watchdog_time] s (0 would never wait for an answer: the link could
  //! never come up). The period (the bridge's --rate), safety and passivity are checked apart.
  template <typename Self, typename Visitor>
  static void for_each_field(Self& p, Visitor&& v) {
    v("receive_timeout", p.receive_timeout,
      Bound::above(0, std::chrono::duration<double>(max_watchdog_time).count(), "s"));
  }

  //! Throws Error naming the field and value.
  void validate() const {
    if (period.count() < 0) {
      ENDOHAPTICS_THROW(
          Error("TeleopLoopConfig: period must be >= 0 ns (0: as fast as the link "
                "allows), got " +
                std::to_string(period.count())));
    }
    for_each_field(*this, ParameterChecker{"TeleopLoopConfig"});
    safety.validate(protocol::endowrist_motors);
    passivity.validate();
    // The watchdog declares the link lost after max_consecutive_misses + 1 missed ticks of at
    // most max(period, receive_timeout) each: that must stay within max_watchdog_time.
    const auto tick = std::max(period, receive_timeout);
    // Divided, not multiplied: a huge period cannot overflow into a "valid" negative product.
    if (tick > max_watchdog_time / (safety.max_consecutive_misses + 1)) {
      ENDOHAPTICS_THROW(Error(
          "TeleopLoopConfig: (safety.max_consecutive_misses + 1) x max(period, receive_timeout) "
          "= " +
          std::to_string(safety.max_consecutive_misses + 1) + " x " + std::to_string(tick.count()) +
          " ns must be <= " + std::to_string(max_watchdog_time.count()) +
          " ns: a lost link must reach the safe state within 0.5 s"));
    }
  }
};

//! The single-thread teleoperation cycle, composed of a Transport to the sbRIO, a HapticDevice,
//! a JointForceEstimator, a TeleopMapper and a Clock (all borrowed). Drive it with tick() or run().
template <transport::Transport Transport, HapticDevice Device, JointForceEstimator Estimator,
          TeleopMapper Mapper, Clock ClockT = SteadyClock>
class TeleopLoop {
 public:
  using Codec = protocol::PacketCodec<loop_motors>;  //!< packet codec for the four motors
  using Config = TeleopLoopConfig;                   //!< the loop's configuration

  //! All parts are owned by the caller and must outlive the loop. Throws Error on a bad config.
  TeleopLoop(Transport& transport, Device& device, Estimator& estimator, Mapper& mapper,
             ClockT& clock, const Config& config = Config{})
      : transport_(&transport),
        device_(&device),
        estimator_(&estimator),
        mapper_(&mapper),
        clock_(&clock),
        config_((config.validate(), config)),
        watchdog_(config.safety.max_consecutive_misses),
        ramp_(config.safety.force_ramp_time),
        limiter_(config.safety.max_setpoint_rate),
        stats_(config.period),
        passivity_(config.passivity),
        max_dt_(config.max_tick_dt()),
        activation_timeout_(std::chrono::duration_cast<std::chrono::nanoseconds>(
            std::chrono::duration<double>(config.safety.activation_timeout))),
        max_hold_(std::chrono::duration_cast<std::chrono::nanoseconds>(
            std::chrono::duration<double>(config.safety.max_hold_time))) {
    enabled_since_.fill(never_enabled);
  }

  //! One cycle. Never throws, never allocates; the result says what happened.
  TickResult tick() noexcept {
    TickResult r;
    const auto start = clock_->now();
    stats_.record_tick_start(start);
    // dt for the rate limit and the ramp, bounded by one nominal period: after a stall (the
    // clock jumped, the thread was preempted) neither moves further than in one normal tick.
    const auto gap = last_start_.count() > 0 ? start - last_start_ : config_.period;
    const double dt =
        std::chrono::duration<double>(std::clamp(gap, std::chrono::nanoseconds(0), max_dt_))
            .count();
    last_start_ = start;

    // 1. Stylus -> desired setpoint (eq. 5.9, range-limited by the mapper).
    StylusSample sample;
    r.device = device_->read(sample);
    if (r.device == DeviceStatus::ok) {
      MotorVector mapped = desired_;
      const auto m = mapper_->map_position(sample.position, mapped);
      if (m.ok()) {
        desired_ = mapped;
        have_desired_ = true;
        r.clamped_mask = m.clamped_mask;
      } else {
        r.mapper_rejected = true;
      }
    }

    // 2. Setpoint to send: safe state, rate limit, enable mask, and last the joint range: no
    //    stylus, mapper or reported state can put a setpoint outside it.
    const MotorVector desired = config_.safety.clamp_to_range(desired_);
    if (have_desired_) passivity_.track_desired(desired);
    const LinkState link_before = watchdog_.state();
    const bool device_ok = r.device != DeviceStatus::error;
    // A lost operator (a failing or silent device) follows the lost link's rules: the setpoint is
    // held, and the motors are released per SafetyConfig::policy (at once, or after
    // max_hold_time). When the device is back after a release, the limiter restarts from where
    // the robot is (a released joint may have moved): never a jump back to the held setpoint.
    if (!device_ok && !device_lost_) {
      device_lost_ = true;
      device_lost_since_ = start;
    } else if (device_ok && device_lost_) {
      device_lost_ = false;
      if (released_for_device_ && have_valid_) {
        limiter_.initialize(config_.safety.clamp_to_range(state_.position));
        passivity_.reset(limiter_.previous());
      }
      released_for_device_ = false;
    }
    Codec::Setpoint out;
    out.enable_mask = config_.safety.enable_mask;
    if (link_before == LinkState::waiting || !have_desired_) {
      out.enable_mask = 0;  // until the robot's position is known, nothing moves
      out.position = have_desired_ ? desired_ : MotorVector::Zero();
    } else if ((link_before == LinkState::lost &&
                (config_.safety.policy != SafeStatePolicy::zero_force || hold_expired(start))) ||
               !device_ok) {
      out.position = limiter_.previous();  // hold
      if (link_before == LinkState::lost &&
          (config_.safety.policy == SafeStatePolicy::disable_motors || hold_expired(start))) {
        out.enable_mask = 0;  // released: disable_motors, or a bounded hold that ran out
        released_during_loss_ = true;
      }
      if (!device_ok && (config_.safety.policy == SafeStatePolicy::disable_motors ||
                         start - device_lost_since_ > max_hold_)) {
        out.enable_mask = 0;  // the operator is lost: released as for a lost link
        released_for_device_ = true;
      }
    } else {
      // The limiter moves towards the desired setpoint inside the joint range, so a stylus beyond
      // the range never parks the limiter outside it (it would stick at the edge on the way back).
      const MotorVector from = limiter_.previous();  // the gate below steps from here too
      r.rate_limited = limiter_.shape(desired, dt, out.position);
      // Robot-side passivity controller: the step the channel's energy allows (the limiter
      // resumes from what is sent, so what it held back is given back when energy allows).
      MotorVector gated;
      if (passivity_.controlling() &&
          passivity_.shape_setpoint(out.position, from, motor_force_, gated)) {
        out.position = gated;
        r.passivity.robot_active = true;
      }
    }
    out.position = config_.safety.clamp_to_range(out.position);
    if (r.passivity.robot_active) limiter_.initialize(out.position);
    passivity_.commit(out.position);
    r.setpoint = out.position;
    r.enable_mask = out.enable_mask;
    // When each motor's enable bit was last switched on (it stays "enabled since" while every
    // setpoint sent keeps it): the robot must report it active once activation_timeout passed.
    for (int j = 0; j < loop_motors; ++j) {
      const bool on = ((out.enable_mask >> j) & 1u) != 0;
      if (!on) {
        enabled_since_[static_cast<std::size_t>(j)] = never_enabled;
      } else if (enabled_since_[static_cast<std::size_t>(j)] == never_enabled) {
        enabled_since_[static_cast<std::size_t>(j)] = start;
      }
    }

    // 3. Exchange: send, then wait for the newest state that decodes until the deadline; check
    //    that it is plausible before anything uses it.
    typename Codec::SetpointBytes tx{};
    bool received = false;
    std::size_t stale_dropped = 0;
    if (Codec::encode_setpoint(out, tx) != protocol::CodecStatus::ok) {
      r.transport =
          transport::TransportStatus::error;  // cannot happen with finite, limited setpoints
    } else {
      const auto sent_at = clock_->now();
      r.transport = transport_->send(tx);
      if (r.transport == transport::TransportStatus::ok) {
        decoder_.reset();
        const transport::ReceiveResult rx = transport::receive_filtered(
            *transport_, std::span<std::byte>(rx_buffer_), config_.receive_timeout, decoder_);
        const auto received_at = clock_->now();
        stale_dropped = rx.dropped;
        r.round_trip = received_at - sent_at;
        r.transport = rx.status;
        r.rejected = decoder_.rejected;
        r.rejected.wrong_size += rx.oversized;
        if (rx.status == transport::TransportStatus::ok) {
          // A transport that knows which packet an answer acknowledges (protocol v2) gives the
          // true round trip; the time this receive waited is less on a pipelined, delayed link.
          if constexpr (requires(const Transport& t) { t.answer_round_trip(); }) {
            const auto answer = transport_->answer_round_trip();
            if (answer.count() > 0) r.round_trip = answer;
          }
          MotorState4 candidate = state_;
          r.decode = Codec::decode_state(std::span<const std::byte>(rx_buffer_.data(), rx.size),
                                         candidate);
          if (r.decode == protocol::CodecStatus::ok) {
            const double elapsed =
                std::chrono::duration<double>(received_at - last_valid_at_).count();
            r.state_fault = config_.safety.plausibility.check(
                candidate, config_.safety.joint_lower, config_.safety.joint_upper,
                have_valid_ ? &state_ : nullptr, elapsed);
            received = r.state_fault == StateFault::none;
            if (received) {
              state_ = candidate;
              have_valid_ = true;
              last_valid_at_ = received_at;
              // Obeyed? A motor enabled for longer than the activation timeout must be active:
              // otherwise the robot answers but ignores the setpoints (a refused session, a
              // foreign console pinned, its own fault), and the link is not up.
              r.not_obeyed_mask = not_obeyed(candidate.active_mask, received_at);
              received = r.not_obeyed_mask == 0;
            }
            r.exchange = r.state_fault != StateFault::none ? TickOutcome::state_fault
                         : received                        ? TickOutcome::received
                                                           : TickOutcome::not_obeyed;
          } else {
            r.exchange = TickOutcome::decode_error;
          }
        } else if (rx.status == transport::TransportStatus::rejected) {
          r.decode = rx.oversized > 0 && decoder_.rejected.total() == 0
                         ? protocol::CodecStatus::wrong_size
                         : decoder_.last;
          r.exchange = TickOutcome::decode_error;
        } else {
          r.exchange = rx.status == transport::TransportStatus::timeout
                           ? TickOutcome::timeout
                           : TickOutcome::transport_error;
        }
      } else {
        r.exchange = TickOutcome::transport_error;
      }
    }
    stats_.record_exchange(r.exchange, r.round_trip, stale_dropped);
    stats_.record_rejected(r.rejected);
    if (r.state_fault != StateFault::none) stats_.record_state_fault(r.state_fault);

    // 4. Watchdog, first contact, recovery. An implausible state is a fault: the safe state at
    //    once (or, before first contact, nothing enabled), never followed.
    const LinkState link = r.state_fault != StateFault::none
                               ? watchdog_.fault()
                               : watchdog_.update(received, ramp_.done());
    if (link == LinkState::lost && link_before != LinkState::lost) lost_since_ = start;
    if (received && (link_before == LinkState::waiting || link_before == LinkState::lost)) {
      ramp_.restart();
      // The limiter starts from where the robot is: on first contact for every joint; after a
      // loss for each joint whose motor was released meanwhile (disable_motors, or the sbRIO's
      // own watchdog: its active bit is clear), because that joint may have moved and its first
      // enabled setpoint must not jump back to an old one. A joint held enabled throughout
      // tracked the limiter's setpoint and keeps it (no step of its tracking error).
      const MotorVector measured = config_.safety.clamp_to_range(state_.position);
      MotorVector from = limiter_.previous();
      const bool released_all = link_before == LinkState::waiting || released_during_loss_;
      released_during_loss_ = false;
      for (int j = 0; j < loop_motors; ++j) {
        const bool active = ((state_.active_mask >> j) & 1u) != 0;
        if (released_all || !active) from[j] = measured[j];
      }
      limiter_.initialize(from);
      estimator_->reset();
      passivity_.reset(limiter_.previous());
    }
    r.link = link;
    r.consecutive_misses = watchdog_.consecutive_misses();
    r.measured = state_;

    // 5. Estimate on fresh data; hold the last estimate through short gaps.
    if (received) {
      MotorVector f;
      if (estimator_->estimate(state_, out.position, f) && f.allFinite()) {
        motor_force_ = f;
      } else {
        r.estimator_rejected = true;
        motor_force_.setZero();
      }
      passivity_.observe_robot(state_.position, motor_force_);
    }
    r.motor_force = motor_force_;

    // 6. Force to render (eq. 5.8 in the mapper), scaled by the ramp, guarded.
    Eigen::Vector3d force = Eigen::Vector3d::Zero();
    const bool render = device_ok && (link == LinkState::up || link == LinkState::degraded ||
                                      link == LinkState::recovering);
    if (render) {
      r.force_scale = ramp_.advance(dt);
      // Operator-side passivity controller: damping on the force to render.
      MotorVector rendered;
      r.passivity.operator_active = passivity_.shape_force(motor_force_, dt, rendered);
      const auto fm = mapper_->map_force(rendered, force);
      if (!fm.ok()) force.setZero();
      r.force_limited = fm.limited;
      if constexpr (requires { fm.channel_limited_mask; }) {
        r.force_limited = r.force_limited || fm.channel_limited_mask != 0;  // a channel clipped
      }
      force *= r.force_scale;
    } else {
      ramp_.hold_at_zero();
      passivity_.render_nothing();
    }
    const double norm = force.norm();
    if (!std::isfinite(norm)) {
      force.setZero();
    } else if (norm > config_.safety.max_stylus_force) {
      force *= config_.safety.max_stylus_force / norm;
      r.force_limited = true;
    }
    r.stylus_force = force;
    const DeviceStatus commanded = device_->command_force(force);
    if (commanded == DeviceStatus::error) r.device = DeviceStatus::error;

    // 7. Status.
    if (r.device == DeviceStatus::error) {
      r.status = TickStatus::device_error;
    } else if (r.state_fault != StateFault::none) {
      r.status = TickStatus::state_fault;
    } else if (link == LinkState::waiting) {
      r.status = TickStatus::waiting;
    } else if (link == LinkState::lost) {
      r.status = TickStatus::link_lost;
    } else if (!received) {
      r.status = TickStatus::degraded;
    } else {
      r.status = TickStatus::ok;
    }
    if (passivity_.enabled()) {
      const bool operator_active = r.passivity.operator_active;
      const bool robot_active = r.passivity.robot_active;
      r.passivity = passivity_.figures();
      r.passivity.operator_active = operator_active;
      r.passivity.robot_active = robot_active;
      stats_.record_passivity(r.passivity);
    }
    stats_.record_compute(clock_->now() - start - r.round_trip);
    return r;
  }

  //! Runs ticks paced by absolute deadlines (start + k * period) until `stop()` returns true;
  //! `on_tick(const TickResult&)` sees every result (keep it cheap). With `busy_wait_tail` > 0 the
  //! last part of each wait spins on the clock instead of sleeping (lower jitter, one busy core).
  //! A period of zero runs as fast as the link allows. Returns the number of ticks.
  template <typename Stop, typename OnTick>
  std::uint64_t run(
      Stop&& stop, OnTick&& on_tick,
      std::chrono::nanoseconds busy_wait_tail = std::chrono::nanoseconds(0)) noexcept {
    std::uint64_t n = 0;
    auto next = clock_->now();
    while (!stop()) {
      on_tick(tick());
      ++n;
      if (config_.period.count() == 0) continue;
      next += config_.period;
      const auto now = clock_->now();
      if (now > next + config_.period) next = now;  // fell behind: do not try to catch up
      if (busy_wait_tail.count() > 0) {
        clock_->sleep_until(next - busy_wait_tail);
        while (clock_->now() < next) {
        }
      } else {
        clock_->sleep_until(next);
      }
    }
    return n;
  }

  //! Timing and exchange statistics of every tick so far.
  [[nodiscard]] const LoopStats& stats() const noexcept { return stats_; }
  //! The link watchdog (state and miss counters).
  [[nodiscard]] const Watchdog& watchdog() const noexcept { return watchdog_; }
  //! The validated configuration.
  [[nodiscard]] const Config& config() const noexcept { return config_; }
  //! The passivity layer (observers and controllers; inactive with PassivityMode::off).
  [[nodiscard]] const TimeDomainPassivity& passivity() const noexcept { return passivity_; }

  //! Orderly stop: zero force on the device and one setpoint with all motors disabled.
  void shutdown() noexcept {
    (void)device_->command_force(Eigen::Vector3d::Zero());
    Codec::Setpoint off;
    off.position = config_.safety.clamp_to_range(limiter_.previous());
    off.enable_mask = 0;
    typename Codec::SetpointBytes tx{};
    if (Codec::encode_setpoint(off, tx) == protocol::CodecStatus::ok) (void)transport_->send(tx);
  }

 private:
  static constexpr std::chrono::nanoseconds never_enabled = std::chrono::nanoseconds::max();

  // True once a loss has lasted max_hold_time: hold_position and zero_force release the motors.
  [[nodiscard]] bool hold_expired(std::chrono::nanoseconds now) const noexcept {
    return now - lost_since_ > max_hold_;
  }

  // The motors enabled for longer than the activation timeout at `now` that `active` omits.
  [[nodiscard]] std::uint8_t not_obeyed(std::uint8_t active,
                                        std::chrono::nanoseconds now) const noexcept {
    unsigned missing = 0;
    for (int j = 0; j < loop_motors; ++j) {
      const auto since = enabled_since_[static_cast<std::size_t>(j)];
      if (since == never_enabled || now - since <= activation_timeout_) continue;
      if (((active >> j) & 1u) == 0) missing |= 1u << j;
    }
    return static_cast<std::uint8_t>(missing);
  }

  Transport* transport_;
  Device* device_;
  Estimator* estimator_;
  Mapper* mapper_;
  ClockT* clock_;
  Config config_;
  Watchdog watchdog_;
  ForceRamp ramp_;
  SetpointRateLimiter<loop_motors> limiter_;
  LoopStats stats_;
  TimeDomainPassivity passivity_;
  MotorVector desired_ = MotorVector::Zero();
  bool have_desired_ = false;
  // The receive filter: a datagram is a candidate only if it decodes; refusals counted by cause.
  struct StateDecoder {
    RejectedDatagrams rejected{};
    protocol::CodecStatus last = protocol::CodecStatus::ok;
    void reset() noexcept { *this = StateDecoder{}; }
    bool operator()(std::span<const std::byte> datagram) noexcept {
      typename Codec::State scratch;
      last = Codec::decode_state(datagram, scratch);
      switch (last) {
        case protocol::CodecStatus::ok:
          return true;
        case protocol::CodecStatus::non_finite:
        case protocol::CodecStatus::out_of_range:
          ++rejected.non_finite;
          break;
        case protocol::CodecStatus::mask_out_of_range:
          ++rejected.bad_mask;
          break;
        case protocol::CodecStatus::wrong_size:
          ++rejected.wrong_size;
          break;
      }
      return false;
    }
  };

  MotorState4 state_{};
  bool have_valid_ = false;  // state_ holds a plausible state received at last_valid_at_
  std::chrono::nanoseconds last_valid_at_{0};
  StateDecoder decoder_;
  MotorVector motor_force_ = MotorVector::Zero();
  // One byte longer than a state packet: a transport that cuts long datagrams to the buffer
  // still hands over a wrong size, never the first state_packet_size bytes of a longer one.
  std::array<std::byte, Codec::state_packet_size + 1> rx_buffer_{};
  std::chrono::nanoseconds max_dt_;
  std::chrono::nanoseconds activation_timeout_;
  std::chrono::nanoseconds max_hold_;
  std::chrono::nanoseconds lost_since_{0};         // when the link was last declared lost
  bool released_during_loss_ = false;              // enable mask 0 was sent during the current loss
  bool device_lost_ = false;                       // the device reported an error on the last read
  std::chrono::nanoseconds device_lost_since_{0};  // when the device last started failing
  bool released_for_device_ = false;  // enable mask 0 was sent while the device was failing
  // Per motor: tick start when its enable bit was switched on (never_enabled while off).
  std::array<std::chrono::nanoseconds, loop_motors> enabled_since_{};
  std::chrono::nanoseconds last_start_{0};
};

}  // namespace endohaptics::teleop
