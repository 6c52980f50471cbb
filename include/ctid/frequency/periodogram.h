// Periodograms on the FFT grid: |X(k)|^2 of a record, zero-padded so that a peak between the
// record's DFT lines can be located, a running median of it (the local noise floor of a
// spectrum, robust to the peaks on it), and the band of lines a signal excites. Bin k of a
// DFT over L samples sits at 2 pi k / (L h) rad/s; with zero padding P, the record's own
// line j (L = P N) is bin j P.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace ctid {

/// |X(k)|^2 of the unnormalised DFT of x zero-padded to L = zero_padding * x.size() samples,
/// on the bins strictly below Nyquist, k = 0 .. L/2 - 1. zero_padding >= 1.
Eigen::VectorXd periodogram(const Eigen::VectorXd& x, int zero_padding = 1);

/// A running median on the record's own lines: entry j (1 <= j < lines) is the median of
/// power(i * stride) over the lines i in [j - half_width, j + half_width] clipped to
/// [1, lines - 1] (of an even count, the upper one); entry 0 (DC) is 0. `stride` is the zero
/// padding of `power` (line i is bin i * stride), which must hold bin (lines - 1) * stride.
/// Size max(lines, 1). half_width >= 1, stride >= 1.
Eigen::VectorXd running_median(const Eigen::VectorXd& power, Eigen::Index lines,
                               Eigen::Index half_width, Eigen::Index stride = 1);

/// The lines j = 1 .. x.size()/2 - 1 of x where the running median (of half-width
/// half_width) of its periodogram reaches min_level times its largest value: the band the
/// signal excites, with a line missing here and there inside it still counted. Size
/// max(x.size()/2, 1); entry 0 (DC) is false. half_width >= 1, min_level in [0, 1].
std::vector<bool> excited_band(const Eigen::VectorXd& x, Eigen::Index half_width, double min_level);

}  // namespace ctid
