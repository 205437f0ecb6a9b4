// Built against an installed endohaptics: includes the umbrella header and round-trips a packet.
#include <endohaptics/endohaptics.hpp>

#include <cstdio>

int main() {
  using Codec = endohaptics::protocol::PacketCodec<4>;
  Codec::Setpoint setpoint;
  setpoint.position << 0.1, -0.2, 0.3, -0.4;
  setpoint.enable_mask = 0x0F;
  Codec::SetpointBytes bytes{};
  if (Codec::encode_setpoint(setpoint, bytes) != endohaptics::protocol::CodecStatus::ok) return 1;
  Codec::Setpoint back;
  if (Codec::decode_setpoint(bytes, back) != endohaptics::protocol::CodecStatus::ok) return 1;
  std::printf("consumer: %zu-byte setpoint packet round trip ok\n", bytes.size());
  return back.enable_mask == 0x0F ? 0 : 1;
}
