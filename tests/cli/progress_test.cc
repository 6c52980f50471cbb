// The progress line of long runs: shown on a terminal (a pseudo-terminal here), never in a pipe
// or file and never with -q. CTID_PROGRESS_AFTER=0 shows it from the start, so the runs are
// short and the checks do not depend on how long anything takes.
#include <fcntl.h>
#include <pty.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cli/run_ctid.h"
#include "ctid/core/mimo_data.h"
#include "ctid/io/mimo_data_csv.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"
#include "support/mimo_systems.h"

namespace ctid::cli::progress_test {
namespace {

using testing::CliTest;
using ::testing::HasSubstr;
using ::testing::Not;
using testing::RunResult;

const char* kFirstOrder = R"({
  "type": "transfer_function",
  "numerator_ascending": [2],
  "denominator_ascending": [1, 0.5]
})";

// Sets an environment variable for the scope (the ctid runs inherit it).
class ScopedEnvironment {
 public:
  ScopedEnvironment(const char* name, const char* value) : name_(name) { ::setenv(name, value, 1); }
  ~ScopedEnvironment() { ::unsetenv(name_); }
  ScopedEnvironment(const ScopedEnvironment&) = delete;
  ScopedEnvironment& operator=(const ScopedEnvironment&) = delete;

 private:
  const char* name_;
};

class CliProgressTest : public CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    write("g.json", kFirstOrder);
    const auto r = ctid({"simulate", "-m", "g.json", "-e", "prbs", "-n", "400", "-T", "0.1",
                         "--noise-std", "0.01", "-o", "d.csv", "-q"});
    ASSERT_EQ(r.status, 0) << r.err;
  }

  /// Runs `ctid args...` in the test directory with stdin, stdout and stderr on a
  /// pseudo-terminal; out holds everything the terminal received.
  RunResult ctid_on_terminal(const std::vector<std::string>& args) const {
    std::vector<std::string> words{CTID_CLI_PATH};
    words.insert(words.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& word : words) argv.push_back(word.data());
    argv.push_back(nullptr);
    const std::string directory = path("").string();

    int terminal = -1;
    const pid_t child = ::forkpty(&terminal, nullptr, nullptr, nullptr);
    RunResult r;
    if (child < 0) {
      ADD_FAILURE() << "forkpty failed: errno " << errno;
      return r;
    }
    if (child == 0) {
      if (::chdir(directory.c_str()) != 0) ::_exit(126);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    char buffer[4096];
    while (true) {
      const ssize_t got = ::read(terminal, buffer, sizeof buffer);
      if (got > 0) {
        r.out.append(buffer, static_cast<std::size_t>(got));
      } else if (got < 0 && errno == EINTR) {
        continue;
      } else {
        break;  // EIO once the child has closed the terminal
      }
    }
    ::close(terminal);
    int raw = 0;
    ::waitpid(child, &raw, 0);
    r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    return r;
  }
};

TEST_F(CliProgressTest, DelayScanShowsProgressOnATerminalOnly) {
  const ScopedEnvironment now("CTID_PROGRESS_AFTER", "0");
  const std::vector<std::string> fit{
      "fit", "d.csv", "--poles", "1", "--zeros", "0", "--delay-scan-samples", "0:5"};
  const auto terminal = ctid_on_terminal(fit);
  EXPECT_EQ(terminal.status, 0) << terminal.out;
  EXPECT_THAT(terminal.out, HasSubstr("\rctid fit: delay scan 1/6 (16 %)"));
  // The last step is always drawn, and the line is blanked before the summary.
  const auto last = terminal.out.find("ctid fit: delay scan 6/6 (100 %)");
  ASSERT_NE(last, std::string::npos) << terminal.out;
  const auto blanked = terminal.out.find("\r     ", last);
  const auto summary = terminal.out.find("ctid fit: srivc on d.csv");
  ASSERT_NE(blanked, std::string::npos) << terminal.out;
  EXPECT_LT(blanked, summary) << terminal.out;

  // stderr to a file: no progress, no carriage return.
  const auto piped = ctid(fit);
  EXPECT_EQ(piped.status, 0) << piped.err;
  EXPECT_THAT(piped.err, Not(HasSubstr("delay scan")));
  EXPECT_THAT(piped.err, Not(HasSubstr("\r")));

  // -q on a terminal: nothing at all.
  std::vector<std::string> quiet = fit;
  quiet.emplace_back("-q");
  const auto silent = ctid_on_terminal(quiet);
  EXPECT_EQ(silent.status, 0) << silent.out;
  EXPECT_EQ(silent.out, "");
}

TEST_F(CliProgressTest, ProgressWaitsForTheThreshold) {
  // An hour: no run of this test reaches it.
  const ScopedEnvironment later("CTID_PROGRESS_AFTER", "3600");
  const auto r = ctid_on_terminal(
      {"fit", "d.csv", "--poles", "1", "--zeros", "0", "--delay-scan-samples", "0:5"});
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_THAT(r.out, Not(HasSubstr("delay scan 1/6")));
  EXPECT_THAT(r.out, HasSubstr("ctid fit: srivc on d.csv"));
}

TEST_F(CliProgressTest, StructureScanShowsProgressOnATerminal) {
  const ScopedEnvironment now("CTID_PROGRESS_AFTER", "0");
  const auto r = ctid_on_terminal({"structure", "d.csv", "--poles", "1:2"});
  EXPECT_THAT(r.out, HasSubstr("ctid structure: structure 2/2 (100 %)"));
  const auto piped = ctid({"structure", "d.csv", "--poles", "1:2"});
  EXPECT_THAT(piped.err, Not(HasSubstr("ctid structure: structure")));
}

// Several outputs: mimo_srivc's iterations as the line ("iteration 1/40"), of at most
// --max-iterations; blanked before the summary; nothing in a pipe. Then fit-frf on the
// record's FRF matrix: its steps.
TEST_F(CliProgressTest, MimoFitShowsItsIterationsOnATerminalOnly) {
  const MimoAdditiveModel g = ctid::testing::two_mode_structure();
  constexpr double kStep = 0.05;
  Eigen::MatrixXd u(1000, 2);
  for (int k = 0; k < 2; ++k) u.col(k) = white_noise(1000, 1.0, 11 + k);
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(1000, 3);
  for (int j = 0; j < 3; ++j) {
    for (int k = 0; k < 2; ++k) y.col(j) += simulate(g.channel(j, k), u.col(k), kStep);
  }
  io::write_mimo_data(path("m.csv"),
                      MimoData(kStep, u, y).with_names({"f1", "f2"}, {"a1", "a2", "a3"}));
  const ScopedEnvironment now("CTID_PROGRESS_AFTER", "0");
  const std::vector<std::string> fit{
      "fit",     "m.csv", "--input-columns",  "f1,f2", "--output-columns", "a1:a3",
      "--modes", "2",     "--max-iterations", "40"};
  const auto terminal = ctid_on_terminal(fit);
  EXPECT_EQ(terminal.status, 0) << terminal.out;
  const auto first = terminal.out.find("\rctid fit: mimo_srivc iteration 1/40 (2 %)");
  ASSERT_NE(first, std::string::npos) << terminal.out;
  const auto summary = terminal.out.find("mimo_srivc: converged");
  ASSERT_NE(summary, std::string::npos) << terminal.out;
  const auto blanked = terminal.out.rfind("\r     ", summary);
  ASSERT_NE(blanked, std::string::npos) << terminal.out;
  EXPECT_LT(first, blanked) << terminal.out;

  const auto piped = ctid(fit);
  EXPECT_EQ(piped.status, 0) << piped.err;
  EXPECT_THAT(piped.out, HasSubstr("mimo_srivc: converged"));
  EXPECT_THAT(piped.err, Not(HasSubstr("iteration")));
  EXPECT_THAT(piped.err, Not(HasSubstr("\r")));

  // Its FRF matrix fitted by fit-frf: the vector-fitting relocations and the iterations.
  const auto frf = ctid({"frf", "m.csv", "--input-columns", "f1,f2", "--output-columns", "a1:a3",
                         "-o", "h.csv", "-q"});
  ASSERT_EQ(frf.status, 0) << frf.err;
  const std::vector<std::string> fit_frf{"fit-frf", "h.csv", "--modes", "2"};
  const auto frf_terminal = ctid_on_terminal(fit_frf);
  // Ran (0), or ran and judged the modes of this short record's coarse FRF unusable (3).
  EXPECT_TRUE(frf_terminal.status == 0 || frf_terminal.status == 3) << frf_terminal.out;
  EXPECT_THAT(frf_terminal.out, HasSubstr("\rctid fit-frf: step 1/"));
  const auto frf_piped = ctid(fit_frf);
  EXPECT_EQ(frf_piped.status, frf_terminal.status) << frf_piped.err;
  EXPECT_THAT(frf_piped.err, Not(HasSubstr("step")));
}

TEST_F(CliProgressTest, StudyCountsItsCasesOnATerminal) {
  const ScopedEnvironment now("CTID_PROGRESS_AFTER", "0");
  // 2 sizes x 2 runs x 1 estimator of Section 6.2.
  const std::vector<std::string> study{
      "study",         "closed-loop", "-o",           "s",     "--runs",   "2", "--sizes", "2",
      "--max-samples", "700",         "--estimators", "srivc", "--no-plot"};
  const auto r = ctid_on_terminal(study);
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("ctid study: case 4/4 (100 %)"));
  std::vector<std::string> again = study;
  again[3] = "s2";
  const auto piped = ctid(again);
  EXPECT_EQ(piped.status, 0) << piped.err;
  EXPECT_THAT(piped.err, Not(HasSubstr("ctid study: case")));
}

TEST_F(CliProgressTest, TrackCountsItsWindowsOnATerminal) {
  const ScopedEnvironment now("CTID_PROGRESS_AFTER", "0");
  // d.csv holds 40 s: four windows of 10 s.
  const auto r =
      ctid_on_terminal({"track", "d.csv", "--window", "10", "--poles", "1", "--zeros", "0"});
  EXPECT_THAT(r.out, HasSubstr("ctid track: window 4/4 (100 %)")) << r.out;
  const auto piped = ctid({"track", "d.csv", "--window", "10", "--poles", "1", "--zeros", "0"});
  EXPECT_THAT(piped.err, Not(HasSubstr("ctid track: window")));
}

}  // namespace
}  // namespace ctid::cli::progress_test
