// Mode tracking over several outputs (track_mimo_modes, docs/decisions/0026-mimo-tracking.md):
// two modes of three sensors crossing in frequency, one drifting 2 %, are followed within their
// standard errors and never swapped, because the matching weighs their shapes (MAC); windows
// that start mid-motion are fitted without bias; the MAC gate and term decide where frequency
// alone would swap; bad options are refused with one message.
#include <algorithm>
#include <cmath>
#include <complex>
#include <random>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/core/state_space.h"
#include "ctid/estimation/mimo_modes.h"
#include "ctid/identification/mode_tracking.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/excitation.h"

namespace ctid::mimo_tracking_test {
namespace {

using ::testing::HasSubstr;

struct ShapedMode {
  double w;
  double zeta;
  Eigen::Vector3d shape;
};

// y_j = sum_i shape_ij x_i with x_i'' + 2 zeta w x_i' + w^2 x_i = w^2 u: the state [x_i, x_i']
// is physical and carried across the segments (segment s holds segments[s] for `length`
// samples), each discretised exactly (ZOH).
Eigen::MatrixXd piecewise_outputs(const std::vector<std::vector<ShapedMode>>& segments, int length,
                                  const Eigen::VectorXd& u, double h) {
  const int k_modes = static_cast<int>(segments.front().size());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(2 * k_modes);
  Eigen::MatrixXd y(u.size(), 3);
  int k = 0;
  for (const std::vector<ShapedMode>& modes : segments) {
    StateSpace ct;
    ct.a = Eigen::MatrixXd::Zero(2 * k_modes, 2 * k_modes);
    ct.b = Eigen::VectorXd::Zero(2 * k_modes);
    ct.c = Eigen::RowVectorXd::Zero(2 * k_modes);
    Eigen::MatrixXd c = Eigen::MatrixXd::Zero(3, 2 * k_modes);
    for (int i = 0; i < k_modes; ++i) {
      const ShapedMode& m = modes[static_cast<std::size_t>(i)];
      ct.a(2 * i, 2 * i + 1) = 1.0;
      ct.a(2 * i + 1, 2 * i) = -m.w * m.w;
      ct.a(2 * i + 1, 2 * i + 1) = -2.0 * m.zeta * m.w;
      ct.b(2 * i + 1) = m.w * m.w;
      c.col(2 * i) = m.shape;
    }
    const StateSpace dt = discretize_zoh(ct, h);
    for (int j = 0; j < length; ++j, ++k) {
      y.row(k) = (c * x).transpose();
      x = dt.a * x + dt.b * u(k);
    }
  }
  return y;
}

const Eigen::Vector3d kShapeA(1.0, 0.8, -0.5);
const Eigen::Vector3d kShapeB(0.3, -0.6, 1.0);

// Mode A stays at 10 rad/s; mode B drifts from 9.9 to 10.1 rad/s (2 %), crossing A halfway.
// Their dampings differ, so the poles stay apart, but their frequencies do not.
std::vector<std::vector<ShapedMode>> crossing_modes(int windows) {
  std::vector<std::vector<ShapedMode>> segments;
  for (int s = 0; s < windows; ++s) {
    const double drift = 0.02 * s / (windows - 1);
    segments.push_back({{10.0, 0.02, kShapeA}, {10.0 * (0.99 + drift), 0.06, kShapeB}});
  }
  return segments;
}

MimoData noisy_record(const std::vector<std::vector<ShapedMode>>& truth, int length, double h,
                      double noise, unsigned seed) {
  const int windows = static_cast<int>(truth.size());
  const Eigen::VectorXd u = white_noise(length * windows, 1.0, seed);
  Eigen::MatrixXd y = piecewise_outputs(truth, length, u, h);
  std::mt19937_64 rng(seed + 1);
  std::normal_distribution<double> normal;
  for (Eigen::Index j = 0; j < y.cols(); ++j) {
    const double sd = noise * std::sqrt(y.col(j).squaredNorm() / static_cast<double>(y.rows()));
    for (Eigen::Index k = 0; k < y.rows(); ++k) y(k, j) += sd * normal(rng);
  }
  return MimoData(h, u, y);
}

const std::vector<SubmodelOrder> kTwoModes(2, SubmodelOrder{2, 0, 0});

TEST(MimoTracking, CrossingModesAreFollowedWithinTheirErrorsAndNeverSwapped) {
  const double h = 0.02;
  const int length = 1000;
  const int windows = 40;
  const std::vector<std::vector<ShapedMode>> truth = crossing_modes(windows);
  const MimoData data = noisy_record(truth, length, h, 0.05, 29);

  MimoTrackingOptions options;
  options.window = length * h;
  int reported = 0;
  const MimoTrackingResult r =
      track_mimo_modes(data, kTwoModes, options, [&](int done, int) { reported = done; });
  EXPECT_EQ(reported, windows);
  ASSERT_EQ(r.windows.size(), static_cast<std::size_t>(windows));
  EXPECT_EQ(r.usable_windows, windows);
  ASSERT_EQ(r.tracks.size(), 2u);
  // The track holding shape A in window 1 is track A.
  const MimoTrackingWindow& first = r.windows.front();
  ASSERT_EQ(first.modes.size(), 2u);
  const int k_a =
      modal_assurance(first.modes[0].shape, kShapeA.cast<std::complex<double>>()) >
              modal_assurance(first.modes[1].shape, kShapeA.cast<std::complex<double>>())
          ? 0
          : 1;
  const int track_a = first.tracks[static_cast<std::size_t>(k_a)];
  int within = 0;
  int checked = 0;
  double smallest_mac = 1.0;
  for (int w = 0; w < windows; ++w) {
    const MimoTrackingWindow& window = r.windows[static_cast<std::size_t>(w)];
    SCOPED_TRACE("window " + std::to_string(w + 1));
    EXPECT_TRUE(window.verdict.usable) << window.verdict.summary();
    EXPECT_EQ(window.start, w == 0 ? WindowStart::automatic : WindowStart::previous_window);
    for (std::size_t k = 0; k < window.modes.size(); ++k) {
      const MimoMode& m = window.modes[k];
      const bool is_a = window.tracks[k] == track_a;
      // Never swapped: the mode on track A has shape A, the other shape B.
      const Eigen::VectorXcd own = (is_a ? kShapeA : kShapeB).cast<std::complex<double>>();
      const Eigen::VectorXcd other = (is_a ? kShapeB : kShapeA).cast<std::complex<double>>();
      EXPECT_GT(modal_assurance(m.shape, own), modal_assurance(m.shape, other));
      const ShapedMode& t = truth[static_cast<std::size_t>(w)][is_a ? 0 : 1];
      ++checked;
      if (std::abs(m.natural_frequency - t.w) <= 3.0 * m.natural_frequency_se &&
          std::abs(m.damping_ratio - t.zeta) <= 3.0 * m.damping_ratio_se) {
        ++within;
      }
      if (w > 0) smallest_mac = std::min(smallest_mac, window.mac[k]);
    }
  }
  EXPECT_EQ(checked, 2 * windows);
  EXPECT_GE(within, 0.95 * checked) << within << " of " << checked;
  EXPECT_GT(smallest_mac, 0.9);
  for (const MimoModeTrack& track : r.tracks) EXPECT_EQ(track.windows_matched, windows);
  const MimoModeTrack& b = r.tracks[static_cast<std::size_t>(1 - track_a)];
  EXPECT_NEAR(b.frequency_drift, 0.2, 0.05);
  EXPECT_NEAR(r.tracks[static_cast<std::size_t>(track_a)].frequency_drift, 0.0, 0.05);
}

TEST(MimoTracking, WindowsStartingMidMotionAreExactWithInitialConditionsAndBiasedWithout) {
  // Noise-free, piecewise-constant modes: every window after the first starts mid-motion.
  const double h = 0.02;
  const int length = 1000;
  const std::vector<std::vector<ShapedMode>> truth = crossing_modes(4);
  const MimoData data = noisy_record(truth, length, h, 0.0, 31);
  MimoTrackingOptions options;
  options.window = length * h;
  const MimoTrackingResult r = track_mimo_modes(data, kTwoModes, options);
  ASSERT_EQ(r.usable_windows, 4);
  options.refined_iv.initial_conditions = InitialConditions::zero;
  const MimoTrackingResult z = track_mimo_modes(data, kTwoModes, options);
  double worst_zero = 0.0;
  for (int w = 0; w < 4; ++w) {
    SCOPED_TRACE("window " + std::to_string(w + 1));
    const auto ws = static_cast<std::size_t>(w);
    for (std::size_t k = 0; k < 2; ++k) {
      const MimoMode& m = r.windows[ws].modes[k];
      const bool is_a = modal_assurance(m.shape, kShapeA.cast<std::complex<double>>()) > 0.5;
      const ShapedMode& t = truth[ws][is_a ? 0 : 1];
      EXPECT_NEAR(m.natural_frequency, t.w, 1e-8 * t.w);
      EXPECT_NEAR(m.damping_ratio, t.zeta, 1e-8);
      if (w > 0 && z.windows[ws].modes.size() == 2) {
        for (const MimoMode& zm : z.windows[ws].modes) {
          const bool z_is_a = modal_assurance(zm.shape, kShapeA.cast<std::complex<double>>()) > 0.5;
          if (z_is_a == is_a)
            worst_zero = std::max(worst_zero, std::abs(zm.natural_frequency - t.w) / t.w);
        }
      }
    }
  }
  EXPECT_GT(worst_zero, 1e-4);
}

TEST(MimoTracking, TheShapesKeepIdentityWhereFrequencyAloneWouldSwap) {
  const auto mode = [](double w, const Eigen::Vector3d& shape) {
    MimoMode m;
    m.natural_frequency = w;
    m.damping_ratio = 0.02;
    m.shape = shape.cast<std::complex<double>>().normalized();
    return m;
  };
  const std::vector<MimoMode> tracks{mode(10.0, kShapeA), mode(10.05, kShapeB)};
  // Mode A moved up and B down past each other's last frequency.
  const std::vector<MimoMode> modes{mode(10.04, kShapeA), mode(10.01, kShapeB)};
  MimoTrackingOptions options;
  EXPECT_EQ(assign_mimo_modes(tracks, modes, options), (std::vector<int>{0, 1}));
  options.mac_weight = 0.0;
  options.min_mac = 0.0;
  EXPECT_EQ(assign_mimo_modes(tracks, modes, options), (std::vector<int>{1, 0}));
  // The gate: a shape like no track's starts a new track.
  options.min_mac = 0.9;
  const std::vector<MimoMode> odd{mode(10.0, Eigen::Vector3d(1.0, -1.0, -1.0))};
  EXPECT_EQ(assign_mimo_modes(tracks, odd, options), (std::vector<int>{-1}));
}

TEST(MimoTracking, BadOptionsAreRefusedWithOneMessage) {
  const MimoData data = noisy_record(crossing_modes(2), 200, 0.02, 0.0, 3);
  MimoTrackingOptions options;
  EXPECT_THAT(
      [&] { track_mimo_modes(data, kTwoModes, options); },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("MimoTrackingOptions.window is 0")));
  options.window = 4.0;
  options.min_mac = 1.5;
  EXPECT_THAT([&] { track_mimo_modes(data, kTwoModes, options); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("min_mac")));
  options.min_mac = 0.5;
  options.window = 100.0;
  EXPECT_THAT(
      [&] { track_mimo_modes(data, kTwoModes, options); },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("the window must not be longer")));
  options.window = 4.0;
  EXPECT_THAT([&] { track_mimo_modes(data, {}, options); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("every window was refused; window 1: mimo_srivc: the structure has no "
                            "submodels")));
  MimoMode three;
  three.shape = Eigen::VectorXcd::Ones(3);
  MimoMode two;
  two.shape = Eigen::VectorXcd::Ones(2);
  EXPECT_THAT([&] { assign_mimo_modes({three}, {two}, options); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("mode 1 has a shape of 2 outputs; track 1's has 3")));
}

}  // namespace
}  // namespace ctid::mimo_tracking_test
