// The DaISy flexible structure (data/daisy_flexible_structure, PROVENANCE.md there) used
// output-only: the 28 accelerations, the two shaker forces ignored. The input-output
// shared-pole fit of the same record has modes at 62.34, 119.01, 154.66, 192.48, 214.98,
// 229.45 and 239.38 Hz; the output-only modes must agree within 0.5 % on the ones the record
// excites well enough to be picked automatically, listed in kWellExcited.
// Settings: 30 block rows, orders to 60. Frequency-domain decomposition (efdd) of the same
// accelerations must find all seven modes within 0.5 %, 154.66 Hz included: a peak of the
// first singular value needs no stable column of poles. pLSCF with four references finds all
// seven within 0.5 % too. Cut into two setups, the record's merged modes have the whole record's
// shapes.
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ctid/oma/multi_setup.h"
#include "ctid/oma/oma.h"
#include "ctid/oma/ssi_cov.h"
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

// pLSCF (decision 0066) with four references (y1, y7, y17, y28) and polynomial orders to 40:
// every mode of the input-output fit within 0.5 %, 62.34 and 154.66 Hz included, each with
// segment standard errors, and the shapes of SSI-cov's modes at the same frequencies
// (MAC >= 0.95).
TEST(OmaFlexibleStructure, PlscfFindsTheInputOutputModesWithSsiCovsShapes) {
  CTID_SKIP_UNDER_SANITIZERS("forty QR factorisations of the projected equations, eleven times");
  const Eigen::MatrixXd y = read_accelerations();
  OmaOptions o;
  o.method = OmaMethod::plscf;
  o.reference_channels = {0, 6, 16, 27};
  const OmaResult r = oma(y, 1.0 / 1024.0, o);
  EXPECT_TRUE(r.verdict.usable) << r.verdict.summary();
  OmaOptions ssi;
  ssi.max_order = 60;
  ssi.block_rows = 30;
  ssi.uncertainty_blocks = 0;
  const OmaResult reference = oma(y, 1.0 / 1024.0, ssi);
  const auto closest = [](const OmaResult& result, double f) {
    const OmaMode* best = nullptr;
    for (const auto& m : result.modes) {
      if (best == nullptr || std::abs(m.frequency_hz - f) < std::abs(best->frequency_hz - f)) {
        best = &m;
      }
    }
    return best;
  };
  for (double f : {62.34, 119.01, 154.66, 192.48, 214.98, 229.45, 239.38}) {
    SCOPED_TRACE(f);
    const OmaMode* m = closest(r, f);
    ASSERT_NE(m, nullptr);
    EXPECT_LT(std::abs(m->frequency_hz - f) / f, 0.005);
    EXPECT_TRUE(std::isfinite(m->frequency_hz_std) && m->frequency_hz_std > 0.0);
    const OmaMode* s = closest(reference, f);
    if (s != nullptr && std::abs(s->frequency_hz - f) / f < 0.005 && f > 100.0) {
      EXPECT_GE(oma_detail::modal_assurance(oma_detail::shape_of(*m), oma_detail::shape_of(*s)),
                0.95);
    }
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

// Multi-setup (decisions 0059, 0062) on measured data: the record cut into two setups of half
// its length each, y1 and y28 the references, y2..y14 roving in the first half and y15..y27 in
// the second. The merged modes that the whole record's analysis also has (within 0.5 %) have
// the same shapes over all 28 channels (MAC >= 0.95), `named` among them.
// `merged` is the merge's result, for the caller's own checks.
void expect_two_halves_merge_to_the_whole_record(OmaMerge merge, const std::vector<double>& named,
                                                 MultiSetupResult& merged) {
  const Eigen::MatrixXd y = read_accelerations();
  const Eigen::Index half = y.rows() / 2;
  OmaOptions o;
  o.max_order = 60;
  o.block_rows = 30;
  o.uncertainty_blocks = 0;
  MultiSetupOptions m;
  m.oma = o;
  m.reference_names = {"y1", "y28"};
  m.merge = merge;
  std::vector<OmaSetup> setups(2);
  for (int s = 0; s < 2; ++s) {
    const Eigen::MatrixXd rows =
        s == 0 ? Eigen::MatrixXd(y.topRows(half)) : Eigen::MatrixXd(y.bottomRows(y.rows() - half));
    std::vector<int> channels = {0, 27};
    for (int j = 1 + 13 * s; j < 14 + 13 * s; ++j) channels.push_back(j);
    setups[static_cast<std::size_t>(s)].sample_time = 1.0 / 1024.0;
    setups[static_cast<std::size_t>(s)].outputs.resize(rows.rows(),
                                                       static_cast<Eigen::Index>(channels.size()));
    for (std::size_t k = 0; k < channels.size(); ++k) {
      setups[static_cast<std::size_t>(s)].outputs.col(static_cast<Eigen::Index>(k)) =
          rows.col(channels[k]);
      setups[static_cast<std::size_t>(s)].channel_names.push_back("y" +
                                                                  std::to_string(channels[k] + 1));
    }
  }
  merged = oma_multi_setup(setups, m);
  ASSERT_TRUE(merged.merged.verdict.usable) << merged.merged.message;
  ASSERT_EQ(merged.merged.channels.size(), 28u);
  const OmaResult whole = oma(y, 1.0 / 1024.0, o);
  int matched = 0;
  for (const OmaMode& g : merged.merged.modes) {
    const OmaMode* w = nullptr;
    for (const OmaMode& candidate : whole.modes) {
      if (std::abs(candidate.frequency_hz / g.frequency_hz - 1.0) < 0.005) w = &candidate;
    }
    if (w == nullptr) continue;
    SCOPED_TRACE(g.frequency_hz);
    // The whole record's shape in the global channel order (y1, y28, y2, ..., y27).
    Eigen::VectorXcd a(28), b(28);
    for (std::size_t k = 0; k < 28; ++k) {
      const int channel = std::stoi(merged.merged.channels[k].substr(1)) - 1;
      a(static_cast<Eigen::Index>(k)) = {g.shape_real[k], g.shape_imag[k]};
      b(static_cast<Eigen::Index>(k)) = {w->shape_real[static_cast<std::size_t>(channel)],
                                         w->shape_imag[static_cast<std::size_t>(channel)]};
    }
    EXPECT_GE(oma_detail::modal_assurance(a, b), 0.95);
    ++matched;
  }
  EXPECT_GE(matched, 3);
  for (const double f : named) {
    bool found = false;
    for (const OmaMode& g : merged.merged.modes)
      found = found || std::abs(g.frequency_hz / f - 1.0) < 0.005;
    EXPECT_TRUE(found) << f;
  }
}

TEST(OmaFlexibleStructure, TwoHalvesAsSetupsMergeToTheWholeRecordsShapes) {
  // The three best-excited input-output modes among the merged ones.
  MultiSetupResult r;
  expect_two_halves_merge_to_the_whole_record(OmaMerge::poser, {119.01, 229.45, 239.38}, r);
}

TEST(OmaFlexibleStructure, TwoHalvesMergedByPregerGiveTheWholeRecordsShapes) {
  CTID_SKIP_UNDER_SANITIZERS(
      "TwoHalvesAsSetupsMergeToTheWholeRecordsShapes runs the same setups through the PoSER "
      "merge, and MultiSetup.PregerThreeSetupsGiveTheShapesOfOneSetupWithEverySensor PreGER's "
      "path");
  // PreGER finds 285.9, 332.6, 351.1 and 416.5 Hz here (docs/oma.md). The 119, 229 and 239 Hz
  // modes have a pole within 0.5 % at every order from 24, but their damping ratios move by
  // more than the 5 % stability bound from order to order on records this short, so too few
  // orders call them stable (decision 0062).
  MultiSetupResult r;
  expect_two_halves_merge_to_the_whole_record(OmaMerge::preger, {}, r);
  std::vector<double> found;
  for (const OmaMode& m : r.merged.modes) found.push_back(std::round(m.frequency_hz * 10.0) / 10.0);
  EXPECT_EQ(found, (std::vector<double>{285.9, 332.6, 351.1, 416.5}));
  for (const double f : {119.01, 229.45, 239.38}) {
    for (int order = 24; order <= 60; order += 2) {
      bool near = false;
      for (const OmaPole& q : r.merged.stabilisation) {
        near = near || (q.order == order && std::abs(q.frequency_hz / f - 1.0) < 0.005);
      }
      EXPECT_TRUE(near) << f << " Hz at order " << order;
    }
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
