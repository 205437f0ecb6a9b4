// Fuzz target for the PacketCodec decoders (the 2016 wire). With clang it links libFuzzer
// (-fsanitize=fuzzer); otherwise corpus_replay_driver.cpp replays the seed corpus.
#include <endohaptics/protocol/packet_codec.hpp>

#include <cstdint>
#include <cstdlib>
#include <span>

namespace {

template <int N>
void check_codec(std::span<const std::byte> bytes) {
  using Codec = endohaptics::protocol::PacketCodec<N>;
  using endohaptics::protocol::CodecStatus;
  typename Codec::State state;
  if (Codec::decode_state(bytes, state) == CodecStatus::ok) {
    // Whatever decodes must re-encode to exactly the same bytes (NaN can never get through).
    typename Codec::StateBytes again{};
    if (Codec::encode_state(state, again) != CodecStatus::ok) std::abort();
    for (std::size_t i = 0; i < again.size(); ++i) {
      if (again[i] != bytes[i]) std::abort();
    }
  }
  typename Codec::Setpoint setpoint;
  if (Codec::decode_setpoint(bytes, setpoint) == CodecStatus::ok) {
    typename Codec::SetpointBytes again{};
    if (Codec::encode_setpoint(setpoint, again) != CodecStatus::ok) std::abort();
    for (std::size_t i = 0; i < again.size(); ++i) {
      if (again[i] != bytes[i]) std::abort();
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data), size);
  check_codec<1>(bytes);
  check_codec<4>(bytes);
  check_codec<7>(bytes);
  check_codec<8>(bytes);
  return 0;
}
