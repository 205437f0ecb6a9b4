// PacketCodec (binary float32 big-endian, worksheet 3.2.2) against the 2016 JSON message it
// replaced (listing 3.1), on the same 4-motor state, in the same run; and protocol v2
// (SecureCodec: header + 2016 packet + keyed BLAKE2b-128 tag) against the 2016 decode, and the v2
// session layer (handshake, per-packet exchange) against the bare codec.
#include <benchmark/benchmark.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <endohaptics/protocol/packet_codec.hpp>
#include <endohaptics/protocol/replay_window.hpp>
#include <endohaptics/protocol/secure_codec.hpp>
#include <endohaptics/protocol/secure_session.hpp>
#include <stdexcept>
#include <string>

#include "legacy_json_codec.hpp"

namespace packet_codec_bench {

namespace {

using Codec = endohaptics::protocol::PacketCodec<4>;
using Json = endohaptics::baseline::LegacyJsonCodec<4>;
using endohaptics::protocol::CodecStatus;

// The first four motors of listing 3.1.
Codec::State listing_state() {
  Codec::State s;
  s.position << 0.18189165291842698, 0.00013089955609757453, -0.0001266769975192886591,
      -0.1987191723699879841951;
  s.velocity << 0.0245981621957453203, 0.0019754796320965562379, 0.0015707947313785552979,
      0.00013089955609757453203;
  s.current << -0.48593282699584960938, -0.31835031509399414063, -0.36891269683837890625,
      -0.39591121673583984375;
  s.active_mask = 0x0F;
  return s;
}

void BM_PacketCodec_decode_state(benchmark::State& st) {
  Codec::StateBytes bytes{};
  if (Codec::encode_state(listing_state(), bytes) != CodecStatus::ok) st.SkipWithError("encode");
  Codec::State out;
  for (auto _ : st) {
    benchmark::DoNotOptimize(bytes);
    const CodecStatus status = Codec::decode_state(bytes, out);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(out);
  }
  st.counters["bytes"] = static_cast<double>(bytes.size());
}
BENCHMARK(BM_PacketCodec_decode_state);

void BM_PacketCodec_encode_state(benchmark::State& st) {
  const Codec::State state = listing_state();
  Codec::StateBytes bytes{};
  for (auto _ : st) {
    benchmark::DoNotOptimize(state);
    const CodecStatus status = Codec::encode_state(state, bytes);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(bytes);
  }
  st.counters["bytes"] = static_cast<double>(bytes.size());
}
BENCHMARK(BM_PacketCodec_encode_state);

void BM_PacketCodec_encode_setpoint(benchmark::State& st) {
  Codec::Setpoint setpoint;
  setpoint.position << -0.7, 0.3, 1.2, -1.2;
  setpoint.enable_mask = 0x0F;
  Codec::SetpointBytes bytes{};
  for (auto _ : st) {
    benchmark::DoNotOptimize(setpoint);
    const CodecStatus status = Codec::encode_setpoint(setpoint, bytes);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(bytes);
  }
  st.counters["bytes"] = static_cast<double>(bytes.size());
}
BENCHMARK(BM_PacketCodec_encode_setpoint);

void BM_Baseline2016_json_parse_state(benchmark::State& st) {
  const std::string text = Json::encode(listing_state());
  Codec::State out;
  for (auto _ : st) {
    benchmark::DoNotOptimize(text.data());
    const bool ok = Json::parse(text, out);
    benchmark::DoNotOptimize(ok);
    benchmark::DoNotOptimize(out);
  }
  st.counters["bytes"] = static_cast<double>(text.size());
}
BENCHMARK(BM_Baseline2016_json_parse_state);

void BM_Baseline2016_json_encode_state(benchmark::State& st) {
  const Codec::State state = listing_state();
  std::size_t size = 0;
  for (auto _ : st) {
    benchmark::DoNotOptimize(state);
    std::string text = Json::encode(state);
    size = text.size();
    benchmark::DoNotOptimize(text.data());
  }
  st.counters["bytes"] = static_cast<double>(size);
}
BENCHMARK(BM_Baseline2016_json_encode_state);

// ---- protocol v2 (docs/protocol.md) ----
using Secure = endohaptics::protocol::SecureCodec<4>;
using endohaptics::protocol::PacketType;
using endohaptics::protocol::SecureHeader;
using endohaptics::protocol::SecureKey;
using endohaptics::protocol::SecureStatus;

SecureKey bench_key() {
  std::array<std::byte, SecureKey::size> k{};
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = std::byte{static_cast<std::uint8_t>(i)};
  return SecureKey(k);
}

// Seal a state (2016 encode + header + tag), a new sequence number each time.
void BM_SecureCodec_encode_state(benchmark::State& st) {
  const SecureKey key = bench_key();
  const Codec::State state = listing_state();
  std::array<std::byte, Secure::state_packet_size> bytes{};
  SecureHeader h{PacketType::state, 0xFEDCBA9876543210ull, 0, 0x0123456789ABCDEFull, 1};
  for (auto _ : st) {
    ++h.sequence;
    benchmark::DoNotOptimize(state);
    const SecureStatus status = Secure::encode_state(key, h, state, bytes);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(bytes);
  }
  st.counters["bytes"] = static_cast<double>(bytes.size());
}
BENCHMARK(BM_SecureCodec_encode_state);

void BM_SecureCodec_encode_setpoint(benchmark::State& st) {
  const SecureKey key = bench_key();
  Codec::Setpoint setpoint;
  setpoint.position << -0.7, 0.3, 1.2, -1.2;
  setpoint.enable_mask = 0x0F;
  std::array<std::byte, Secure::setpoint_packet_size> bytes{};
  SecureHeader h{PacketType::setpoint, 0x0123456789ABCDEFull, 0, 0xFEDCBA9876543210ull, 1};
  for (auto _ : st) {
    ++h.sequence;
    benchmark::DoNotOptimize(setpoint);
    const SecureStatus status = Secure::encode_setpoint(key, h, setpoint, bytes);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(bytes);
  }
  st.counters["bytes"] = static_cast<double>(bytes.size());
}
BENCHMARK(BM_SecureCodec_encode_setpoint);

// Verify the tag (constant-time compare), then the 2016 decode: what a receiver does per packet
// before the replay window (BM_ReplayWindow_check_accept).
void BM_SecureCodec_verify_decode_state(benchmark::State& st) {
  const SecureKey key = bench_key();
  std::array<std::byte, Secure::state_packet_size> bytes{};
  const SecureHeader h{PacketType::state, 0xFEDCBA9876543210ull, 1, 0x0123456789ABCDEFull, 1};
  if (Secure::encode_state(key, h, listing_state(), bytes) != SecureStatus::ok) {
    st.SkipWithError("encode");
  }
  SecureHeader header;
  Codec::State out;
  for (auto _ : st) {
    benchmark::DoNotOptimize(bytes);
    const SecureStatus status = Secure::decode_state(key, bytes, header, out);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(out);
  }
  st.counters["bytes"] = static_cast<double>(bytes.size());
}
BENCHMARK(BM_SecureCodec_verify_decode_state);

void BM_SecureCodec_verify_decode_setpoint(benchmark::State& st) {
  const SecureKey key = bench_key();
  Codec::Setpoint setpoint;
  setpoint.position << -0.7, 0.3, 1.2, -1.2;
  setpoint.enable_mask = 0x0F;
  std::array<std::byte, Secure::setpoint_packet_size> bytes{};
  const SecureHeader h{PacketType::setpoint, 0x0123456789ABCDEFull, 1, 0, 0};
  if (Secure::encode_setpoint(key, h, setpoint, bytes) != SecureStatus::ok) {
    st.SkipWithError("encode");
  }
  SecureHeader header;
  Codec::Setpoint out;
  for (auto _ : st) {
    benchmark::DoNotOptimize(bytes);
    const SecureStatus status = Secure::decode_setpoint(key, bytes, header, out);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(out);
  }
  st.counters["bytes"] = static_cast<double>(bytes.size());
}
BENCHMARK(BM_SecureCodec_verify_decode_setpoint);

// A forged state is refused after one tag computation, like a valid one.
void BM_SecureCodec_reject_forged_state(benchmark::State& st) {
  const SecureKey key = bench_key();
  std::array<std::byte, Secure::state_packet_size> bytes{};
  const SecureHeader h{PacketType::state, 1, 1, 2, 1};
  if (Secure::encode_state(key, h, listing_state(), bytes) != SecureStatus::ok) {
    st.SkipWithError("encode");
  }
  bytes[40] ^= std::byte{1};
  SecureHeader header;
  Codec::State out;
  for (auto _ : st) {
    benchmark::DoNotOptimize(bytes);
    const SecureStatus status = Secure::decode_state(key, bytes, header, out);
    benchmark::DoNotOptimize(status);
  }
}
BENCHMARK(BM_SecureCodec_reject_forged_state);

// ---- protocol v2 sessions: per packet and per handshake ----
using endohaptics::protocol::HandshakeCodec;
using Initiator = endohaptics::protocol::SecureInitiator<4>;
using Responder = endohaptics::protocol::SecureResponder<4>;

endohaptics::protocol::InitiatorConfig console_config() {
  endohaptics::protocol::InitiatorConfig c;
  c.rig = endohaptics::protocol::make_rig_id("bench");
  return c;
}
endohaptics::protocol::ResponderConfig robot_config() {
  endohaptics::protocol::ResponderConfig c;
  c.rig = endohaptics::protocol::make_rig_id("bench");
  return c;
}

// HELLO, WELCOME and both sides' key derivations at `now`: the console is then established.
void handshake(Initiator& pc, Responder& robot, std::chrono::nanoseconds now) {
  HandshakeCodec::Bytes hello{};
  std::array<std::byte, Initiator::send_payload_size> got{};
  std::array<std::byte, Initiator::receive_payload_size> state{};
  if (!pc.hello_due(now, hello) || robot.open(hello, got, now) != SecureStatus::hello ||
      pc.open(robot.take_reply(), state, now) != SecureStatus::welcome) {
    throw std::runtime_error("handshake failed");
  }
}

// One exchange of the session layer, per packet both ways: the console seals a setpoint, the
// robot side verifies it (tag, session, window, order, freshness) and seals its state, the console
// verifies that. Against the baseline below: the same four codec calls and two replay windows,
// the per-packet work of the session layer before the handshake (its tags under the long-term
// key, no freshness lookup).
void BM_V2Session_exchange(benchmark::State& st) {
  Initiator pc(bench_key(), console_config());
  Responder robot(bench_key(), robot_config());
  handshake(pc, robot, std::chrono::nanoseconds(0));
  std::array<std::byte, Initiator::send_payload_size> setpoint{};
  std::array<std::byte, Responder::send_payload_size> state{};
  std::array<std::byte, Initiator::send_packet_size> sp{};
  std::array<std::byte, Responder::send_packet_size> sp_state{};
  std::int64_t t = 0;
  for (auto _ : st) {
    const std::chrono::nanoseconds now(t += 1000);
    if (pc.seal(setpoint, sp) != SecureStatus::ok ||
        robot.open(sp, setpoint, now) != SecureStatus::ok ||
        robot.seal(state, sp_state) != SecureStatus::ok ||
        pc.open(sp_state, state, now) != SecureStatus::ok) {
      st.SkipWithError("exchange refused");
      break;
    }
  }
  st.SetItemsProcessed(st.iterations() * 2);
}
BENCHMARK(BM_V2Session_exchange);

void BM_V2Codec_exchange_baseline(benchmark::State& st) {
  const SecureKey key = bench_key();
  std::array<std::byte, Secure::Legacy::setpoint_packet_size> setpoint{};
  std::array<std::byte, Secure::Legacy::state_packet_size> state{};
  std::array<std::byte, Secure::setpoint_packet_size> sp{};
  std::array<std::byte, Secure::state_packet_size> sp_state{};
  endohaptics::protocol::ReplayWindow robot_window, pc_window;
  std::uint64_t sequence = 0;
  for (auto _ : st) {
    ++sequence;
    SecureHeader h;
    std::span<const std::byte> payload;
    if (Secure::seal(key, {PacketType::setpoint, 1, sequence, 2, sequence - 1}, setpoint, sp) !=
            SecureStatus::ok ||
        Secure::open(key, PacketType::setpoint, sp, h, payload) != SecureStatus::ok ||
        robot_window.check_and_accept(h.sequence) != endohaptics::protocol::WindowStatus::ok ||
        Secure::seal(key, {PacketType::state, 2, sequence, 1, sequence}, state, sp_state) !=
            SecureStatus::ok ||
        Secure::open(key, PacketType::state, sp_state, h, payload) != SecureStatus::ok ||
        pc_window.check_and_accept(h.sequence) != endohaptics::protocol::WindowStatus::ok) {
      st.SkipWithError("exchange refused");
      break;
    }
    std::memcpy(setpoint.data(), payload.data(), 1);
  }
  st.SetItemsProcessed(st.iterations() * 2);
}
BENCHMARK(BM_V2Codec_exchange_baseline);

// The handshake's CPU cost, both sides: HELLO sealed and verified, WELCOME sealed and verified,
// four session key derivations, and the first setpoint that makes the new session the robot
// side's (a rekey of a live pair every iteration: the sessions' locked key slots are allocated
// once, at construction, as in the programs).
void BM_V2Handshake_cpu(benchmark::State& st) {
  endohaptics::protocol::InitiatorConfig cfg = console_config();
  cfg.rekey_after = std::chrono::seconds(1);
  endohaptics::protocol::ResponderConfig slow = robot_config();
  slow.expiry = std::chrono::seconds(60);
  Initiator pc(bench_key(), cfg);
  Responder robot(bench_key(), slow);
  std::array<std::byte, Initiator::send_payload_size> setpoint{};
  std::array<std::byte, Initiator::send_packet_size> sp{};
  std::chrono::nanoseconds now{0};
  for (auto _ : st) {
    handshake(pc, robot, now);
    if (pc.seal(setpoint, sp) != SecureStatus::ok ||
        robot.open(sp, setpoint, now) != SecureStatus::ok) {
      st.SkipWithError("the new session was not taken");
      break;
    }
    now += std::chrono::milliseconds(1001);
  }
  st.counters["sessions"] = static_cast<double>(robot.sessions());
}
BENCHMARK(BM_V2Handshake_cpu);

void BM_ReplayWindow_check_accept(benchmark::State& st) {
  endohaptics::protocol::ReplayWindow window;
  std::uint64_t sequence = 0;
  for (auto _ : st) {
    sequence += 1 + (sequence & 1u);  // in order with gaps: the window slides every time
    benchmark::DoNotOptimize(window.check_and_accept(sequence));
  }
}
BENCHMARK(BM_ReplayWindow_check_accept);

}  // namespace

}  // namespace packet_codec_bench
