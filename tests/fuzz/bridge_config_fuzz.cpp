// Fuzz target for the bridge configuration (files/bridge_config.hpp): the input is a
// configuration file's content, read as load_bridge_config reads it once the file is read
// (parse_bridge_config: the strict, bounded JSON parse with comments, the schema, the library's
// checks and the clamp model file it names). Model file names resolve against a private folder
// holding three valid model files (clamp.json: Hammerstein-Wiener, stall.json: stall_hold,
// bidirectional.json: bidirectional_load_observer), so that the seeds reach the model loading. It
// may refuse an input only with endohaptics::Error; whatever it accepts must write back
// (bridge_config_json) to a text that reads back to the same text again.
#include <stdlib.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <endohaptics/files/bridge_config.hpp>
#include <endohaptics/model/presets_2016.hpp>
#include <filesystem>
#include <string>
#include <string_view>

namespace {

namespace files = endohaptics::files;

std::filesystem::path g_dir;

void remove_dir() {
  std::error_code ec;
  std::filesystem::remove_all(g_dir, ec);
}

void write_models() {
  const std::vector<files::SignalInfo> clamp_inputs{{"current", "A"}, {"velocity", "rad/s"}};
  files::save_model(g_dir / "clamp.json",
                    files::make_model_file(endohaptics::model::yaw_force_2016_hw(0.3), clamp_inputs,
                                           {{"force", "N"}}));
  endohaptics::estimation::StallHoldParameters<double> stall;
  stall.gain = -7.5;
  stall.side = endohaptics::estimation::StallHoldSide::negative;
  stall.sample_time = 0.01;
  files::save_model(g_dir / "stall.json",
                    files::make_joint_model_file(stall, clamp_inputs, {{"force", "N"}}));
  endohaptics::estimation::BidirectionalLoadObserverParameters<double> b;
  b.forward_gain = -1.41e-3;
  b.forward_gain_stroke = -2.3e-4;
  b.forward_offset = 0.066;
  b.backward_gain = -6.1e-4;
  b.backward_offset = -0.09;
  b.backward_offset_stroke = 0.035;
  b.forward_variance = 9000.0;
  b.backward_variance = 30000.0;
  b.friction_variance = 62.0;
  b.load_process_variance = 0.002;
  b.initial_load = -65.8;
  b.initial_variance = 1180.0;
  b.output_offset = 0.26;
  b.output_shape << 0.2, 0.25, -0.38, 1.15, 1.1, 0.66, 0.12, -0.78;
  b.output_shape_per_load << 0.008, -0.012, 0.003, 0.0, -0.003, 0.0, 0.01, 0.089;
  files::save_model(g_dir / "bidirectional.json",
                    files::make_joint_model_file(b, clamp_inputs, {{"grip_torque", "mN m"}}));
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
  char templ[] = "/tmp/endohaptics-fuzz-bridge-XXXXXX";
  const char* made = ::mkdtemp(templ);
  if (made == nullptr) {
    std::perror("fuzz_bridge_config: mkdtemp");
    std::exit(2);
  }
  g_dir = made;
  std::atexit(remove_dir);
  write_models();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  std::string written;
  try {
    written = files::bridge_config_json(files::parse_bridge_config(text, "fuzz input", g_dir));
  } catch (const endohaptics::Error&) {
    return 0;  // a refusal with a message: expected for most inputs
  }
  // What the bridge writes must read back, to the same configuration.
  try {
    const files::BridgeConfig again = files::parse_bridge_config(written, "round trip", g_dir);
    if (files::bridge_config_json(again) != written) std::abort();
  } catch (const endohaptics::Error& e) {
    std::fprintf(stderr, "fuzz_bridge_config: the configuration written does not read back: %s\n",
                 e.what());
    std::abort();
  }
  return 0;
}
