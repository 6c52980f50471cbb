// Mode tracking (issue 17): on a noise-free record whose modes change from window to window every
// window's modes come out exact and stay on their tracks; the matching keeps a mode's identity
// where sorting by frequency would swap two modes and when a window loses a mode; bad windows
// and options are refused with messages naming them.
#include "ctid/identification/mode_tracking.h"

#include <cmath>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/core/state_space.h"
#include "ctid/estimation/termination.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/excitation.h"

namespace ctid::mode_tracking_test {
namespace {

using ::testing::HasSubstr;

struct Mode {
  double w;
  double zeta;
  double gain;
};

// y = sum_i y_i with a2 y_i'' + a1 y_i' + y_i = b0 u (a2 = 1/w^2, a1 = 2 zeta/w, b0 = gain),
// state [y_i, y_i'] per mode: a physical state, carried across the switches of `segments`
// (segment s holds modes[s] for `length` samples), each segment discretised exactly (ZOH).
Eigen::VectorXd piecewise_output(const std::vector<std::vector<Mode>>& segments, int length,
                                 const Eigen::VectorXd& u, double h) {
  const int k_modes = static_cast<int>(segments.front().size());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(2 * k_modes);
  Eigen::VectorXd y(u.size());
  int k = 0;
  for (const std::vector<Mode>& modes : segments) {
    StateSpace ct;
    ct.a = Eigen::MatrixXd::Zero(2 * k_modes, 2 * k_modes);
    ct.b = Eigen::VectorXd::Zero(2 * k_modes);
    ct.c = Eigen::RowVectorXd::Zero(2 * k_modes);
    for (int i = 0; i < k_modes; ++i) {
      const Mode& m = modes[static_cast<std::size_t>(i)];
      ct.a(2 * i, 2 * i + 1) = 1.0;
      ct.a(2 * i + 1, 2 * i) = -m.w * m.w;
      ct.a(2 * i + 1, 2 * i + 1) = -2.0 * m.zeta * m.w;
      ct.b(2 * i + 1) = m.gain * m.w * m.w;
      ct.c(2 * i) = 1.0;
    }
    const StateSpace dt = discretize_zoh(ct, h);
    for (int j = 0; j < length; ++j, ++k) {
      y(k) = ct.c.dot(x);
      x = dt.a * x + dt.b * u(k);
    }
  }
  return y;
}

std::vector<std::vector<Mode>> drifting_modes(int windows) {
  std::vector<std::vector<Mode>> segments;
  for (int s = 0; s < windows; ++s) {
    segments.push_back(
        {{2.0 * (1.0 + 0.01 * s), 0.05 - 0.002 * s, 1.0}, {5.0 * (1.0 - 0.01 * s), 0.03, 0.5}});
  }
  return segments;
}

TEST(ModeTracking, NoiseFreePiecewiseConstantModesAreExactInEveryWindow) {
  const double h = 0.02;
  const int length = 1500;
  const int windows = 4;
  const std::vector<std::vector<Mode>> truth = drifting_modes(windows);
  const Eigen::VectorXd u = white_noise(length * windows, 1.0, 17);
  const SampledData data(h, u, piecewise_output(truth, length, u, h));

  TrackingOptions options;
  options.window = length * h;
  options.identification.refined_iv.initial_conditions = InitialConditions::estimate;
  int reported = 0;
  const TrackingResult r =
      track_modes(data, ModelStructure::modes(2), options, [&](int done, int total) {
        EXPECT_EQ(total, windows);
        reported = done;
      });
  EXPECT_EQ(reported, windows);
  ASSERT_EQ(r.windows.size(), static_cast<std::size_t>(windows));
  EXPECT_EQ(r.window_samples, length);
  EXPECT_EQ(r.step_samples, length);
  EXPECT_EQ(r.usable_windows, windows);
  ASSERT_EQ(r.tracks.size(), 2u);
  // The slow mode was found first in window 1's modes or second; whichever track holds 2 rad/s
  // in window 1 must hold the slow mode in every window.
  const int slow = std::abs(r.tracks[0].natural_frequency[0] - 2.0) < 0.1 ? 0 : 1;
  for (int w = 0; w < windows; ++w) {
    const TrackingWindow& window = r.windows[static_cast<std::size_t>(w)];
    SCOPED_TRACE("window " + std::to_string(w + 1));
    EXPECT_TRUE(window.verdict.usable) << window.verdict.summary();
    EXPECT_EQ(window.start, w == 0 ? WindowStart::automatic : WindowStart::previous_window);
    EXPECT_EQ(window.first_sample, w * length);
    EXPECT_DOUBLE_EQ(window.start_time, w * length * h);
    EXPECT_DOUBLE_EQ(window.end_time, (w * length + length - 1) * h);
    EXPECT_DOUBLE_EQ(window.centre_time, (w * length + 0.5 * (length - 1)) * h);
    for (int t = 0; t < 2; ++t) {
      const Mode& m = truth[static_cast<std::size_t>(w)][t == slow ? 0 : 1];
      const ModeTrack& track = r.tracks[static_cast<std::size_t>(t)];
      EXPECT_NEAR(track.natural_frequency[static_cast<std::size_t>(w)], m.w, 1e-8 * m.w);
      EXPECT_NEAR(track.damping_ratio[static_cast<std::size_t>(w)], m.zeta, 1e-8);
    }
  }
  for (const ModeTrack& track : r.tracks) EXPECT_EQ(track.windows_matched, windows);
  EXPECT_NEAR(r.tracks[static_cast<std::size_t>(slow)].frequency_drift, 2.0 * 0.03, 1e-7);
  EXPECT_NEAR(r.tracks[static_cast<std::size_t>(1 - slow)].frequency_drift, -5.0 * 0.03, 1e-7);
}

TEST(ModeTracking, OverlappingWindowsFollowTheStep) {
  const double h = 0.02;
  const Eigen::VectorXd u = white_noise(3000, 1.0, 3);
  const SampledData data(h, u, piecewise_output({{{2.0, 0.05, 1.0}}}, 3000, u, h));
  TrackingOptions options;
  options.window = 20.0;  // 1000 samples
  options.step = 10.0;    // 500 samples
  options.identification.refined_iv.initial_conditions = InitialConditions::estimate;
  const TrackingResult r = track_modes(data, ModelStructure::modes(1), options);
  ASSERT_EQ(r.windows.size(), 5u);
  EXPECT_EQ(r.windows[4].first_sample, 2000);
  ASSERT_EQ(r.tracks.size(), 1u);
  EXPECT_EQ(r.tracks[0].windows_matched, 5);
  for (double w : r.tracks[0].natural_frequency) EXPECT_NEAR(w, 2.0, 1e-8);
}

TEST(ModeTracking, AWindowWithoutExcitationIsNotUsableAndTheTracksResumeAfterIt) {
  const double h = 0.02;
  const int length = 1500;
  const int windows = 5;
  const std::vector<std::vector<Mode>> truth = drifting_modes(windows);
  Eigen::VectorXd u = white_noise(length * windows, 1.0, 23);
  u.segment(2 * length, length).setZero();  // window 3: the input is off
  const SampledData data(h, u, piecewise_output(truth, length, u, h));
  TrackingOptions options;
  options.window = length * h;
  options.identification.refined_iv.initial_conditions = InitialConditions::estimate;
  const TrackingResult r = track_modes(data, ModelStructure::modes(2), options);
  ASSERT_EQ(r.windows.size(), 5u);
  EXPECT_EQ(r.usable_windows, 4);
  const TrackingWindow& quiet = r.windows[2];
  EXPECT_FALSE(quiet.verdict.usable);
  EXPECT_EQ(quiet.termination, Termination::not_run);
  ASSERT_EQ(quiet.verdict.reasons.size(), 1u);
  EXPECT_THAT(quiet.verdict.reasons[0],
              HasSubstr("the estimator refused the window: additive_srivc: the input is "
                        "persistently exciting of order 0 only"));
  EXPECT_FALSE(quiet.model.has_value());
  EXPECT_EQ(r.windows[3].start, WindowStart::after_unusable);
  EXPECT_EQ(r.windows[4].start, WindowStart::previous_window);
  // The window lost both modes; each track takes its mode back in window 4.
  ASSERT_EQ(r.tracks.size(), 2u);
  const int slow = r.tracks[0].natural_frequency[0] < r.tracks[1].natural_frequency[0] ? 0 : 1;
  for (int t = 0; t < 2; ++t) {
    const ModeTrack& track = r.tracks[static_cast<std::size_t>(t)];
    EXPECT_TRUE(std::isnan(track.natural_frequency[2]));
    EXPECT_EQ(track.windows_matched, 4);
    for (int w : {3, 4}) {
      const double truth_w = truth[static_cast<std::size_t>(w)][t == slow ? 0 : 1].w;
      EXPECT_NEAR(track.natural_frequency[static_cast<std::size_t>(w)], truth_w, 1e-8 * truth_w);
    }
  }
}

TEST(ModeTracking, EveryWindowRefusedIsBadInput) {
  const SampledData data(0.02, Eigen::VectorXd::Zero(3000), Eigen::VectorXd::Zero(3000));
  TrackingOptions options;
  options.window = 20.0;
  try {
    (void)track_modes(data, ModelStructure::modes(1), options);
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("every window was refused; window 1: additive_srivc: the "
                                    "input is persistently exciting of order 0 only"));
  }
}

ModalParameters mode(double w, double zeta) { return ModalParameters{w, zeta, 1.0}; }

TEST(ModeTracking, MatchingKeepsIdentityWhereSortingByFrequencyWouldSwapModes) {
  // Two close modes cross in frequency from one window to the next; the damping tells them
  // apart. Sorted by frequency (or matched on frequency alone) they would swap tracks.
  const std::vector<ModalParameters> tracks{mode(1.00, 0.01), mode(1.04, 0.20)};
  const std::vector<ModalParameters> window{mode(1.01, 0.20), mode(1.03, 0.01)};
  TrackingOptions options;
  EXPECT_EQ(assign_modes(tracks, window, options), (std::vector<int>{1, 0}));
  options.damping_weight = 0.0;  // frequency alone: the nearer frequencies win
  EXPECT_EQ(assign_modes(tracks, window, options), (std::vector<int>{0, 1}));
}

TEST(ModeTracking, MatchingIsOptimalNotGreedy) {
  // Greedy on the cheapest pair would give track 0 to the mode at 1.05 and leave the mode at
  // 0.96 beyond track 1's gate: one pair. The optimum pairs both.
  const std::vector<ModalParameters> tracks{mode(1.04, 0.0), mode(1.10, 0.0)};
  const std::vector<ModalParameters> window{mode(1.05, 0.0), mode(0.96, 0.0)};
  TrackingOptions options;
  EXPECT_EQ(assign_modes(tracks, window, options), (std::vector<int>{1, 0}));
}

TEST(ModeTracking, AWindowThatLosesAModeKeepsTheOthersOnTheirTracks) {
  const std::vector<ModalParameters> tracks{mode(2.0, 0.05), mode(5.0, 0.03), mode(9.0, 0.02)};
  TrackingOptions options;
  // The middle mode is missing: the others keep their tracks, none takes track 1.
  EXPECT_EQ(assign_modes(tracks, {mode(8.9, 0.02), mode(2.01, 0.05)}, options),
            (std::vector<int>{2, 0}));
  // A mode beyond every gate starts a new track (-1), and no track is forced onto it.
  EXPECT_EQ(assign_modes(tracks, {mode(3.5, 0.05), mode(5.02, 0.03)}, options),
            (std::vector<int>{-1, 1}));
  // A wider gate: the most pairs first (3 may join 2 or 5, 5.02 may join 5 or 9), then the
  // least cost (3 to 2 and 5.02 to 5: 0.504, against 0.872 for 3 to 5 and 5.02 to 9).
  options.max_frequency_jump = 0.6;
  EXPECT_EQ(assign_modes(tracks, {mode(3.0, 0.05), mode(5.02, 0.03)}, options),
            (std::vector<int>{0, 1}));
  EXPECT_EQ(assign_modes({}, {mode(1.0, 0.1)}, options), (std::vector<int>{-1}));
}

std::string message_of(const TrackingOptions& options, int samples = 1000) {
  const Eigen::VectorXd u = white_noise(samples, 1.0, 1);
  const SampledData data(0.01, u, u);
  try {
    (void)track_modes(data, ModelStructure::modes(1), options);
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(ModeTracking, BadWindowsAndOptionsAreRefusedWithOneMessage) {
  TrackingOptions options;
  EXPECT_THAT(message_of(options), HasSubstr("TrackingOptions.window is 0; give the window"));
  options.window = 20.0;
  EXPECT_THAT(message_of(options),
              HasSubstr("TrackingOptions.window is 20 s (2000 samples); the record has 1000"));
  options.window = 6.0;
  EXPECT_THAT(message_of(options), HasSubstr("fits 1 time in a record of 1000 samples; tracking "
                                             "needs at least 2 windows"));
  options.window = 2.0;
  options.step = 0.0;
  EXPECT_THAT(message_of(options),
              HasSubstr("TrackingOptions.step is 0; it must be finite and > 0"));
  options.step = 0.001;
  EXPECT_THAT(message_of(options), HasSubstr("TrackingOptions.step is 0.001 s, less than half"));
  options.step.reset();
  options.max_frequency_jump = -1.0;
  EXPECT_THAT(message_of(options), HasSubstr("TrackingOptions.max_frequency_jump is -1"));
  options.max_frequency_jump = 0.1;
  options.identification.refined_iv.max_iterations = 0;
  EXPECT_THAT(message_of(options),
              HasSubstr("TrackingOptions.identification.refined_iv.max_iterations is 0"));
}

}  // namespace
}  // namespace ctid::mode_tracking_test
