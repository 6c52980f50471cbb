#include "ctid/io/excitation_spec.h"

#include <cmath>

#include "ctid/core/error.h"
#include "ctid/io/json.h"

namespace ctid::io {

std::string to_string(ExcitationKind kind) { return std::string(enum_name(kind)); }

ExcitationKind excitation_kind_from_string(std::string_view name) {
  if (const auto kind = enum_from_name<ExcitationKind>(name)) return *kind;
  throw InvalidArgument(ctid::internal::concat("excitation signal '", name,
                                               "' is unknown; use white, prbs or multisine"));
}

std::string to_string(FrequencyGrid grid) { return std::string(enum_name(grid)); }

FrequencyGrid frequency_grid_from_string(std::string_view name) {
  if (const auto grid = enum_from_name<FrequencyGrid>(name)) return *grid;
  throw InvalidArgument(
      ctid::internal::concat("frequency grid '", name, "' is unknown; use full or odd"));
}

void ExcitationSpec::validate() const {
  require(samples >= 2, "ExcitationSpec.samples is ", samples, "; it must be >= 2");
  require(std::isfinite(sample_time) && sample_time > 0.0, "ExcitationSpec.sample_time is ",
          sample_time, "; it must be positive and finite");
  switch (kind) {
    case ExcitationKind::white_noise:
      require(std::isfinite(standard_deviation) && standard_deviation > 0.0,
              "ExcitationSpec.standard_deviation is ", standard_deviation,
              "; it must be positive and finite");
      break;
    case ExcitationKind::prbs:
      prbs_options().validate();
      break;
    case ExcitationKind::multisine:
      require(periods >= 1, "ExcitationSpec.periods is ", periods, "; it must be >= 1");
      require(samples % periods == 0, "ExcitationSpec.samples is ", samples,
              "; it must be a multiple of periods (", periods, ")");
      multisine_options().validate();
      break;
  }
}

PrbsOptions ExcitationSpec::prbs_options() const {
  PrbsOptions options;
  assign_shared_fields(options, *this);  // register_length, amplitude, samples_per_bit
  if (register_length >= 2 && register_length <= 62) {
    const std::uint64_t states = (std::uint64_t{1} << register_length) - 1;
    options.initial_state = 1 + seed % states;
  }
  return options;
}

MultisineOptions ExcitationSpec::multisine_options() const {
  MultisineOptions options;
  assign_shared_fields(options, *this);  // periods, sample_time, grid, rms, seed
  options.period_length = periods >= 1 ? samples / periods : samples;
  options.min_frequency = min_frequency_hz;
  options.max_frequency = max_frequency_hz;
  return options;
}

Eigen::VectorXd generate_excitation(const ExcitationSpec& spec) {
  spec.validate();
  switch (spec.kind) {
    case ExcitationKind::white_noise:
      return white_noise(spec.samples, spec.standard_deviation, spec.seed);
    case ExcitationKind::prbs:
      return prbs(spec.samples, spec.prbs_options());
    case ExcitationKind::multisine:
      return multisine(spec.multisine_options()).signal;
  }
  throw InvalidArgument("unknown excitation kind");
}

nlohmann::json to_json(const ExcitationSpec& spec) {
  nlohmann::json j = {{"type", "excitation"},
                      {"signal", to_string(spec.kind)},
                      {"samples", spec.samples},
                      {"sample_time", spec.sample_time},
                      {"seed", spec.seed}};
  switch (spec.kind) {
    case ExcitationKind::white_noise:
      j["standard_deviation"] = spec.standard_deviation;
      break;
    case ExcitationKind::prbs:
      j["register_length"] = spec.register_length;
      j["amplitude"] = spec.amplitude;
      j["samples_per_bit"] = spec.samples_per_bit;
      break;
    case ExcitationKind::multisine:
      j["periods"] = spec.periods;
      j["min_frequency_hz"] = spec.min_frequency_hz;
      j["max_frequency_hz"] = spec.max_frequency_hz;
      j["grid"] = to_string(spec.grid);
      j["rms"] = spec.rms;
      break;
  }
  return j;
}

namespace {

int int_field(const JsonObject& o, std::string_view key, int fallback) {
  const long long v = o.integer_or(key, fallback);
  if (v < -2147483647LL || v > 2147483647LL) o.fail(key, "is out of the range of an int");
  return static_cast<int>(v);
}

}  // namespace

ExcitationSpec excitation_spec_from_json(const nlohmann::json& value, const std::string& source) {
  const JsonObject o(value, source);
  const std::string type = o.string("type");
  if (type != "excitation") {
    o.fail("type", ctid::internal::concat("is '", type, "' but an excitation is expected here"));
  }
  o.string_or("description", "");
  ExcitationSpec spec;
  try {
    spec.kind = excitation_kind_from_string(o.string("signal"));
  } catch (const InvalidArgument& e) {
    o.fail("signal", e.what());
  }
  spec.samples = int_field(o, "samples", spec.samples);
  spec.sample_time = o.number("sample_time");
  const long long seed = o.integer_or("seed", static_cast<long long>(spec.seed));
  if (seed < 0) o.fail("seed", ctid::internal::concat("is ", seed, "; it must be >= 0"));
  spec.seed = static_cast<std::uint64_t>(seed);
  switch (spec.kind) {
    case ExcitationKind::white_noise:
      spec.standard_deviation = o.number_or("standard_deviation", spec.standard_deviation);
      break;
    case ExcitationKind::prbs:
      spec.register_length = int_field(o, "register_length", spec.register_length);
      spec.amplitude = o.number_or("amplitude", spec.amplitude);
      spec.samples_per_bit = int_field(o, "samples_per_bit", spec.samples_per_bit);
      break;
    case ExcitationKind::multisine:
      spec.periods = int_field(o, "periods", spec.periods);
      spec.min_frequency_hz = o.number_or("min_frequency_hz", spec.min_frequency_hz);
      spec.max_frequency_hz = o.number_or("max_frequency_hz", spec.max_frequency_hz);
      try {
        spec.grid = frequency_grid_from_string(o.string_or("grid", "full"));
      } catch (const InvalidArgument& e) {
        o.fail("grid", e.what());
      }
      spec.rms = o.number_or("rms", spec.rms);
      break;
  }
  o.finish();
  try {
    spec.validate();
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(ctid::internal::concat(source, ": excitation: ", e.what()));
  }
  return spec;
}

ExcitationSpec read_excitation_spec(const std::filesystem::path& path) {
  return excitation_spec_from_json(read_json(path), path.string());
}

}  // namespace ctid::io
