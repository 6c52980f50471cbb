#include "ctid/io/excitation_spec.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/io/json.h"

namespace ctid::io::excitation_spec_test {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

std::string spec_error(const std::string& text) {
  try {
    excitation_spec_from_json(parse_json(text, "x.json"), "x.json");
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

TEST(ExcitationSpec, MultisineMatchesTheSimulationLayerCall) {
  ExcitationSpec spec;
  spec.kind = ExcitationKind::multisine;
  spec.samples = 600;
  spec.periods = 3;
  spec.sample_time = 0.01;
  spec.min_frequency_hz = 1.0;
  spec.max_frequency_hz = 20.0;
  spec.grid = FrequencyGrid::odd;
  spec.rms = 2.0;
  spec.seed = 42;
  MultisineOptions direct;
  direct.period_length = 200;
  direct.periods = 3;
  direct.sample_time = 0.01;
  direct.min_frequency = 1.0;
  direct.max_frequency = 20.0;
  direct.grid = FrequencyGrid::odd;
  direct.rms = 2.0;
  direct.seed = 42;
  EXPECT_EQ(generate_excitation(spec), multisine(direct).signal);
}

TEST(ExcitationSpec, WhiteAndPrbsMatchTheSimulationLayerCalls) {
  ExcitationSpec spec;
  spec.kind = ExcitationKind::white_noise;
  spec.samples = 100;
  spec.standard_deviation = 0.5;
  spec.seed = 9;
  EXPECT_EQ(generate_excitation(spec), white_noise(100, 0.5, 9));

  spec.kind = ExcitationKind::prbs;
  spec.register_length = 5;
  spec.amplitude = 3.0;
  spec.samples_per_bit = 2;
  spec.seed = 40;  // 1 + 40 mod 31 = 10
  PrbsOptions options;
  options.register_length = 5;
  options.amplitude = 3.0;
  options.samples_per_bit = 2;
  options.initial_state = 10;
  EXPECT_EQ(generate_excitation(spec), prbs(100, options));
}

TEST(ExcitationSpec, JsonRoundTripForEachSignal) {
  for (const ExcitationKind kind :
       {ExcitationKind::white_noise, ExcitationKind::prbs, ExcitationKind::multisine}) {
    ExcitationSpec spec;
    spec.kind = kind;
    spec.samples = 512;
    spec.sample_time = 0.05;
    spec.seed = 123456789012345ULL;
    spec.standard_deviation = 0.3;
    spec.register_length = 7;
    spec.amplitude = 0.1;
    spec.samples_per_bit = 3;
    spec.periods = 4;
    spec.min_frequency_hz = 0.5;
    spec.max_frequency_hz = 3.0;
    spec.grid = FrequencyGrid::odd;
    spec.rms = 1.0 / 3.0;
    const ExcitationSpec back =
        excitation_spec_from_json(nlohmann::json::parse(to_json(spec).dump()), "x.json");
    EXPECT_EQ(generate_excitation(back), generate_excitation(spec)) << to_string(kind);
  }
}

TEST(ExcitationSpec, FieldsOfAnotherSignalAreUnknown) {
  EXPECT_THAT(spec_error(R"({"type": "excitation", "signal": "white", "samples": 10,
                             "sample_time": 1, "rms": 2})"),
              StartsWith("x.json: rms: unknown field"));
}

TEST(ExcitationSpec, BadValuesAreNamed) {
  EXPECT_THAT(spec_error(R"({"type": "excitation", "signal": "chirp", "sample_time": 1})"),
              StartsWith("x.json: signal: excitation signal 'chirp' is unknown"));
  EXPECT_THAT(spec_error(R"({"type": "excitation", "signal": "white", "sample_time": 0})"),
              StartsWith("x.json: excitation: ExcitationSpec.sample_time is 0"));
  EXPECT_THAT(spec_error(R"({"type": "excitation", "signal": "multisine", "samples": 100,
                             "periods": 3, "sample_time": 1})"),
              HasSubstr("ExcitationSpec.samples is 100; it must be a multiple of periods (3)"));
  EXPECT_THAT(spec_error(R"({"type": "excitation", "signal": "prbs", "sample_time": 1,
                             "register_length": 40})"),
              StartsWith("x.json: excitation: "));
  EXPECT_THAT(spec_error(R"({"type": "excitation", "signal": "white", "sample_time": 1,
                             "seed": -1})"),
              StartsWith("x.json: seed: is -1"));
}

}  // namespace
}  // namespace ctid::io::excitation_spec_test
