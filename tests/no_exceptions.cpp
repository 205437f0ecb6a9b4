// Built with -fno-exceptions: the real-time headers must not need exceptions.
#include <endohaptics/protocol/packet_codec.hpp>

#include <cstdio>

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
  std::puts("no-exceptions build: codec round trip ok");
  return 0;
}
