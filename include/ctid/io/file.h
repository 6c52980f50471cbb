// Whole-file text input and output for the io layer. Errors name the file. Writes go to a
// temporary file beside the target and are then moved into place, so a reader never sees
// a half-written file, and an existing file is replaced only when the caller asks for it.
// Symbolic links are followed, never replaced; streams (devices, pipes) are written into
// (docs/decisions/0021-output-targets.md).
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace ctid::io {

/// The operating system failed a read or write that the caller could not have foreseen
/// (disk full, permission lost mid-way). Bad input, such as a missing input file or an
/// output that exists, is ctid::InvalidArgument instead.
class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Whether an existing output file may be replaced.
enum class Overwrite { no, yes };

/// The whole file as text. Throws InvalidArgument if it does not exist or cannot be opened
/// (the message names the path and the reason), if it is a device other than a terminal
/// (/dev/zero would be read until memory ran out), or if a pipe or terminal gives more than
/// 1 GiB.
std::string read_text_file(const std::filesystem::path& path);

/// Writes `content` to `path` through a temporary file in the same directory. With
/// Overwrite::no an existing `path` is left untouched and InvalidArgument is thrown (the
/// check and the move are one atomic step where the file system supports hard links).
/// The parent directory must exist (InvalidArgument otherwise). Throws IoError when the
/// write itself fails.
///
/// What `path` names decides how it is written (decision 0021):
/// - a symbolic link: the file it finally names is written (through a temporary beside that
///   file); the link stays;
/// - a character device or a pipe (/dev/null, a terminal, a FIFO), or an open descriptor
///   through /proc (/dev/stdout redirected to a file): appended to in place, without
///   Overwrite and without creating, truncating or renaming anything;
/// - a block device, a socket or anything else that is not a regular file: InvalidArgument;
/// - a read-only regular file: InvalidArgument even with Overwrite::yes; a replaced file
///   keeps its permissions.
/// The temporary is flushed to the disk (fsync) before it takes the target's name, and the
/// folder after, so a crash leaves the old file or the new one, never a partial one; dead
/// processes' temporaries of the same target are removed first.
void write_text_file(const std::filesystem::path& path, std::string_view content,
                     Overwrite overwrite = Overwrite::no);

/// InvalidArgument ("permission denied: ...") when this user could not write `path`: an
/// existing regular file it may not write (even where its folder would let a rename replace
/// it), or a folder it may not write into. write_text_file checks it; commands call it before
/// their work so that the refusal comes first. Streams and missing folders are left to
/// write_text_file.
void check_permission_to_write(const std::filesystem::path& path);

/// Removes the temporary files that writes in progress have created. Async-signal-safe:
/// meant for a SIGINT/SIGTERM handler, which then ends the process (the CLI installs one).
void remove_pending_temporaries() noexcept;

/// Removes from `folder` every temporary "<file>.tmp-<pid>-<n>" whose process no longer runs
/// (write_text_file does so for its own target, unless CTID_NO_TEMPORARY_SWEEP is set).
void remove_dead_temporaries_in(const std::filesystem::path& folder);

}  // namespace ctid::io
