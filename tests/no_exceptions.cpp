// Built with -fno-exceptions: every header compiles without exceptions (configuration errors
// then print their message and abort), and the real-time path runs.
#include <endohaptics/endohaptics.hpp>
#include <endohaptics/estimation/force_estimator.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace {

struct Hand {
  int t = 0;
  endohaptics::teleop::DeviceStatus read(endohaptics::teleop::StylusSample& s) noexcept {
    s.position = Eigen::Vector3d(0.0, 0.12 + 1e-4 * (t++ % 50), 0.03);
    return endohaptics::teleop::DeviceStatus::ok;
  }
  endohaptics::teleop::DeviceStatus command_force(const Eigen::Vector3d&) noexcept {
    return endohaptics::teleop::DeviceStatus::ok;
  }
};

}  // namespace

int main() {
  using Codec = endohaptics::protocol::PacketCodec<4>;
  Codec::State state;
  state.position << 1.0, 2.0, 3.0, 4.0;
  state.active_mask = 0x0F;
  Codec::StateBytes bytes{};
  if (Codec::encode_state(state, bytes) != endohaptics::protocol::CodecStatus::ok) return 1;
  Codec::State back;
  if (Codec::decode_state(bytes, back) != endohaptics::protocol::CodecStatus::ok) return 1;
  if (!(back == state)) return 1;

  auto model = endohaptics::model::yaw_force_2016_hw();
  const auto y = model.step(Eigen::Vector2d(0.5, 0.1));
  if (!y.allFinite()) return 1;

  // The 2016 force estimator (rate::Decimate, 1 ms loop) on one second of a 2 Hz motion with
  // currents above the friction gates: every step ok, every force finite, and not all zero.
  namespace est = endohaptics::estimation;
  est::ForceEstimator<est::rate::Decimate> force_estimator;
  est::JointState<> joints;
  est::ForceEstimator<est::rate::Decimate>::Forces forces;
  const Eigen::Vector4d amplitude(0.1, 0.2, 0.3, 0.3);  // rad
  const Eigen::Vector4d current(0.9, 0.4, 0.6, 0.6);    // A
  const double omega = 2.0 * 3.14159265358979 * 2.0;    // rad/s
  double largest_force = 0.0;
  for (int i = 0; i < 1000; ++i) {
    const double t = 1e-3 * i;
    joints.position = amplitude * std::sin(omega * t);
    joints.velocity = amplitude * (omega * std::cos(omega * t));
    joints.current = current * std::sin(omega * t);
    joints.setpoint = joints.position + Eigen::Vector4d::Constant(0.01);
    if (force_estimator.step(joints, forces) != est::NumericStatus::ok) return 1;
    if (!forces.allFinite()) return 1;
    largest_force = std::max(largest_force, forces.cwiseAbs().maxCoeff());
  }
  if (!(largest_force > 0.0)) return 1;

  // The bidirectional load observer (a joint model of cable-driven instruments) on the same
  // motion: every step ok, the force finite.
  est::BidirectionalLoadObserverParameters<double> bp;
  bp.forward_gain = 1.4e-3;
  bp.backward_gain = 0.7e-3;
  est::BidirectionalLoadObserver<double> observer(bp);
  for (int i = 0; i < 1000; ++i) {
    const double t = 1e-3 * i;
    const est::JointSignals<double> s{0.5 * std::sin(omega * t), 0.0,
                                      0.1 + 0.05 * std::cos(omega * t), 0.0};
    if (observer.advance(s) != endohaptics::model::NumericStatus::ok) return 1;
    if (!std::isfinite(observer.force(s))) return 1;
  }

  auto echo = [](std::span<const std::byte> in, auto& reply) {
    Codec::Setpoint sp;
    Codec::State s;
    if (Codec::decode_setpoint(in, sp) != endohaptics::protocol::CodecStatus::ok) return;
    s.position = sp.position;
    s.active_mask = sp.enable_mask;
    Codec::StateBytes out{};
    if (Codec::encode_state(s, out) == endohaptics::protocol::CodecStatus::ok)
      (void)reply.send(out);
  };
  endohaptics::transport::RespondingTransport<decltype(echo)> transport(echo);
  Hand hand;
  endohaptics::teleop::NoForceEstimator estimator;
  endohaptics::kinematics::CylindricalMapper<> mapper;
  endohaptics::ManualClock clock;
  endohaptics::teleop::TeleopLoop loop(transport, hand, estimator, mapper, clock);
  int ok = 0;
  for (int i = 0; i < 100; ++i) {
    ok += loop.tick().ok() ? 1 : 0;
    clock.advance(std::chrono::milliseconds(1));
  }
  if (ok < 99) return 1;
  std::puts("no-exceptions build: codec, model, 1000 force estimator steps and 100 loop ticks ok");
  return 0;
}
