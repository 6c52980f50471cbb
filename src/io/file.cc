#include "ctid/io/file.h"

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <system_error>

#include <unistd.h>

#include "ctid/core/error.h"

namespace ctid::io {
namespace fs = std::filesystem;

std::string read_text_file(const fs::path& path) {
  std::error_code ec;
  const auto status = fs::status(path, ec);
  require(fs::exists(status), path.string(), ": no such file");
  require(!fs::is_directory(status), path.string(), ": is a directory, not a file");
  std::ifstream in(path, std::ios::binary);
  require(in.good(), path.string(), ": cannot open for reading (", std::strerror(errno), ")");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw IoError(path.string() + ": read failed");
  return buffer.str();
}

namespace {

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

}  // namespace

void write_text_file(const fs::path& path, std::string_view content, Overwrite overwrite) {
  require(!path.empty() && path.has_filename(), "output path '", path.string(),
          "' does not name a file");
  const fs::path parent = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  std::error_code ec;
  require(fs::is_directory(parent, ec), path.string(), ": directory '", parent.string(),
          "' does not exist");
  require(!fs::is_directory(path, ec), path.string(), ": is a directory, not a file");
  const fs::file_status status = fs::status(path, ec);
  if (fs::exists(status) && !fs::is_regular_file(status)) {
    // A device, pipe or socket (/dev/null, /dev/stdout, a FIFO): write into it. Moving a
    // temporary file over it would replace the node itself, and nothing is overwritten here.
    std::ofstream out(path, std::ios::binary);
    if (!out) {
      throw IoError(path.string() + ": cannot open for writing (" + std::strerror(errno) + ")");
    }
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    out.flush();
    if (!out) throw IoError(path.string() + ": write failed (" + std::strerror(errno) + ")");
    return;
  }
  require(overwrite == Overwrite::yes || !fs::exists(status), path.string(),
          ": file exists and overwriting was not requested");

  const fs::path temporary = temporary_path_for(path);
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) {
      throw IoError(path.string() + ": cannot create temporary file '" + temporary.string() +
                    "' (" + std::strerror(errno) + ")");
    }
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    out.flush();
    if (!out) {
      out.close();
      remove_quietly(temporary);
      throw IoError(path.string() + ": write failed (" + std::strerror(errno) + ")");
    }
  }

  if (overwrite == Overwrite::yes) {
    fs::rename(temporary, path, ec);
    if (ec) {
      remove_quietly(temporary);
      throw IoError(path.string() + ": cannot move the temporary file into place (" + ec.message() +
                    ")");
    }
    return;
  }
  // A hard link fails if the target exists, so "check, then move" cannot race with another
  // writer. File systems without hard links fall back to an existence check and a rename.
  fs::create_hard_link(temporary, path, ec);
  if (!ec) {
    remove_quietly(temporary);
    return;
  }
  if (ec == std::errc::file_exists) {
    remove_quietly(temporary);
    throw InvalidArgument(path.string() + ": file exists and overwriting was not requested");
  }
  std::error_code exists_ec;
  if (fs::exists(path, exists_ec)) {
    remove_quietly(temporary);
    throw InvalidArgument(path.string() + ": file exists and overwriting was not requested");
  }
  fs::rename(temporary, path, ec);
  if (ec) {
    remove_quietly(temporary);
    throw IoError(path.string() + ": cannot move the temporary file into place (" + ec.message() +
                  ")");
  }
}

}  // namespace ctid::io
