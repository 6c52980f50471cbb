// Whole-file text input and output for the io layer. Errors name the file. Writes go to a
// temporary file beside the target and are then moved into place, so a reader never sees
// a half-written file, and an existing file is replaced only when the caller asks for it.
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
/// (the message names the path and the reason).
std::string read_text_file(const std::filesystem::path& path);

/// Writes `content` to `path` through a temporary file in the same directory. With
/// Overwrite::no an existing `path` is left untouched and InvalidArgument is thrown (the
/// check and the move are one atomic step where the file system supports hard links).
/// The parent directory must exist (InvalidArgument otherwise). Throws IoError when the
/// write itself fails.
void write_text_file(const std::filesystem::path& path, std::string_view content,
                     Overwrite overwrite = Overwrite::no);

}  // namespace ctid::io
