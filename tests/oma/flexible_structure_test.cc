// The DaISy flexible structure (data/daisy_flexible_structure, PROVENANCE.md there) used
// output-only: the 28 accelerations, the two shaker forces ignored. The input-output
// shared-pole fit of the same record has modes at 62.34, 119.01, 154.66, 192.48, 214.98,
// 229.45 and 239.38 Hz; the output-only modes must agree within 0.5 % on the ones the record
// excites well enough to be picked automatically, listed in kWellExcited.
// Settings: 30 block rows, orders to 60. Frequency-domain decomposition (efdd) of the same
// accelerations must find all seven modes within 0.5 %, 154.66 Hz included: a peak of the
// first singular value needs no stable column of poles.
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ctid/oma/oma.h"
#include "support/sanitizers.h"

namespace ctid::flexible_structure_test {
namespace {

// 62.34 Hz comes out about 0.5 % low (damping near 1 %, fewer cycles in the lags) and 154.66 Hz
// is not picked: the two shakers excite it little; both are left out.
constexpr double kWellExcited[] = {119.01, 192.48, 214.98, 229.45, 239.38};

Eigen::MatrixXd read_accelerations() {
  std::ifstream in(std::string(CTID_SOURCE_DIR) +
                   "/data/daisy_flexible_structure/flexible_structure.csv");
  std::string line;
  std::getline(in, line);  // t_s,u1_force,u2_force,y1_acc..y28_acc
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::string cell;
    std::vector<double> row;
    while (std::getline(s, cell, ',')) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  Eigen::MatrixXd y(static_cast<Eigen::Index>(rows.size()), 28);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    for (int j = 0; j < 28; ++j) y(static_cast<Eigen::Index>(k), j) = rows[k][3 + j];
  }
  return y;
}

TEST(OmaFlexibleStructure, WellExcitedModesAgreeWithTheInputOutputFit) {
  const Eigen::MatrixXd y = read_accelerations();
  ASSERT_EQ(y.rows(), 8523);
  OmaOptions o;
  o.max_order = 60;
  // Lags to 59 samples (about 3.6 periods of the 62 Hz mode); the standard errors are
  // another test's subject (they cost ten more SVDs of the 840 x 840 Hankel matrix).
  o.block_rows = 30;
  o.uncertainty_blocks = 0;
  const OmaResult r = oma(y, 1.0 / 1024.0, o);
  EXPECT_TRUE(r.verdict.usable);
  for (double f : kWellExcited) {
    SCOPED_TRACE(f);
    double closest = 0.0;
    for (const auto& m : r.modes) {
      if (std::abs(m.frequency_hz - f) < std::abs(closest - f)) closest = m.frequency_hz;
    }
    EXPECT_LT(std::abs(closest - f) / f, 0.005);
  }
}

// ssi-data (20 block rows, to keep the LQ of the 8484 x 1120 transposed Hankel matrix to about
// two seconds): the well-excited modes picked automatically except 214.98 Hz, whose poles are
// stable in frequency and shape but not in damping at most orders, so its cluster is too small;
// named with modes_near_hz, it and 154.66 Hz are found within 0.5 % too.
TEST(OmaFlexibleStructure, SsiDataWellExcitedModesAgreeWithTheInputOutputFit) {
  CTID_SKIP_UNDER_SANITIZERS("two LQ factorisations of a 8484 x 1120 matrix");
  const Eigen::MatrixXd y = read_accelerations();
  OmaOptions o;
  o.method = OmaMethod::ssi_data;
  o.max_order = 60;
  o.block_rows = 20;
  o.uncertainty_blocks = 0;
  const OmaResult r = oma(y, 1.0 / 1024.0, o);
  EXPECT_TRUE(r.verdict.usable) << r.verdict.summary();
  auto closest_to = [](const OmaResult& result, double f) {
    double closest = 0.0;
    for (const auto& m : result.modes) {
      if (std::abs(m.frequency_hz - f) < std::abs(closest - f)) closest = m.frequency_hz;
    }
    return closest;
  };
  for (double f : {119.01, 192.48, 229.45, 239.38}) {
    SCOPED_TRACE(f);
    EXPECT_LT(std::abs(closest_to(r, f) - f) / f, 0.005);
  }
  o.modes_near_hz = {154.66, 214.98};
  const OmaResult named = oma(y, 1.0 / 1024.0, o);
  ASSERT_EQ(named.modes.size(), 2u) << named.verdict.summary();
  for (double f : o.modes_near_hz) {
    SCOPED_TRACE(f);
    EXPECT_LT(std::abs(closest_to(named, f) - f) / f, 0.005);
  }
}

// All seven input-output modes, each matched by the nearest efdd mode.
TEST(OmaFlexibleStructure, EfddFindsEveryInputOutputModeWithinHalfAPercent) {
  const Eigen::MatrixXd y = read_accelerations();
  OmaOptions o;
  o.method = OmaMethod::efdd;
  const OmaResult r = oma(y, 1.0 / 1024.0, o);
  EXPECT_TRUE(r.verdict.usable) << r.verdict.summary();
  for (double f : {62.34, 119.01, 154.66, 192.48, 214.98, 229.45, 239.38}) {
    SCOPED_TRACE(f);
    double closest = 0.0;
    for (const auto& m : r.modes) {
      if (std::abs(m.frequency_hz - f) < std::abs(closest - f)) closest = m.frequency_hz;
    }
    EXPECT_LT(std::abs(closest - f) / f, 0.005);
  }
}

// Decision 0035: the default block rows (10 by the order rule) are raised so that the lags
// span 4 periods of the lowest spectral peak (near 62 Hz: 2p - 1 >= 4 * 1024 / 62, p = 34);
// with them the default analysis (orders to 60) finds the lowest input-output mode.
TEST(OmaFlexibleStructure, DefaultBlockRowsSpanTheLowestMode) {
  CTID_SKIP_UNDER_SANITIZERS("ten segment SVDs of a 952 x 952 Hankel matrix");
  const Eigen::MatrixXd y = read_accelerations();
  OmaOptions o;
  o.max_order = 60;
  const OmaResult r = oma(y, 1.0 / 1024.0, o);
  EXPECT_EQ(r.block_rows, 34);
  EXPECT_GE((2.0 * r.block_rows - 1.0) / 1024.0 * 62.0, 4.0);
  double closest = 0.0;
  for (const auto& m : r.modes) {
    if (std::abs(m.frequency_hz - 62.34) < std::abs(closest - 62.34)) closest = m.frequency_hz;
  }
  EXPECT_LT(std::abs(closest - 62.34) / 62.34, 0.01);
  // A budget that stops the raise is said in the message.
  const Eigen::MatrixXd few = y.topRows(600);
  OmaOptions small;
  small.max_order = 20;
  small.uncertainty_blocks = 0;
  const OmaResult short_record = oma(few, 1.0 / 1024.0, small);
  EXPECT_EQ(short_record.block_rows, 30);  // 600 samples / 20 per block row
  EXPECT_NE(short_record.message.find("periods of the lowest spectral peak"), std::string::npos)
      << short_record.message;
}

}  // namespace
}  // namespace ctid::flexible_structure_test
