// Covariance-driven SSI: correlations by FFT, one SVD, every order from one QR.
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
  // Zero-padded to >= 2N (a power of two) so the circular correlation has no wrap-around.
  std::size_t nfft = 1;
  while (nfft < static_cast<std::size_t>(2 * n)) nfft *= 2;
  Eigen::FFT<double> fft;
  std::vector<std::vector<std::complex<double>>> spectra(static_cast<std::size_t>(l));
  std::vector<double> buffer(nfft, 0.0);
  for (Eigen::Index j = 0; j < l; ++j) {
    const double mean = y.col(j).mean();
    std::fill(buffer.begin(), buffer.end(), 0.0);
    for (Eigen::Index k = 0; k < n; ++k) buffer[static_cast<std::size_t>(k)] = y(k, j) - mean;
    fft.fwd(spectra[static_cast<std::size_t>(j)], buffer);
  }
  const auto r = static_cast<Eigen::Index>(references.size());
  std::vector<Eigen::MatrixXd> out(static_cast<std::size_t>(max_lag), Eigen::MatrixXd(l, r));
  std::vector<std::complex<double>> product(nfft);
  std::vector<double> correlation;
  for (Eigen::Index a = 0; a < l; ++a) {
    for (Eigen::Index b = 0; b < r; ++b) {
      const auto& ya = spectra[static_cast<std::size_t>(a)];
      const auto& yb = spectra[static_cast<std::size_t>(references[static_cast<std::size_t>(b)])];
      for (std::size_t k = 0; k < ya.size(); ++k) product[k] = ya[k] * std::conj(yb[k]);
      fft.inv(correlation, product);
      for (int i = 1; i <= max_lag; ++i) {
        out[static_cast<std::size_t>(i - 1)](a, b) =
            correlation[static_cast<std::size_t>(i)] / static_cast<double>(n);
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
  const Eigen::Index l = outputs;
  const Eigen::Index p = left_vectors.rows() / l;
  SsiFactor f;
  f.outputs = outputs;
  const Eigen::VectorXd& sv = singular_values;
  f.rank = static_cast<int>((sv.array() > 1e-12 * sv(0)).count());
  f.observability = left_vectors.leftCols(max_order) * sv.head(max_order).cwiseSqrt().asDiagonal();
  const Eigen::MatrixXd up = f.observability.topRows((p - 1) * l);
  const Eigen::MatrixXd down = f.observability.bottomRows((p - 1) * l);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(up);
  f.r = qr.matrixQR().topRows(max_order).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd qt_down = qr.householderQ().adjoint() * down;
  f.s = qt_down.topRows(max_order);
  return f;
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
    ModalPole pole;
    pole.s = std::log(lambda) / sample_time;
    const double wn = std::abs(pole.s);
    pole.damping_ratio = -pole.s.real() / wn;
    if (!(pole.damping_ratio > 0.0 && pole.damping_ratio < max_damping)) continue;
    pole.frequency_hz = wn / (2.0 * std::numbers::pi);
    pole.shape = normalise_shape(c * eig.eigenvectors().col(k));
    if (!pole.shape.allFinite()) continue;
    pole.mpc = modal_phase_collinearity(pole.shape);
    pole.mpd = mean_phase_deviation(pole.shape);
    poles.push_back(std::move(pole));
  }
  std::sort(poles.begin(), poles.end(),
            [](const ModalPole& x, const ModalPole& y) { return x.frequency_hz < y.frequency_hz; });
  return poles;
}

}  // namespace ctid::oma_detail
