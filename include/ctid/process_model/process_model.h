// Process models: the low-order structures control engineers tune with, named as MATLAB's
// `procest` names them and parameterised physically,
//   G(s) = K (1 + Tz s) / ((1 + Tp1 s)(1 + Tp2 s)(1 + Tp3 s)) · e^{-Td s}   [· 1/s with I],
// the first two poles replaced by the pair 1 + 2 Zeta Tw s + (Tw s)^2 with U. They are
// estimated from a sampled SISO record by continuous-time output-error minimisation
// (Levenberg–Marquardt, Ceres) of the exact sampled response under the record's input hold,
// the dead time Td a continuous parameter off the sample grid; the standard errors come from
// the Gauss–Newton covariance sigma^2 (J^T J)^{-1}. Docs: docs/process-models.md; decision
// 0040.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/fields.h"
#include "ctid/core/sampled_data.h"
#include "ctid/core/transfer_function.h"
#include "ctid/estimation/termination.h"
#include "ctid/estimation/verdict.h"

namespace ctid {

/// A process-model structure: P + poles (0..3), then any of D (dead time), Z (zero),
/// I (integrator), U (underdamped pair; two poles or more), e.g. "P1D", "P2DU", "P1DI".
struct ProcessStructure {
  int poles = 1;
  bool delay = false;
  bool zero = false;
  bool integrator = false;
  bool underdamped = false;

  /// Reads a name as procest writes it (letters after the digit in any order, each once,
  /// case-insensitive). Throws InvalidArgument naming what is wrong: an unknown letter, a
  /// pole count outside 0..3, U with fewer than two poles, a repeated letter.
  static ProcessStructure parse(std::string_view name);
  /// The canonical name: P, the poles, then D, Z, I, U in that order present.
  std::string name() const;
  /// The parameters in the structure's order: K, then Tp1 Tp2 Tp3 (Tw Zeta in place of Tp1
  /// Tp2 with U), Tz with Z, Td with D.
  std::vector<std::string> parameter_names() const;
};

/// What is known or asked about one parameter (by its procest name).
struct ProcessParameterSetting {
  std::string name;
  /// The start (or the held value, with fixed); none: from the automatic start.
  std::optional<double> value;
  /// Hold the parameter at `value` (which must be given).
  bool fixed = false;
  /// Bounds; the structure's own always apply too (Td >= 0, time constants and Zeta > 0).
  std::optional<double> lower;
  std::optional<double> upper;

  static constexpr std::string_view type_name = "ProcessParameterSetting";
  static constexpr auto fields() {
    using S = ProcessParameterSetting;
    return std::tuple{
        field("name", &S::name, "Parameter: K, Tp1, Tp2, Tp3, Tw, Zeta, Tz or Td."),
        field("value", &S::value, Finite{},
              "Start, or the held value with fixed; None: automatic."),
        field("fixed", &S::fixed, "Hold the parameter at value."),
        field("lower", &S::lower, Finite{}, "Lower bound, or None."),
        field("upper", &S::upper, Finite{}, "Upper bound, or None."),
    };
  }
  void validate() const { validate_fields(*this); }
};

struct ProcessModelOptions {
  /// Starts, held values and bounds of named parameters (each name at most once).
  std::vector<ProcessParameterSetting> parameters;
  /// Largest dead time [s] the automatic start scans; none: a quarter of the record (at most
  /// 200 samples). Ignored without D or when Td has a start.
  std::optional<double> max_delay;
  /// Levenberg–Marquardt iterations of each refinement.
  int max_iterations = 200;

  static constexpr std::string_view type_name = "ProcessModelOptions";
  static constexpr auto fields() {
    using O = ProcessModelOptions;
    return std::tuple{
        field("parameters", &O::parameters, "ProcessParameterSetting of named parameters."),
        field("max_delay", &O::max_delay, Finite{AtLeast{0.0}},
              "Largest dead time [s] the automatic start scans; None: N/4 samples (<= 200)."),
        field("max_iterations", &O::max_iterations, AtLeast{1},
              "Levenberg-Marquardt iterations of each refinement."),
    };
  }
  void validate() const { validate_fields(*this); }
};

/// The estimate: parameters in ProcessStructure::parameter_names() order with their standard
/// errors (0 for a held parameter), the output-error fit and the quality verdict.
struct ProcessModelResult : Outcome {
  std::string structure;                      ///< canonical name, e.g. "P1D"
  std::vector<std::string> parameter_names;   ///< K, Tp1, ..., Td
  Eigen::VectorXd parameters;                 ///< values, same order
  Eigen::VectorXd standard_errors;            ///< sqrt of the covariance's diagonal
  Eigen::MatrixXd covariance;                 ///< sigma^2 (J^T J)^{-1}; zero rows for held ones
  std::vector<std::string> fixed_parameters;  ///< names held at their given value
  Eigen::VectorXd start;                      ///< the refinement's start, same order
  std::string start_method;                   ///< "user", "srivc" or "default"
  double fit_percent = 0.0;                   ///< 100 (1 - ||y - y_model|| / ||y - mean y||)
  double start_fit_percent = 0.0;
  double mean_squared_error = 0.0;  ///< sum of squared residuals / N
  double noise_variance = 0.0;      ///< sum of squared residuals / (N - free parameters)
  Verdict verdict;

  static constexpr std::string_view type_name = "ProcessModelResult";
  static constexpr auto fields() {
    using S = ProcessModelResult;
    return join_fields(
        Outcome::fields(),
        std::tuple{
            field("structure", &S::structure, "Process structure, e.g. P1D."),
            field("parameter_names", &S::parameter_names, "K, Tp1, ..., Td in order."),
            field("parameters", &S::parameters, "Estimated values, in parameter_names order."),
            field("standard_errors", &S::standard_errors,
                  "One standard error of each (0 for a held parameter)."),
            field("covariance", &S::covariance, "sigma^2 (J^T J)^{-1} of the parameters."),
            field("fixed_parameters", &S::fixed_parameters, "Parameters held at a given value."),
            field("start", &S::start, "Start of the refinement, in parameter_names order."),
            field("start_method", &S::start_method, "user, srivc or default."),
            field("fit_percent", &S::fit_percent, "Output-error fit [%]."),
            field("start_fit_percent", &S::start_fit_percent, "Fit of the start [%]."),
            field("mean_squared_error", &S::mean_squared_error, "Mean squared output error."),
            field("noise_variance", &S::noise_variance,
                  "Residual sum of squares / (N - free parameters)."),
            field("verdict", &S::verdict, "Quality verdict."),
        });
  }

  /// The value of a parameter by name; throws InvalidArgument if the structure has none.
  double parameter(std::string_view name) const;
  double standard_error(std::string_view name) const;
  /// The model as a transfer function with its dead time as the input delay.
  TransferFunction transfer_function() const;
};

/// The transfer function (input delay Td) of `structure` at `parameters` (in
/// parameter_names() order). Throws InvalidArgument for a size mismatch.
TransferFunction process_transfer_function(const ProcessStructure& structure,
                                           const Eigen::VectorXd& parameters);

/// Exact sampled response from rest of the process model to the record's input, held as
/// `hold` says, the dead time split into whole samples and an exact fraction.
Eigen::VectorXd process_model_output(const ProcessStructure& structure,
                                     const Eigen::VectorXd& parameters,
                                     const Eigen::VectorXd& input, double sample_time,
                                     Hold hold = Hold::zero_order_hold);

/// Throws InvalidArgument naming the first problem: a setting for a parameter the structure
/// does not have, a name given twice, a held parameter without a value, a bound that
/// contradicts the structure (a time constant or Zeta bounded at or below 0, Td below 0),
/// lower above upper, a start or held value outside its bounds.
void validate_process_model(const ProcessStructure& structure, const ProcessModelOptions& options);

/// Estimates `structure` from `data` (open loop, SISO, from rest). The automatic start
/// (decision 0040): SRIVC of the matching order at each whole-sample delay up to max_delay,
/// the best three refined with Td continuous; starts the user gives replace it. Throws
/// InvalidArgument for bad options (validate_process_model) or fewer than 10 samples per free
/// parameter; how the minimisation ended is the result's termination.
ProcessModelResult estimate_process_model(const SampledData& data,
                                          const ProcessStructure& structure,
                                          const ProcessModelOptions& options = {});

}  // namespace ctid
