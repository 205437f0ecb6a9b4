// One declaration per parameter set: a struct's field list (for_each_field) gives its
// validate(), its JSON form and its readers' messages. A test-only parameter set shows what one
// added field costs: the two lines marked "added" (a member and its entry in the list) are the
// whole change; writing, reading, the unknown-key check and the range check follow.
#include <doctest/doctest.h>

#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "endohaptics/core/parameter.hpp"
#include "endohaptics/files/parameter_json.hpp"
#include "test_support.hpp"

namespace files_parameter_json_test {

namespace files = endohaptics::files;
using endohaptics::Bound;
using endohaptics::ParameterChecker;
using endohaptics::test::message_of;
using nlohmann::json;

namespace {

// A joint model's parameters as the estimation types declare them.
struct DemoParameters {
  double gain = 1.0;
  double lag = 0.1;  // added
  double sample_time = 0.001;

  template <typename Self, typename Visitor>
  static void for_each_field(Self& p, Visitor&& v) {
    v("gain", p.gain, Bound::in(-1e6, 1e6));
    v("lag", p.lag, Bound::in(0, 10, "s"));  // added
  }
  void validate() const { for_each_field(*this, ParameterChecker{"DemoParameters"}); }
};

std::string read_error(const json& j) {
  return message_of([&] {
    DemoParameters p;
    files::parameters_from_json(j, p, "model file m.json", "parameters", "for kind \"demo\"");
    files::validate_parameters(p, "model file m.json", "parameters");
  });
}

}  // namespace

TEST_CASE("parameter lists: one added field is written, read, required and checked") {
  DemoParameters p;
  p.lag = 0.25;
  const json j = files::parameters_to_json(p);
  CHECK(j == json{{"gain", 1.0}, {"lag", 0.25}});
  DemoParameters back;
  files::parameters_from_json(j, back, "model file m.json", "parameters");
  CHECK(back.lag == 0.25);
  CHECK(back.sample_time == 0.001);  // not in the list: kept
  CHECK(files::parameter_names<DemoParameters>() == std::vector<std::string>{"gain", "lag"});

  json missing = j;
  missing.erase("lag");
  CHECK(read_error(missing) == "model file m.json: parameters: missing field \"lag\"");
  json out_of_range = j;
  out_of_range["lag"] = 11.0;
  CHECK(read_error(out_of_range) ==
        "model file m.json: field \"parameters.lag\" must be in [0, 10] s, got 11");
  json unknown = j;
  unknown["lag_s"] = 1.0;
  CHECK(read_error(unknown) ==
        "model file m.json: unknown field \"parameters.lag_s\" for kind \"demo\" (known: gain, "
        "lag)");
  json wrong_type = j;
  wrong_type["lag"] = "slow";
  CHECK(read_error(wrong_type) ==
        "model file m.json: field \"parameters.lag\" is not a number (\"slow\")");
  // The type's own validate() says the same rule without the file.
  DemoParameters bad;
  bad.lag = -1.0;
  CHECK(message_of([&] { bad.validate(); }) == "DemoParameters: lag must be in [0, 10] s, got -1");
}

TEST_CASE("parameter lists: bounds say their rule one way") {
  const double inf = std::numeric_limits<double>::infinity();
  CHECK(Bound::in(0, 1e6, "A").describe() == "in [0, 1e6] A");
  CHECK(Bound::above(0, 1).describe() == "in (0, 1]");
  CHECK(Bound::magnitude(1e-9, 1e6).describe() == "of magnitude in [1e-9, 1e6]");
  CHECK(Bound::zero_or_magnitude(1e-9, 1e6).describe() == "0 or of magnitude in [1e-9, 1e6]");
  CHECK(Bound::unit_sign().describe() == "+1 or -1");
  CHECK(Bound::above(0, inf, "s").describe() == "finite and > 0 s");
  CHECK(Bound::finite("rad").describe() == "finite rad");
  for (const double v : {0.0, 1.0, -1.0, 1e300}) {
    CHECK(Bound::finite().contains(v));
  }
  CHECK_FALSE(Bound::finite().contains(inf));
  CHECK_FALSE(Bound::in(0, 1).contains(std::numeric_limits<double>::quiet_NaN()));
  CHECK_FALSE(Bound::zero_or_magnitude(1e-9, 1).contains(1e-12));
  CHECK(Bound::zero_or_magnitude(1e-9, 1).contains(0.0));
  CHECK(Bound::unit_sign().contains(-1.0));
  CHECK_FALSE(Bound::unit_sign().contains(0.5));
}

}  // namespace files_parameter_json_test
