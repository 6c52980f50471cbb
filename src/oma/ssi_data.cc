// Data-driven SSI: the past columns of the LQ factor of the data Hankel matrix, the SVD of L21.
#include "ctid/oma/ssi_data.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Dense>

#include "ctid/core/parallel.h"

namespace ctid::oma_detail {

Eigen::Index ssi_data_samples_needed(int block_rows, Eigen::Index outputs,
                                     Eigen::Index references) {
  const Eigen::Index p = block_rows;
  return p * (references + outputs) + 2 * p - 1;
}

namespace {

// The record and what turns it into rows of H^T.
struct DataHankel {
  const Eigen::MatrixXd& y;
  const std::vector<int>& references;
  Eigen::Index p;
  Eigen::RowVectorXd mean;
  double scale;
};

// The rows [start, start + rows) of H^T, mean removed and scaled, into the bottom rows of `out`.
// H^T row t: y_ref(t)..y_ref(t+p-1), then y(t+p)..y(t+2p-1).
void hankel_rows(const DataHankel& h, Eigen::Index start, Eigen::Index rows, Eigen::MatrixXd& out) {
  const Eigen::Index p = h.p;
  const Eigen::Index l = h.y.cols();
  const auto r = static_cast<Eigen::Index>(h.references.size());
  const Eigen::Index past = p * r;
  const Eigen::MatrixXd& y = h.y;
  const Eigen::RowVectorXd& mean = h.mean;
  const double scale = h.scale;
  for (Eigen::Index i = 0; i < p; ++i) {
    for (Eigen::Index b = 0; b < r; ++b) {
      const int c = h.references[static_cast<std::size_t>(b)];
      out.col(i * r + b).tail(rows) = (y.col(c).segment(start + i, rows).array() - mean(c)) * scale;
    }
    for (Eigen::Index c = 0; c < l; ++c) {
      out.col(past + i * l + c).tail(rows) =
          (y.col(c).segment(start + p + i, rows).array() - mean(c)) * scale;
    }
  }
}

// Householder reflections that zero the first `past` columns of `stacked` below the diagonal
// (in place), applied to the rest of it; returns the rows that stay nonzero in those columns
// ([R11 R12]). R22 (future on future) is never needed, so the future columns are only transformed.
Eigen::MatrixXd reduce_past_columns(Eigen::MatrixXd& stacked, Eigen::Index past) {
  const Eigen::Index keep = std::min(stacked.rows(), past);
  const Eigen::Index future = stacked.cols() - past;
  Eigen::Ref<Eigen::MatrixXd> left = stacked.leftCols(past);
  const Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(left);
  stacked.rightCols(future).applyOnTheLeft(qr.householderQ().adjoint());
  Eigen::MatrixXd top(keep, stacked.cols());
  top.leftCols(past) = qr.matrixQR().topRows(keep);
  top.leftCols(past).triangularView<Eigen::StrictlyLower>().setZero();
  top.rightCols(future) = stacked.rightCols(future).topRows(keep);
  return top;
}

// The rows [begin, end) of H^T reduced a chunk at a time, each chunk stacked under the [R11 R12]
// of the rows before it, so memory stays at a few times width^2 whatever N is.
Eigen::MatrixXd reduce_stripe(const DataHankel& h, Eigen::Index begin, Eigen::Index end,
                              Eigen::Index width) {
  const Eigen::Index past = h.p * static_cast<Eigen::Index>(h.references.size());
  const Eigen::Index chunk = std::max<Eigen::Index>(4 * width, 4096);
  Eigen::MatrixXd top(0, width);
  for (Eigen::Index start = begin; start < end; start += chunk) {
    const Eigen::Index rows = std::min(chunk, end - start);
    Eigen::MatrixXd stacked(top.rows() + rows, width);
    stacked.topRows(top.rows()) = top;
    hankel_rows(h, start, rows, stacked);
    top = reduce_past_columns(stacked, past);
  }
  return top;
}

}  // namespace

Eigen::Index ssi_data_stripes(Eigen::Index hankel_columns, Eigen::Index width) {
  return std::clamp<Eigen::Index>(hankel_columns / (kSsiDataStripeWidths * width), 1,
                                  kSsiDataMaxStripes);
}

Eigen::MatrixXd ssi_data_past_columns(const Eigen::MatrixXd& y, const std::vector<int>& references,
                                      int block_rows, int threads) {
  const Eigen::Index p = block_rows;
  const Eigen::Index columns = y.rows() - 2 * p + 1;  // j: columns of H, rows of H^T
  const Eigen::Index past = p * static_cast<Eigen::Index>(references.size());
  const Eigen::Index width = past + p * y.cols();
  const DataHankel h{y, references, p, y.colwise().mean(),
                     1.0 / std::sqrt(static_cast<double>(columns))};
  // Stripes of rows reduced independently (on threads), then merged pairwise in a fixed tree:
  // the stripes depend on the size of H alone, so the bits do not depend on the thread count.
  const Eigen::Index stripes = ssi_data_stripes(columns, width);
  std::vector<Eigen::MatrixXd> tops(static_cast<std::size_t>(stripes));
  parallel_for(static_cast<int>(stripes), threads, [&](int s) {
    tops[static_cast<std::size_t>(s)] =
        reduce_stripe(h, columns * s / stripes, columns * (s + 1) / stripes, width);
  });
  for (std::size_t step = 1; step < tops.size(); step *= 2) {
    for (std::size_t s = 0; s + step < tops.size(); s += 2 * step) {
      Eigen::MatrixXd stacked(tops[s].rows() + tops[s + step].rows(), width);
      stacked << tops[s], tops[s + step];
      tops[s] = reduce_past_columns(stacked, past);
    }
  }
  return tops.front().transpose();
}

SsiFactor ssi_data_factor(const Eigen::MatrixXd& y, const std::vector<int>& references,
                          int block_rows, int max_order, int threads) {
  const Eigen::Index p = block_rows;
  const Eigen::Index l = y.cols();
  const Eigen::MatrixXd lower = ssi_data_past_columns(y, references, block_rows, threads);
  // The projection of the future outputs on the past references is L21 Q1^T; Q1 has orthonormal
  // rows, so its left singular vectors and singular values are those of L21.
  const Eigen::MatrixXd l21 = lower.bottomRows(p * l);
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(l21, Eigen::ComputeThinU);
  return observability_factor(svd.matrixU(), svd.singularValues(), static_cast<int>(l), max_order);
}

}  // namespace ctid::oma_detail
