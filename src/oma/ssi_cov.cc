// Covariance-driven SSI: correlations by blocked FFT, one SVD, every order from one QR.
#include "ctid/oma/ssi_cov.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <unsupported/Eigen/FFT>

namespace ctid::oma_detail {

std::vector<Eigen::MatrixXd> output_correlations(const Eigen::MatrixXd& y,
                                                 const std::vector<int>& references, int max_lag) {
  const Eigen::Index n = y.rows();
  const Eigen::Index l = y.cols();
  const auto r = static_cast<Eigen::Index>(references.size());
  const Eigen::Index lags = max_lag;
  // Overlap-save: the record in blocks of `step` reference samples; block k's references
  // (zero-padded to nfft) against the outputs from the same start over nfft samples hold every
  // lag 0..max_lag of that block without wrap-around (step + max_lag <= nfft). The blocks'
  // cross-spectra are summed, so each channel pair needs one inverse transform of nfft points.
  Eigen::Index nfft = 1;
  while (nfft < std::min<Eigen::Index>(4 * (lags + 1), n + lags)) nfft *= 2;
  const Eigen::Index step = nfft - lags;
  const Eigen::Index bins = nfft / 2 + 1;
  Eigen::FFT<double> fft;
  fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
  const Eigen::RowVectorXd mean = y.colwise().mean();
  Eigen::MatrixXcd cross = Eigen::MatrixXcd::Zero(bins, l * r);  // column a + l b
  Eigen::MatrixXcd out_spectra(bins, l);
  Eigen::MatrixXcd ref_spectra(bins, r);
  std::vector<double> buffer(static_cast<std::size_t>(nfft));
  const auto transform = [&](Eigen::Index channel, Eigen::Index start, Eigen::Index count,
                             std::complex<double>* spectrum) {
    const Eigen::Index used = std::max<Eigen::Index>(0, std::min(count, n - start));
    for (Eigen::Index k = 0; k < used; ++k) {
      buffer[static_cast<std::size_t>(k)] = y(start + k, channel) - mean(channel);
    }
    std::fill(buffer.begin() + used, buffer.end(), 0.0);
    fft.fwd(spectrum, buffer.data(), nfft);
  };
  for (Eigen::Index start = 0; start < n; start += step) {
    for (Eigen::Index a = 0; a < l; ++a) transform(a, start, nfft, out_spectra.col(a).data());
    for (Eigen::Index b = 0; b < r; ++b) {
      transform(references[static_cast<std::size_t>(b)], start, step, ref_spectra.col(b).data());
    }
    for (Eigen::Index b = 0; b < r; ++b) {
      for (Eigen::Index a = 0; a < l; ++a) {
        cross.col(a + l * b).array() +=
            out_spectra.col(a).array() * ref_spectra.col(b).array().conjugate();
      }
    }
  }
  std::vector<Eigen::MatrixXd> out(static_cast<std::size_t>(max_lag), Eigen::MatrixXd(l, r));
  for (Eigen::Index b = 0; b < r; ++b) {
    for (Eigen::Index a = 0; a < l; ++a) {
      fft.inv(buffer.data(), cross.col(a + l * b).data(), nfft);
      for (Eigen::Index i = 1; i <= lags; ++i) {
        out[static_cast<std::size_t>(i - 1)](a, b) =
            buffer[static_cast<std::size_t>(i)] / static_cast<double>(n);
      }
    }
  }
  return out;
}

Eigen::MatrixXd correlation_hankel(const std::vector<Eigen::MatrixXd>& correlations,
                                   int block_rows) {
  const Eigen::Index l = correlations.front().rows();
  const Eigen::Index r = correlations.front().cols();
  const Eigen::Index p = block_rows;
  Eigen::MatrixXd hankel(p * l, p * r);
  for (Eigen::Index i = 0; i < p; ++i) {
    for (Eigen::Index j = 0; j < p; ++j) {
      hankel.block(i * l, j * r, l, r) = correlations[static_cast<std::size_t>(i + j)];
    }
  }
  return hankel;
}

SsiFactor ssi_factor(const std::vector<Eigen::MatrixXd>& correlations, int block_rows,
                     int max_order) {
  return hankel_factor(correlation_hankel(correlations, block_rows),
                       static_cast<int>(correlations.front().rows()), max_order);
}

SsiFactor hankel_factor(const Eigen::MatrixXd& hankel, int outputs, int max_order) {
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(hankel, Eigen::ComputeThinU);
  return observability_factor(svd.matrixU(), svd.singularValues(), outputs, max_order);
}

SsiFactor observability_factor(const Eigen::MatrixXd& left_vectors,
                               const Eigen::VectorXd& singular_values, int outputs, int max_order) {
  SsiFactor f;
  f.outputs = outputs;
  const Eigen::VectorXd& sv = singular_values;
  f.rank = static_cast<int>((sv.array() > 1e-12 * sv(0)).count());
  f.observability = left_vectors.leftCols(max_order) * sv.head(max_order).cwiseSqrt().asDiagonal();
  shift_factor(f);
  return f;
}

void shift_factor(SsiFactor& f) {
  const Eigen::Index l = f.outputs;
  const Eigen::Index p = f.observability.rows() / l;
  const Eigen::Index n = f.observability.cols();
  const Eigen::MatrixXd up = f.observability.topRows((p - 1) * l);
  const Eigen::MatrixXd down = f.observability.bottomRows((p - 1) * l);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(up);
  f.r = qr.matrixQR().topRows(n).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd qt_down = qr.householderQ().adjoint() * down;
  f.s = qt_down.topRows(n);
}

Eigen::VectorXcd normalise_shape(const Eigen::VectorXcd& shape) {
  Eigen::Index largest = 0;
  shape.cwiseAbs().maxCoeff(&largest);
  Eigen::VectorXcd out = shape / shape(largest);
  out(largest) = 1.0;
  return out;
}

double modal_assurance(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b) {
  return std::norm(a.dot(b)) / (a.squaredNorm() * b.squaredNorm());
}

double modal_phase_collinearity(const Eigen::VectorXcd& shape) {
  const double sxx = shape.real().squaredNorm();
  const double syy = shape.imag().squaredNorm();
  const double sxy = shape.real().dot(shape.imag());
  const double d = syy - sxx;
  return (d * d + 4.0 * sxy * sxy) / ((sxx + syy) * (sxx + syy));
}

double mean_phase_deviation(const Eigen::VectorXcd& shape) {
  Eigen::MatrixXd parts(shape.size(), 2);
  parts.col(0) = shape.real();
  parts.col(1) = shape.imag();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(parts, Eigen::ComputeThinV);
  const double angle = std::atan2(svd.matrixV()(1, 0), svd.matrixV()(0, 0));
  const std::complex<double> rotate = std::polar(1.0, -angle);
  double weighted = 0.0;
  double weights = 0.0;
  for (Eigen::Index j = 0; j < shape.size(); ++j) {
    const double m = std::abs(shape(j));
    if (m == 0.0) continue;
    double d = std::abs(std::arg(shape(j) * rotate));  // in [0, pi]
    d = std::min(d, std::numbers::pi - d);             // a line, not a ray
    weighted += m * d;
    weights += m;
  }
  return weights > 0.0 ? weighted / weights * 180.0 / std::numbers::pi : 0.0;
}

std::vector<ModalPole> ssi_poles(const SsiFactor& factor, int order, double sample_time,
                                 double max_damping) {
  order = std::min(order, factor.rank);
  if (order < 1) return {};
  const Eigen::MatrixXd a = factor.r.topLeftCorner(order, order)
                                .triangularView<Eigen::Upper>()
                                .solve(factor.s.topLeftCorner(order, order));
  const Eigen::MatrixXd c = factor.observability.topLeftCorner(factor.outputs, order);
  const Eigen::EigenSolver<Eigen::MatrixXd> eig(a);
  std::vector<ModalPole> poles;
  for (Eigen::Index k = 0; k < order; ++k) {
    const std::complex<double> lambda = eig.eigenvalues()(k);
    if (!(lambda.imag() > 0.0) || !(std::abs(lambda) < 1.0)) continue;
    auto pole = modal_pole(std::log(lambda) / sample_time, max_damping,
                           [&] { return Eigen::VectorXcd(c * eig.eigenvectors().col(k)); });
    if (pole) poles.push_back(std::move(*pole));
  }
  sort_by_frequency(poles);
  return poles;
}

void sort_by_frequency(std::vector<ModalPole>& poles) {
  std::sort(poles.begin(), poles.end(),
            [](const ModalPole& x, const ModalPole& y) { return x.frequency_hz < y.frequency_hz; });
}

}  // namespace ctid::oma_detail
