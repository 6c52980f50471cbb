// Issue 33: ctid run by a user without the permissions a file needs. CI runs as root, whom no
// permission stops, so each case runs ctid in a child that has dropped to the user nobody
// (65534): an input it may not read, an output folder it may not write into, and an output
// file of another user in a folder it owns (where a rename could replace the file). Each must
// be exit 2 with one line naming the file and saying what is wrong, and leave every file as it
// was. Skipped, saying why, when the test cannot switch users (not root).
#include <fcntl.h>
#include <grp.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"

namespace ctid::cli::permissions_test {
namespace {

using testing::expect_bad_input;
using ::testing::HasSubstr;
using testing::slurp;

constexpr uid_t kNobody = 65534;
constexpr int kCannotSwitch = 125;  // the child's status when setuid failed
constexpr int kCannotReach = 124;   // nobody may not run ctid or enter the test folder

class PermissionsTest : public testing::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    if (::geteuid() != 0) GTEST_SKIP() << "needs root to run ctid as the user nobody (65534)";
    write("g.json", R"({"type": "transfer_function", "numerator_ascending": [4.0],)"
                    R"( "denominator_ascending": [4.0, 0.8, 1.0]})");
    const auto r = ctid({"simulate", "-m", "g.json", "-e", "white", "-n", "400", "-T", "0.05",
                         "--seed", "1", "-o", "d.csv", "-q"});
    ASSERT_EQ(r.status, 0) << r.err;
  }

  // Every file and folder below the test folder (but ctid's captured output): its bytes (or
  // "dir"), owner and mode.
  std::map<std::string, std::string> snapshot() const {
    std::map<std::string, std::string> files;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(path("."))) {
      const std::string name = std::filesystem::relative(entry.path(), path(".")).string();
      if (name == ".stdout" || name == ".stderr") continue;
      struct stat s {};
      ::lstat(entry.path().c_str(), &s);
      files[name] = (entry.is_directory() ? std::string("dir") : slurp(entry.path())) + " uid " +
                    std::to_string(s.st_uid) + " mode " + std::to_string(s.st_mode & 07777);
    }
    return files;
  }

  // Runs ctid as the user nobody in the test folder (fork, setgroups, setgid, setuid, exec).
  testing::RunResult ctid_as_nobody(const std::vector<std::string>& args) const {
    const std::string out_file = path(".stdout").string();
    const std::string err_file = path(".stderr").string();
    const int out = ::open(out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    const int err = ::open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    std::vector<std::string> words{"ctid"};
    words.insert(words.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& word : words) argv.push_back(word.data());
    argv.push_back(nullptr);
    const std::string dir = path(".").string();
    testing::RunResult r;
    const pid_t child = ::fork();
    if (child < 0) return r;
    if (child == 0) {
      if (::setgroups(0, nullptr) != 0 || ::setgid(kNobody) != 0 || ::setuid(kNobody) != 0 ||
          ::getuid() != kNobody) {
        ::_exit(kCannotSwitch);
      }
      // A build below a private folder (/root) is out of nobody's reach: skipped, not failed.
      if (::access(CTID_CLI_PATH, X_OK) != 0 || ::chdir(dir.c_str()) != 0) ::_exit(kCannotReach);
      ::dup2(out, STDOUT_FILENO);
      ::dup2(err, STDERR_FILENO);
      ::execv(CTID_CLI_PATH, argv.data());
      ::_exit(127);
    }
    ::close(out);
    ::close(err);
    int raw = 0;
    ::waitpid(child, &raw, 0);
    r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    r.out = slurp(out_file);
    r.err = slurp(err_file);
    return r;
  }

  // A case that must be refused as nobody: exit 2, one line holding every fragment, and
  // every file, owner and mode as it was.
  void expect_refused(const std::vector<std::string>& args,
                      const std::vector<std::string>& fragments) {
    const auto before = snapshot();
    const auto r = ctid_as_nobody(args);
    if (r.status == kCannotSwitch) GTEST_SKIP() << "cannot switch to the user nobody (65534)";
    if (r.status == kCannotReach) {
      GTEST_SKIP() << "the user nobody may not run " << CTID_CLI_PATH
                   << " or enter the test folder (a build in a private folder)";
    }
    ASSERT_NE(r.status, 127) << "ctid could not be run as nobody: " << r.err;
    for (const std::string& fragment : fragments) expect_bad_input(r, args.front(), fragment);
    EXPECT_EQ(r.out, "");
    EXPECT_EQ(snapshot(), before) << "a file was changed or left behind";
  }

  void make_owned_by_nobody(const std::string& name, mode_t mode) const {
    ASSERT_EQ(::chown(path(name).c_str(), kNobody, kNobody), 0);
    ASSERT_EQ(::chmod(path(name).c_str(), mode), 0);
  }
};

TEST_F(PermissionsTest, AnInputThisUserMayNotReadIsRefused) {
  write("secret.csv", slurp(path("d.csv")));
  ASSERT_EQ(::chmod(path("secret.csv").c_str(), 0600), 0);
  std::filesystem::create_directory(path("mine"));
  make_owned_by_nobody("mine", 0755);
  expect_refused({"fit", "secret.csv", "--modes", "1", "-o", "mine/r.json"},
                 {"secret.csv", "Permission denied"});
}

TEST_F(PermissionsTest, AnOutputFolderThisUserMayNotWriteIsRefused) {
  std::filesystem::create_directory(path("theirs"));
  ASSERT_EQ(::chmod(path("theirs").c_str(), 0755), 0);  // root's, readable by all
  expect_refused(
      {"fit", "d.csv", "--modes", "1", "-o", "theirs/r.json"},
      {"theirs/r.json", "permission denied", "this user may not write into the folder 'theirs'"});
}

TEST_F(PermissionsTest, AnotherUsersFileIsNotReplacedEvenInAFolderThisUserOwns) {
  // nobody owns the folder, so a rename could replace root's file: it must not.
  std::filesystem::create_directory(path("mine"));
  make_owned_by_nobody("mine", 0755);
  write("mine/r.json", "root's result\n");
  ASSERT_EQ(::chmod(path("mine/r.json").c_str(), 0644), 0);
  expect_refused(
      {"fit", "d.csv", "--modes", "1", "-o", "mine/r.json", "--force"},
      {"mine/r.json", "permission denied", "belongs to user 0", "ctid does not replace it"});
  // Its own file in its own folder is replaced as before: the check is about permission.
  std::filesystem::remove(path("mine/r.json"));
  const auto r = ctid_as_nobody({"fit", "d.csv", "--modes", "1", "-o", "mine/r.json", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto again =
      ctid_as_nobody({"fit", "d.csv", "--modes", "1", "-o", "mine/r.json", "--force", "-q"});
  EXPECT_EQ(again.status, 0) << again.err;
  EXPECT_THAT(slurp(path("mine/r.json")), HasSubstr("\"submodels\""));
}

}  // namespace
}  // namespace ctid::cli::permissions_test
