// Built against an installed endohaptics: includes the umbrella header and round-trips a packet,
// then (component model_files) round-trips the appendix C yaw model through its JSON form.
#include <endohaptics/endohaptics.hpp>
#include <endohaptics/files/model_file.hpp>

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
  return 0;
}
