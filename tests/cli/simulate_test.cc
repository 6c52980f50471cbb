// `ctid simulate` and the tool's frame (help, version, exit statuses), run as a user would.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"
#include "ctid/estimation/validation.h"
#include "ctid/io/csv.h"
#include "ctid/io/excitation_spec.h"
#include "ctid/io/json.h"
#include "ctid/io/model_json.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/noise.h"
#include "ctid/simulation/simulate.h"
#include "support/paper_systems.h"

namespace ctid::cli::simulate_test {
namespace {

using testing::CliTest;
using ::testing::HasSubstr;
using testing::line_count;
using ::testing::StartsWith;

const char* kFirstOrder = R"({
  "type": "transfer_function",
  "numerator_ascending": [2],
  "denominator_ascending": [1, 0.5]
})";

// A bad-input run: exit status 2 and exactly one line on stderr, starting as `prefix`.
void expect_bad_input(const testing::RunResult& r, const std::string& prefix) {
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_THAT(r.err, StartsWith(prefix));
}

TEST_F(CliTest, VersionAndHelpExitZero) {
  const auto version = ctid({"--version"});
  EXPECT_EQ(version.status, 0);
  EXPECT_EQ(version.out, std::string("ctid ") + CTID_VERSION + "\n");
  const auto help = ctid({"--help"});
  EXPECT_EQ(help.status, 0);
  EXPECT_THAT(help.out, HasSubstr("simulate"));
  EXPECT_THAT(help.out, HasSubstr("Exit status: 0 ran, 2 bad usage or input, 1 other error"));
  EXPECT_THAT(help.out, HasSubstr("3 ran but no usable model (fit)"));
}

TEST_F(CliTest, SimulateHelpExplainsEveryFlag) {
  const auto help = ctid({"simulate", "--help"});
  EXPECT_EQ(help.status, 0);
  for (const char* flag : {"--model",
                           "--output",
                           "--force",
                           "--quiet",
                           "--input",
                           "--input-column",
                           "--time-column",
                           "--excitation",
                           "--excitation-spec",
                           "--samples",
                           "--sample-time",
                           "--seed",
                           "--std",
                           "--amplitude",
                           "--register-length",
                           "--samples-per-bit",
                           "--periods",
                           "--min-frequency-hz",
                           "--max-frequency-hz",
                           "--grid",
                           "--rms",
                           "--controller",
                           "--noise-filter",
                           "--noise-std",
                           "--snr",
                           "--noise-seed"}) {
    EXPECT_THAT(help.out, HasSubstr(std::string(flag) + " ")) << flag;
  }
  EXPECT_THAT(help.out, HasSubstr("ascending powers"));
}

TEST_F(CliTest, UnknownFlagsExitTwoWithOneLine) {
  expect_bad_input(ctid({"simulate", "--bogus"}),
                   "ctid simulate: error: The following argument was not expected: --bogus");
  expect_bad_input(ctid({"--bogus"}), "ctid: error: The following argument was not expected");
  expect_bad_input(ctid({"frobnicate"}), "ctid: error:");
  expect_bad_input(ctid({}), "ctid: error: A subcommand is required");
}

TEST_F(CliTest, MissingRequiredFlagsAndInputs) {
  expect_bad_input(ctid({"simulate", "--output", "y.csv"}),
                   "ctid simulate: error: --model is required");
  const std::string model = write("g.json", kFirstOrder);
  expect_bad_input(ctid({"simulate", "-m", model, "-o", "y.csv"}),
                   "ctid simulate: error: give one input");
  expect_bad_input(ctid({"simulate", "-m", model, "-o", "y.csv", "-e", "white", "-n", "10"}),
                   "ctid simulate: error: --excitation needs --sample-time");
  expect_bad_input(ctid({"simulate", "-m", "absent.json", "-o", "y.csv"}),
                   "ctid simulate: error: --model: File does not exist");
}

TEST_F(CliTest, MalformedJsonNamesFileAndLine) {
  const std::string model = write("bad.json", R"({
  "type": "transfer_function",
  "numerator_ascending": [NaN],
  "denominator_ascending": [1, 0.5]
})");
  const auto r = ctid({"simulate", "-m", model, "-o", "y.csv", "-e", "white", "-T", "0.1"});
  expect_bad_input(r, "ctid simulate: error: " + model + ":3:");
  EXPECT_THAT(r.err, HasSubstr("malformed JSON"));
  EXPECT_FALSE(std::filesystem::exists(path("y.csv")));
}

TEST_F(CliTest, NonFiniteAndZeroLeadingCoefficientsAreRejected) {
  const std::string huge = write("huge.json", R"({"type": "transfer_function",
      "numerator_ascending": [1e400], "denominator_ascending": [1, 0.5]})");
  expect_bad_input(ctid({"simulate", "-m", huge, "-o", "y.csv", "-e", "white", "-T", "0.1"}),
                   "ctid simulate: error: " + huge + ":2:");
  const std::string lead = write("lead.json", R"({"type": "transfer_function",
      "numerator_ascending": [1], "denominator_ascending": [1, 0.5, 0]})");
  const auto r = ctid({"simulate", "-m", lead, "-o", "y.csv", "-e", "white", "-T", "0.1"});
  expect_bad_input(r, "ctid simulate: error: " + lead + ": denominator_ascending: ");
  EXPECT_THAT(r.err, HasSubstr("leading coefficient"));
}

TEST_F(CliTest, NonPositiveSampleTimesAreRejected) {
  const std::string model = write("g.json", kFirstOrder);
  expect_bad_input(ctid({"simulate", "-m", model, "-o", "y.csv", "-e", "white", "-T", "0"}),
                   "ctid simulate: error: --sample-time");
  expect_bad_input(ctid({"simulate", "-m", model, "-o", "y.csv", "-e", "white", "-T", "-0.1"}),
                   "ctid simulate: error: --sample-time");
  const std::string controller = write("c.json", R"({"type": "discrete_transfer_function",
      "numerator_ascending": [0.5], "denominator_ascending": [-1, 1], "sample_time": -0.05})");
  expect_bad_input(ctid({"simulate", "-m", model, "-o", "y.csv", "-e", "white", "-c", controller}),
                   "ctid simulate: error: " + controller + ": discrete transfer function: ");
}

TEST_F(CliTest, MalformedCsvNamesFileLineAndColumn) {
  const std::string model = write("g.json", kFirstOrder);
  const std::string csv = write("in.csv", "t,u\n0,1\n0.1,2\n0.2,x3\n");
  expect_bad_input(
      ctid({"simulate", "-m", model, "-o", "y.csv", "-i", csv}),
      "ctid simulate: error: " + csv + ":4: column 'u' (field 2): malformed number 'x3'");
  const std::string nan = write("nan.csv", "t,u\n0,1\n0.1,nan\n");
  expect_bad_input(
      ctid({"simulate", "-m", model, "-o", "y.csv", "-i", nan}),
      "ctid simulate: error: " + nan + ":3: column 'u' (field 2): value 'nan' is not finite");
}

TEST_F(CliTest, MismatchedLengthsAreRejected) {
  const std::string model = write("g.json", kFirstOrder);
  const std::string csv = write("in.csv", "t,u\n0,1\n0.1\n");
  expect_bad_input(ctid({"simulate", "-m", model, "-o", "y.csv", "-i", csv}),
                   "ctid simulate: error: " + csv + ":3: expected 2 fields (t, u) but found 1");
  expect_bad_input(ctid({"simulate", "-m", model, "-o", "y.csv", "-e", "multisine", "-n", "100",
                         "--periods", "3", "-T", "0.1"}),
                   "ctid simulate: error: ExcitationSpec.samples is 100; it must be a multiple");
  const std::string controller = write("c.json", R"({"type": "discrete_transfer_function",
      "numerator_ascending": [0.5], "denominator_ascending": [-1, 1], "sample_time": 0.05})");
  expect_bad_input(
      ctid({"simulate", "-m", model, "-o", "y.csv", "-e", "white", "-T", "0.1", "-c", controller}),
      "ctid simulate: error: the controller in " + controller + " has sample time 0.05");
}

TEST_F(CliTest, NonUniformTimeStampsAreRejected) {
  const std::string model = write("g.json", kFirstOrder);
  const std::string csv = write("in.csv", "t,u\n0,1\n0.1,2\n0.25,3\n0.3,4\n");
  const auto r = ctid({"simulate", "-m", model, "-o", "y.csv", "-i", csv});
  expect_bad_input(r, "ctid simulate: error: " + csv + ": column 't': time stamps are not uniform");
}

TEST_F(CliTest, NeverOverwritesWithoutForce) {
  const std::string model = write("g.json", kFirstOrder);
  write("y.csv", "precious\n");
  const std::vector<std::string> args = {"simulate", "-m", model, "-o", "y.csv", "-e",
                                         "white",    "-n", "20",  "-T", "0.1"};
  expect_bad_input(ctid(args), "ctid simulate: error: y.csv: file exists; pass --force");
  EXPECT_EQ(testing::slurp(path("y.csv")), "precious\n");
  auto forced = args;
  forced.push_back("--force");
  EXPECT_EQ(ctid(forced).status, 0);
  EXPECT_EQ(io::read_csv(path("y.csv")).rows(), 20);
}

TEST_F(CliTest, OpenLoopOutputEqualsTheLibrarysSimulation) {
  const std::string model = example("gonzalez_6_1_open_loop.json");
  const auto r = ctid({"simulate", "-m", model, "-o", "y.csv", "-e", "multisine", "-n", "2000",
                       "--periods", "2", "-T", "0.05", "--max-frequency-hz", "3", "--seed", "5"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("wrote 2000 samples"));
  const io::CsvTable table = io::read_csv(path("y.csv"));
  ASSERT_EQ(table.names, (std::vector<std::string>{"t", "u", "y"}));

  MultisineOptions options;
  options.period_length = 1000;
  options.periods = 2;
  options.sample_time = 0.05;
  options.max_frequency = 3.0;
  options.seed = 5;
  const Eigen::VectorXd u = multisine(options).signal;
  const auto g = std::get<AdditiveModel>(io::read_continuous_model(model));
  EXPECT_EQ(table.column("u"), u);
  EXPECT_EQ(table.column("y"), simulate(g, u, 0.05));
  EXPECT_DOUBLE_EQ(table.column("t")(1999), 1999 * 0.05);
}

TEST_F(CliTest, FirstOrderHoldInputIsDeclaredAndSimulatedExactly) {
  // --hold foh: the input is linear between samples, the output is the exact response to it
  // (checked against the same piecewise-linear input sampled 20 times finer), and the CSV
  // declares it for `ctid fit`.
  const std::string model = example("gonzalez_6_2_plant.json");
  const auto r = ctid({"simulate", "-m", model, "-o", "y.csv", "-e", "multisine", "-n", "1000",
                       "-T", "0.05", "--max-frequency-hz", "3", "--seed", "5", "--hold", "foh"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("input foh"));
  EXPECT_THAT(testing::slurp(path("y.csv")), ::testing::StartsWith("# input_hold: foh\n"));
  const io::CsvTable table = io::read_csv(path("y.csv"));
  const auto g = std::get<AdditiveModel>(io::read_continuous_model(model));
  const Eigen::VectorXd u = table.column("u");
  const int fine = 20;
  Eigen::VectorXd dense(u.size() * fine);
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    const double next = k + 1 < u.size() ? u(k + 1) : u(k);
    for (int j = 0; j < fine; ++j) {
      dense(k * fine + j) = u(k) + (next - u(k)) * j / static_cast<double>(fine);
    }
  }
  const Eigen::VectorXd y_fine = model_output(g, dense, 0.05 / fine, Hold::first_order_hold);
  Eigen::VectorXd y_ref(u.size());
  for (Eigen::Index k = 0; k < u.size(); ++k) y_ref(k) = y_fine(k * fine);
  EXPECT_LT((table.column("y") - y_ref).cwiseAbs().maxCoeff(), 1e-10);
  // And the ZOH simulation differs by far more.
  EXPECT_GT((simulate(g, u, 0.05) - y_ref).cwiseAbs().maxCoeff(), 1e-3);
  // ctid fit reads the declaration and recovers the model exactly.
  const auto fit = ctid({"fit", "y.csv", "--modes", "2", "-o", "r.json", "-q"});
  ASSERT_EQ(fit.status, 0) << fit.err;
  const Eigen::VectorXd theta =
      (Eigen::VectorXd(6) << 0.25, 0.25, 3.0, 0.01, 0.025, 1.0).finished();
  const nlohmann::json j = io::read_json(path("r.json"));
  Eigen::VectorXd got(6);
  for (int k = 0; k < 6; ++k) got(k) = j.at("parameters")[static_cast<std::size_t>(k)];
  EXPECT_LT((got - theta).norm() / theta.norm(), 1e-8);
}

TEST_F(CliTest, InputColumnWithTimeColumnGivesTheSampleTime) {
  const std::string model = write("g.json", kFirstOrder);
  const std::string csv = write("in.csv", "time,x\n1.0,1\n1.5,-1\n2.0,2\n2.5,0\n");
  const auto r = ctid({"simulate", "-m", model, "-o", "y.csv", "-i", csv, "--input-column", "x",
                       "--time-column", "time"});
  ASSERT_EQ(r.status, 0) << r.err;
  const io::CsvTable table = io::read_csv(path("y.csv"));
  const Eigen::Vector4d u(1, -1, 2, 0);
  EXPECT_EQ(table.column("u"), Eigen::VectorXd(u));
  EXPECT_EQ(table.column("y"), simulate(TransferFunction(Polynomial{2.0}, Polynomial{1.0, 0.5}),
                                        Eigen::VectorXd(u), 0.5));
  EXPECT_EQ(table.column("t")(0), 1.0);
  expect_bad_input(ctid({"simulate", "-m", model, "-o", "z.csv", "-i", csv, "--input-column", "x",
                         "--time-column", "time", "-T", "0.1"}),
                   "ctid simulate: error: --sample-time 0.1 disagrees");
}

// The shipped models of González et al. are the tests' fixtures, to the 17 digits of JSON.
TEST_F(CliTest, ShippedPaperModelsAreTheTestFixtures) {
  const auto expect_same_model = [](const AdditiveModel& read, const AdditiveModel& fixture) {
    ASSERT_EQ(read.size(), fixture.size());
    for (int i = 0; i < read.size(); ++i) {
      EXPECT_TRUE(read[i].a.coefficients().isApprox(fixture[i].a.coefficients(), 1e-15)) << i;
      EXPECT_TRUE(read[i].b.coefficients().isApprox(fixture[i].b.coefficients(), 1e-15)) << i;
      EXPECT_EQ(read[i].integrators, fixture[i].integrators) << i;
    }
    EXPECT_EQ(read.input_delay(), fixture.input_delay());
  };
  const auto expect_same_filter = [](const DiscreteTransferFunction& read,
                                     const DiscreteTransferFunction& fixture) {
    EXPECT_TRUE(
        read.numerator().coefficients().isApprox(fixture.numerator().coefficients(), 1e-15));
    EXPECT_TRUE(
        read.denominator().coefficients().isApprox(fixture.denominator().coefficients(), 1e-15));
    EXPECT_EQ(read.sample_time(), fixture.sample_time());
  };
  expect_same_model(
      std::get<AdditiveModel>(io::read_continuous_model(example("gonzalez_6_1_open_loop.json"))),
      ctid::testing::open_loop_four_modes());
  expect_same_filter(io::read_discrete_transfer_function(example("gonzalez_6_1_noise_filter.json")),
                     ctid::testing::open_loop_noise_filter());
  expect_same_model(
      std::get<AdditiveModel>(io::read_continuous_model(example("gonzalez_6_2_plant.json"))),
      ctid::testing::closed_loop_two_modes());
  expect_same_filter(io::read_discrete_transfer_function(example("gonzalez_6_2_pid.json")),
                     ctid::testing::closed_loop_pid());
}

TEST_F(CliTest, ClosedLoopWithColouredNoiseEqualsTheLibrarysSimulation) {
  const std::string plant = example("gonzalez_6_2_plant.json");
  const std::string pid = example("gonzalez_6_2_pid.json");
  const std::string filter = example("gonzalez_6_1_noise_filter.json");
  const auto r =
      ctid({"simulate", "-m", plant, "-c", pid, "-o", "y.csv", "-e", "white", "-n", "500", "--seed",
            "3", "--noise-filter", filter, "--noise-std", "0.1", "--noise-seed", "4"});
  ASSERT_EQ(r.status, 0) << r.err;
  const io::CsvTable table = io::read_csv(path("y.csv"));
  ASSERT_EQ(table.names, (std::vector<std::string>{"t", "u", "y", "r"}));

  const Eigen::VectorXd ref = white_noise(500, 1.0, 3);
  const DiscreteTransferFunction c = io::read_discrete_transfer_function(pid);
  const Eigen::VectorXd v =
      colored_noise(io::read_discrete_transfer_function(filter), 500, 0.01, 4);
  const auto g = std::get<AdditiveModel>(io::read_continuous_model(plant));
  const ClosedLoopSimulation loop = simulate_closed_loop(g, c, ref, v);
  EXPECT_EQ(table.column("r"), ref);
  EXPECT_EQ(table.column("u"), loop.input);
  EXPECT_EQ(table.column("y"), loop.output);
  EXPECT_DOUBLE_EQ(table.column("t")(1), 0.05);  // the controller's sample time
}

TEST_F(CliTest, SnrScalesTheNoiseAgainstTheNoiseFreeOutput) {
  const std::string model = write("g.json", kFirstOrder);
  const auto r = ctid({"simulate", "-m", model, "-o", "y.csv", "-e", "prbs", "-n", "1023", "-T",
                       "0.1", "--snr", "10", "--noise-seed", "8"});
  ASSERT_EQ(r.status, 0) << r.err;
  const io::CsvTable table = io::read_csv(path("y.csv"));
  const Eigen::VectorXd y0 =
      simulate(TransferFunction(Polynomial{2.0}, Polynomial{1.0, 0.5}), table.column("u"), 0.1);
  EXPECT_NEAR(snr_db(y0, table.column("y") - y0), 10.0, 1e-9);
}

TEST_F(CliTest, ExcitationSpecFileEqualsTheFlags) {
  const std::string model = write("g.json", kFirstOrder);
  const std::string spec = example("multisine_0.01_3hz.json");
  ASSERT_EQ(ctid({"simulate", "-m", model, "-o", "a.csv", "--excitation-spec", spec}).status, 0);
  const auto flags = ctid({"simulate", "-m", model, "-o", "b.csv", "-e", "multisine", "-n", "8192",
                           "-T", "0.05", "--seed", "1", "--periods", "4", "--min-frequency-hz",
                           "0.01", "--max-frequency-hz", "3"});
  ASSERT_EQ(flags.status, 0) << flags.err;
  EXPECT_EQ(testing::slurp(path("a.csv")), testing::slurp(path("b.csv")));
  expect_bad_input(
      ctid({"simulate", "-m", model, "-o", "c.csv", "--excitation-spec", spec, "-e", "white"}),
      "ctid simulate: error: --excitation excludes --excitation-spec");
}

TEST_F(CliTest, FlagsThatWouldHaveNoEffectAreRejected) {
  const std::string model = write("g.json", kFirstOrder);
  const std::vector<std::string> base = {"simulate", "-m", model, "-o", "y.csv", "-T", "0.1"};
  const auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = base;
    args.insert(args.end(), extra.begin(), extra.end());
    return ctid(args);
  };
  expect_bad_input(with({"-e", "white", "--rms", "2"}),
                   "ctid simulate: error: --rms applies to --excitation multisine only, not white");
  expect_bad_input(with({"-e", "prbs", "--std", "2"}),
                   "ctid simulate: error: --std applies to --excitation white only, not prbs");
  const std::string csv = write("in.csv", "u\n1\n2\n");
  expect_bad_input(with({"-i", csv, "--seed", "3"}),
                   "ctid simulate: error: --seed has no effect with --input");
  expect_bad_input(with({"--excitation-spec", example("multisine_0.01_3hz.json"), "-n", "10"}),
                   "ctid simulate: error: --samples has no effect with --excitation-spec");
  expect_bad_input(
      with({"-e", "white", "--noise-seed", "3"}),
      "ctid simulate: error: --noise-seed needs a noise level: --noise-std or --snr (or "
      "--nsr for a loop)");
  EXPECT_FALSE(std::filesystem::exists(path("y.csv")));
}

}  // namespace
}  // namespace ctid::cli::simulate_test
