#include "progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <utility>

#include "command.h"

namespace ctid::cli {
namespace {

// Redrawn at most this often (a scan may report hundreds of steps a second).
constexpr std::chrono::milliseconds kRedrawInterval{100};

}  // namespace

double progress_after_seconds() {
  constexpr double kDefault = 2.0;
  const char* text = std::getenv("CTID_PROGRESS_AFTER");
  if (text == nullptr) return kDefault;
  const std::optional<double> seconds = parse_number<double>(text);
  return seconds && std::isfinite(*seconds) && *seconds >= 0.0 ? *seconds : kDefault;
}

Progress::Progress(std::string command, bool quiet)
    : command_(std::move(command)),
      enabled_(!quiet && ::isatty(STDERR_FILENO) == 1),
      after_(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
          std::chrono::duration<double>(progress_after_seconds()))),
      start_(std::chrono::steady_clock::now()) {}

Progress::~Progress() { clear(); }

std::function<void(int, int)> Progress::callback(std::string what) {
  if (!enabled_) return {};
  return [this, what = std::move(what)](int done, int total) { update(what, done, total); };
}

void Progress::update(const std::string& what, int done, int total) {
  if (!enabled_ || total <= 0) return;
  const std::lock_guard<std::mutex> lock(mutex_);
  const auto now = std::chrono::steady_clock::now();
  if (now - start_ < after_) return;
  if (last_shown_ && now - *last_shown_ < kRedrawInterval && done < total) return;
  last_shown_ = now;
  std::string line =
      command_ + ": " + what + " " + std::to_string(done) + "/" + std::to_string(total) + " (" +
      std::to_string(100LL * done / total) + " %), " +
      std::to_string(std::chrono::duration_cast<std::chrono::seconds>(now - start_).count()) + " s";
  const std::size_t shown = line.size();
  if (shown < width_) line.append(width_ - shown, ' ');  // cover a longer previous line
  width_ = std::max(width_, shown);
  std::cerr << '\r' << line << std::flush;
}

void Progress::clear() {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (width_ == 0) return;
  std::cerr << '\r' << std::string(width_, ' ') << '\r' << std::flush;
  width_ = 0;
  last_shown_.reset();
}

}  // namespace ctid::cli
