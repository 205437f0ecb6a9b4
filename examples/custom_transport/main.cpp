// Plugging your own transport and haptic device into a TeleopLoop: anything with the right
// noexcept member functions satisfies the concepts (no base classes, no virtuals). Here the
// "transport" is an in-process mailbox served by a toy sbRIO, and the "device" a scripted hand.
#include <fmt/format.h>
#include <array>
#include <cmath>
#include <endohaptics/kinematics/cylindrical_mapper.hpp>
#include <endohaptics/teleop/teleop_loop.hpp>
#include <endohaptics/workflow/command_line.hpp>

#include "options.hpp"

namespace tp = endohaptics::teleop;
namespace transport = endohaptics::transport;
using Codec = endohaptics::protocol::PacketCodec<4>;

// Your transport: send() hands the datagram to the toy sbRIO, receive() returns its answer.
struct MailboxTransport {
  Codec::State robot;  // the toy sbRIO: motors jump 10 % towards their setpoints
  Codec::StateBytes reply{};
  bool has_reply = false;

  transport::TransportStatus send(std::span<const std::byte> datagram) noexcept {
    Codec::Setpoint sp;
    if (Codec::decode_setpoint(datagram, sp) != endohaptics::protocol::CodecStatus::ok) {
      return transport::TransportStatus::ok;  // the sbRIO ignores garbage
    }
    const Eigen::Vector4d enabled =
        Eigen::Vector4d(sp.enable_mask & 1, (sp.enable_mask >> 1) & 1, (sp.enable_mask >> 2) & 1,
                        (sp.enable_mask >> 3) & 1);
    robot.velocity = (0.1 * (sp.position - robot.position)).cwiseProduct(enabled) / 1e-3;
    robot.position += robot.velocity * 1e-3;
    robot.current = 3.0 * (sp.position - robot.position);
    robot.active_mask = sp.enable_mask;
    has_reply = Codec::encode_state(robot, reply) == endohaptics::protocol::CodecStatus::ok;
    return transport::TransportStatus::ok;
  }
  transport::ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds) noexcept {
    if (!has_reply) return {};  // timeout
    has_reply = false;
    std::copy(reply.begin(), reply.end(), buffer.begin());
    return {transport::TransportStatus::ok, reply.size(), 0};
  }
};
static_assert(transport::Transport<MailboxTransport>);

// Your haptic device: a hand closing the stylus towards the base, then holding.
struct ScriptedHand {
  int t = 0;
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  tp::DeviceStatus read(tp::StylusSample& s) noexcept {
    const double r = 0.20 - 0.08 * std::min(1.0, t++ / 1000.0);
    s.position = Eigen::Vector3d(0.0, r, 0.03);
    return tp::DeviceStatus::ok;
  }
  tp::DeviceStatus command_force(const Eigen::Vector3d& f) noexcept {
    force = f;
    return tp::DeviceStatus::ok;
  }
};
static_assert(tp::HapticDevice<ScriptedHand>);

int main(int argc, char** argv) {
  custom_transport::Options options;
  const examples::Parsed parsed = custom_transport::parse_options(argc, argv, options);
  if (parsed.exit_code) return *parsed.exit_code;
  const int ticks = options.ticks;

  MailboxTransport transport;
  ScriptedHand hand;
  tp::NoForceEstimator estimator;  // or your own: estimate(measured, setpoint, force) noexcept
  endohaptics::kinematics::CylindricalMapper<> mapper;
  endohaptics::ManualClock clock;  // simulated time; use endohaptics::SteadyClock on a real rig
  tp::TeleopLoop loop(transport, hand, estimator, mapper, clock);

  int n = 0;
  loop.run([&] { return n >= ticks; },
           [&](const tp::TickResult& r) {
             if (++n % 500 == 0) {
               fmt::print("tick {:5}  {:<9} clamp1 setpoint {:+.3f} rad  position {:+.3f} rad\n", n,
                          to_string(r.status), r.setpoint[2], r.measured.position[2]);
             }
           });
  fmt::print("{}", loop.stats().to_table());
  try {
    endohaptics::workflow::require_written(stdout, "standard output");
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
  return loop.stats().received() == static_cast<std::uint64_t>(ticks) ? 0 : 1;
}
