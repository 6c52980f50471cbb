// Output-only mode tracking (track_output_only_modes, decision 0060): each window is exactly
// oma() of that stretch of the record, every mode of a seeded ambient chain record is followed
// through every window near its true frequency with shapes that agree from window to window,
// and bad windows or records are refused in one line.
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/identification/mode_tracking.h"
#include "oma/chain_model.h"

namespace ctid::output_only_tracking_test {
namespace {

using oma_test::ChainModel;
using ::testing::HasSubstr;

OmaTrackingOptions tracking_options() {
  OmaTrackingOptions o;
  o.window = 50.0;  // 10000 samples of 5 ms
  o.step = 25.0;
  o.oma.max_order = 16;
  o.oma.block_rows = 20;
  return o;
}

TEST(OutputOnlyTracking, EachWindowIsTheAnalysisOfItsStretch) {
  const ChainModel model(3);
  const Eigen::MatrixXd y = model.simulate(30000, 0.05, 61);
  const OmaTrackingOptions o = tracking_options();
  const MimoTrackingResult r = track_output_only_modes(y, model.h, 2.0, {}, o);
  ASSERT_EQ(r.windows.size(), 5u);  // 150 s in windows of 50 s every 25 s
  EXPECT_EQ(r.output_names, (std::vector<std::string>{"y1", "y2", "y3"}));
  EXPECT_DOUBLE_EQ(r.windows[1].start_time, 2.0 + 25.0);
  for (std::size_t w = 0; w < r.windows.size(); ++w) {
    const OmaResult direct =
        oma(y.middleRows(r.windows[w].first_sample, r.window_samples), model.h, o.oma);
    ASSERT_EQ(r.windows[w].modes.size(), direct.modes.size()) << w;
    for (std::size_t k = 0; k < direct.modes.size(); ++k) {
      EXPECT_EQ(r.windows[w].modes[k].natural_frequency,
                2.0 * std::numbers::pi * direct.modes[k].frequency_hz);
      EXPECT_EQ(r.windows[w].modes[k].damping_ratio, direct.modes[k].damping_ratio);
    }
  }
}

TEST(OutputOnlyTracking, EveryModeIsFollowedThroughEveryWindow) {
  const ChainModel model(3);
  const Eigen::MatrixXd y = model.simulate(30000, 0.05, 62);
  const MimoTrackingResult r = track_output_only_modes(y, model.h, 0.0, {}, tracking_options());
  EXPECT_EQ(r.usable_windows, 5);
  ASSERT_EQ(r.tracks.size(), model.modes.size());
  for (std::size_t t = 0; t < r.tracks.size(); ++t) {
    const MimoModeTrack& track = r.tracks[t];
    const double truth = 2.0 * std::numbers::pi * model.modes[t].frequency_hz;
    SCOPED_TRACE(model.modes[t].frequency_hz);
    EXPECT_EQ(track.windows_matched, 5);
    for (std::size_t w = 0; w < 5; ++w) {
      EXPECT_LT(std::abs(track.natural_frequency[w] / truth - 1.0), 0.01) << w;
      EXPECT_LT(std::abs(track.natural_frequency[w] - truth), 4.0 * track.natural_frequency_se[w]);
      if (w > 0) {
        EXPECT_GE(track.mac[w], 0.99) << w;
      }
    }
  }
}

TEST(OutputOnlyTracking, RefusalsNameWhatIsWrong) {
  const ChainModel model(3);
  const Eigen::MatrixXd y = model.simulate(4000, 0.05, 63);
  OmaTrackingOptions o = tracking_options();
  try {
    track_output_only_modes(y, model.h, 0.0, {}, o);
    ADD_FAILURE() << "a window longer than the record was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("OmaTrackingOptions.window is 50 s (10000 samples); the "
                                    "record has 4000 samples"));
  }
  o.window = 10.0;
  o.step.reset();
  try {
    track_output_only_modes(y.leftCols(1), model.h, 0.0, {}, o);
    ADD_FAILURE() << "one channel was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("every window was refused; window 1: "));
  }
}

}  // namespace
}  // namespace ctid::output_only_tracking_test
