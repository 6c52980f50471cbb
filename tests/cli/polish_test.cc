// `ctid fit --polish` (decision 0057): the polish line of the summary and the result
// document's `polish` object, which reads back through validate; an IV fit at a whole-sample
// delay polished to the fractional delay; the refusals of closed loops and several files.
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"
#include "ctid/core/additive_model.h"
#include "ctid/io/json.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"

namespace ctid::cli::polish_test {
namespace {

using testing::expect_bad_input;
using ::testing::HasSubstr;

// t,u,y of 2 (1 + 0.3 p) / (1 + 0.4 p + 0.25 p^2) with an input delay of 3.4 samples,
// noise-free, h = 0.05.
std::string delayed_csv(int n = 1200) {
  const AdditiveModel g({{Polynomial({1.0, 0.4, 0.25}), Polynomial({2.0, 0.6}), 0}}, 0.17);
  const Eigen::VectorXd u = white_noise(n, 1.0, 5);
  return testing::tuy_csv(0.05, u, simulate(g, u, 0.05));
}

class PolishFlag : public testing::CliTest {};

TEST_F(PolishFlag, ReportsThePolishedModelBesideTheIvFit) {
  const std::string data = write("delayed.csv", delayed_csv());
  const auto r = ctid({"fit", data, "--poles", "2", "--zeros", "1", "--input-delay-samples", "3",
                       "--polish", "-o", "fit.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("polish (output error): "));
  EXPECT_THAT(r.out, HasSubstr("; input delay 0.17"));
  const nlohmann::json doc = io::read_json(path("fit.json"));
  ASSERT_TRUE(doc["polish"].is_object());
  EXPECT_EQ(doc["polish"]["criterion"], "output error");
  EXPECT_NEAR(doc["polish"]["parameters"][4].get<double>(), 0.17, 1e-9);
  EXPECT_LE(doc["polish"]["cost"].get<double>(), doc["polish"]["start_cost"].get<double>());
  EXPECT_EQ(doc["polish"]["restarted_from_polish"], false);
  // The result still reads back as the IV fit's.
  const auto v = ctid({"validate", "fit.json", data});
  EXPECT_EQ(v.status, 0) << v.err;
  // Without --polish (and a converged iteration) there is no polish.
  ASSERT_EQ(ctid({"fit", data, "--poles", "2", "--zeros", "1", "--input-delay-samples", "3", "-o",
                  "plain.json", "-q"})
                .status,
            0);
  EXPECT_FALSE(io::read_json(path("plain.json")).contains("polish"));
}

TEST_F(PolishFlag, HeldDelayAndTheRefusals) {
  const std::string data = write("delayed.csv", delayed_csv());
  const auto held = ctid({"fit", data, "--poles", "2", "--zeros", "1", "--input-delay-samples", "3",
                          "--polish", "--no-polish-estimate-delay", "-o", "held.json"});
  ASSERT_EQ(held.status, 0) << held.err;
  EXPECT_EQ(io::read_json(path("held.json"))["polish"]["parameters"].size(), 4u);
  const auto gain = ctid({"fit", data, "--poles", "2", "--zeros", "1", "--input-delay-samples", "3",
                          "--dc-gain", "1.9", "--bound", "theta1.a1=0.395:", "-o", "gain.json"});
  ASSERT_EQ(gain.status, 0) << gain.err;
  EXPECT_THAT(gain.out, HasSubstr("  held: theta1.b0\n"));
  EXPECT_THAT(gain.out, HasSubstr("  at a bound: theta1.a1\n"));
  const nlohmann::json g = io::read_json(path("gain.json"));
  EXPECT_EQ(g["polish"]["parameters"][2].get<double>(), 1.9);
  EXPECT_DOUBLE_EQ(g["polish"]["parameters"][0].get<double>(), 0.395);
  EXPECT_EQ(g["parameters"][2].get<double>(), 1.9);  // the IV fit holds b0 = G(0) too
  // Decision 0058: a bound the IV fit would cross holds its coefficient there, and says so.
  const auto bound = ctid({"fit", data, "--poles", "2", "--zeros", "1", "--input-delay-samples",
                           "3", "--bound", "theta1.b0=:1.5", "-o", "bound.json"});
  ASSERT_EQ(bound.status, 0) << bound.err;
  EXPECT_THAT(bound.out, HasSubstr("constraint acted: theta1.b0 is at its bound 1.5\n"));
  const nlohmann::json b = io::read_json(path("bound.json"));
  EXPECT_EQ(b["parameters"][2].get<double>(), 1.5);
  EXPECT_EQ(b["standard_errors"][2].get<double>(), 0.0);
  EXPECT_EQ(b["verdict"]["active_constraints"][0], "theta1.b0 is at its bound 1.5");
  expect_bad_input(ctid({"fit", data, "--poles", "2", "--zeros", "1", "--fix", "b0=2"}), "fit",
                   "parameter 'b0' is not in the model (its parameters: theta1.a1");
  expect_bad_input(ctid({"fit", data, "--poles", "2", "--zeros", "1", "--bound", "tau"}), "fit",
                   "--bound 'tau': expected NAME=LOWER:UPPER");
  expect_bad_input(ctid({"fit", data, data, "--poles", "2", "--zeros", "1", "--polish"}), "fit",
                   "polish works on one record");
  expect_bad_input(ctid({"fit", data, "--poles", "2", "--zeros", "1", "--polish", "--irregular"}),
                   "fit", "--polish does not go with --irregular");
}

}  // namespace
}  // namespace ctid::cli::polish_test
