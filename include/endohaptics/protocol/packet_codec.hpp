//! @file
//! PacketCodec: the 2016 sbRIO binary UDP protocol (worksheet 3.2.2, 3.3.1, figure 3.4).
//! State packet sbRIO -> PC: position[N], velocity[N], current[N] (the worksheet's "effort") as
//! IEEE-754 float32 big-endian, then one byte of active bits (12N + 1 bytes). Setpoint packet PC ->
//! sbRIO: setpoint[N] float32 big-endian, then one byte of enable bits (4N + 1 bytes). Units on the
//! wire: rad (motor side, after gearing), rad/s, A. See docs/protocol.md.
#pragma once

#include <Eigen/Core>
#include <array>
#include <bit>
#include <boost/endian/conversion.hpp>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string_view>

namespace endohaptics::protocol {

//! Outcome of an encode or decode. On anything but `ok` the output is left untouched.
enum class CodecStatus : std::uint8_t {
  ok = 0,
  wrong_size,         //!< datagram length differs from the packet size (short, long, empty)
  non_finite,         //!< NaN or +-Inf in a value field
  out_of_range,       //!< encode: finite value too large for float32 (|x| > FLT_MAX)
  mask_out_of_range,  //!< enable/active bit set at or above the number of motors
};

//! Human-readable name of a status, for logs and error messages.
[[nodiscard]] constexpr std::string_view to_string(CodecStatus status) noexcept {
  switch (status) {
    case CodecStatus::ok:
      return "ok";
    case CodecStatus::wrong_size:
      return "wrong packet size";
    case CodecStatus::non_finite:
      return "non-finite value";
    case CodecStatus::out_of_range:
      return "value out of float32 range";
    case CodecStatus::mask_out_of_range:
      return "mask bit at or above the number of motors";
  }
  return "unknown status";
}

//! What the sbRIO reports for N motors: rad, rad/s, A, and bit i set when motor i is active.
template <int N>
struct MotorState {
  //! One value per motor.
  using Vector = Eigen::Matrix<double, N, 1>;
  Vector position = Vector::Zero();  //!< rad, motor side after gearing
  Vector velocity = Vector::Zero();  //!< rad/s
  Vector current = Vector::Zero();   //!< motor current, A (the 2016 protocol's "effort" field)
  std::uint8_t active_mask = 0;      //!< bit i: motor i is enabled and following its setpoint

  //! Member-wise equality.
  friend bool operator==(const MotorState&, const MotorState&) = default;
};

//! What the PC commands for N motors: position setpoints (rad) and bit i to enable motor i.
template <int N>
struct MotorSetpoint {
  //! One value per motor.
  using Vector = Eigen::Matrix<double, N, 1>;
  Vector position = Vector::Zero();  //!< rad, motor side after gearing
  std::uint8_t enable_mask = 0;      //!< bit i: enable motor i

  //! Member-wise equality.
  friend bool operator==(const MotorSetpoint&, const MotorSetpoint&) = default;
};

//! Bit-exact encoder/decoder of the 2016 sbRIO protocol for `NumMotors` motors (1..8).
//! All functions are static, noexcept, allocation-free and safe on any input bytes.
template <int NumMotors = 4>
class PacketCodec {
  static_assert(NumMotors >= 1 && NumMotors <= 8,
                "the protocol carries one mask byte: 1 to 8 motors");

 public:
  static constexpr int num_motors = NumMotors;  //!< motors per packet
  static constexpr std::size_t value_size = 4;  //!< float32
  static constexpr std::size_t state_packet_size = 3 * NumMotors * value_size + 1;  //!< bytes
  static constexpr std::size_t setpoint_packet_size = NumMotors * value_size + 1;   //!< bytes
  //! Bits that may be set in a mask byte.
  static constexpr std::uint8_t valid_mask = static_cast<std::uint8_t>((1u << NumMotors) - 1u);

  using State = MotorState<NumMotors>;                                //!< decoded state packet
  using Setpoint = MotorSetpoint<NumMotors>;                          //!< setpoint to encode
  using StateBytes = std::array<std::byte, state_packet_size>;        //!< one state datagram
  using SetpointBytes = std::array<std::byte, setpoint_packet_size>;  //!< one setpoint datagram

  //! Writes the setpoint packet. Refuses non-finite or float32-overflowing setpoints and mask
  //! bits >= NumMotors; `out` is untouched unless the result is `ok`.
  [[nodiscard]] static CodecStatus encode_setpoint(
      const Setpoint& setpoint, std::span<std::byte, setpoint_packet_size> out) noexcept {
    if (const CodecStatus s = check_mask(setpoint.enable_mask); s != CodecStatus::ok) return s;
    if (const CodecStatus s = check_encodable(setpoint.position); s != CodecStatus::ok) return s;
    store_vector(setpoint.position, out.data());
    out[setpoint_packet_size - 1] = std::byte{setpoint.enable_mask};
    return CodecStatus::ok;
  }

  //! Reads a setpoint packet (the sbRIO side). `out` is untouched unless the result is `ok`.
  [[nodiscard]] static CodecStatus decode_setpoint(std::span<const std::byte> bytes,
                                                   Setpoint& out) noexcept {
    if (bytes.size() != setpoint_packet_size) return CodecStatus::wrong_size;
    const auto mask = std::to_integer<std::uint8_t>(bytes[setpoint_packet_size - 1]);
    if (const CodecStatus s = check_mask(mask); s != CodecStatus::ok) return s;
    if (!all_finite(bytes.data(), motors)) return CodecStatus::non_finite;
    load_vector(bytes.data(), out.position);
    out.enable_mask = mask;
    return CodecStatus::ok;
  }

  //! Writes the state packet (the sbRIO side). Same refusals as `encode_setpoint`.
  [[nodiscard]] static CodecStatus encode_state(
      const State& state, std::span<std::byte, state_packet_size> out) noexcept {
    if (const CodecStatus s = check_mask(state.active_mask); s != CodecStatus::ok) return s;
    for (const auto* v : {&state.position, &state.velocity, &state.current}) {
      if (const CodecStatus s = check_encodable(*v); s != CodecStatus::ok) return s;
    }
    std::byte* p = out.data();
    store_vector(state.position, p);
    store_vector(state.velocity, p + block_size);
    store_vector(state.current, p + 2 * block_size);
    out[state_packet_size - 1] = std::byte{state.active_mask};
    return CodecStatus::ok;
  }

  //! Reads a state packet. Rejects any length but `state_packet_size`, NaN/Inf values and mask
  //! bits >= NumMotors. `out` is untouched unless the result is `ok`.
  [[nodiscard]] static CodecStatus decode_state(std::span<const std::byte> bytes,
                                                State& out) noexcept {
    if (bytes.size() != state_packet_size) return CodecStatus::wrong_size;
    const auto mask = std::to_integer<std::uint8_t>(bytes[state_packet_size - 1]);
    if (const CodecStatus s = check_mask(mask); s != CodecStatus::ok) return s;
    const std::byte* p = bytes.data();
    if (!all_finite(p, 3 * motors)) return CodecStatus::non_finite;
    load_vector(p, out.position);
    load_vector(p + block_size, out.velocity);
    load_vector(p + 2 * block_size, out.current);
    out.active_mask = mask;
    return CodecStatus::ok;
  }

 private:
  using Vector = Eigen::Matrix<double, NumMotors, 1>;
  static constexpr auto motors = static_cast<std::size_t>(NumMotors);
  static constexpr std::size_t block_size = motors * value_size;

  static constexpr CodecStatus check_mask(std::uint8_t mask) noexcept {
    return (mask & ~valid_mask) != 0 ? CodecStatus::mask_out_of_range : CodecStatus::ok;
  }

  // A double converts to float32 without undefined behaviour only when |x| <= FLT_MAX
  // (values between FLT_MAX and the next float up round to FLT_MAX or overflow; refuse both).
  static CodecStatus check_encodable(const Vector& v) noexcept {
    constexpr double max_float = static_cast<double>(std::numeric_limits<float>::max());
    for (int i = 0; i < NumMotors; ++i) {
      if (!std::isfinite(v[i])) return CodecStatus::non_finite;
      if (std::fabs(v[i]) > max_float) return CodecStatus::out_of_range;
    }
    return CodecStatus::ok;
  }

  static void store_vector(const Vector& v, std::byte* p) noexcept {
    for (int i = 0; i < NumMotors; ++i) {
      const auto bits = std::bit_cast<std::uint32_t>(static_cast<float>(v[i]));
      boost::endian::store_big_u32(as_uchar(p) + static_cast<std::size_t>(i) * value_size, bits);
    }
  }

  static std::uint32_t word(const std::byte* p, std::size_t i) noexcept {
    return boost::endian::load_big_u32(as_uchar(p) + i * value_size);
  }

  // True when none of the `count` words is NaN or Inf (exponent bits all ones, IEEE-754
  // binary32). Checked before anything is written, so the caller's output stays untouched.
  static bool all_finite(const std::byte* p, std::size_t count) noexcept {
    std::uint32_t non_finite = 0;
    for (std::size_t i = 0; i < count; ++i) {
      non_finite |= static_cast<std::uint32_t>((word(p, i) & 0x7F800000u) == 0x7F800000u);
    }
    return non_finite == 0;
  }

  static void load_vector(const std::byte* p, Vector& v) noexcept {
    for (int i = 0; i < NumMotors; ++i) {
      v[i] = static_cast<double>(std::bit_cast<float>(word(p, static_cast<std::size_t>(i))));
    }
  }

  // std::byte and unsigned char may alias each other; Boost.Endian takes unsigned char.
  static const unsigned char* as_uchar(const std::byte* p) noexcept {
    return reinterpret_cast<const unsigned char*>(p);
  }
  static unsigned char* as_uchar(std::byte* p) noexcept {
    return reinterpret_cast<unsigned char*>(p);
  }
};

}  // namespace endohaptics::protocol
