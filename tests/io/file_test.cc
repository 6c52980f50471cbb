// write_text_file must never replace what a user had: an existing device, pipe or socket
// given as output (/dev/null, /dev/stdout, a FIFO) is written into, not renamed over.
#include "ctid/io/file.h"

#include <array>
#include <filesystem>
#include <string>

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "io/test_directory.h"

namespace ctid::io::file_test {
namespace {

TEST(WriteTextFile, WritesIntoAnExistingPipeInsteadOfReplacingIt) {
  const testing::TestDirectory dir;
  const std::filesystem::path fifo = dir / "pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // A non-blocking reader lets the writer open the pipe without a second thread.
  const int reader = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(reader, 0);
  write_text_file(fifo, "t,u,y\n0,1,2\n", Overwrite::no);
  std::array<char, 64> buffer{};
  const ssize_t got = ::read(reader, buffer.data(), buffer.size());
  ::close(reader);
  EXPECT_EQ(std::string(buffer.data(), got > 0 ? static_cast<size_t>(got) : 0u), "t,u,y\n0,1,2\n");
  EXPECT_TRUE(std::filesystem::is_fifo(fifo)) << "the pipe was replaced by a regular file";
}

TEST(WriteTextFile, RegularFilesStillNeedOverwrite) {
  const testing::TestDirectory dir;
  write_text_file(dir / "a.csv", "1\n", Overwrite::no);
  EXPECT_THROW(write_text_file(dir / "a.csv", "2\n", Overwrite::no), InvalidArgument);
  EXPECT_EQ(read_text_file(dir / "a.csv"), "1\n");
  write_text_file(dir / "a.csv", "2\n", Overwrite::yes);
  EXPECT_EQ(read_text_file(dir / "a.csv"), "2\n");
}

TEST(WriteTextFile, ASymlinkIsWrittenThroughAndKept) {
  const testing::TestDirectory dir;
  write_text_file(dir / "target.csv", "old\n", Overwrite::no);
  std::filesystem::create_symlink("target.csv", dir / "link.csv");
  EXPECT_THROW(write_text_file(dir / "link.csv", "new\n", Overwrite::no), InvalidArgument);
  write_text_file(dir / "link.csv", "new\n", Overwrite::yes);
  EXPECT_TRUE(std::filesystem::is_symlink(std::filesystem::symlink_status(dir / "link.csv")));
  EXPECT_EQ(read_text_file(dir / "target.csv"), "new\n");
  // A dangling link creates its target.
  std::filesystem::create_symlink("fresh.csv", dir / "dangling.csv");
  write_text_file(dir / "dangling.csv", "x\n", Overwrite::no);
  EXPECT_TRUE(std::filesystem::is_symlink(std::filesystem::symlink_status(dir / "dangling.csv")));
  EXPECT_EQ(read_text_file(dir / "fresh.csv"), "x\n");
}

TEST(WriteTextFile, ADescriptorLinkThroughProcIsAppendedToNotReplaced) {
  // /dev/stdout redirected to a file is /proc/self/fd/1 -> that file.
  const testing::TestDirectory dir;
  write_text_file(dir / "shell.txt", "before\n", Overwrite::no);
  const int fd = ::open((dir / "shell.txt").c_str(), O_WRONLY | O_APPEND);
  ASSERT_GE(fd, 0);
  std::filesystem::create_symlink("/proc/self/fd/" + std::to_string(fd), dir / "stdout");
  write_text_file(dir / "stdout", "data\n", Overwrite::yes);
  ::close(fd);
  EXPECT_TRUE(std::filesystem::is_symlink(std::filesystem::symlink_status(dir / "stdout")));
  EXPECT_EQ(read_text_file(dir / "shell.txt"), "before\ndata\n");
}

TEST(WriteTextFile, AReadOnlyFileIsNotReplacedAndAReplacedFileKeepsItsMode) {
  const testing::TestDirectory dir;
  write_text_file(dir / "ro.csv", "keep\n", Overwrite::no);
  std::filesystem::permissions(dir / "ro.csv", std::filesystem::perms::owner_read);
  EXPECT_THROW(write_text_file(dir / "ro.csv", "new\n", Overwrite::yes), InvalidArgument);
  EXPECT_EQ(read_text_file(dir / "ro.csv"), "keep\n");

  write_text_file(dir / "x.csv", "1\n", Overwrite::no);
  ASSERT_EQ(::chmod((dir / "x.csv").c_str(), 0640), 0);
  write_text_file(dir / "x.csv", "2\n", Overwrite::yes);
  struct stat info {};
  ASSERT_EQ(::stat((dir / "x.csv").c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0640u);
}

TEST(WriteTextFile, NoTemporaryIsLeftBehindAndNoneIsPendingAfterwards) {
  const testing::TestDirectory dir;
  write_text_file(dir / "a.csv", "1\n", Overwrite::no);
  remove_pending_temporaries();  // nothing pending: removes nothing
  int files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    ++files;
  }
  EXPECT_EQ(files, 1);
  EXPECT_EQ(read_text_file(dir / "a.csv"), "1\n");
}

// A process id that is certainly not running: a child that has exited and been reaped.
pid_t dead_process_id() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  int status = 0;
  ::waitpid(child, &status, 0);
  return child;
}

// Issue 33: temporaries of a process killed with -9 (no handler ran) are removed by the next
// write of the same file; a live process's temporary and other files' temporaries are not.
TEST(WriteTextFile, ADeadProcesssTemporaryIsRemovedByTheNextWrite) {
  const testing::TestDirectory dir;
  const std::string dead = std::to_string(dead_process_id());
  const std::string alive = std::to_string(::getppid());
  write_text_file(dir / ("a.json.tmp-" + dead + "-0"), "half", Overwrite::no);
  write_text_file(dir / ("a.json.tmp-" + alive + "-3"), "busy", Overwrite::no);
  write_text_file(dir / ("b.json.tmp-" + dead + "-1"), "other", Overwrite::no);
  write_text_file(dir / "a.json", "{}\n", Overwrite::no);
  EXPECT_FALSE(std::filesystem::exists(dir / ("a.json.tmp-" + dead + "-0")));
  EXPECT_TRUE(std::filesystem::exists(dir / ("a.json.tmp-" + alive + "-3")));
  EXPECT_TRUE(std::filesystem::exists(dir / ("b.json.tmp-" + dead + "-1")));
  // A folder sweep (what ctid batch does once) removes every dead one and keeps the rest.
  remove_dead_temporaries_in(dir.path());
  EXPECT_FALSE(std::filesystem::exists(dir / ("b.json.tmp-" + dead + "-1")));
  EXPECT_TRUE(std::filesystem::exists(dir / ("a.json.tmp-" + alive + "-3")));
  EXPECT_EQ(read_text_file(dir / "a.json"), "{}\n");
}

}  // namespace
}  // namespace ctid::io::file_test
