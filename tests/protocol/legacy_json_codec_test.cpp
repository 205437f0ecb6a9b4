#include "legacy_json_codec.hpp"

#include <doctest/doctest.h>

namespace protocol_legacy_json_codec_test {

using Json4 = endohaptics::baseline::LegacyJsonCodec<4>;

TEST_CASE("legacy JSON baseline: round trip and rejection of malformed messages") {
  Json4::State state;
  state.position << 0.18189165291842698, 0.00013089955609757453, -0.0001266769975192886591,
      -0.1987191723699879841951;
  state.velocity << 0.0245981621957453203, 0.0019754796320965562379, 0.0015707947313785552979,
      0.00013089955609757453203;
  state.current << -0.48593282699584960938, -0.31835031509399414063, -0.36891269683837890625,
      -0.39591121673583984375;
  const std::string text = Json4::encode(state);
  CHECK(text.rfind(R"({"p4_primary":{"effort":[)", 0) == 0);
  // The binary packet is 49 bytes; the JSON carries the same values in roughly 7x the bytes.
  CHECK(text.size() > 5 * 49);

  Json4::State back;
  REQUIRE(Json4::parse(text, back));
  CHECK(back.position == state.position);  // 17 significant digits: exact round trip
  CHECK(back.current == state.current);

  Json4::State untouched;
  untouched.position.setConstant(3.0);
  auto out = untouched;
  CHECK_FALSE(Json4::parse(R"({"p4_primary":{"position":[1,2,3]}})", out));
  CHECK_FALSE(Json4::parse(text.substr(0, text.size() / 2), out));
  CHECK_FALSE(Json4::parse(R"({"p4_primary":{"position":[1,2,3,"x"],"velocity":[1,2,3,4],)"
                           R"("effort":[1,2,3,4]}})",
                           out));
  CHECK(out == untouched);
}

}  // namespace protocol_legacy_json_codec_test
