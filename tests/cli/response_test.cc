// `ctid step` and `ctid impulse` run as a user would: on a fit result the printed DC gain and
// its standard error are the model's B(0)/A(0) and the delta method of the result's covariance;
// on a plain model file the CSV is the closed-form response, delay included, with no band;
// models without a final value say why; bad input exits 2 with one line naming the problem.
#include <cmath>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/output_conventions.h"
#include "cli/run_ctid.h"
#include "ctid/core/format.h"
#include "ctid/io/csv.h"
#include "ctid/io/result_json.h"

namespace ctid::cli::response_test {
namespace {

using testing::expect_bad_input;
using ::testing::HasSubstr;
using ::testing::Not;

class ResponseCommand : public testing::CliTest {
 protected:
  // 2 e^{-0.1 s} / (0.5 s + 1).
  std::string first_order() const {
    return write("g.json",
                 R"({"type": "transfer_function", "numerator_ascending": [2],
                     "denominator_ascending": [1, 0.5], "input_delay": 0.1})");
  }
};

TEST_F(ResponseCommand, FitResultPrintsTheDeltaMethodDcGain) {
  first_order();
  ASSERT_EQ(ctid({"simulate", "-m", "g.json", "--excitation", "white", "--samples", "600", "-T",
                  "0.05", "--noise-std", "0.1", "-o", "d.csv", "-q"})
                .status,
            0);
  const auto fit = ctid({"fit", "d.csv", "--poles", "1", "--zeros", "0", "--input-delay-samples",
                         "2", "-o", "r.json", "-q"});
  ASSERT_EQ(fit.status, 0) << fit.err;
  const auto r = ctid({"step", "r.json", "-o", "s.csv"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(testing::convention_violations(r.out), ::testing::IsEmpty()) << r.out;
  // theta = [a1, b0]: the DC gain is b0, its variance the covariance's (1, 1) entry.
  const io::FittedModel fitted = io::read_fitted_model(path("r.json"));
  const double gain = fitted.model[0].b[0];
  const double error = std::sqrt(fitted.covariance(1, 1));
  EXPECT_THAT(r.out, HasSubstr("DC gain: " + format_brief(gain) + " ± " + format_brief(error)));
  EXPECT_THAT(r.out, HasSubstr("rise time (10-90 %): "));
  EXPECT_THAT(r.out, HasSubstr("settling time (2 %): "));
  EXPECT_THAT(r.out, HasSubstr("overshoot: none"));
  const io::CsvTable table = io::read_csv(path("s.csv"));
  EXPECT_EQ(table.names, (std::vector<std::string>{"t", "y", "y_std", "lower", "upper"}));
  EXPECT_EQ(table.rows(), 1000);
  EXPECT_EQ(table.column("y")(0), 0.0);  // before the 0.1 s delay
  EXPECT_NEAR(table.column("y")(table.rows() - 1), gain, 0.01 * std::abs(gain));
}

TEST_F(ResponseCommand, ModelFileGivesTheClosedFormWithoutBand) {
  first_order();
  const auto r =
      ctid({"step", "g.json", "--final-time", "3", "--sample-time", "0.05", "-o", "s.csv"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("DC gain: 2\n"));
  EXPECT_THAT(r.out, Not(HasSubstr("±")));
  EXPECT_THAT(r.out, HasSubstr("no standard errors"));
  const io::CsvTable table = io::read_csv(path("s.csv"));
  EXPECT_EQ(table.names, (std::vector<std::string>{"t", "y"}));
  ASSERT_EQ(table.rows(), 61);
  for (int k = 0; k < table.rows(); ++k) {
    const double t = table.column("t")(k);
    const double expected = t < 0.1 ? 0.0 : 2.0 * (1.0 - std::exp(-(t - 0.1) / 0.5));
    EXPECT_NEAR(table.column("y")(k), expected, 1e-12) << "t = " << t;
  }
  const auto impulse = ctid({"impulse", "g.json", "--points", "11", "-t", "1.1", "-o", "h.csv"});
  ASSERT_EQ(impulse.status, 0) << impulse.err;
  const io::CsvTable h = io::read_csv(path("h.csv"));
  EXPECT_NEAR(h.column("y")(10), 4.0 * std::exp(-2.0), 1e-12);
}

TEST_F(ResponseCommand, IntegratorSaysTheCharacteristicsAreNotDefined) {
  write("i.json", R"({"type": "transfer_function", "numerator_ascending": [1],
                      "denominator_ascending": [0, 1, 1]})");
  const auto r = ctid({"step", "i.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("DC gain: none"));
  EXPECT_THAT(r.out, HasSubstr("not defined: the model has an integrator"));
  EXPECT_THAT(r.out, Not(HasSubstr("nan")));
}

TEST_F(ResponseCommand, BadInputIsOneLine) {
  first_order();
  expect_bad_input(ctid({"step", "missing.json"}), "step", "missing.json");
  write("v.json", R"({"type": "validation_report", "version": 1})");
  expect_bad_input(ctid({"impulse", "v.json"}), "impulse",
                   "v.json is a validation_report document; ctid impulse reads a ctid fit result");
  expect_bad_input(ctid({"step", "g.json", "--final-time", "0"}), "step",
                   "--final-time: '0' is not a positive number");
  expect_bad_input(ctid({"step", "g.json", "--points", "100000000"}), "step",
                   "--points is 100000000; it must be in [2, ");
  expect_bad_input(ctid({"step", "g.json", "--final-time", "1e4", "--sample-time", "1e-4"}), "step",
                   "gives 100000001 points; at most 1000000 are computed");
  expect_bad_input(ctid({"step", "g.json", "--points", "10", "--sample-time", "0.1"}), "step",
                   "--points and --sample-time both set the grid");
}

TEST_F(ResponseCommand, PlotDrawsTheResponseWithItsBand) {
  if (testing::python_package().empty()) GTEST_SKIP() << "no ctid Python package in this build";
  first_order();
  const auto r = ctid({"step", "g.json", "--plot", "figures", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  testing::expect_png(path("figures") / "step.png");
}

}  // namespace
}  // namespace ctid::cli::response_test
