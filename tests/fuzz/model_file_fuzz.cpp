// Fuzz target for the model-file loader (files/model_file.hpp): the input is a file's content,
// parsed and validated exactly as load_model does after reading the file (the strict, bounded
// JSON parse with the model-file limits, then model_from_json). It may refuse an input only with
// endohaptics::Error; whatever it accepts must convert back to JSON and load again equal.
// (load_model itself is not called per input: its read_bounded zeroes a 64 MB buffer on every
// call, which leaves about 11 executions per second.)
#include <endohaptics/files/model_file.hpp>

#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace files = endohaptics::files;
  namespace jt = files::detail::json_text;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const files::ModelFile m =
        files::model_from_json(jt::parse_strict(text, "fuzz input",
                                                {.max_depth = files::model_file_max_depth,
                                                 .needed = "a model file needs 4",
                                                 .comments = false}),
                               "fuzz input");
    const files::ModelFile again = files::model_from_json(files::to_json(m), "fuzz round trip");
    if (again.state_space.A() != m.state_space.A() || again.state_space.B() != m.state_space.B() ||
        again.state_space.C() != m.state_space.C() || again.state_space.D() != m.state_space.D()) {
      std::abort();
    }
  } catch (const endohaptics::Error&) {
  }
  return 0;
}
