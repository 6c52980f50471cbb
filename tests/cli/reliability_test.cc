// The bad-input catalogue of issue 16: each case runs ctid on a hostile input and checks the
// exit status (2), the one-line message, that every file that existed before is unchanged
// byte for byte, and that no output (or temporary file) is left behind.
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"

namespace ctid::cli::reliability_test {
namespace {

using testing::expect_bad_input;
using ::testing::HasSubstr;
using testing::slurp;

// A small noise-free record (second-order system, 400 samples at h = 0.05 s), so every case
// runs in well under a second.
class ReliabilityTest : public testing::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    write("g.json", R"({"type": "transfer_function", "numerator_ascending": [4.0],)"
                    R"( "denominator_ascending": [4.0, 0.8, 1.0]})");
    const auto r = ctid({"simulate", "-m", "g.json", "-e", "white", "-n", "400", "-T", "0.05",
                         "--seed", "1", "-o", "d.csv", "-q"});
    ASSERT_EQ(r.status, 0) << r.err;
  }

  // Every file in the test folder (but ctid's captured stdout/stderr) and its bytes.
  std::map<std::string, std::string> snapshot() const {
    std::map<std::string, std::string> files;
    for (const auto& entry : std::filesystem::directory_iterator(path("."))) {
      const std::string name = entry.path().filename().string();
      if (name == ".stdout" || name == ".stderr") continue;
      files[name] = std::filesystem::is_symlink(entry.symlink_status())
                        ? "-> " + std::filesystem::read_symlink(entry.path()).string()
                        : slurp(entry.path());
    }
    return files;
  }

  // Runs a case that must be refused: exit 2, one line holding `fragment`, and the folder
  // exactly as it was (nothing changed, nothing added).
  void expect_refused(const std::vector<std::string>& args, const std::string& fragment) {
    const auto before = snapshot();
    const auto r = ctid(args);
    expect_bad_input(r, args.front(), fragment);
    EXPECT_EQ(snapshot(), before) << "a file was changed or left behind";
  }
};

// Finding 1: deep nesting in every JSON input is refused before it is parsed or copied.
TEST_F(ReliabilityTest, DeeplyNestedJsonModelIsRefused) {
  write("deep.json", std::string(140000, '[') + std::string(140000, ']'));
  expect_refused({"simulate", "-m", "deep.json", "-e", "white", "-n", "10", "-o", "y.csv"},
                 "deep.json:1:257: malformed JSON: arrays and objects nested deeper than 256");
}

TEST_F(ReliabilityTest, DeeplyNestedDescriptionInAValidModelIsRefused) {
  write("deep.json", R"({"type": "transfer_function", "numerator_ascending": [4.0],)"
                     R"( "denominator_ascending": [4.0, 0.8, 1.0], "description": )" +
                         std::string(200000, '[') + std::string(200000, ']') + "}");
  expect_refused({"validate", "deep.json", "d.csv"}, "nested deeper than 256");
}

TEST_F(ReliabilityTest, DeeplyNestedControllerAndStartAreRefused) {
  write("deep.json", std::string(100000, '{'));
  expect_refused({"fit", "d.csv", "--poles", "2", "--zeros", "0", "--initial", "deep.json"},
                 "nested deeper than 256");
  expect_refused(
      {"simulate", "-m", "g.json", "-c", "deep.json", "-e", "white", "-n", "10", "-o", "y.csv"},
      "nested deeper than 256");
}

TEST_F(ReliabilityTest, JsonArrayWhereAnObjectIsExpectedIsRefused) {
  write("array.json", "[1, 2, 3]");
  expect_refused({"validate", "array.json", "d.csv"}, "array.json: expected a JSON object");
}

// Finding 2: outputs through symbolic links and onto devices.
TEST_F(ReliabilityTest, OutputThroughASymlinkWritesItsTargetAndKeepsTheLink) {
  std::filesystem::create_symlink("target.csv", path("link.csv"));
  const auto r = ctid({"simulate", "-m", "g.json", "-e", "white", "-n", "10", "-T", "0.05", "-o",
                       "link.csv", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(std::filesystem::is_symlink(std::filesystem::symlink_status(path("link.csv"))));
  EXPECT_THAT(slurp(path("target.csv")), ::testing::StartsWith("t,u,y\n"));
}

TEST_F(ReliabilityTest, ForcedOutputOntoASymlinkToStdoutDoesNotReplaceTheLink) {
  // /dev/stdout, here redirected to a file by the test: the link stays, the data is appended
  // to what the descriptor names.
  std::filesystem::create_symlink("/dev/stdout", path("out"));
  const auto r = ctid({"simulate", "-m", "g.json", "-e", "white", "-n", "10", "-T", "0.05", "-o",
                       "out", "-q", "--force"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(std::filesystem::is_symlink(std::filesystem::symlink_status(path("out"))));
  EXPECT_THAT(r.out, ::testing::StartsWith("t,u,y\n"));
}

TEST_F(ReliabilityTest, OutputOntoStdoutRedirectedToAFileNeedsNoForce) {
  // The test's runner sends stdout to a file: -o /dev/stdout appends to it as a stream.
  const auto r = ctid({"simulate", "-m", "g.json", "-e", "white", "-n", "10", "-T", "0.05", "-o",
                       "/dev/stdout", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, ::testing::StartsWith("t,u,y\n"));
}

TEST_F(ReliabilityTest, OutputOntoDevNullNeedsNoForce) {
  const auto r = ctid(
      {"simulate", "-m", "g.json", "-e", "white", "-n", "10", "-T", "0.05", "-o", "/dev/null"});
  EXPECT_EQ(r.status, 0) << r.err;
}

TEST_F(ReliabilityTest, ForcedOutputOntoAReadOnlyFileIsRefused) {
  write("ro.csv", "keep\n");
  std::filesystem::permissions(path("ro.csv"), std::filesystem::perms::owner_read);
  expect_refused({"simulate", "-m", "g.json", "-e", "white", "-n", "10", "-T", "0.05", "-o",
                  "ro.csv", "--force"},
                 "ro.csv: file is read-only");
}

// Finding 3: an output that is an input, or two outputs that are one file, even with --force.
TEST_F(ReliabilityTest, SimulateOutputOntoItsInputIsRefused) {
  expect_refused({"simulate", "-m", "g.json", "-i", "d.csv", "-o", "d.csv", "--force"},
                 "--output 'd.csv' is the input file 'd.csv' (--input)");
}

TEST_F(ReliabilityTest, FitOutputOntoItsDataIsRefused) {
  expect_refused({"fit", "d.csv", "--poles", "2", "--zeros", "0", "-o", "d.csv", "--force"},
                 "--output 'd.csv' is the input file 'd.csv' (data)");
}

TEST_F(ReliabilityTest, FitModelOutputOntoItsDataIsRefused) {
  expect_refused(
      {"fit", "d.csv", "--poles", "2", "--zeros", "0", "--model-output", "./d.csv", "--force"},
      "--model-output './d.csv' is the input file 'd.csv' (data)");
}

TEST_F(ReliabilityTest, FitTwoOutputsOntoOneFileAreRefused) {
  expect_refused(
      {"fit", "d.csv", "--poles", "2", "--zeros", "0", "-o", "r.json", "--model-output", "r.json"},
      "--output 'r.json' and --model-output 'r.json' are the same file");
}

TEST_F(ReliabilityTest, FrfOutputOntoItsDataIsRefused) {
  expect_refused({"frf", "d.csv", "-o", "d.csv", "--force"},
                 "--output 'd.csv' is the input file 'd.csv' (data)");
}

TEST_F(ReliabilityTest, ValidateOutputOntoItsModelIsRefused) {
  expect_refused({"validate", "g.json", "d.csv", "-o", "g.json", "--force"},
                 "--output 'g.json' is the input file 'g.json' (model)");
}

TEST_F(ReliabilityTest, OutputThroughALinkToTheInputIsRefused) {
  std::filesystem::create_symlink("d.csv", path("alias.csv"));
  ASSERT_EQ(::link(path("d.csv").c_str(), path("hard.csv").c_str()), 0);
  expect_refused({"frf", "d.csv", "-o", "alias.csv", "--force"},
                 "--output 'alias.csv' is the input file 'd.csv'");
  expect_refused({"frf", "d.csv", "-o", "hard.csv", "--force"},
                 "--output 'hard.csv' is the input file 'd.csv'");
}

TEST_F(ReliabilityTest, ExistingOutputWithoutForceIsRefused) {
  write("f.csv", "keep\n");
  expect_refused({"frf", "d.csv", "-o", "f.csv"},
                 "f.csv: file exists; pass --force to replace it (--output)");
}

// Finding 8: every number ctid frf writes is finite.
TEST_F(ReliabilityTest, FrfOfAZeroOutputIsRefused) {
  std::string text = "t,u,y\n";
  for (int k = 0; k < 400; ++k) {
    text += std::to_string(0.05 * k) + "," + std::to_string(k % 7 - 3) + ",0\n";
  }
  write("zero.csv", text);
  expect_refused({"frf", "zero.csv", "-o", "f.csv"},
                 "zero.csv: output column 'y' is zero at every sample");
}

TEST_F(ReliabilityTest, FrfOfAConstantInputIsRefused) {
  // A constant input leaks into line 1 through the window and looked like a 1-line FRF.
  std::string text = "t,u,y,u2\n";
  for (int k = 0; k < 400; ++k) {
    text += std::to_string(0.05 * k) + ",1," + std::to_string(k % 7 - 3) + "," +
            std::to_string(k % 5) + "\n";
  }
  write("flat.csv", text);
  // One line: no warning about the constant column's mean before the error.
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"frf", "flat.csv", "-o", "f.csv"},
        std::vector<std::string>{"frf", "flat.csv", "--input-columns", "u2,u", "--output-columns",
                                 "y"}}) {
    const auto r = ctid(args);
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_THAT(r.err, HasSubstr("ctid frf: error: flat.csv: input column 'u' is 1 at every "
                                 "sample; an FRF needs an input that varies"));
    EXPECT_EQ(testing::line_count(r.err), 1) << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(path("f.csv")));
}

TEST_F(ReliabilityTest, FrfOfValuesTooLargeForTheSpectraIsRefused) {
  std::string text = "t,u,y\n";
  for (int k = 0; k < 400; ++k) {
    text += std::to_string(0.05 * k) + "," + std::to_string(k % 7 - 3) + "e200," +
            std::to_string(k % 5) + "\n";
  }
  write("big.csv", text);
  expect_refused({"frf", "big.csv", "-o", "f.csv"},
                 "big.csv: column 'u' reaches a magnitude of 3e+200");
}

// Finding 9: messages that used to mislead.
TEST_F(ReliabilityTest, ByteOrderMarkIsNotPartOfTheFirstColumnName) {
  write("bom.csv", "\xEF\xBB\xBF" + slurp(path("d.csv")));
  const auto r = ctid({"frf", "bom.csv", "-q"});
  EXPECT_EQ(r.status, 0) << r.err;
}

TEST_F(ReliabilityTest, CarriageReturnLineEndingsAreRead) {
  std::string text = slurp(path("d.csv"));
  std::replace(text.begin(), text.end(), '\n', '\r');
  write("cr.csv", text);
  const auto r = ctid({"frf", "cr.csv", "-q"});
  EXPECT_EQ(r.status, 0) << r.err;
}

TEST_F(ReliabilityTest, HugeFieldIsCutInTheMessage) {
  write("huge.csv", "t,u,y\n0,1," + std::string(100000, 'x') + "\n");
  const auto before = snapshot();
  const auto r = ctid({"frf", "huge.csv"});
  expect_bad_input(r, "frf", "malformed number 'xxxxxxxx");
  EXPECT_THAT(r.err, HasSubstr("... (100000 bytes)"));
  EXPECT_LT(r.err.size(), 400u);
  EXPECT_EQ(snapshot(), before);
}

TEST_F(ReliabilityTest, ControlBytesAreEscapedInTheMessage) {
  write("binary.csv", std::string("t,u,y\n0,1,\x01\x02\x1b[31m\n", 18));
  const auto r = ctid({"frf", "binary.csv"});
  expect_bad_input(r, "frf", "malformed number '\\x01\\x02\\x1b[31m'");
}

// Finding 7: the fit refuses a structure it could not read back.
TEST_F(ReliabilityTest, FitWithMoreIntegratorsThanAModelHoldsIsRefused) {
  expect_refused(
      {"fit", "d.csv", "--poles", "2", "--zeros", "0", "--integrators", "20", "-o", "r.json"},
      "--integrators is 20; a model document holds at most 16");
  expect_refused({"fit", "d.csv", "--submodel", "2,0,17", "-o", "r.json"},
                 "--submodel '2,0,17': 17 integrators; a model document holds at most 16");
}

// Finding 10: values that used to be changed silently.
TEST_F(ReliabilityTest, NegativeAndOversizedSeedsAreRefused) {
  expect_refused({"simulate", "-m", "g.json", "-e", "white", "-n", "10", "-T", "0.05", "--seed",
                  "-1", "-o", "y.csv"},
                 "'-1' is not a seed: expected a whole number from 0 to 18446744073709551615");
  expect_refused({"simulate", "-m", "g.json", "-e", "white", "-n", "10", "-T", "0.05", "--seed",
                  "18446744073709551616", "-o", "y.csv"},
                 "is not a seed");
  expect_refused({"simulate", "-m", "g.json", "-e", "white", "-n", "10", "-T", "0.05",
                  "--noise-std", "0.1", "--noise-seed", "-3", "-o", "y.csv"},
                 "'-3' is not a seed");
}

TEST_F(ReliabilityTest, ZeroSegmentLengthIsRefused) {
  expect_refused({"frf", "d.csv", "--segment-length", "0", "-o", "f.csv"},
                 "--segment-length is 0; give a positive number of samples");
}

// Finding 10: SIGTERM while the output is being written removes the temporary file and ends
// ctid by the signal; the output never appears half-written.
TEST_F(ReliabilityTest, TerminatedWriteLeavesNoTemporaryFile) {
  const auto temporaries = [&] {
    int found = 0;
    for (const auto& entry : std::filesystem::directory_iterator(path("."))) {
      found += entry.path().filename().string().find(".tmp-") != std::string::npos ? 1 : 0;
    }
    return found;
  };
  const std::string dir = path(".").string();
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    if (::chdir(dir.c_str()) != 0) ::_exit(127);
    ::execl(CTID_CLI_PATH, "ctid", "simulate", "-m", "g.json", "-e", "white", "-n", "400000", "-T",
            "0.05", "-o", "big.csv", "-q", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  bool caught = false;
  int status = 0;
  for (int i = 0; i < 2000000 && !caught; ++i) {
    if (temporaries() > 0) {
      ::kill(child, SIGTERM);
      caught = true;
    } else if (::waitpid(child, &status, WNOHANG) == child) {
      break;
    }
  }
  if (!caught) GTEST_SKIP() << "the write finished before it could be interrupted";
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  if (WIFEXITED(status) || std::filesystem::exists(path("big.csv"))) {
    GTEST_SKIP() << "the write finished before the signal arrived";
  }
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM);
  EXPECT_EQ(temporaries(), 0);
}

}  // namespace
}  // namespace ctid::cli::reliability_test
