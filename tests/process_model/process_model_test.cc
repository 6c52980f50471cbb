// Process models: each structure recovered exactly from noise-free data with the dead time
// off the sample grid, from the automatic start; names, held parameters and bad settings.
#include "ctid/process_model/process_model.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "ctid/core/additive_model.h"
#include "ctid/core/error.h"
#include "ctid/estimation/validation.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"

namespace ctid::process_model_test {
namespace {

using ::testing::HasSubstr;

// A PRBS held 4 samples a bit: rich enough for three poles, a zero and a dead time.
SampledData noise_free_record(const TransferFunction& g, double h, int n = 1500) {
  PrbsOptions prbs_options;
  prbs_options.register_length = 9;
  prbs_options.samples_per_bit = 4;
  const Eigen::VectorXd u = prbs(n, prbs_options);
  // Reference output by the simulation layer's own exact ZOH simulation (zoh_equivalent with
  // the fractional delay), not the module's.
  return SampledData(h, u, simulate(g, u, h));
}

struct Case {
  std::string name;
  std::vector<double> truth;  // in parameter_names() order
};

class ExactRecovery : public ::testing::TestWithParam<Case> {};

TEST_P(ExactRecovery, FromTheAutomaticStartWithTheDelayOffTheGrid) {
  const Case& c = GetParam();
  const ProcessStructure s = ProcessStructure::parse(c.name);
  const Eigen::VectorXd truth =
      Eigen::Map<const Eigen::VectorXd>(c.truth.data(), static_cast<Eigen::Index>(c.truth.size()));
  const double h = 0.1;
  const SampledData data = noise_free_record(process_transfer_function(s, truth), h);
  const ProcessModelResult r = estimate_process_model(data, s);
  ASSERT_EQ(r.parameters.size(), truth.size());
  for (Eigen::Index i = 0; i < truth.size(); ++i) {
    EXPECT_NEAR(r.parameters(i), truth(i), 1e-8 * std::abs(truth(i)))
        << c.name << " " << r.parameter_names[static_cast<std::size_t>(i)] << " from "
        << r.start_method << " start " << r.start.transpose();
  }
  EXPECT_TRUE(r.verdict.usable) << r.verdict.summary();
  EXPECT_GT(r.fit_percent, 99.9999);
}

// Dead times 0.37 s and 0.73 s: 3.7 and 7.3 samples of h = 0.1 s.
INSTANTIATE_TEST_SUITE_P(
    Structures, ExactRecovery,
    ::testing::Values(Case{"P1D", {2.0, 1.5, 0.37}}, Case{"P2D", {-1.3, 2.0, 0.6, 0.73}},
                      Case{"P2DU", {1.5, 0.8, 0.3, 0.37}}, Case{"P2DZ", {0.8, 1.8, 0.5, 0.9, 0.37}},
                      Case{"P1DI", {0.4, 0.7, 0.37}}, Case{"P3D", {1.2, 2.5, 1.0, 0.4, 0.73}},
                      Case{"P3DZ", {1.2, 2.5, 1.0, 0.4, -0.6, 0.37}},
                      Case{"P3DU", {1.0, 1.2, 0.2, 0.5, 0.37}}, Case{"P1", {3.0, 0.9}}),
    [](const ::testing::TestParamInfo<Case>& p) { return p.param.name; });

// A first-order hold: the record's input is linear between samples, and the fit follows it.
// The reference output comes from validation's model_output, whose filters realise the
// fractional delay by another route (SampledFilter).
TEST(ProcessModel, AFirstOrderHoldRecordIsRecoveredExactly) {
  const ProcessStructure s = ProcessStructure::parse("P2DZ");
  Eigen::VectorXd truth(5);
  truth << 0.8, 1.8, 0.5, 0.9, 0.37;
  const TransferFunction g = process_transfer_function(s, truth);
  const AdditiveModel model({Submodel{g.denominator(), g.numerator(), 0}}, g.input_delay());
  const Eigen::VectorXd u = white_noise(1500, 1.0, 5);
  const double h = 0.1;
  const SampledData data = SampledData(h, u, model_output(model, u, h, Hold::first_order_hold))
                               .with_input_hold(Hold::first_order_hold);
  const ProcessModelResult r = estimate_process_model(data, s);
  for (Eigen::Index i = 0; i < truth.size(); ++i) {
    EXPECT_NEAR(r.parameters(i), truth(i), 1e-8 * std::abs(truth(i)))
        << r.parameter_names[static_cast<std::size_t>(i)];
  }
  // Read as a ZOH record, the same samples give another model.
  const ProcessModelResult zoh =
      estimate_process_model(data.with_input_hold(Hold::zero_order_hold), s);
  EXPECT_GT(std::abs(zoh.parameter("Td") - 0.37), 1e-3);
}

TEST(ProcessModel, TheModuleSimulationAgreesWithTheSimulationLayer) {
  const ProcessStructure s = ProcessStructure::parse("P2DZ");
  Eigen::VectorXd p(5);
  p << 0.8, 1.8, 0.5, 0.9, 0.37;
  const TransferFunction g = process_transfer_function(s, p);
  const Eigen::VectorXd u = prbs(300, {});
  const Eigen::VectorXd a = process_model_output(s, p, u, 0.1);
  const Eigen::VectorXd b = simulate(g, u, 0.1);
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-12 * b.cwiseAbs().maxCoeff());
}

TEST(ProcessModel, NamesRoundTripAndParametersFollowProcest) {
  EXPECT_EQ(ProcessStructure::parse("p2udz").name(), "P2DZU");
  EXPECT_EQ(ProcessStructure::parse("P1DI").parameter_names(),
            (std::vector<std::string>{"K", "Tp1", "Td"}));
  EXPECT_EQ(ProcessStructure::parse("P3DZU").parameter_names(),
            (std::vector<std::string>{"K", "Tw", "Zeta", "Tp3", "Tz", "Td"}));
  EXPECT_EQ(ProcessStructure::parse("P0D").parameter_names(),
            (std::vector<std::string>{"K", "Td"}));
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "no error";
}

TEST(ProcessModel, UnknownNamesAreRefusedSayingWhy) {
  EXPECT_THAT(message_of([] { ProcessStructure::parse("P4"); }),
              HasSubstr("4 poles; a process model has 0 to 3"));
  EXPECT_THAT(message_of([] { ProcessStructure::parse("P1X"); }),
              HasSubstr("'X' is not a process-model letter"));
  EXPECT_THAT(message_of([] { ProcessStructure::parse("P1U"); }),
              HasSubstr("U (an underdamped pair) needs at least 2 poles"));
  EXPECT_THAT(message_of([] { ProcessStructure::parse("P1DD"); }),
              HasSubstr("the letter D is given twice"));
  EXPECT_THAT(message_of([] { ProcessStructure::parse("Q1"); }),
              HasSubstr("a name is P, the number of poles 0 to 3"));
}

TEST(ProcessModel, SettingsTheStructureCannotHoldAreRefused) {
  const ProcessStructure p1d = ProcessStructure::parse("P1D");
  const auto check = [&](ProcessParameterSetting s) {
    ProcessModelOptions o;
    o.parameters = {std::move(s)};
    return message_of([&] { validate_process_model(p1d, o); });
  };
  EXPECT_THAT(check({"Tz", 1.0, true, {}, {}}),
              HasSubstr("parameter 'Tz' is not in process model P1D (its parameters: K, Tp1, Td)"));
  EXPECT_THAT(check({"Tp1", {}, false, {}, -1.0}),
              HasSubstr("the upper bound -1 of Tp1 contradicts the structure: Tp1 is positive"));
  EXPECT_THAT(check({"Td", {}, false, {}, -0.5}),
              HasSubstr("of Td contradicts the structure: the dead time is >= 0"));
  EXPECT_THAT(check({"K", {}, false, 2.0, 1.0}),
              HasSubstr("the bounds of K are empty: lower 2 > upper 1"));
  EXPECT_THAT(check({"K", {}, true, {}, {}}), HasSubstr("'K' is held fixed but has no value"));
  EXPECT_THAT(check({"Tp1", 5.0, false, {}, 3.0}),
              HasSubstr("the value 5 of Tp1 is above its upper bound 3"));
}

TEST(ProcessModel, TooFewSamplesAreRefused) {
  const Eigen::VectorXd u = prbs(25, {});
  const SampledData data(0.1, u, u);
  EXPECT_THAT(message_of([&] { estimate_process_model(data, ProcessStructure::parse("P1D")); }),
              HasSubstr("the record has 25 samples; process model P1D with 3 free parameters "
                        "needs at least 10 per free parameter (30)"));
}

TEST(ProcessModel, AHeldParameterKeepsItsValueAndTheOthersAreRecovered) {
  const ProcessStructure s = ProcessStructure::parse("P2D");
  Eigen::VectorXd truth(4);
  truth << 1.0, 2.0, 0.6, 0.43;
  const SampledData data = noise_free_record(process_transfer_function(s, truth), 0.1);
  ProcessModelOptions o;
  o.parameters = {{"Tp2", 0.6, true, {}, {}}};
  const ProcessModelResult r = estimate_process_model(data, s, o);
  EXPECT_EQ(r.parameter("Tp2"), 0.6);
  EXPECT_EQ(r.standard_error("Tp2"), 0.0);
  EXPECT_EQ(r.fixed_parameters, std::vector<std::string>{"Tp2"});
  EXPECT_NEAR(r.parameter("Tp1"), 2.0, 1e-8);
  EXPECT_NEAR(r.parameter("Td"), 0.43, 1e-8);

  // Held at a wrong value: the held parameter still does not move.
  o.parameters = {{"Tp2", 0.3, true, {}, {}}};
  const ProcessModelResult wrong = estimate_process_model(data, s, o);
  EXPECT_EQ(wrong.parameter("Tp2"), 0.3);
}

TEST(ProcessModel, AnUpperBoundHolds) {
  const ProcessStructure s = ProcessStructure::parse("P1D");
  Eigen::VectorXd truth(3);
  truth << 2.0, 1.5, 0.37;
  const SampledData data = noise_free_record(process_transfer_function(s, truth), 0.1);
  ProcessModelOptions o;
  o.parameters = {{"Tp1", {}, false, {}, 1.0}};
  const ProcessModelResult r = estimate_process_model(data, s, o);
  EXPECT_LE(r.parameter("Tp1"), 1.0);
  EXPECT_NEAR(r.parameter("Tp1"), 1.0, 1e-6);  // the bound is active
}

}  // namespace
}  // namespace ctid::process_model_test
