// A misspelt flag or command: the one-line usage error (exit 2) names the closest valid flag of
// that command, or the closest command, and names nothing when no name is close.
#include "cli/run_ctid.h"

namespace ctid::cli::did_you_mean_test {
namespace {

using testing::CliTest;
using testing::expect_bad_input;
using ::testing::HasSubstr;
using ::testing::Not;

const char* kFirstOrder = R"({
  "type": "transfer_function",
  "numerator_ascending": [2],
  "denominator_ascending": [1, 0.5]
})";

TEST_F(CliTest, MisspeltFlagNamesTheClosestFlagOfItsCommand) {
  write("d.csv", "t,u,y\n0,1,0\n0.1,1,1\n");
  // Two letters swapped, a letter missing, a letter doubled.
  const auto swapped = ctid({"fit", "d.csv", "--mdoes", "4"});
  expect_bad_input(swapped, "fit", "--mdoes");
  EXPECT_THAT(swapped.err, HasSubstr("; did you mean --modes? (see 'ctid fit --help')"));
  expect_bad_input(ctid({"fit", "d.csv", "--input-colums", "u1,u2"}), "fit",
                   "did you mean --input-columns?");
  expect_bad_input(ctid({"fit", "d.csv", "--poles", "1", "--zeros", "0", "--forrce"}), "fit",
                   "did you mean --force?");
  // With =VALUE attached, and in another command: that command's flags.
  expect_bad_input(ctid({"structure", "d.csv", "--mode=2:4"}), "structure",
                   "did you mean --modes?");
  expect_bad_input(ctid({"simulate", "--noise-sdt", "0.1"}), "simulate",
                   "did you mean --noise-std?");
}

TEST_F(CliTest, FlagFarFromEveryNameGetsNoSuggestion) {
  const auto r = ctid({"simulate", "--bogus"});
  expect_bad_input(r, "simulate", "The following argument was not expected: --bogus");
  EXPECT_THAT(r.err, Not(HasSubstr("did you mean")));
  const auto far = ctid({"fit", "d.csv", "--completely-unrelated-words"});
  expect_bad_input(far, "fit", "--completely-unrelated-words");
  EXPECT_THAT(far.err, Not(HasSubstr("did you mean")));
}

TEST_F(CliTest, MisspeltCommandNamesTheClosestCommand) {
  const auto r = ctid({"fti", "d.csv"});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(testing::line_count(r.err), 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("ctid: error: "));
  EXPECT_THAT(r.err, HasSubstr("did you mean fit? (see 'ctid --help')"));
  EXPECT_THAT(ctid({"simulat"}).err, HasSubstr("did you mean simulate?"));
  EXPECT_THAT(ctid({"frobnicate"}).err, Not(HasSubstr("did you mean")));
}

TEST_F(CliTest, CorrectlySpeltFlagsStillRun) {
  const std::string model = write("g.json", kFirstOrder);
  const auto r =
      ctid({"simulate", "-m", model, "-e", "white", "-n", "50", "-T", "0.1", "-o", "y.csv", "-q"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err, "");
}

}  // namespace
}  // namespace ctid::cli::did_you_mean_test
