// PacketCodec (binary float32 big-endian, worksheet 3.2.2) against the 2016 JSON message it
// replaced (listing 3.1), on the same 4-motor state, in the same run.
#include <benchmark/benchmark.h>

#include <endohaptics/protocol/packet_codec.hpp>
#include <string>

#include "legacy_json_codec.hpp"

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

}  // namespace
