// A progress line for long runs of a ctid command: "ctid fit: delay scan 12/40 (30 %), 5 s" on
// stderr, rewritten in place with '\r'. It is shown only when stderr is a terminal and the
// command is not quiet, and only once the run has lasted CTID_PROGRESS_AFTER seconds (default
// 2; 0 shows it at once), so short runs and logs or pipes never see it. The line is cleared
// before the command prints anything else (clear(), or when the Progress is destroyed, also on
// an error). The library reports progress through optional std::function<void(int, int)>
// arguments; this is the one place that prints it.
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <mutex>
#include <optional>
#include <string>

namespace ctid::cli {

class Progress {
 public:
  /// `command` names the line ("ctid fit"); `quiet` (-q) turns it off.
  Progress(std::string command, bool quiet);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// A callback for the library that reports "<command>: <what> done/total (p %), s s"; empty
  /// when the line is off.
  std::function<void(int, int)> callback(std::string what);
  /// Shows "<command>: <what> done/total (p %), s s" (s: seconds since the Progress was made) if
  /// the line is on and the threshold has passed.
  /// Safe to call from several threads.
  void update(const std::string& what, int done, int total);
  /// Erases the line if one was shown (the next output starts at the left margin).
  void clear();

  /// Whether a line would ever be shown (stderr a terminal, not quiet).
  bool enabled() const { return enabled_; }

 private:
  std::string command_;
  bool enabled_ = false;
  std::chrono::steady_clock::duration after_{};
  std::chrono::steady_clock::time_point start_;
  std::optional<std::chrono::steady_clock::time_point> last_shown_;
  std::size_t width_ = 0;  // characters of the line on screen
  std::mutex mutex_;
};

/// Seconds a run lasts before its progress line appears: CTID_PROGRESS_AFTER if it holds a
/// non-negative number, else 2.
double progress_after_seconds();

}  // namespace ctid::cli
