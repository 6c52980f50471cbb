// Nonparametric FRF matrices of records with several inputs and outputs (issue 13), with the
// one-input, one-output FRF of frf.h as the special case. H(k) is n_y x n_u at each DFT line,
// entry (j, i) from input i to output j. Welch (non-periodic inputs that are measured together):
// the H1 estimate H = S_yu S_uu^-1 from the cross-spectral matrices of Hann-windowed segments,
// the multiple coherence of each output, gamma_j^2 = S_yju S_uu^-1 S_uyj / S_yjyj, and the
// variance Var H_ji = sigma_j^2 [S_uu^-1]_ii with sigma_j^2 = S_yjyj (1 - gamma_j^2) / (M - n_u)
// over M segments (Bendat & Piersol, Random Data, 4th ed., Sec. 7.3 and 9.3: multiple-input
// FRFs and their random errors; Pintelon & Schoukens, System Identification, 2nd ed., Sec. 2.5
// and 2.7: multiple-input FRFs and the orthogonal multisines). Periodic (several experiments
// whose inputs form a nonsingular matrix at each line, e.g. Hadamard-phased multisines):
// H_p = Y_p U_p^-1 per period, averaged, variance over periods / P (docs/decisions/0017).
// Frequencies in rad/s; DFT line k of a block of L samples sits at 2 pi k / (L h).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/mimo_data.h"
#include "ctid/frequency/frf.h"

namespace ctid {

/// Above this condition number of the normalised input spectral matrix (see
/// MimoFrf::input_condition) the inputs are too correlated at a line for H = S_yu S_uu^-1 to be
/// trusted: with two inputs it means a squared coherence between them above 0.96.
inline constexpr double kCorrelatedInputCondition = 100.0;

/// An FRF matrix on a set of DFT lines.
struct MimoFrf {
  std::vector<int> lines;       ///< DFT line k of each frequency (of one period / segment)
  Eigen::VectorXd frequencies;  ///< 2 pi k / (L h) [rad/s], increasing
  /// Per line, n_y x n_u: entry (j, i) is the response of output j to input i.
  std::vector<Eigen::MatrixXcd> response;
  /// Per line, n_y x n_u: estimated E|H_hat_ji - H_ji|^2 of each entry.
  std::vector<Eigen::MatrixXd> variance;
  /// lines x n_y: multiple coherence of each output with all inputs, in [0, 1].
  Eigen::MatrixXd coherence;
  /// lines x n_y: each output's auto-spectrum S_yjyj, the mean |Y_j(k)|^2 over the windowed
  /// segments (Welch) or over periods and experiments (periodic), of the unscaled DFT.
  Eigen::MatrixXd output_power;
  /// lines x n_u: each input's amplitude at the line over its largest line's, in [0, 1]
  /// (Welch: sqrt(S_uu,ii); periodic: the experiments' largest |mean U_i|).
  Eigen::MatrixXd input_level;
  /// Per line, the 2-norm condition number of the input matrix with its rows scaled to unit
  /// norm (Welch: D^-1/2 S_uu D^-1/2 with D = diag S_uu; periodic: the experiments' input
  /// matrix U): 1 for uncorrelated inputs, infinite for a singular one. 1 for one input.
  Eigen::VectorXd input_condition;
  int averages = 0;      ///< periods (periodic) or segments (Welch) averaged
  int block_length = 0;  ///< L: samples per period or per segment
  std::vector<std::string> input_names;
  std::vector<std::string> output_names;

  int input_count() const { return static_cast<int>(input_names.size()); }
  int output_count() const { return static_cast<int>(output_names.size()); }
  /// Whether the inputs are too correlated at position `index` (input_condition > max).
  bool inputs_correlated(int index, double max_condition = kCorrelatedInputCondition) const;
  /// The SISO view of entry (output, input): its response and variance, the output's multiple
  /// coherence and the input's level. For a 1 x 1 FRF this is the SISO estimate.
  Frf channel(int input, int output) const;
};

/// H1 estimate with several simultaneous inputs, by the segments of welch_frf (the same Hann
/// window, overlap and lines k = 1..L/2). At a line where S_uu is singular (an input without
/// power there, or exactly dependent inputs) the response, coherence and variance are NaN.
/// For one input and one output, response, coherence and input level equal welch_frf's; the
/// variance is welch_frf's times M / (M - 1) (the unbiased residual, see the header).
/// The variance is NaN when M <= n_u. Throws InvalidArgument when the record is shorter than L.
MimoFrf welch_frf(const MimoData& data, const WelchOptions& options = {});

/// FRF matrix from n_e >= n_u periodic experiments of one system with the same period length
/// N (options.period_length), e.g. n_u records with Hadamard-phased multisines. Period p of
/// each experiment, after options.transient_periods, forms one column of U_p (n_u x n_e) and
/// Y_p (n_y x n_e); H_p = Y_p U_p^+ and H is their mean over the P periods, with the sample
/// variance over periods / P. Every experiment must hold the same whole number of periods, and
/// at least two after the transient. Lines: options.lines, or those where every input reaches
/// options.line_threshold of its largest line in some experiment and U is not singular. The
/// coherence of output j is the share of its power at the line that the inputs explain over
/// periods and experiments (1 noise-free). One experiment with one input is periodic_frf.
MimoFrf periodic_frf(const std::vector<MimoData>& experiments, const PeriodicFrfOptions& options);

/// The record cut into `experiments` consecutive blocks of equal length, each one experiment of
/// periodic_frf above (the layout `ctid simulate` writes for orthogonal multisines).
MimoFrf periodic_frf(const MimoData& record, const PeriodicFrfOptions& options, int experiments);

/// The lines where every input's level exceeds `line_threshold` (all when input_level is
/// empty). Throws InvalidArgument for a threshold outside [0, 1).
MimoFrf excited_lines(const MimoFrf& frf, double line_threshold);

/// One FRF that stands for all channels, for picking the modes they share: response
/// sqrt(sum_ji |H_ji|^2) (real; the Frobenius norm of H), variance sum_ji Var H_ji (the expected
/// squared Frobenius-norm error), coherence the share of the summed output power the inputs
/// explain, sum_j gamma_j^2 S_yjyj / sum_j S_yjyj, and input level the smallest over inputs.
/// resonance_peaks() of it gives the peaks over all channels; a line where H is NaN stays NaN.
Frf summed_power_frf(const MimoFrf& frf);

}  // namespace ctid
