// Excitation specifications: which test signal to generate (white noise, maximum-length
// PRBS, random-phase multisine) and its parameters, as one plain struct shared by the CLI
// flags of `ctid simulate` and the JSON format "excitation" (docs/formats.md). The signals
// themselves come from ctid/simulation/excitation.h.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "ctid/core/fields.h"
#include "ctid/simulation/excitation.h"

namespace ctid::io {

enum class ExcitationKind { white_noise, prbs, multisine };

inline constexpr std::array<Enumerator<ExcitationKind>, 3> excitation_kind_enumerators{{
    {ExcitationKind::white_noise, "white", "Gaussian white noise."},
    {ExcitationKind::prbs, "prbs", "Maximum-length pseudo-random binary sequence."},
    {ExcitationKind::multisine, "multisine", "Random-phase multisine."},
}};
constexpr std::span<const Enumerator<ExcitationKind>> enumerators(ExcitationKind) {
  return excitation_kind_enumerators;
}

/// "white", "prbs" or "multisine".
std::string to_string(ExcitationKind kind);
/// Inverse of to_string; throws InvalidArgument listing the valid names.
ExcitationKind excitation_kind_from_string(std::string_view name);
/// "full" or "odd".
std::string to_string(FrequencyGrid grid);
FrequencyGrid frequency_grid_from_string(std::string_view name);

struct ExcitationSpec {
  ExcitationKind kind = ExcitationKind::multisine;
  int samples = 1024;        ///< total length N (multisine: periods * period length)
  double sample_time = 1.0;  ///< h in seconds
  /// White noise and multisine phases: the mt19937_64 seed. PRBS: picks the register's
  /// start state, 1 + seed mod (2^n - 1), i.e. a circular shift of the sequence.
  std::uint64_t seed = 1;

  double standard_deviation = 1.0;  ///< white noise

  int register_length = 10;  ///< PRBS n, period (2^n - 1) * samples_per_bit
  double amplitude = 1.0;    ///< PRBS levels +-amplitude
  int samples_per_bit = 1;   ///< PRBS

  int periods = 1;                ///< multisine repetitions; samples must be a multiple
  double min_frequency_hz = 0.0;  ///< multisine band lower edge, Hz
  double max_frequency_hz = 0.0;  ///< multisine band upper edge, Hz (0: up to Nyquist)
  FrequencyGrid grid = FrequencyGrid::full;
  double rms = 1.0;  ///< multisine root mean square

  static constexpr std::string_view type_name = "ExcitationSpec";
  /// The fields, documented; their rules depend on the kind, so validate() checks them.
  static constexpr auto fields() {
    using S = ExcitationSpec;
    return std::tuple{
        field("kind", &S::kind, "The signal: white, prbs or multisine.").with_flag("excitation"),
        field("samples", &S::samples, "Number of samples N."),
        field("sample_time", &S::sample_time, "Sample time h [s]."),
        field("seed", &S::seed,
              "Seed of the white noise or multisine phases; for prbs it picks the start state."),
        field("standard_deviation", &S::standard_deviation, "white: standard deviation.")
            .with_flag("std"),
        field("register_length", &S::register_length,
              "prbs: shift-register length n, period 2^n - 1 bits."),
        field("amplitude", &S::amplitude, "prbs: levels +-amplitude."),
        field("samples_per_bit", &S::samples_per_bit, "prbs: samples each bit is held."),
        field("periods", &S::periods, "multisine: periods in the record (N must be a multiple)."),
        field("min_frequency_hz", &S::min_frequency_hz, "multisine: band lower edge [Hz]."),
        field("max_frequency_hz", &S::max_frequency_hz,
              "multisine: band upper edge [Hz] (0: up to Nyquist)."),
        field("grid", &S::grid,
              "multisine: excite every DFT line in the band (full) or odd lines only (odd)."),
        field("rms", &S::rms, "multisine: root mean square."),
    };
  }
  /// Throws InvalidArgument naming the field, its value and the rule.
  void validate() const;
  PrbsOptions prbs_options() const;
  MultisineOptions multisine_options() const;
};

/// The signal, `samples` long.
Eigen::VectorXd generate_excitation(const ExcitationSpec& spec);

/// {"type": "excitation", "signal": ..., the fields of that signal}.
nlohmann::json to_json(const ExcitationSpec& spec);
/// Fields that do not belong to the chosen signal are rejected as unknown.
ExcitationSpec excitation_spec_from_json(const nlohmann::json& value, const std::string& source);
ExcitationSpec read_excitation_spec(const std::filesystem::path& path);

}  // namespace ctid::io
