#include "ctid/io/file.h"

#include <array>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <system_error>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "ctid/core/error.h"

namespace ctid::io {
namespace fs = std::filesystem;

namespace {
// The most read_text_file takes from a pipe or terminal, whose size is not known up front.
constexpr size_t kMaxStreamBytes = size_t{1} << 30;
}  // namespace

std::string read_text_file(const fs::path& path) {
  std::error_code ec;
  const auto status = fs::status(path, ec);
  require(fs::exists(status), path.string(), ": no such file");
  require(!fs::is_directory(status), path.string(), ": is a directory, not a file");
  // A device other than a terminal (/dev/zero, /dev/urandom, a disk) never ends or is not a
  // document: reading it whole grew the string until memory ran out. Pipes and terminals
  // (`ctid fit /dev/stdin`) are read as streams, at most kMaxStreamBytes.
  if (fs::is_character_file(status) || fs::is_block_file(status)) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_NOCTTY | O_NONBLOCK);
    const bool terminal = fd >= 0 && ::isatty(fd) == 1;
    if (fd >= 0) ::close(fd);
    require(terminal, path.string(),
            ": is a device, not a file (give a file, a pipe or a terminal)");
  }
  std::ifstream in(path, std::ios::binary);
  require(in.good(), path.string(), ": cannot open for reading (", std::strerror(errno), ")");
  // Read in blocks straight into the string (a regular file's size reserved up front):
  // a stringstream copy doubled the cost of reading a long record.
  std::string content;
  if (fs::is_regular_file(status)) {
    const std::uintmax_t size = fs::file_size(path, ec);
    if (!ec) content.reserve(static_cast<size_t>(size));
  }
  std::array<char, 1 << 16> block;
  const bool stream = !fs::is_regular_file(status);
  while (in.read(block.data(), block.size()) || in.gcount() > 0) {
    content.append(block.data(), static_cast<size_t>(in.gcount()));
    require(!stream || content.size() <= kMaxStreamBytes, path.string(), ": more than ",
            kMaxStreamBytes >> 20,
            " MiB from a pipe or terminal; ctid reads at most that from a stream (save it to "
            "a file)");
  }
  if (in.bad()) throw IoError(path.string() + ": read failed");
  return content;
}

namespace {

// Temporaries being written, so that a signal handler can remove them
// (remove_pending_temporaries). Fixed-size slots: the handler may neither allocate nor lock.
constexpr size_t kTemporarySlots = 64;
constexpr size_t kTemporaryPathBytes = 4096;
std::array<std::atomic<int>, kTemporarySlots> slot_state{};  // 0 free, 1 claimed, 2 pending
std::array<std::array<char, kTemporaryPathBytes>, kTemporarySlots> slot_path{};

// Remembers `path` until the returned guard is destroyed; paths that do not fit (or when
// every slot is taken) are simply not remembered.
class PendingTemporary {
 public:
  explicit PendingTemporary(const fs::path& path) {
    const std::string& text = path.native();
    if (text.size() >= kTemporaryPathBytes) return;
    for (size_t i = 0; i < kTemporarySlots; ++i) {
      int expected = 0;
      if (slot_state[i].compare_exchange_strong(expected, 1)) {
        std::memcpy(slot_path[i].data(), text.c_str(), text.size() + 1);
        slot_state[i].store(2);
        slot_ = static_cast<int>(i);
        return;
      }
    }
  }
  ~PendingTemporary() {
    if (slot_ >= 0) slot_state[static_cast<size_t>(slot_)].store(0);
  }
  PendingTemporary(const PendingTemporary&) = delete;
  PendingTemporary& operator=(const PendingTemporary&) = delete;

 private:
  int slot_ = -1;
};

// A name for the temporary file that no other writer in this or another process picks.
fs::path temporary_path_for(const fs::path& path) {
  static std::atomic<unsigned> counter{0};
  const std::string suffix = ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
  return path.parent_path() / (path.filename().string() + suffix);
}

void remove_quietly(const fs::path& path) {
  std::error_code ignored;
  fs::remove(path, ignored);
}

// The process id in a temporary's name "<file>.tmp-<pid>-<n>", or 0 when `name` is not one
// of `file`'s temporaries.
pid_t temporary_owner(const std::string& name, const std::string& file) {
  const std::string prefix = file + ".tmp-";
  if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) return 0;
  pid_t pid = 0;
  std::size_t at = prefix.size();
  for (; at < name.size() && name[at] >= '0' && name[at] <= '9'; ++at) {
    if (pid > 100000000) return 0;
    pid = pid * 10 + (name[at] - '0');
  }
  return at < name.size() && name[at] == '-' ? pid : 0;
}

// Removes from `folder` the temporaries of `file` (of every file when `file` is empty) left
// by processes that no longer run.
void remove_dead_temporaries_of(const fs::path& folder, const std::string& file) {
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    const std::size_t tmp = file.empty() ? name.rfind(".tmp-") : file.size();
    if (tmp == std::string::npos || tmp == 0) continue;
    const pid_t owner = temporary_owner(name, name.substr(0, tmp));
    if (owner > 0 && owner != ::getpid() && (file.empty() || name.compare(0, tmp, file) == 0) &&
        ::kill(owner, 0) != 0 && errno == ESRCH) {
      remove_quietly(it->path());
    }
  }
}

// Removes the temporaries of `target` left by processes that no longer run (killed with -9
// or by a power cut, so no handler removed them). A batch sweeps its folder once and tells
// its records not to (CTID_NO_TEMPORARY_SWEEP), which keeps a large batch linear.
void remove_dead_temporaries(const fs::path& target) {
  if (std::getenv("CTID_NO_TEMPORARY_SWEEP") != nullptr) return;
  const fs::path parent = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  remove_dead_temporaries_of(parent, target.filename().string());
}

// Writes `content` to a new file and flushes it to the disk, so that the rename that follows
// never puts an empty or partial file in the target's place after a crash.
void write_new_file_durably(const fs::path& temporary, std::string_view content,
                            const fs::path& path) {
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0) {
    throw IoError(path.string() + ": cannot create temporary file '" + temporary.string() + "' (" +
                  std::strerror(errno) + ")");
  }
  size_t written = 0;
  int error = 0;
  while (written < content.size()) {
    const ssize_t n = ::write(fd, content.data() + written, content.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      error = n < 0 ? errno : ENOSPC;
      break;
    }
    written += static_cast<size_t>(n);
  }
  if (error == 0 && ::fsync(fd) != 0 && errno != EINVAL) error = errno;
  if (::close(fd) != 0 && error == 0 && errno != EINTR) error = errno;
  if (error != 0) {
    remove_quietly(temporary);
    throw IoError(path.string() + ": write failed (" + std::strerror(error) + ")");
  }
}

// Flushes a folder's entries, so a rename into it survives a crash (errors ignored: some file
// systems cannot sync a folder, and the file itself is already on the disk).
void sync_folder(const fs::path& folder) {
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

// Follows the chain of symbolic links that starts at `path` (at most 40 links, as the
// kernel does). `through_proc` is set when a link leads into /proc: /dev/stdout and
// /dev/fd/N name an open file descriptor of the process, a stream, whatever file is
// behind it.
fs::path resolve_links(const fs::path& path, bool& through_proc) {
  fs::path current = path;
  through_proc = false;
  for (int hop = 0; hop < 40; ++hop) {
    std::error_code ec;
    if (!fs::is_symlink(fs::symlink_status(current, ec))) return current;
    const fs::path target = fs::read_symlink(current, ec);
    if (ec) return current;
    current = target.is_absolute() ? target : current.parent_path() / target;
    const std::string text = current.lexically_normal().string();
    if (text.rfind("/proc/", 0) == 0) through_proc = true;
  }
  throw InvalidArgument(path.string() + ": too many levels of symbolic links");
}

std::string kind_of_node(const fs::file_status& status) {
  if (fs::is_block_file(status)) return "a block device";
  if (fs::is_socket(status)) return "a socket";
  if (fs::is_character_file(status)) return "a character device";
  if (fs::is_fifo(status)) return "a pipe";
  return "not a regular file";
}

// Appends `content` to a stream the user named (a character device, a pipe, an open file
// descriptor through /dev/stdout): nothing is created, truncated or renamed.
void write_into_stream(const fs::path& path, std::string_view content) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) {
    throw IoError(path.string() + ": cannot open for writing (" + std::strerror(errno) + ")");
  }
  size_t written = 0;
  while (written < content.size()) {
    const ssize_t n = ::write(fd, content.data() + written, content.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = errno;
      ::close(fd);
      throw IoError(path.string() + ": write failed (" + std::strerror(error) + ")");
    }
    written += static_cast<size_t>(n);
  }
  ::close(fd);
}

}  // namespace

void remove_dead_temporaries_in(const fs::path& folder) { remove_dead_temporaries_of(folder, ""); }

void remove_pending_temporaries() noexcept {
  for (size_t i = 0; i < kTemporarySlots; ++i) {
    if (slot_state[i].load() == 2) ::unlink(slot_path[i].data());
  }
}

void check_permission_to_write(const fs::path& path) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (fs::exists(status) && !fs::is_regular_file(status)) return;  // a stream or a folder
  bool through_proc = false;
  const fs::path target = resolve_links(path, through_proc);
  if (through_proc) return;
  const fs::path parent = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  // Permissions answer for the user (issue 33): a file this user may not write is refused even
  // when the folder would let a rename replace it (it belonged to another user), and a folder
  // this user may not write into is bad input named as such, not a failed temporary.
  struct stat existing {};
  if (fs::exists(status) && ::stat(target.c_str(), &existing) == 0 &&
      ::faccessat(AT_FDCWD, target.c_str(), W_OK, AT_EACCESS) != 0 && errno == EACCES) {
    throw InvalidArgument(path.string() + ": permission denied: the file belongs to user " +
                          std::to_string(existing.st_uid) +
                          " and this user may not write it; ctid does not replace it");
  }
  if (::faccessat(AT_FDCWD, parent.c_str(), W_OK | X_OK, AT_EACCESS) != 0 && errno == EACCES) {
    const std::string what = ": permission denied: this user may not write into the folder '";
    throw InvalidArgument(path.string() + what + parent.string() + "'");
  }
}

void write_text_file(const fs::path& path, std::string_view content, Overwrite overwrite) {
  require(!path.empty() && path.has_filename(), "output path '", path.string(),
          "' does not name a file");
  std::error_code ec;
  require(!fs::is_directory(path, ec), path.string(), ": is a directory, not a file");
  const fs::file_status status = fs::status(path, ec);
  bool through_proc = false;
  // A symbolic link is never replaced: the file it names is written instead.
  const fs::path target = resolve_links(path, through_proc);
  if (fs::exists(status) && !fs::is_regular_file(status)) {
    // Streams the user meant (/dev/null, a terminal, a FIFO, /dev/stdout onto a pipe) are
    // written into; other nodes (a block device, a socket) are refused. Moving a temporary
    // over either would replace the node itself (decision 0021).
    require(fs::is_character_file(status) || fs::is_fifo(status), path.string(), ": is ",
            kind_of_node(status),
            "; ctid writes regular files, character devices (/dev/null, a terminal) and pipes");
    write_into_stream(path, content);
    return;
  }
  if (through_proc && fs::exists(status)) {
    // /dev/stdout redirected to a file (ctid ... -o /dev/stdout > out.csv): the shell opened
    // that file; append to the descriptor rather than rename anything (decision 0021).
    write_into_stream(path, content);
    return;
  }
  const fs::path parent = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  require(fs::is_directory(parent, ec), path.string(), ": directory '", parent.string(),
          "' does not exist");
  require(overwrite == Overwrite::yes || !fs::exists(status), path.string(),
          ": file exists and overwriting was not requested");
  struct stat existing {};
  const bool replacing = fs::exists(status) && ::stat(target.c_str(), &existing) == 0;
  // A read-only file is one the user protected: --force does not override that.
  require(!replacing || (existing.st_mode & 0222) != 0, path.string(),
          ": file is read-only; make it writable first to replace it");
  check_permission_to_write(path);

  remove_dead_temporaries(target);
  const fs::path temporary = temporary_path_for(target);
  const PendingTemporary pending(temporary);
  write_new_file_durably(temporary, content, path);
  // The replaced file keeps its permissions.
  if (replacing) ::chmod(temporary.c_str(), existing.st_mode & 07777);

  if (overwrite == Overwrite::yes) {
    fs::rename(temporary, target, ec);
    if (ec) {
      remove_quietly(temporary);
      throw IoError(path.string() + ": cannot move the temporary file into place (" + ec.message() +
                    ")");
    }
    sync_folder(parent);
    return;
  }
  // A hard link fails if the target exists, so "check, then move" cannot race with another
  // writer. File systems without hard links fall back to an existence check and a rename.
  fs::create_hard_link(temporary, target, ec);
  if (!ec) {
    remove_quietly(temporary);
    sync_folder(parent);
    return;
  }
  if (ec == std::errc::file_exists) {
    remove_quietly(temporary);
    throw InvalidArgument(path.string() + ": file exists and overwriting was not requested");
  }
  std::error_code exists_ec;
  if (fs::exists(target, exists_ec)) {
    remove_quietly(temporary);
    throw InvalidArgument(path.string() + ": file exists and overwriting was not requested");
  }
  fs::rename(temporary, target, ec);
  if (ec) {
    remove_quietly(temporary);
    throw IoError(path.string() + ": cannot move the temporary file into place (" + ec.message() +
                  ")");
  }
  sync_folder(parent);
}

}  // namespace ctid::io
