#include "ctid/io/result_json.h"

#include <cmath>
#include <limits>
#include <numbers>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/io/json.h"
#include "ctid/io/model_json.h"
#include "io/test_directory.h"

namespace ctid::io::result_json_test {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

// Two modes, the second with an integrator-free biproper-free numerator of degree 1.
AdditiveModel two_modes() {
  return AdditiveModel({Submodel{Polynomial{1.0, 0.25, 0.25}, Polynomial{3.0}, 0},
                        Submodel{Polynomial{1.0, 0.01, 0.025}, Polynomial{1.0, 0.002}, 0}},
                       0.1);
}

EstimationResult example_result() {
  const AdditiveModel model = two_modes();
  EstimationResult r(model, model.to_transfer_function());
  r.additive_view = model;
  r.parameters = model.parameters();
  const Eigen::Index p = r.parameters.size();
  r.covariance = Eigen::MatrixXd::Identity(p, p) * 1e-6;
  r.covariance(0, 1) = r.covariance(1, 0) = 2e-7;
  r.standard_errors = r.covariance.diagonal().cwiseSqrt();
  ModalEstimate mode;
  mode.submodel = 0;
  mode.value = *model.modal_parameters(0);
  mode.standard_error = {0.01, std::numeric_limits<double>::quiet_NaN(), 0.02};
  r.modes.push_back(mode);
  r.termination = Termination::converged;
  r.message = "converged after 7 iterations";
  r.iterations = 7;
  r.off_diagonal_norm = 0.125;
  r.unstable_reflections = 2;
  r.sensitivity_fallbacks = 1;
  r.input_delay_samples = 2;
  r.noise_variance = 0.5;
  r.fit_percent = 97.5;
  r.checks.persistently_exciting = false;
  r.checks.warnings.push_back("the input is not persistently exciting");
  return r;
}

TEST(ResultJson, ParameterNamesFollowTheStackedThetaOrder) {
  EXPECT_THAT(parameter_names(two_modes()),
              ElementsAre("theta1.a1", "theta1.a2", "theta1.b0", "theta2.a1", "theta2.a2",
                          "theta2.b0", "theta2.b1"));
  EXPECT_EQ(parameter_names(two_modes()).size(),
            static_cast<size_t>(two_modes().parameter_count()));
}

TEST(ResultJson, HoldsEveryFieldOfTheResult) {
  const EstimationResult r = example_result();
  const nlohmann::json j = to_json(r);
  EXPECT_EQ(j.at("type"), kEstimationResultType);
  EXPECT_EQ(j.at("termination"), "converged");
  EXPECT_TRUE(j.at("converged").get<bool>());
  EXPECT_EQ(j.at("message"), r.message);
  EXPECT_EQ(j.at("iterations"), 7);
  EXPECT_EQ(j.at("off_diagonal_norm"), 0.125);
  EXPECT_EQ(j.at("unstable_reflections"), 2);
  EXPECT_EQ(j.at("sensitivity_fallbacks"), 1);
  EXPECT_EQ(j.at("input_delay_samples"), 2);
  EXPECT_EQ(j.at("input_delay"), 0.1);
  EXPECT_EQ(j.at("noise_variance"), 0.5);
  EXPECT_EQ(j.at("fit_percent"), 97.5);
  EXPECT_FALSE(j.at("data_checks").at("persistently_exciting").get<bool>());
  EXPECT_EQ(j.at("data_checks").at("warnings").size(), 1u);
  ASSERT_EQ(j.at("parameters").size(), static_cast<size_t>(r.parameters.size()));
  for (Eigen::Index i = 0; i < r.parameters.size(); ++i) {
    EXPECT_EQ(j.at("parameters")[static_cast<size_t>(i)].get<double>(), r.parameters(i));
    EXPECT_EQ(j.at("standard_errors")[static_cast<size_t>(i)].get<double>(), r.standard_errors(i));
  }
  EXPECT_EQ(j.at("covariance")[0][1].get<double>(), 2e-7);
  // Modes: the Hz value is rad/s over 2 pi; an unknown standard error is null, not NaN.
  const nlohmann::json& mode = j.at("modes")[0];
  EXPECT_DOUBLE_EQ(mode.at("natural_frequency").get<double>(), 2.0);  // 1/sqrt(0.25)
  EXPECT_DOUBLE_EQ(mode.at("natural_frequency_hz").get<double>(), 1.0 / std::numbers::pi);
  EXPECT_DOUBLE_EQ(mode.at("damping_ratio").get<double>(), 0.25);  // 0.25/(2 sqrt(0.25))
  EXPECT_TRUE(mode.at("damping_ratio_standard_error").is_null());
  EXPECT_EQ(mode.at("gain_standard_error").get<double>(), 0.02);
  // The document is valid JSON text (no NaN literal).
  EXPECT_NO_THROW(parse_json(j.dump(), "r.json"));
}

TEST(ResultJson, ModelInsideIsAModelDocumentAndReadsBackBitForBit) {
  const EstimationResult r = example_result();
  const nlohmann::json j = nlohmann::json::parse(to_json(r).dump());
  // The "model" field alone is what ctid simulate --model reads.
  const ContinuousModel alone = continuous_model_from_json(j.at("model"), "model");
  ASSERT_TRUE(std::holds_alternative<AdditiveModel>(alone));
  EXPECT_EQ(std::get<AdditiveModel>(alone).parameters(), r.parameters);

  const FittedModel fitted = fitted_model_from_json(j, "r.json");
  EXPECT_EQ(fitted.model.parameters(), r.parameters);
  EXPECT_EQ(fitted.model.input_delay(), 0.1);
  EXPECT_EQ(fitted.covariance, r.covariance);
}

TEST(ResultJson, ReadsPlainModelDocumentsWithoutCovariance) {
  const FittedModel fitted = fitted_model_from_json(to_json(two_modes()), "m.json");
  EXPECT_EQ(fitted.model.parameters(), two_modes().parameters());
  EXPECT_EQ(fitted.covariance.size(), 0);
}

TEST(ResultJson, TransferFunctionBecomesOneAntiMonicSubmodel) {
  // Rao-Garnier benchmark: A = D / 1600, B = N / 1600.
  const TransferFunction g(Polynomial{1600.0, -6400.0}, Polynomial{1600.0, 416.0, 408.0, 5.0, 1.0});
  const AdditiveModel m = as_additive_model(g);
  ASSERT_EQ(m.size(), 1);
  EXPECT_EQ(m[0].a[0], 1.0);
  EXPECT_EQ(m[0].a[4], 1.0 / 1600.0);
  EXPECT_EQ(m[0].b[1], -4.0);
  for (double w : {0.1, 1.0, 20.0, 300.0}) {
    EXPECT_LT(std::abs(m.frequency_response(w) - g.frequency_response(w)),
              1e-13 * std::abs(g.frequency_response(w)));
  }
}

TEST(ResultJson, PolesAtTheOriginBecomeIntegrators) {
  // EMPS rigid body 0.3696/(s (s + 2.14)), delay 0.01 s.
  const TransferFunction g(Polynomial{0.3696}, Polynomial{0.0, 2.14, 1.0}, 0.01);
  const AdditiveModel m = as_additive_model(g);
  ASSERT_EQ(m.size(), 1);
  EXPECT_EQ(m[0].integrators, 1);
  EXPECT_EQ(m[0].n(), 1);
  EXPECT_EQ(m.input_delay(), 0.01);
  for (double w : {0.01, 1.0, 50.0}) {
    EXPECT_LT(std::abs(m.frequency_response(w) - g.frequency_response(w)),
              1e-13 * std::abs(g.frequency_response(w)));
  }
  EXPECT_THROW(as_additive_model(TransferFunction(Polynomial{1.0, 1.0, 1.0}, Polynomial{1.0, 1.0})),
               InvalidArgument);
}

std::string read_error(const nlohmann::json& value) {
  try {
    fitted_model_from_json(value, "r.json");
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

TEST(ResultJson, BadResultDocumentsNameTheFileAndField) {
  nlohmann::json j = to_json(example_result());
  j.erase("model");
  EXPECT_THAT(read_error(j), HasSubstr("r.json: model: required field is missing"));

  j = to_json(example_result());
  j["covariance"] = nlohmann::json::array({nlohmann::json::array({1.0})});
  EXPECT_THAT(read_error(j), HasSubstr("r.json: covariance: has 1 rows but the model has 7"));

  j = to_json(example_result());
  j["model"]["submodels"][0]["denominator_ascending"] = {2.0, 0.25, 0.25};
  EXPECT_THAT(read_error(j), HasSubstr("r.json: model"));

  EXPECT_THAT(read_error(nlohmann::json{{"type", "excitation"}}), HasSubstr("r.json: type"));
}

TEST(ResultJson, TerminationNamesRoundTrip) {
  for (Termination t :
       {Termination::converged, Termination::iteration_limit, Termination::singular_equations,
        Termination::non_finite, Termination::closed_loop_unstable}) {
    EXPECT_EQ(termination_from_string(to_string(t)), t);
  }
  EXPECT_THROW(termination_from_string("done"), InvalidArgument);
}

TEST(ResultJson, WrittenFileReadsBack) {
  const testing::TestDirectory dir;
  write_json(dir / "r.json", to_json(example_result()));
  const FittedModel fitted = read_fitted_model(dir / "r.json");
  EXPECT_EQ(fitted.model.parameters(), example_result().parameters);
}

}  // namespace
}  // namespace ctid::io::result_json_test
