// write_text_file must never replace what a user had: an existing device, pipe or socket
// given as output (/dev/null, /dev/stdout, a FIFO) is written into, not renamed over.
#include "ctid/io/file.h"

#include <array>
#include <filesystem>
#include <string>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "io/test_directory.h"

namespace ctid::io {
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

}  // namespace
}  // namespace ctid::io
