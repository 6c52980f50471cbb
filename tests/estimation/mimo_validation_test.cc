// validate_model for several inputs and outputs: output j's simulation is the sum of its
// channels' responses, and the estimated initial state makes a noise-free record cut out of a
// longer one (so it starts mid-motion) fit exactly; one input and one output is the SISO
// validation.
#include <string>

#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/estimation/validation.h"
#include "ctid/simulation/excitation.h"

namespace ctid::mimo_validation_test {
namespace {

constexpr double kH = 0.05;

// Two modes (1.4 and 4 rad/s) seen by three outputs from two inputs, and a direct term.
MimoAdditiveModel two_modes() {
  const double shapes[2][3] = {{1.0, 0.5, -0.3}, {-0.4, 1.0, 0.6}};
  const double participation[2][2] = {{1.0, 0.6}, {-0.5, 0.8}};
  std::vector<MimoSubmodel> submodels;
  for (int i = 0; i < 2; ++i) {
    const double w = i == 0 ? 1.4 : 4.0;
    MimoSubmodel s{Polynomial{1.0, 0.1 / w, 1.0 / (w * w)}, {}};
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 2; ++k)
        s.b.push_back(Polynomial{shapes[i][j] * participation[i][k], 0.1});
    }
    submodels.push_back(std::move(s));
  }
  Eigen::MatrixXd d(3, 2);
  d << 0.1, 0.0, -0.2, 0.3, 0.0, 0.05;
  return MimoAdditiveModel(2, 3, std::move(submodels), d);
}

// The model's response from rest to white inputs over `total` samples, the first `skip` cut.
MimoData record(const MimoAdditiveModel& model, int total, int skip) {
  Eigen::MatrixXd u(total, 2);
  for (int k = 0; k < 2; ++k) u.col(k) = white_noise(total, 1.0, 11 + static_cast<unsigned>(k));
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(total, 3);
  for (int j = 0; j < 3; ++j) {
    for (int k = 0; k < 2; ++k) y.col(j) += model_output(model.channel(j, k), u.col(k), kH);
  }
  return MimoData(kH, u.bottomRows(total - skip), y.bottomRows(total - skip));
}

TEST(MimoValidation, EstimatedStateFitsARecordThatStartsMidMotion) {
  const MimoAdditiveModel model = two_modes();
  const MimoData data = record(model, 1600, 400);
  ValidationOptions options;
  options.initial_state = InitialState::estimate;
  const MimoValidationReport r = validate_model(model, data, options);
  ASSERT_EQ(r.fit_percent.size(), 3);
  for (int j = 0; j < 3; ++j) {
    EXPECT_NEAR(r.fit_estimated_state(j), 100.0, 1e-6) << "output " << j;
    EXPECT_EQ(r.fit_percent(j), r.fit_estimated_state(j));
    // From rest the cut-off history shows as a transient.
    EXPECT_LT(r.fit_zero_state(j), 99.9) << "output " << j;
  }
  EXPECT_EQ(r.window_samples, 1200);
  // From rest on the whole record (nothing cut) the zero-state fit is exact too.
  const MimoValidationReport rest = validate_model(model, record(model, 1200, 0));
  EXPECT_EQ(rest.initial_state, InitialState::zero);
  for (int j = 0; j < 3; ++j) EXPECT_NEAR(rest.fit_percent(j), 100.0, 1e-6);
}

TEST(MimoValidation, OneInputAndOutputIsTheSisoValidation) {
  const MimoAdditiveModel two = two_modes();
  const MimoAdditiveModel one(1, 1,
                              {MimoSubmodel{two[0].a, {Polynomial{0.7, 0.2}}},
                               MimoSubmodel{two[1].a, {Polynomial{-0.3, 0.1}}}});
  const MimoData data = record(two, 1000, 200);
  const MimoData single(kH, data.inputs().leftCols(1),
                        data.outputs().col(1) * 0.5 + data.inputs().col(0) * 0.01);
  ValidationOptions options;
  options.initial_state = InitialState::estimate;
  options.window_start = 10.0;
  const MimoValidationReport m = validate_model(one, single, options);
  const ValidationReport s = validate_model(one.channel(0, 0), single.channel(0, 0), options);
  EXPECT_DOUBLE_EQ(m.fit_percent(0), s.fit_percent);
  EXPECT_DOUBLE_EQ(m.fit_zero_state(0), s.fit_zero_state);
  EXPECT_DOUBLE_EQ(m.max_residual_autocorrelation(0), s.max_residual_autocorrelation);
  EXPECT_DOUBLE_EQ(m.max_cross_correlation(0), s.max_cross_correlation);
  EXPECT_EQ(m.window_samples, s.window_samples);
}

TEST(MimoValidation, ChannelCountsMustAgree) {
  const MimoData data = record(two_modes(), 300, 0);
  const MimoData fewer(kH, data.inputs().leftCols(1), data.outputs());
  try {
    validate_model(two_modes(), fewer);
    FAIL() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("the model is 3 x 2 (outputs x inputs) but the record "
                                         "has 3 outputs and 1 inputs"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace ctid::mimo_validation_test
