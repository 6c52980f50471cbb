// The output convention of docs/conventions.md ("What ctid prints"): the check itself
// (output_conventions.h) catches each forbidden form; the printed forms of models; the
// summaries of successful runs of every estimating command pass it; a misspelt flag of every
// command names the flag it resembles. (The messages of refused runs are checked in
// catalogue_test.cc.)
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/output_conventions.h"
#include "cli/run_ctid.h"
#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/error.h"
#include "ctid/core/polynomial.h"
#include "ctid/core/transfer_function.h"
#include "support/sanitizers.h"

namespace ctid::cli::conventions_test {
namespace {

using testing::convention_violations;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::Not;
using ::testing::SizeIs;

TEST(OutputConventionCheck, CatchesEachForbiddenForm) {
  EXPECT_THAT(convention_violations("submodel 1: (2) / (p^1 0.000224 p^2 + 1)"), Not(IsEmpty()));
  EXPECT_THAT(convention_violations("(2) / (0.5 p + 1)"), SizeIs(1));
  EXPECT_THAT(convention_violations("(2) / (s^1 (0.5 s + 1))"), SizeIs(1));
  EXPECT_THAT(convention_violations("submodel 0: numerator B is zero"), SizeIs(1));
  EXPECT_THAT(convention_violations("the output 0 is constant"), SizeIs(1));
  EXPECT_THAT(convention_violations("experiment 0 has 2 inputs"), SizeIs(1));
  EXPECT_THAT(convention_violations("h = 0.100000 s"), SizeIs(1));
  EXPECT_THAT(convention_violations("sampled every 0.10000000000000001 s"), SizeIs(1));
  EXPECT_THAT(convention_violations("a delay of 2.500000 s"), SizeIs(1));
}

TEST(OutputConventionCheck, PassesTheConventionsOwnForms) {
  EXPECT_THAT(convention_violations("submodel 1: (2) / (s (0.000224 s^2 + 0.0123 s + 1))\n"
                                    "submodel 2: (1) / s^2\n"),
              IsEmpty());
  EXPECT_THAT(convention_violations("submodel 10: mode 11, output 20, window 1000 of 2.5 s."),
              IsEmpty());
  // The shortest text of 0.1 + 0.2 needs 17 digits; %g forms; a file name; the user's words.
  EXPECT_THAT(convention_violations("0.30000000000000004 1e-10 1.41629 d2.0.csv 3. 92.77 % "
                                    "version 0.1.0, '--delay 0.500000' 'p^2' don't"),
              IsEmpty());
}

TEST(PrintedForms, ModelsPrintInSDescendingWithTheIntegratorFactorApart) {
  const Submodel integrating{Polynomial({1.0, 0.0224, 0.000224}), Polynomial({2.0}), 1};
  EXPECT_EQ(integrating.to_string(), "(2) / (s (0.000224 s^2 + 0.0224 s + 1))");
  const Submodel double_integrator{Polynomial({1.0}), Polynomial({0.5}), 2};
  EXPECT_EQ(double_integrator.to_string(), "(0.5) / s^2");
  const Submodel mode{Polynomial({1.0, 0.25, 0.25}), Polynomial({3.0, -1.0}), 0};
  EXPECT_EQ(mode.to_string(), "(-s + 3) / (0.25 s^2 + 0.25 s + 1)");
  const AdditiveModel model({mode, integrating}, 0.1);
  EXPECT_EQ(model.to_string(),
            "(-s + 3) / (0.25 s^2 + 0.25 s + 1) + (2) / (s (0.000224 s^2 + 0.0224 s + 1)), "
            "input delay 0.1 s");
  // Six significant digits, %g form, for every coefficient and the delay.
  const TransferFunction g(Polynomial({1.0 / 3.0}), Polynomial({1.0, 2.0 / 3.0}), 0.05);
  EXPECT_EQ(g.to_string(), "(0.333333) / (0.666667 s + 1) * exp(-0.05 s)");
  const DiscreteTransferFunction c(Polynomial({-0.5, 1.0}), Polynomial({0.0, 1.0}), 0.1);
  EXPECT_EQ(c.to_string(), "(q - 0.5) / (q), h = 0.1 s");
  for (const std::string& text : {integrating.to_string(), double_integrator.to_string(),
                                  model.to_string(), g.to_string(), c.to_string()}) {
    EXPECT_THAT(convention_violations(text), IsEmpty()) << text;
  }
}

TEST(PrintedForms, MessagesShowNumbersInTheirShortestForm) {
  try {
    require(false, "sampled every ", 0.1, " s, ", 1e-10, ", ", 0.1 + 0.2, ", ", 3, ", ", 2.5f);
    FAIL() << "require did not throw";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()), "sampled every 0.1 s, 1e-10, 0.30000000000000004, 3, 2.5");
  }
  // A model's own message numbers its submodels from 1.
  try {
    AdditiveModel({Submodel{Polynomial({1.0, 0.5}), Polynomial({1.0}), 0},
                   Submodel{Polynomial({2.0, 0.5}), Polynomial({1.0}), 0}});
    FAIL() << "a denominator that is not anti-monic was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("submodel 2: denominator A must be anti-monic"));
    EXPECT_THAT(convention_violations(e.what()), IsEmpty()) << e.what();
  }
}

// 1/(p (1 + 0.5 p)) + 2/(1 + 0.2 p + 0.04 p^2) (Remark 5), sampled every 0.05 s under a PRBS.
const char* kIntegrating = R"({
  "type": "additive_model",
  "submodels": [
    {"denominator_ascending": [1, 0.5], "numerator_ascending": [1], "integrators": 1},
    {"denominator_ascending": [1, 0.2, 0.04], "numerator_ascending": [2]}
  ]
})";

class ConventionsOfRuns : public testing::Section61Test {
 protected:
  // stdout and stderr of a run that must succeed, checked against the convention.
  std::string expect_conventional(const std::vector<std::string>& args) {
    const auto r = ctid(args);
    EXPECT_EQ(r.status, 0) << r.err;
    const std::string printed = r.out + r.err;
    for (const std::string& violation : convention_violations(printed)) {
      ADD_FAILURE() << "ctid " << args.front() << ": " << violation;
    }
    return printed;
  }
};

TEST_F(ConventionsOfRuns, SummariesOfEveryEstimatingCommand) {
  CTID_SKIP_UNDER_SANITIZERS(
      "every command's own CLI tests run its summary path; this runs all of them again");
  // Section 6.1: four second-order modes with their modal table, the paper's two models.
  const std::string fit =
      expect_conventional({"fit", "d.csv", "--modes", "4", "--noise", "white", "-o", "r.json"});
  EXPECT_THAT(fit, HasSubstr("submodel 1: ("));
  EXPECT_THAT(fit, HasSubstr("  submodel 4: w_n = "));
  expect_conventional({"validate", "r.json", "d.csv"});
  expect_conventional({"structure", "d.csv", "--modes", "3:4"});
  expect_conventional({"frf", "d.csv", "-o", "frf.csv"});
  expect_conventional(
      {"fit", "d.csv", "--poles", "2", "--zeros", "1", "--delay-scan-samples", "0:2"});

  // An integrator: its factor is printed apart from A's terms.
  write("i.json", kIntegrating);
  ASSERT_EQ(ctid({"simulate", "-m", "i.json", "-e", "prbs", "-n", "2000", "-T", "0.05", "-o",
                  "i.csv", "-q"})
                .status,
            0);
  const std::string integrating =
      expect_conventional({"fit", "i.csv", "--submodel", "1,0,1", "--submodel", "2,0"});
  EXPECT_THAT(integrating, HasSubstr("submodel 1: (1) / (s (0.5 s + 1))")) << integrating;

  // The closed loop with a delay in its feedback path: F(s), H(s).
  const auto loop = ctid({"simulate", "-m", example("de_iuliis_section4_loop.json"), "-e", "prbs",
                          "-n", "2000", "-T", "0.05", "-o", "loop.csv", "-q"});
  ASSERT_EQ(loop.status, 0) << loop.err;
  const std::string feedback = expect_conventional(
      {"feedback", "loop.csv", "--forward-order", "3", "--feedback-order", "3", "--delay", "0.5"});
  // A coefficient that rounds to 1 is left out of its term, as an exact 1 is.
  EXPECT_THAT(feedback, HasSubstr("F(s) = (2 s^2 + s + 2) / (s^3 + 3 s^2 + 2 s + 3)"));
}

// Every command's help lists its flags; one of them misspelt (two letters swapped) is named
// back in the usage error.
TEST_F(ConventionsOfRuns, EveryCommandSuggestsTheFlagAMisspeltOneResembles) {
  const std::string help = ctid({"--help"}).out;
  const std::size_t list = help.find("Subcommands:");
  ASSERT_NE(list, std::string::npos) << help;
  std::vector<std::string> commands;
  for (std::size_t line = help.find('\n', list); line != std::string::npos;
       line = help.find('\n', line + 1)) {
    const std::size_t begin = help.find_first_not_of(' ', line + 1);
    if (begin == std::string::npos || begin != line + 3) continue;  // "  name   description"
    commands.push_back(help.substr(begin, help.find(' ', begin) - begin));
  }
  ASSERT_GE(commands.size(), 10u) << help;
  for (const std::string& command : commands) {
    const std::string flags = ctid({command, "--help"}).out;
    // The first long flag of at least six letters whose 2nd and 3rd letters differ.
    std::string flag;
    for (std::size_t at = flags.find("--"); at != std::string::npos && flag.empty();
         at = flags.find("--", at + 2)) {
      const std::size_t end = flags.find_first_of(" ,=\n", at);
      const std::string name = flags.substr(at + 2, end - at - 2);
      if (name.size() >= 6 && name != "help" && name[1] != name[2] &&
          name.find_first_not_of("abcdefghijklmnopqrstuvwxyz-") == std::string::npos) {
        flag = name;
      }
    }
    ASSERT_FALSE(flag.empty()) << command << ": no long flag in\n" << flags;
    std::string typo = flag;
    std::swap(typo[1], typo[2]);
    const auto r = ctid({command, "--" + typo, "1"});
    EXPECT_EQ(r.status, 2) << command << " --" << typo << ": " << r.err;
    EXPECT_THAT(r.err, HasSubstr("did you mean --" + flag + "?"))
        << command << " --" << typo << ": " << r.err;
  }
}

}  // namespace
}  // namespace ctid::cli::conventions_test
