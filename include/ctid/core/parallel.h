// A parallel loop whose outcome does not depend on the number of threads: indices handed out
// in increasing order, each body writing only to storage owned by its index. Studies run their
// cases with it, and the scans of the estimators (delays, structures) their fits.
#pragma once

#include <functional>
#include <memory>

namespace ctid {

/// The worker count used for `threads`: `threads` itself if > 0, otherwise
/// std::thread::hardware_concurrency() (at least 1).
int resolve_thread_count(int threads);

/// The threads worth starting now for work that could use every core: the caller's own plus
/// the cores the one-minute load average leaves idle, between 1 and
/// resolve_thread_count(0). A team of threads that meet every few tens of microseconds runs
/// slower than one thread on a core another process keeps busy (decision 0068).
int idle_thread_count();

/// Calls body(i) for every i in [0, count) on up to `threads` threads (0: all cores). Indices
/// are handed out in increasing order; body must write only to storage owned by index i,
/// which makes the outcome independent of the thread count. The first exception thrown by a
/// body is rethrown after all threads have stopped (remaining indices are skipped).
void parallel_for(int count, int threads, const std::function<void(int)>& body);

/// Whether the calling thread is running a body of parallel_for (on one thread or several) or
/// is a worker of a ThreadTeam: code that could split its own work over threads
/// (RefinedIvOptions::threads) then runs on one, rather than nesting parallel loops.
bool inside_parallel_loop();

/// A team of threads kept for many short parallel loops in a row (the phases of one estimate's
/// passes over a long record), so that no thread is started per loop. run() hands the indices
/// out as parallel_for does, with the same contract: body(i) writes only to storage owned by i,
/// so the outcome does not depend on the team's size. Not reentrant: one run() at a time.
class ThreadTeam {
 public:
  /// `threads` participants in every run(), the calling thread included (>= 1; 1 starts no
  /// thread and runs every body on the caller).
  explicit ThreadTeam(int threads);
  ~ThreadTeam();
  ThreadTeam(const ThreadTeam&) = delete;
  ThreadTeam& operator=(const ThreadTeam&) = delete;

  int size() const;
  /// body(i) for every i in [0, count); returns when all have returned. The first exception a
  /// body throws is rethrown here once every participant has stopped.
  void run(int count, const std::function<void(int)>& body);

 private:
  struct Shared;
  std::unique_ptr<Shared> shared_;
};

}  // namespace ctid
