// Codec round trip over UDP loopback: a stand-in sbRIO thread answers every setpoint packet
// with a state packet (position = setpoint, all enabled motors active); the PC side encodes,
// sends, waits for the answer, decodes and prints both packets.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <utility>  // before Asio: its awaitable.hpp uses std::exchange without it

#include <boost/asio.hpp>
#include <chrono>
#include <endohaptics/protocol/packet_codec.hpp>
#include <endohaptics/workflow/command_line.hpp>
#include <exception>
#include <string>
#include <thread>

#include "options.hpp"

using Codec = endohaptics::protocol::PacketCodec<4>;
using boost::asio::ip::udp;
using endohaptics::protocol::CodecStatus;

namespace {

void fake_sbrio(udp::socket& socket, int count) {
  for (int i = 0; i < count; ++i) {
    Codec::SetpointBytes in{};
    udp::endpoint sender;
    const std::size_t n = socket.receive_from(boost::asio::buffer(in), sender);
    Codec::Setpoint setpoint;
    if (Codec::decode_setpoint(std::span(in.data(), n), setpoint) != CodecStatus::ok) continue;
    Codec::State state;
    state.position = setpoint.position;
    state.velocity.setConstant(0.01 * i);
    state.current.setConstant(-0.25);
    state.active_mask = setpoint.enable_mask;
    Codec::StateBytes out{};
    if (Codec::encode_state(state, out) == CodecStatus::ok) {
      socket.send_to(boost::asio::buffer(out), sender);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  codec_loopback::Options options;
  const examples::Parsed parsed = codec_loopback::parse_options(argc, argv, options);
  if (parsed.exit_code) return *parsed.exit_code;
  const int count = options.count;

  boost::asio::io_context io;
  udp::socket sbrio(io, udp::endpoint(boost::asio::ip::make_address("127.0.0.1"), 0));
  udp::socket pc(io, udp::endpoint(boost::asio::ip::make_address("127.0.0.1"), 0));
  pc.connect(sbrio.local_endpoint());
  std::thread responder(fake_sbrio, std::ref(sbrio), count);

  int ok = 0;
  for (int i = 0; i < count; ++i) {
    Codec::Setpoint setpoint;
    setpoint.position << 0.01 * i, -0.54, 0.7, -0.7;
    setpoint.enable_mask = 0x0F;
    Codec::SetpointBytes out{};
    if (Codec::encode_setpoint(setpoint, out) != CodecStatus::ok) return 1;
    const auto t0 = std::chrono::steady_clock::now();
    pc.send(boost::asio::buffer(out));
    Codec::StateBytes in{};
    const std::size_t n = pc.receive(boost::asio::buffer(in));
    const auto rtt = std::chrono::steady_clock::now() - t0;
    Codec::State state;
    const CodecStatus status = Codec::decode_state(std::span(in.data(), n), state);
    ok += status == CodecStatus::ok ? 1 : 0;
    if (i < 3 || i == count - 1) {
      std::string hex;
      for (const std::byte b : out) hex += fmt::format("{:02x}", std::to_integer<unsigned>(b));
      fmt::print("#{:<4} sent {:2} B  {}\n", i, out.size(), hex);
      fmt::print("      got  {:2} B  {} ({}), rtt {:.1f} us\n", n, to_string(status),
                 fmt::join(state.position, " "),
                 std::chrono::duration<double, std::micro>(rtt).count());
    }
  }
  responder.join();
  fmt::print("{}/{} round trips ok\n", ok, count);
  try {
    endohaptics::workflow::require_written(stdout, "standard output");
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
  return ok == count ? 0 : 1;
}
