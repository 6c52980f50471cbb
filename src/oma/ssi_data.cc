// Data-driven SSI: the LQ factor of the data Hankel matrix, the SVD of its L21 block.
#include "ctid/oma/ssi_data.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Dense>

namespace ctid::oma_detail {

Eigen::Index ssi_data_samples_needed(int block_rows, Eigen::Index outputs,
                                     Eigen::Index references) {
  const Eigen::Index p = block_rows;
  return p * (references + outputs) + 2 * p - 1;
}

Eigen::MatrixXd ssi_data_triangle(const Eigen::MatrixXd& y, const std::vector<int>& references,
                                  int block_rows) {
  const Eigen::Index p = block_rows;
  const Eigen::Index l = y.cols();
  const auto r = static_cast<Eigen::Index>(references.size());
  const Eigen::Index columns = y.rows() - 2 * p + 1;  // j: columns of H, rows of H^T
  const Eigen::Index width = p * (r + l);
  const Eigen::Index past = p * r;
  const Eigen::RowVectorXd mean = y.colwise().mean();
  const double scale = 1.0 / std::sqrt(static_cast<double>(columns));
  // H^T row t: y_ref(t)..y_ref(t+p-1), then y(t+p)..y(t+2p-1). The rows go through the QR a
  // chunk at a time, each chunk stacked under the R of the rows before it, so memory stays at a
  // few times width^2 whatever N is.
  const Eigen::Index chunk = std::max<Eigen::Index>(4 * width, 4096);
  Eigen::MatrixXd triangle(0, width);
  for (Eigen::Index start = 0; start < columns; start += chunk) {
    const Eigen::Index rows = std::min(chunk, columns - start);
    const Eigen::Index above = triangle.rows();
    Eigen::MatrixXd stacked(above + rows, width);
    stacked.topRows(above) = triangle;
    for (Eigen::Index i = 0; i < p; ++i) {
      for (Eigen::Index b = 0; b < r; ++b) {
        const int c = references[static_cast<std::size_t>(b)];
        stacked.col(i * r + b).tail(rows) =
            (y.col(c).segment(start + i, rows).array() - mean(c)) * scale;
      }
      for (Eigen::Index c = 0; c < l; ++c) {
        stacked.col(past + i * l + c).tail(rows) =
            (y.col(c).segment(start + p + i, rows).array() - mean(c)) * scale;
      }
    }
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(stacked);
    triangle = qr.matrixQR().topRows(std::min(stacked.rows(), width));
    triangle.triangularView<Eigen::StrictlyLower>().setZero();
  }
  return triangle.transpose();
}

SsiFactor ssi_data_factor(const Eigen::MatrixXd& y, const std::vector<int>& references,
                          int block_rows, int max_order) {
  const Eigen::Index p = block_rows;
  const Eigen::Index l = y.cols();
  const Eigen::Index past = p * static_cast<Eigen::Index>(references.size());
  const Eigen::MatrixXd lower = ssi_data_triangle(y, references, block_rows);
  // The projection of the future outputs on the past references is L21 Q1^T; Q1 has orthonormal
  // rows, so its left singular vectors and singular values are those of L21.
  const Eigen::MatrixXd l21 = lower.block(past, 0, p * l, past);
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(l21, Eigen::ComputeThinU);
  return observability_factor(svd.matrixU(), svd.singularValues(), static_cast<int>(l), max_order);
}

}  // namespace ctid::oma_detail
