#include "endohaptics/protocol/packet_codec.hpp"

#include <doctest/doctest.h>

#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace protocol_packet_codec_test {

namespace {

using endohaptics::protocol::CodecStatus;
using endohaptics::protocol::PacketCodec;
using Codec4 = PacketCodec<4>;

template <std::size_t N>
std::array<std::byte, N> bytes_of(const std::array<std::uint8_t, N>& raw) {
  std::array<std::byte, N> out{};
  for (std::size_t i = 0; i < N; ++i) out[i] = std::byte{raw[i]};
  return out;
}

// Random float32 bit patterns that are finite: exercises +-0, subnormals, normals, +-max.
float random_finite_float(std::mt19937_64& rng) {
  for (;;) {
    const auto bits = static_cast<std::uint32_t>(rng());
    if ((bits & 0x7F800000u) != 0x7F800000u) return std::bit_cast<float>(bits);
  }
}

bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

}  // namespace

TEST_CASE("packet sizes are those of the worksheet (49 and 17 bytes for 4 motors)") {
  CHECK(Codec4::state_packet_size == 49);
  CHECK(Codec4::setpoint_packet_size == 17);
  CHECK(PacketCodec<1>::state_packet_size == 13);
  CHECK(PacketCodec<8>::state_packet_size == 97);
  CHECK(PacketCodec<7>::setpoint_packet_size == 29);
  CHECK(PacketCodec<8>::valid_mask == 0xFF);
  CHECK(PacketCodec<3>::valid_mask == 0x07);
}

TEST_CASE("state packet: golden bytes worked out by hand") {
  // float32 big-endian, by hand from IEEE-754 binary32 (sign | 8-bit exponent | 23-bit mantissa):
  //   1.0 = 0x3F800000, -2.0 = 0xC0000000, 0.5 = 0x3F000000, 0.25 = 0x3E800000,
  //   0.0 = 0x00000000, -0.0 = 0x80000000, 2.0 = 0x40000000, -0.5 = 0xBF000000,
  //   0.1875 = 1.5 * 2^-3 = 0x3E400000, 100 = 1.5625 * 2^6 = 0x42C80000,
  //   -1.5 = 0xBFC00000, 3.0 = 1.5 * 2^1 = 0x40400000; mask motors 0 and 2 active = 0x05.
  const auto golden = bytes_of<49>({0x3F, 0x80, 0x00, 0x00, 0xC0, 0x00, 0x00, 0x00,
                                    0x3F, 0x00, 0x00, 0x00, 0x3E, 0x80, 0x00, 0x00,  // positions
                                    0x00, 0x00, 0x00, 0x00, 0x80, 0x00, 0x00, 0x00,
                                    0x40, 0x00, 0x00, 0x00, 0xBF, 0x00, 0x00, 0x00,  // velocities
                                    0x3E, 0x40, 0x00, 0x00, 0x42, 0xC8, 0x00, 0x00,
                                    0xBF, 0xC0, 0x00, 0x00, 0x40, 0x40, 0x00, 0x00,  // efforts
                                    0x05});
  Codec4::State state;
  state.position << 1.0, -2.0, 0.5, 0.25;
  state.velocity << 0.0, -0.0, 2.0, -0.5;
  state.current << 0.1875, 100.0, -1.5, 3.0;
  state.active_mask = 0x05;

  Codec4::StateBytes encoded{};
  REQUIRE(Codec4::encode_state(state, encoded) == CodecStatus::ok);
  CHECK(encoded == golden);

  Codec4::State decoded;
  REQUIRE(Codec4::decode_state(golden, decoded) == CodecStatus::ok);
  CHECK(decoded == state);
  CHECK(std::signbit(decoded.velocity[1]));  // -0.0 survives
}

TEST_CASE("state packet: the values of worksheet listing 3.1 (first four motors)") {
  // Bytes from Python: struct.pack('>f', x) for the first four entries of each array of
  // listing 3.1, all motors active (0x0F).
  const auto golden =
      bytes_of<49>({0x3E, 0x3A, 0x41, 0xCE, 0x39, 0x09, 0x42, 0x15, 0xB9, 0x04, 0xD4, 0x99, 0xBE,
                    0x4B, 0x7D, 0x0A, 0x3C, 0xC9, 0x82, 0x16, 0x3B, 0x01, 0x77, 0x0C, 0x3A, 0xCD,
                    0xE3, 0x20, 0x39, 0x09, 0x42, 0x15, 0xBE, 0xF8, 0xCC, 0x30, 0xBE, 0xA2, 0xFE,
                    0xD0, 0xBE, 0xBC, 0xE2, 0x20, 0xBE, 0xCA, 0xB4, 0xE0, 0x0F});
  Codec4::State decoded;
  REQUIRE(Codec4::decode_state(golden, decoded) == CodecStatus::ok);
  CHECK(decoded.position[0] == 0.18189164996147156);  // nearest float32 of 0.181891652918...
  CHECK(decoded.position[3] == -0.19871917366981506);
  CHECK(decoded.velocity[1] == 0.0019754795357584953);
  CHECK(decoded.current[0] == -0.4859328269958496);  // exactly representable in float32
  CHECK(decoded.active_mask == 0x0F);

  // Encoding the listing's double values gives the same bytes (round to nearest float32).
  Codec4::State listing;
  listing.position << 0.18189165291842698526913, 0.00013089955609757453203,
      -0.0001266769975192886591, -0.1987191723699879841951;
  listing.velocity << 0.0245981621957453203, 0.0019754796320965562379, 0.0015707947313785552979,
      0.00013089955609757453203;
  listing.current << -0.48593282699584960938, -0.31835031509399414063, -0.36891269683837890625,
      -0.39591121673583984375;
  listing.active_mask = 0x0F;
  Codec4::StateBytes encoded{};
  REQUIRE(Codec4::encode_state(listing, encoded) == CodecStatus::ok);
  CHECK(encoded == golden);
}

TEST_CASE("setpoint packet: golden bytes worked out by hand") {
  // -0.7 is not representable: nearest float32 is 0xBF333333 (= -0.699999988079071).
  // 5.384 -> 0x40AC49BA (nearest float32 5.38399982452392578125).
  const auto golden =
      bytes_of<17>({0xBF, 0x33, 0x33, 0x33, 0x40, 0xAC, 0x49, 0xBA, 0x00, 0x00, 0x00, 0x00, 0xC1,
                    0x20, 0x00, 0x00, 0x0B});  // -10.0 = 0xC1200000; mask motors 0, 1, 3
  Codec4::Setpoint setpoint;
  setpoint.position << -0.7, 5.384, 0.0, -10.0;
  setpoint.enable_mask = 0x0B;
  Codec4::SetpointBytes encoded{};
  REQUIRE(Codec4::encode_setpoint(setpoint, encoded) == CodecStatus::ok);
  CHECK(encoded == golden);

  Codec4::Setpoint decoded;
  REQUIRE(Codec4::decode_setpoint(golden, decoded) == CodecStatus::ok);
  CHECK(decoded.position[0] == static_cast<double>(-0.7f));
  CHECK(decoded.position[3] == -10.0);
  CHECK(decoded.enable_mask == 0x0B);
}

TEST_CASE_TEMPLATE("round trips are bit-exact for every finite float32", Codec, PacketCodec<1>,
                   PacketCodec<3>, PacketCodec<4>, PacketCodec<7>, PacketCodec<8>) {
  std::mt19937_64 rng(20161220);
  const std::array<float, 8> specials = {0.0f,
                                         -0.0f,
                                         std::numeric_limits<float>::denorm_min(),
                                         -std::numeric_limits<float>::denorm_min(),
                                         std::numeric_limits<float>::min(),
                                         std::numeric_limits<float>::max(),
                                         -std::numeric_limits<float>::max(),
                                         std::numeric_limits<float>::lowest()};
  for (int trial = 0; trial < 2000; ++trial) {
    typename Codec::State state;
    typename Codec::Setpoint setpoint;
    for (int i = 0; i < Codec::num_motors; ++i) {
      const bool special = trial < 64;
      auto pick = [&] {
        return static_cast<double>(special ? specials[rng() % specials.size()]
                                           : random_finite_float(rng));
      };
      state.position[i] = pick();
      state.velocity[i] = pick();
      state.current[i] = pick();
      setpoint.position[i] = pick();
    }
    state.active_mask = static_cast<std::uint8_t>(rng() & Codec::valid_mask);
    setpoint.enable_mask = static_cast<std::uint8_t>(rng() & Codec::valid_mask);

    typename Codec::StateBytes sbytes{};
    REQUIRE(Codec::encode_state(state, sbytes) == CodecStatus::ok);
    typename Codec::State sback;
    REQUIRE(Codec::decode_state(sbytes, sback) == CodecStatus::ok);
    for (int i = 0; i < Codec::num_motors; ++i) {
      REQUIRE(same_bits(sback.position[i], state.position[i]));
      REQUIRE(same_bits(sback.velocity[i], state.velocity[i]));
      REQUIRE(same_bits(sback.current[i], state.current[i]));
    }
    REQUIRE(sback.active_mask == state.active_mask);

    typename Codec::SetpointBytes pbytes{};
    REQUIRE(Codec::encode_setpoint(setpoint, pbytes) == CodecStatus::ok);
    typename Codec::Setpoint pback;
    REQUIRE(Codec::decode_setpoint(pbytes, pback) == CodecStatus::ok);
    for (int i = 0; i < Codec::num_motors; ++i) {
      REQUIRE(same_bits(pback.position[i], setpoint.position[i]));
    }
    REQUIRE(pback.enable_mask == setpoint.enable_mask);
  }
}

TEST_CASE_TEMPLATE("every wrong length is rejected and leaves the output untouched", Codec,
                   PacketCodec<1>, PacketCodec<4>, PacketCodec<8>) {
  typename Codec::State sentinel;
  sentinel.position.setConstant(42.0);
  sentinel.active_mask = 1;
  typename Codec::Setpoint sp_sentinel;
  sp_sentinel.position.setConstant(-7.0);
  sp_sentinel.enable_mask = 1;

  std::vector<std::byte> buffer(Codec::state_packet_size + 8, std::byte{0});
  for (std::size_t len = 0; len <= Codec::state_packet_size + 8; ++len) {
    auto state = sentinel;
    const auto status = Codec::decode_state(std::span(buffer.data(), len), state);
    if (len == Codec::state_packet_size) {
      CHECK(status == CodecStatus::ok);
    } else {
      CAPTURE(len);
      CHECK(status == CodecStatus::wrong_size);
      CHECK(state == sentinel);
    }
  }
  for (std::size_t len = 0; len <= Codec::setpoint_packet_size + 8; ++len) {
    auto setpoint = sp_sentinel;
    const auto status = Codec::decode_setpoint(std::span(buffer.data(), len), setpoint);
    if (len == Codec::setpoint_packet_size) {
      CHECK(status == CodecStatus::ok);
    } else {
      CAPTURE(len);
      CHECK(status == CodecStatus::wrong_size);
      CHECK(setpoint == sp_sentinel);
    }
  }
}

TEST_CASE("NaN and Inf anywhere in a received packet are rejected") {
  const std::array<std::uint32_t, 5> bad = {0x7FC00000u, 0xFFC00000u, 0x7F800001u, 0x7F800000u,
                                            0xFF800000u};  // qNaN, -qNaN, sNaN, +Inf, -Inf
  Codec4::State good;
  good.position << 0.1, 0.2, 0.3, 0.4;
  good.active_mask = 0x0F;
  Codec4::StateBytes clean{};
  REQUIRE(Codec4::encode_state(good, clean) == CodecStatus::ok);
  for (std::size_t field = 0; field < 12; ++field) {
    for (const auto pattern : bad) {
      auto bytes = clean;
      boost::endian::store_big_u32(reinterpret_cast<unsigned char*>(bytes.data()) + 4 * field,
                                   pattern);
      Codec4::State out = good;
      CAPTURE(field);
      CHECK(Codec4::decode_state(bytes, out) == CodecStatus::non_finite);
      CHECK(out == good);
    }
  }
  Codec4::SetpointBytes sp{};
  boost::endian::store_big_u32(reinterpret_cast<unsigned char*>(sp.data()) + 8, 0x7F800000u);
  Codec4::Setpoint sp_out;
  CHECK(Codec4::decode_setpoint(sp, sp_out) == CodecStatus::non_finite);
}

TEST_CASE("mask bits at or above the number of motors are rejected") {
  Codec4::StateBytes bytes{};
  for (unsigned mask = 0; mask < 256; ++mask) {
    bytes.back() = std::byte{static_cast<std::uint8_t>(mask)};
    Codec4::State out;
    const auto status = Codec4::decode_state(bytes, out);
    CAPTURE(mask);
    CHECK(status == (mask < 16 ? CodecStatus::ok : CodecStatus::mask_out_of_range));
  }
  PacketCodec<8>::SetpointBytes full{};
  full.back() = std::byte{0xFF};
  PacketCodec<8>::Setpoint out8;
  CHECK(PacketCodec<8>::decode_setpoint(full, out8) == CodecStatus::ok);
  CHECK(out8.enable_mask == 0xFF);
}

TEST_CASE("encoding refuses what it cannot send faithfully and leaves the buffer untouched") {
  Codec4::SetpointBytes buffer{};
  buffer.fill(std::byte{0xAA});
  const auto untouched = buffer;
  Codec4::Setpoint setpoint;

  SUBCASE("NaN setpoint") {
    setpoint.position[2] = std::numeric_limits<double>::quiet_NaN();
    CHECK(Codec4::encode_setpoint(setpoint, buffer) == CodecStatus::non_finite);
  }
  SUBCASE("infinite setpoint") {
    setpoint.position[0] = -std::numeric_limits<double>::infinity();
    CHECK(Codec4::encode_setpoint(setpoint, buffer) == CodecStatus::non_finite);
  }
  SUBCASE("finite double beyond float32 range") {
    setpoint.position[1] = 1e39;
    CHECK(Codec4::encode_setpoint(setpoint, buffer) == CodecStatus::out_of_range);
  }
  SUBCASE("enable bit for a motor that does not exist") {
    setpoint.enable_mask = 0x10;
    CHECK(Codec4::encode_setpoint(setpoint, buffer) == CodecStatus::mask_out_of_range);
  }
  CHECK(buffer == untouched);

  Codec4::State state;
  state.current[3] = std::numeric_limits<double>::signaling_NaN();
  Codec4::StateBytes sbytes{};
  CHECK(Codec4::encode_state(state, sbytes) == CodecStatus::non_finite);
}

TEST_CASE("status names are readable") {
  CHECK(to_string(CodecStatus::ok) == "ok");
  CHECK(to_string(CodecStatus::wrong_size) == "wrong packet size");
  CHECK(to_string(CodecStatus::non_finite) == "non-finite value");
  CHECK(to_string(CodecStatus::mask_out_of_range) == "mask bit at or above the number of motors");
}

}  // namespace protocol_packet_codec_test
