// Data-driven SSI's factorisation (issues 34 and 38): ssi_data_past_columns, which reduces only
// the past-reference columns of the transposed data Hankel matrix (decision 0054), against the
// previous implementation kept here as the reference: the whole triangle, every chunk of 4096
// (or 4 x width) rows stacked under the full R of the rows before it and re-factorised.
// The record: the 8-mass chain of tests/oma/chain_model.h (h = 5 ms, unit white forces, 5 %
// sensor noise, seed 1), N = 1e5 samples of the 8 displacements. Cases (Args): references, block
// rows. 8 references with 62 block rows is what `ctid oma --method ssi-data --max-order 60`
// chooses on this record (p (r + l) <= 1000, decision 0035); 2 references with 100 block rows
// the same budget with fewer references.
// The third argument is the thread count of the new one (0: all cores; the stripes and their
// merge order do not depend on it, so neither do the bits). BM_PastColumns also times the
// previous one (single-threaded, once per case) in the same process and reports previous_s,
// ratio (previous / new, wall clock) and sv_rel_diff, the largest relative difference of the
// 60 largest singular values of L21 between the two (the SVD the poles come from; L21's column
// signs may differ, its singular values and left singular vectors may not).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>
#include <Eigen/Dense>

#include "ctid/oma/ssi_data.h"
#include "oma/chain_model.h"

namespace {

const Eigen::MatrixXd& chain_record() {
  static const Eigen::MatrixXd y = ctid::oma_test::ChainModel(8).simulate(100000, 0.05, 1);
  return y;
}

std::vector<int> first_channels(int count) {
  std::vector<int> refs;
  for (int i = 0; i < count; ++i) refs.push_back(i);
  return refs;
}

// The previous ssi_data_triangle: the full lower triangle L (width x width).
Eigen::MatrixXd previous_triangle(const Eigen::MatrixXd& y, const std::vector<int>& references,
                                  int block_rows) {
  const Eigen::Index p = block_rows;
  const Eigen::Index l = y.cols();
  const auto r = static_cast<Eigen::Index>(references.size());
  const Eigen::Index columns = y.rows() - 2 * p + 1;
  const Eigen::Index width = p * (r + l);
  const Eigen::Index past = p * r;
  const Eigen::RowVectorXd mean = y.colwise().mean();
  const double scale = 1.0 / std::sqrt(static_cast<double>(columns));
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

double seconds_since(std::chrono::steady_clock::time_point begin) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
}

Eigen::VectorXd l21_singular_values(const Eigen::MatrixXd& l21) {
  return Eigen::BDCSVD<Eigen::MatrixXd>(l21).singularValues();
}

struct Previous {
  Eigen::MatrixXd triangle;
  double seconds = 0.0;
};

// The previous implementation's triangle and time, once per case.
const Previous& previous(const std::vector<int>& refs, int p) {
  static std::map<std::pair<std::size_t, int>, Previous> done;
  const auto key = std::make_pair(refs.size(), p);
  auto it = done.find(key);
  if (it == done.end()) {
    const auto begin = std::chrono::steady_clock::now();
    Eigen::MatrixXd triangle = previous_triangle(chain_record(), refs, p);
    it = done.emplace(key, Previous{std::move(triangle), seconds_since(begin)}).first;
  }
  return it->second;
}

void BM_PastColumns(benchmark::State& state) {
  const Eigen::MatrixXd& y = chain_record();
  const std::vector<int> refs = first_channels(static_cast<int>(state.range(0)));
  const int p = static_cast<int>(state.range(1));
  const int threads = static_cast<int>(state.range(2));
  const Eigen::Index future = p * y.cols();
  const Eigen::Index past = p * static_cast<Eigen::Index>(refs.size());
  Eigen::MatrixXd lower;
  double seconds = 0.0;
  for (auto _ : state) {
    const auto begin = std::chrono::steady_clock::now();
    lower = ctid::oma_detail::ssi_data_past_columns(y, refs, p, threads);
    seconds = seconds_since(begin);
    benchmark::DoNotOptimize(lower.data());
  }
  const Previous& previous_run = previous(refs, p);
  const Eigen::MatrixXd& previous = previous_run.triangle;
  const double previous_s = previous_run.seconds;
  const Eigen::VectorXd s_new = l21_singular_values(lower.bottomRows(future));
  const Eigen::VectorXd s_old = l21_singular_values(previous.block(past, 0, future, past));
  state.counters["previous_s"] = previous_s;
  state.counters["ratio"] = previous_s / seconds;
  state.counters["sv_rel_diff"] =
      ((s_new - s_old).array().abs() / s_old.array()).head(60).maxCoeff();
}
BENCHMARK(BM_PastColumns)
    ->Args({8, 62, 1})
    ->Args({8, 62, 0})
    ->Args({2, 100, 1})
    ->Args({2, 100, 0})
    ->Unit(benchmark::kSecond)
    ->Iterations(1)
    ->UseRealTime();

}  // namespace
