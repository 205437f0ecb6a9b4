// Built against an installed endohaptics (or one added with add_subdirectory): round-trips a
// packet, then (component model_files) round-trips the appendix C yaw model through its JSON form,
// and (component secure_protocol, when the consumer links it: ENDOHAPTICS_CONSUMER_SECURE_PROTOCOL)
// seals and opens a protocol v2 setpoint (libsodium).
// The find_package consumer includes the umbrella header (the whole library, its offline layers in
// header-only form: 11 s of clang's time); the add_subdirectory consumer
// (ENDOHAPTICS_CONSUMER_COMPONENT_HEADERS) the headers it uses, which is what it tests (the
// targets and their include paths through add_subdirectory), in 3 s.
#if defined(ENDOHAPTICS_CONSUMER_COMPONENT_HEADERS)
#include <endohaptics/model/presets_2016.hpp>
#include <endohaptics/protocol/packet_codec.hpp>
#else
#include <endohaptics/endohaptics.hpp>
#endif
#include <endohaptics/files/model_file.hpp>
#if defined(ENDOHAPTICS_CONSUMER_SECURE_PROTOCOL)
#include <endohaptics/protocol/secure_codec.hpp>
#endif

#include <array>
#include <cstddef>
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
  if (back.enable_mask != 0x0F) return 1;

  namespace files = endohaptics::files;
  const auto yaw = endohaptics::model::yaw_force_2016();
  const files::ModelFile file =
      files::make_model_file(yaw, {{"current", "A"}, {"velocity", "rad/s"}}, {{"force", "N"}});
  const endohaptics::model::StateSpace<6, 2, 1> loaded(
      files::model_from_json(files::to_json(file)).state_space);
  if (!loaded.A().isApprox(yaw.A())) return 1;
  std::printf("consumer: model file JSON round trip ok\n");

#if defined(ENDOHAPTICS_CONSUMER_SECURE_PROTOCOL)
  namespace protocol = endohaptics::protocol;
  using Secure = protocol::SecureCodec<4>;
  std::array<std::byte, protocol::SecureKey::size> key_bytes{};
  key_bytes[0] = std::byte{1};
  const protocol::SecureKey key(key_bytes);
  const protocol::SecureHeader header{protocol::PacketType::setpoint, 7, 1, 0, 0};
  std::array<std::byte, Secure::setpoint_packet_size> sealed{};
  if (Secure::encode_setpoint(key, header, setpoint, sealed) != protocol::SecureStatus::ok)
    return 1;
  protocol::SecureHeader opened;
  Codec::Setpoint again;
  if (Secure::decode_setpoint(key, sealed, opened, again) != protocol::SecureStatus::ok) return 1;
  sealed[20] ^= std::byte{1};
  if (Secure::decode_setpoint(key, sealed, opened, again) != protocol::SecureStatus::forged)
    return 1;
  std::printf("consumer: protocol v2 seal, open and forgery check ok\n");
#endif
  return 0;
}
